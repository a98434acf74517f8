"""Verification and timing of the rotor's axisymmetric thermo-elastic stress solver.

Run: python benchmarks/bench_rotor_stress.py [--nodes 5000] — prints

1. the point-stress error of a long hollow cylinder (b/a = 5, parabolic ΔT, free ends =
   generalized plane strain) against Timoshenko & Goodier §151 at the bore and the outer
   surface, on meshes halving h, and the observed order (P2 theory: 2);
2. the time to build the solver, the first solve (assembly + LU), a repeat solve (LU reused)
   and the affine stress operator at four points by adjoint solves, on a section of about
   ``--nodes`` nodes, wall and CPU time, with the machine's load.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.integrate import quad
from skfem import MeshTri

from steamtwin.rotor.elasticity import RATED_SPEED, AxisymmetricElasticity
from steamtwin.rotor.material import REFERENCE_TEMPERATURE, ConstantMaterial

E, NU, ALPHA = 2.1e11, 0.3, 1.2e-5
STEEL = ConstantMaterial("steel", 7850.0, 460.0, 40.0, E, NU, ALPHA)
INNER, OUTER = 0.1, 0.5


def rise(r: np.ndarray) -> np.ndarray:
    return 80.0 * ((r - INNER) / (OUTER - INNER)) ** 2


def exact(r: float) -> np.ndarray:
    """σ_r, σ_θ, σ_z (Pa) of the long hollow cylinder, free ends (T&G eqs. 247–249)."""
    scale = ALPHA * E / (1 - NU)
    total = quad(lambda s: rise(s) * s, INNER, OUTER)[0] / (OUTER ** 2 - INNER ** 2)
    partial = quad(lambda s: rise(s) * s, INNER, r)[0] / r ** 2
    return scale * np.array([(1 - INNER ** 2 / r ** 2) * total - partial,
                             (1 + INNER ** 2 / r ** 2) * total + partial - rise(r),
                             2 * total - rise(r)])


def convergence() -> None:
    points = np.array([[INNER, 0.02], [OUTER, 0.02]])
    expected = np.array([exact(r) for r in points[:, 0]]).T
    print("n_radial  h (m)     bore σθ err  surface σθ err  max err / max|σ|")
    sizes, errors = [], []
    for n in (6, 12, 24, 48, 96):
        mesh = MeshTri.init_tensor(np.linspace(INNER, OUTER, n + 1), np.linspace(0, 0.05, 3))
        model = AxisymmetricElasticity(mesh, STEEL)
        state = model.stress(model.solve(REFERENCE_TEMPERATURE + rise(mesh.p[0]), 0.0), points)
        got = np.array([state.radial, state.hoop, state.axial])
        error = np.abs(got - expected)
        sizes.append((OUTER - INNER) / n)
        errors.append(error.max())
        print(f"{n:8d}  {sizes[-1]:.5f}  {error[1, 0] / abs(expected[1, 0]):11.2e}  "
              f"{error[1, 1] / abs(expected[1, 1]):14.2e}  "
              f"{error.max() / np.abs(expected).max():.2e}")
    orders = np.diff(np.log(errors)) / np.diff(np.log(sizes))
    print("observed orders (max error):", " ".join(f"{o:.2f}" for o in orders))


def timing(nodes: int) -> None:
    side = int(np.sqrt(nodes / 2.0))
    mesh = MeshTri.init_tensor(np.linspace(INNER, OUTER, side + 1),
                               np.linspace(0.0, 0.8, 2 * side + 1))
    field = REFERENCE_TEMPERATURE + 200.0 + rise(mesh.p[0]) + 50.0 * np.sin(mesh.p[1] * 8)
    points = [[INNER, 0.4], [OUTER, 0.4], [0.3, 0.4], [OUTER, 0.0]]
    marks = []

    def timed(label, step):
        wall, cpu = time.perf_counter(), time.process_time()
        result = step()
        marks.append((label, time.perf_counter() - wall, time.process_time() - cpu))
        return result

    model = timed("build (basis, constraints, centrifugal load)",
                  lambda: AxisymmetricElasticity(mesh, STEEL))
    timed("first solve (assembly + LU)", lambda: model.solve(field, RATED_SPEED))
    timed("repeat solve (LU reused)", lambda: model.solve(field + 1.0, RATED_SPEED))
    timed("stress operator, 4 points (16 adjoint solves)",
          lambda: model.stress_operator(points, 600.0))
    print(f"section: {mesh.p.shape[1]} nodes, {model.basis.N} P2 displacement dofs")
    for label, wall, cpu in marks:
        print(f"  {label:48s} wall {wall:7.3f} s  CPU {cpu:7.3f} s")
    print(f"load average: {os.getloadavg()}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=5000)
    args = parser.parse_args()
    convergence()
    timing(args.nodes)


if __name__ == "__main__":
    main()
