"""Every blade row through the geometry chain: scan -> preprocessing -> reconstruction -> STL.

For each of the 13 HP rotor rows and 9 IP stator rows (or those named), runs
``bench_geometry.main(row, seed, quick=True)`` and prints one Markdown table row: STL
deviation from the exact blade (RMS, max), the worst chord / stagger / throat error over the
hub, mid and tip sections, the recovered view poses (all views) and the raw views -> STL wall
time, each against the issue's limits (RMS <= 0.02 mm, max <= 0.1 mm, chord and throat
<= 0.05 mm, stagger <= 0.1 deg, poses <= 0.02 mm / 0.01 deg, <= 60 s for a ~150k-point scan).
Each row is scanned with the points :func:`~steamtwin.geometry.scanner.planned_points` plans
(150k for hp1, up to 485k for ip9), so the wall time is judged per 150k scanned points.

A row the reconstruction refuses (``ReconstructionError``) is printed as refused with its
message and the run goes on; the exit status is 1 when any row was refused or missed a limit.
``--model-edges`` / ``--no-model-edges`` and ``--bridge-holes`` / ``--no-bridge-holes`` set
``ReconstructionSettings.model_edges`` and ``GuardSettings.bridge_holes`` (default: the
library's defaults).

Run: python benchmarks/bench_geometry_rows.py [--seed N] [--rows hp1 ip9 ...] [--json FILE]
     [--[no-]model-edges] [--[no-]bridge-holes]
(about 23 min for all 22 rows on this 2-core machine).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings

from bench_geometry import main as bench_row
from bench_geometry import settings_from
from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.row_sizing import ROWS
from steamtwin.geometry.scanner import METHOD_SCAN_POINTS

LIMITS = {"rms": 0.02, "max": 0.1, "chord": 0.05, "stagger": 0.1, "throat": 0.05,
          "pose_mm": 0.02, "pose_deg": 0.01, "seconds": 60.0}
"""The issue's acceptance limits (mm, deg; s per 150k scanned points)."""


def summarise(figures: dict) -> dict:
    """The figures of one row that the limits judge, and whether each holds."""
    reconstruction = figures["reconstruction"]
    metrics = reconstruction["metric_errors"]
    poses = figures["pose_recovery"]["all_views"]
    row = {"rms": reconstruction["deviation_mm"]["rms"],
           "max": reconstruction["deviation_mm"]["max"],
           **{name: max(abs(section[name]) for section in metrics.values())
              for name in ("chord", "stagger", "throat")},
           "pose_mm": poses["translation_max_mm"], "pose_deg": poses["rotation_max_deg"],
           "points": figures["scan_points"], "total_s": figures["raw_views_to_stl_s"],
           "seconds": figures["raw_views_to_stl_s"] * METHOD_SCAN_POINTS / figures["scan_points"]}
    row["failed"] = [name for name, limit in LIMITS.items() if not row[name] <= limit]
    return row


def main() -> int:
    """Run the rows; 1 when any row was refused or missed a limit, else 0."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="scan seed")
    parser.add_argument("--rows", nargs="+", default=list(ROWS), choices=ROWS, metavar="ROW")
    parser.add_argument("--json", help="also write one JSON line per row to this file")
    parser.add_argument("--model-edges", action=argparse.BooleanOptionalAction, default=None,
                        help="fit sparse edges as circles tangent to both flanks "
                             "(ReconstructionSettings.model_edges; default: the library's)")
    parser.add_argument("--bridge-holes", action=argparse.BooleanOptionalAction, default=None,
                        help="the guard takes a vertex across a scan hole as bridged "
                             "(GuardSettings.bridge_holes; default: the library's)")
    arguments = parser.parse_args()
    settings = settings_from(arguments.model_edges, arguments.bridge_holes)
    warnings.simplefilter("ignore")
    guard = settings.guard
    print(f"seed {arguments.seed}, model_edges {settings.model_edges}, bridge_holes "
          f"{guard.bridge_holes if guard else None}\n")
    print("| row | scan points | RMS / max mm | chord mm | stagger ° | throat mm | poses mm / ° "
          "| raw → STL s (per 150k) | meets the limits |")
    print("|---|---|---|---|---|---|---|---|---|")
    lines, bad = [], 0
    for name in arguments.rows:
        try:
            row = summarise(bench_row(name, arguments.seed, quick=True, settings=settings))
        except ReconstructionError as error:
            bad += 1
            print(f"| {name} | | | | | | | | refused: {error} |", flush=True)
            lines.append(json.dumps({"row": name, "seed": arguments.seed,
                                     "refused": str(error)}))
            continue
        bad += bool(row["failed"])
        verdict = "✓" if not row["failed"] else "✗ " + ", ".join(row["failed"])
        print(f"| {name} | {row['points']} | {row['rms']:.4f} / {row['max']:.3f} "
              f"| {row['chord']:.3f} | {row['stagger']:.3f} | {row['throat']:.3f} "
              f"| {row['pose_mm']:.4f} / {row['pose_deg']:.4f} | {row['total_s']:.0f} "
              f"({row['seconds']:.0f}) | {verdict} |", flush=True)
        lines.append(json.dumps({"row": name, "seed": arguments.seed, **row}))
    if arguments.json:
        with open(arguments.json, "w", encoding="utf-8") as stream:
            stream.write("\n".join(lines) + "\n")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
