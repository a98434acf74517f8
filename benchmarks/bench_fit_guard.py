"""The two-way guard on the issue-19 slender case: a blade that is not ours, reconstructed or
refused, against its exact surface.

The blade is the tests' independent construction (tests/geometry/test_fit_guard.py: NACA
2412-type sections, 0.2 mm trailing-edge radius at the root, chord and stagger linear along
the span). The cloud: points uniform over the exact surface with σ = 0.017 mm noise along the
normal, 1 % outliers 0.2–2 mm off along the normal, ten 2 mm holes — as in issue 19. Prints,
per seed, the outcome (watertight or the refusal message), the guard's figures, the wall time
and, for a watertight result, the deviation of the reconstructed surface from the exact one
(RMS and max over 100k samples) as JSON.

Run: python benchmarks/bench_fit_guard.py [--points 80000] [--seeds 0 1] [--span-mm 250]
     [--chord-mm 40 30] [--stagger 10 50]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.fidelity import distances_to_mesh, surface_samples
from steamtwin.geometry.reconstruct import reconstruct_blade

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "geometry"))
from test_fit_guard import foreign_blade, noisy_cloud  # the tests' construction


def scan_like(vertices: np.ndarray, triangles: np.ndarray, count: int, seed: int
              ) -> np.ndarray:
    """σ 0.017 mm cloud with 1 % outliers 0.2–2 mm off and ten 2 mm holes (m)."""
    rng = np.random.default_rng(seed + 1000)
    points = noisy_cloud(vertices, triangles, count, 0.017e-3, seed)
    centre = points.mean(axis=0)
    for middle in points[rng.choice(len(points), 10, replace=False)]:
        points = points[np.linalg.norm(points - middle, axis=1) > 1.0e-3]
    stray = rng.choice(len(points), len(points) // 100, replace=False)
    outward = points[stray] - centre
    outward[:, 2] = 0.0
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    points[stray] += rng.uniform(0.2e-3, 2e-3, len(stray))[:, None] * outward
    return points


def main(points: int, seeds: list[int], span: float, chords: tuple[float, float],
         stagger: tuple[float, float]) -> list[dict]:
    vertices, triangles = foreign_blade(span, chords[0], chords[1], stagger, 0.2e-3,
                                        levels=max(40, int(span / 1e-3)))
    results = []
    for seed in seeds:
        cloud = scan_like(vertices, triangles, points, seed)
        start = time.perf_counter()
        row: dict = {"seed": seed, "points": len(cloud)}
        try:
            result = reconstruct_blade(cloud)
        except ReconstructionError as error:
            row.update(outcome="refused", message=str(error),
                       seconds=time.perf_counter() - start)
            results.append(row)
            continue
        row["seconds"] = time.perf_counter() - start
        summary = result.summary()
        samples = surface_samples(result.vertices, result.triangles, 100_000,
                                  np.random.default_rng(seed))
        deviation = distances_to_mesh(samples, vertices, triangles)
        row.update(outcome="watertight",
                   deviation_rms_mm=float(np.sqrt(np.mean(deviation**2))) * 1e3,
                   deviation_max_mm=float(deviation.max()) * 1e3,
                   **{key: value for key, value in summary.items() if key.startswith("guard")
                      or key in ("side_fit_rms_mm", "patch_points")})
        results.append(row)
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=80_000)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--span-mm", type=float, default=250.0)
    parser.add_argument("--chord-mm", type=float, nargs=2, default=[40.0, 30.0])
    parser.add_argument("--stagger", type=float, nargs=2, default=[10.0, 50.0])
    args = parser.parse_args()
    print(json.dumps(main(args.points, args.seeds, args.span_mm * 1e-3,
                          (args.chord_mm[0] * 1e-3, args.chord_mm[1] * 1e-3),
                          tuple(args.stagger)), indent=2, default=str))
