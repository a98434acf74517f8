"""The blade frame from the data on every row, in random rigid poses (issue 19, item 1).

For each of the 22 rows (or those named): an 80k-point cloud of the exact surface like the
issue's fused clouds (N(0, 0.017 mm) along the normal, 1 % stray points 0.2–2 mm off), put in
``--poses`` random rigid poses (scipy's uniform random rotations, the first turned upside down:
the span axis flipped); :func:`~steamtwin.geometry.frame.estimate_blade_frame` with this
package's handedness (suction side +y) and without it. Prints one Markdown table row per row:
largest span-axis and chord-direction errors (deg) against the pose, hub/tip right in how many
poses and by which rule, hub/tip ambiguous without the handedness, largest error of the hub
cap's z (mm) and the estimate's wall time.

Run: python benchmarks/bench_frame.py [--rows hp1 ip9 ...] [--poses N] [--points N]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.spatial.transform import Rotation

from steamtwin.geometry.fidelity import chord_line, sample_triangles, truth_section
from steamtwin.geometry.frame import estimate_blade_frame
from steamtwin.geometry.profile import make_blade, reference_surface
from steamtwin.geometry.row_sizing import ROWS
from steamtwin.spec import load_spec


def fused_like_cloud(blade, count: int, rng: np.random.Generator) -> np.ndarray:
    """Exact surface points with the issue's noise and stray points (m, blade frame)."""
    vertices, triangles, _ = reference_surface(blade)
    points, _, normals = sample_triangles(vertices, triangles, count, rng)
    offset = rng.normal(0.0, 0.017e-3, count)
    stray = rng.random(count) < 0.01
    offset[stray] = rng.uniform(0.2e-3, 2e-3, stray.sum())
    return points + offset[:, None] * normals


def degrees(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(np.dot(a, b), -1.0, 1.0))))


def bench_row(spec, row: str, poses: int, points: int, seed: int = 0) -> dict:
    blade = make_blade(spec, row)
    rng = np.random.default_rng(seed)
    cloud = fused_like_cloud(blade, points, rng)
    radius = blade.design.hub_radius + 0.5 * blade.design.span
    first, second, _ = chord_line(truth_section(blade, radius))
    chord = np.append((second - first) / np.linalg.norm(second - first), 0.0)
    hub_point = np.array([*blade.profile.centroid, blade.design.hub_radius])
    axis_err, chord_err, hub_err, seconds, right, ambiguous, rules = [], [], [], [], 0, 0, set()
    rotations = Rotation.random(poses, random_state=seed).as_matrix()
    rotations[0] = rotations[0] @ np.diag([1.0, -1.0, -1.0])  # upside down
    for rotation in rotations:
        shift = rng.uniform(-0.5, 0.5, 3)
        scan = cloud @ rotation.T + shift
        start = time.perf_counter()
        frame = estimate_blade_frame(scan, suction_side="+y", keep_scan_frame=False)
        seconds.append(time.perf_counter() - start)
        span = rotation @ np.array([0.0, 0.0, 1.0])
        axis_err.append(min(degrees(frame.span_axis, span), degrees(frame.span_axis, -span)))
        chord_err.append(degrees(frame.chord_direction, rotation @ chord))
        right += int(np.dot(frame.span_axis, span) > 0.0)
        rules.add(frame.rules["hub_tip"].split(":")[0])
        hub_err.append(abs(frame.to_blade((rotation @ hub_point + shift)[None])[0, 2]))
        plain = estimate_blade_frame(scan, keep_scan_frame=False)
        ambiguous += int(plain.hub_tip_ambiguous)
    return {"row": row, "span_axis_deg": max(axis_err), "chord_deg": max(chord_err),
            "hub_tip_right": f"{right}/{poses}", "rule": "/".join(sorted(rules)),
            "ambiguous_without_handedness": f"{ambiguous}/{poses}",
            "hub_z_mm": max(hub_err) * 1e3, "seconds": max(seconds)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", nargs="*", default=list(ROWS))
    parser.add_argument("--poses", type=int, default=4)
    parser.add_argument("--points", type=int, default=80_000)
    args = parser.parse_args()
    spec = load_spec("reference")
    print("| row | span axis (°) | chord (°) | hub/tip right | rule | ambiguous without "
          "handedness | hub cap z (mm) | time (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for row in args.rows:
        r = bench_row(spec, row, args.poses, args.points)
        print(f"| {r['row']} | {r['span_axis_deg']:.3f} | {r['chord_deg']:.2f} | "
              f"{r['hub_tip_right']} | {r['rule']} | {r['ambiguous_without_handedness']} | "
              f"{r['hub_z_mm']:.3f} | {r['seconds']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
