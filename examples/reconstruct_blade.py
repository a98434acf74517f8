"""Reconstruct a turbine blade from a 3-D scan: point cloud → watertight STL + deviation.

What it shows: the reverse geometric modelling chain of ``steamtwin.geometry`` from Python,
on a blade whose exact shape is known, so the reconstruction's error can be measured.

1. The exact blade of a row (``make_blade``: Pritchard sections sized from the turbine spec;
   the first HP rotor row ``hp1`` by default) is scanned by the virtual handheld scanner:
   partial views with self-occlusion, ±0.05 mm range noise, outliers, reference spheres on the
   fixture and the scanner's own (slightly wrong) pose of each view. The views are written as
   PLY files, as a real scanner exports them.
2. Cleaning and registration: reference spheres found and removed, statistical outliers
   removed, MLS smoothing, joint multi-view ICP (the spheres' centres as datums), fusion and
   feature-preserving downsampling; the fused cloud is written as ``fused.ply``.
3. The cloud is best-fitted to the nominal blade (its frame), segmented by region growing
   (pressure and suction sides, edges, root and tip caps), the side fitted by a periodic
   B-spline surface and closed by the caps: ``blade.stl`` (binary, m, watertight).
4. The STL's deviation from the exact blade (mean, RMS, 95th percentile, max, Hausdorff),
   the row metrics (chord, stagger, throat …) of the reconstructed sections against the exact
   ones, and the deviation map are printed and written (``deviation.json``, ``.csv``, ``.png``).

Your own scan enters at step 2 (``read_point_cloud`` reads PLY/PCD/XYZ views) or, already
fused, at step 3.

How long (CPU time, measured on a 2-core x86_64): ``--quick`` (20 000 scan points) about
30 s; the default (the method's 150 000 points) about a minute (docs/benchmarks.md, "Geometry").

    python examples/reconstruct_blade.py --quick --out blade-output [--row hp5]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import steamtwin
from steamtwin.geometry.pointcloud import write_point_cloud
from steamtwin.geometry.workflow import (
    preprocess_scan,
    reconstruct_cloud,
    report_reconstruction,
    scan_row,
    write_blade_stl,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("blade-output"),
                        help="folder for the scan, the fused cloud, the STL and the reports")
    parser.add_argument("--row", default="hp1", help="blade row of the reference unit")
    parser.add_argument("--quick", action="store_true",
                        help="20 000 scan points (seconds, for tests)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the virtual scanner")
    args = parser.parse_args()

    points = 20_000 if args.quick else 150_000
    scan = scan_row(steamtwin.load_spec("reference"), args.row, args.out / "scan",
                    points=points, random_state=args.seed)
    print(f"scan of {args.row}: {scan.points} points in {len(scan.scan.views)} views → "
          f"{args.out / 'scan'}")

    fused = preprocess_scan(scan.scan)  # spheres, outliers, MLS, joint ICP, fusion
    steps = fused.report
    write_point_cloud(fused.cloud, args.out / "fused.ply")
    print(f"cleaned and registered: {sum(steps.spheres_found)} sphere sightings, "
          f"{sum(steps.outliers_removed)} outliers removed, {sum(steps.input_points)} → "
          f"{len(fused.cloud)} points (joint ICP RMS {steps.joint_rms * 1e3:.4f} mm)")

    result = reconstruct_cloud(fused.cloud, scan.blade)  # best fit to the nominal, then fit
    stl = write_blade_stl(result, args.out / "blade.stl")
    summary = result.reconstruction.summary()
    print(f"reconstructed: {summary['triangles']} triangles, {summary['volume_cm3']:.3f} cm³ "
          f"(exact blade {scan.blade.volume * 1e6:.3f} cm³), side fit RMS "
          f"{summary['side_fit_rms_mm']:.4f} mm → {stl}")

    report = report_reconstruction(result, args.out / "deviation", scan.blade)
    d = report.fidelity.deviation
    print(f"deviation from the exact blade (mm): mean {d.mean * 1e3:.4f}, RMS "
          f"{d.rms * 1e3:.4f}, p95 {d.p95 * 1e3:.4f}, max {d.max * 1e3:.4f}, Hausdorff "
          f"{d.hausdorff * 1e3:.4f}")
    print("row metrics at mid-span (truth → measured):")
    for row in report.fidelity.metric_rows():
        print(f"  {row['metric']:<20}{row['truth']:>10.4f} → {row['measured']:>10.4f} "
              f"{row['unit']}")
    print(f"deviation report: {report.json}, {report.csv}; deviation map: {report.png}")


if __name__ == "__main__":
    main()
