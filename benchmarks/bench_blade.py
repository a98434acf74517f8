"""Benchmark and verification of the blade conduction FEM.

Run: python benchmarks/bench_blade.py [--nodes 200000] — prints

1. the analytic fin (2-D exact mode, convective sides and end): L² and H¹ errors on four meshes
   and the observed orders (P1 theory: 2 and 1);
2. the energy balance of the control-stage blade at 30 % and 100 % load (heat in − heat out);
3. a mesh-convergence study of the blade at rated load (element sizes 4, 2, 1, 0.5 mm) with
   Richardson extrapolation of the maximum temperature and the root heat flow;
4. the steady solve on a ~200k-node blade mesh: assembly + AMG setup + CG wall time and the
   solving process's peak memory (a fresh process that loads the mesh and the boundary
   conditions from a file, so meshing and the FOM are not counted).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.blade.conduction import BladeConduction
from steamtwin.blade.mesh import SolidMesh, block_mesh
from steamtwin.blade.steam import SteamBoundary, control_stage_states
from steamtwin.blade.verification import (
    FinSolution,
    fin_errors,
    mesh_convergence,
    observed_order,
    richardson,
)
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import operating_point
from steamtwin.spec import load_spec

FIN = FinSolution(conductivity=34.0, wavenumber=100.0, half_thickness=0.005, length=0.03,
                  amplitude=10.0, ambient=800.0, end_htc=2000.0)


def fin_study(material) -> None:
    print("\n1. analytic fin (T = T∞ + A·cosh(mx)·cos(my), exact 2-D mode)")
    sizes, l2, h1 = [], [], []
    for n in (2, 4, 8, 16):
        mesh = block_mesh(np.linspace(0, 0.03, 6 * n + 1), np.linspace(-0.005, 0.005, 2 * n + 1),
                          np.linspace(0, 0.005, n + 1))
        model = BladeConduction(mesh, material)
        convection = FIN.convection(model)
        temperature = model.solve_steady(convection, tol=1e-12)
        errors = fin_errors(model, temperature, FIN)
        flows = model.heat_flows(temperature, convection)
        sizes.append(0.005 / n)
        l2.append(errors["l2"])
        h1.append(errors["h1"])
        print(f"   h = {sizes[-1] * 1e3:6.3f} mm  nodes {model.n_nodes:7d}  L2 {errors['l2']:.3e}"
              f"  H1 {errors['h1']:.3e}  max nodal {errors['max_nodal']:.4f} K  "
              f"Σ heat {sum(flows.values()):+.2e} W")
    print(f"   observed order: L2 {observed_order(sizes, l2):.3f} (theory 2), "
          f"H1 {observed_order(sizes, h1):.3f} (theory 1)")


def state_at(model, spec, load):
    point = operating_point(spec, load)
    inputs = pd.DataFrame({k: [float(v)] for k, v in point.items()},
                          index=pd.to_datetime(["2026-01-01T00:00:00Z"]))
    return control_stage_states(model, inputs)[0][0]


def blade_studies(spec, model) -> None:
    print("\n2. energy balance of the control-stage blade (default mesh)")
    mesh = blade_volume_mesh(spec, "hp1")
    conduction = BladeConduction(mesh, spec.rotor_material)
    boundary = SteamBoundary(conduction, spec)
    for load in (0.3, 1.0):
        state = state_at(model, spec, load)
        convection = boundary.convection(state)
        field = conduction.solve_steady(convection)
        flows = conduction.heat_flows(field, convection)
        heat_in = sum(q for q in flows.values() if q > 0)
        print(f"   load {load:.0%}: nodes {conduction.n_nodes}, heat in {heat_in:.3f} W, "
              f"residual {sum(flows.values()):+.3e} W ({sum(flows.values()) / heat_in:+.1e}), "
              f"root {flows['root']:+.3f} W, T {field.min() - 273.15:.2f}…"
              f"{field.max() - 273.15:.2f} °C")

    print("\n3. mesh convergence at rated load")
    state = state_at(model, spec, 1.0)

    def build(size):
        conduction = BladeConduction(blade_volume_mesh(spec, "hp1", element_size=size),
                                     spec.rotor_material)
        return conduction, SteamBoundary(conduction, spec).convection(state)

    def monitor(conduction, temperature, convection):
        flows = conduction.heat_flows(temperature, convection)
        volume_mean = conduction.heat_content(temperature) / (
            spec.rotor_material.density * spec.rotor_material.specific_heat
            * conduction.volume())
        return {"max_T": float(temperature.max()), "mean_T": volume_mean,
                "root_heat": flows["root"]}

    rows = mesh_convergence(build, [0.004, 0.002, 0.001, 0.0005], monitor)
    for row in rows:
        q = row.quantities
        print(f"   size {row.element_size * 1e3:4.1f} mm  nodes {row.nodes:7d}  max T "
              f"{q['max_T'] - 273.15:.4f} °C  mean T {q['mean_T'] - 273.15:.4f} °C  root "
              f"{q['root_heat']:+.4f} W")
    for quantity in ("max_T", "mean_T", "root_heat"):
        estimate = richardson(rows, quantity)
        print(f"   Richardson {quantity}: order {estimate['order']:.2f}, finest-mesh error "
              f"{estimate['error_estimate']:+.2e}")


def big_solve(spec, model, nodes: int) -> None:
    print(f"\n4. steady solve at ~{nodes // 1000}k nodes")
    size = 0.0005 * (134604 / nodes) ** (1 / 3)  # 134 604 nodes at 0.5 mm on the reference blade
    start = time.perf_counter()
    mesh = blade_volume_mesh(spec, "hp1", element_size=size)
    meshing = time.perf_counter() - start
    conduction = BladeConduction(mesh, spec.rotor_material)
    convection = SteamBoundary(conduction, spec).convection(state_at(model, spec, 1.0))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "case.npz"
        arrays = {"points": mesh.points, "tetrahedra": mesh.tetrahedra,
                  "boundary_triangles": mesh.boundary_triangles,
                  "boundary_regions": mesh.boundary_regions}
        for region, (h, t) in convection.items():
            arrays[f"h_{region}"] = np.asarray(h)
            arrays[f"t_{region}"] = np.asarray(t)
        np.savez(path, **arrays)
        result = subprocess.run([sys.executable, __file__, "--solve", str(path)],
                                capture_output=True, text=True, check=True)
    report = json.loads(result.stdout.strip().splitlines()[-1])
    print(f"   mesh: {report['nodes']} nodes, {report['tetrahedra']} tetrahedra, element size "
          f"{size * 1e3:.3f} mm (meshing {meshing:.1f} s, not counted)")
    print(f"   assembly {report['assembly_s']:.2f} s + AMG/CG solve {report['solve_s']:.2f} s = "
          f"{report['assembly_s'] + report['solve_s']:.2f} s; peak memory of the solving process "
          f"{report['peak_rss_gb']:.2f} GB (imports and mesh included); energy residual "
          f"{report['residual_w']:+.2e} W of {report['heat_in_w']:.2f} W")


def solve_case(path: str) -> None:
    """Child process: load a case, assemble and solve, print a JSON line with figures."""
    from steamtwin.spec.turbine import Material

    with np.load(path) as archive:
        arrays = {k: archive[k] for k in archive.files}
    mesh = SolidMesh(arrays["points"], arrays["tetrahedra"], arrays["boundary_triangles"],
                     arrays["boundary_regions"])
    convection = {k[2:]: (arrays[k], arrays["t_" + k[2:]]) for k in arrays if k.startswith("h_")}
    start = time.perf_counter()
    conduction = BladeConduction(mesh, Material(7800.0, 600.0, 34.0))
    _ = conduction.stiffness
    assembled = time.perf_counter()
    temperature = conduction.solve_steady(convection, tol=1e-9)
    solved = time.perf_counter()
    flows = conduction.heat_flows(temperature, convection)
    print(json.dumps({
        "nodes": conduction.n_nodes, "tetrahedra": int(mesh.tetrahedra.shape[0]),
        "assembly_s": assembled - start, "solve_s": solved - assembled,
        "peak_rss_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
        "residual_w": sum(flows.values()), "heat_in_w": sum(q for q in flows.values() if q > 0),
    }))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=200_000)
    parser.add_argument("--solve", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.solve:
        solve_case(args.solve)
        return
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    _ = model.design_
    fin_study(spec.rotor_material)
    blade_studies(spec, model)
    big_solve(spec, model, args.nodes)


if __name__ == "__main__":
    main()
