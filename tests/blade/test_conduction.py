"""The conduction FEM against analytic solutions, and its energy balance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.blade.conduction import BladeConduction
from steamtwin.blade.mesh import REGIONS, MeshError, SolidMesh, block_mesh
from steamtwin.blade.verification import (
    FinSolution,
    fin_errors,
    mesh_convergence,
    observed_order,
    richardson,
)
from steamtwin.spec.turbine import Material

STEEL = Material(density=7800.0, specific_heat=600.0, thermal_conductivity=34.0)
FIN = FinSolution(conductivity=34.0, wavenumber=100.0, half_thickness=0.005, length=0.03,
                  amplitude=10.0, ambient=800.0, end_htc=2000.0)


def fin_model(n: int) -> BladeConduction:
    mesh = block_mesh(np.linspace(0.0, 0.03, 6 * n + 1), np.linspace(-0.005, 0.005, 2 * n + 1),
                      np.linspace(0.0, 0.005, n + 1))
    return BladeConduction(mesh, STEEL)


@given(h_a=st.floats(10.0, 1e5), h_b=st.floats(10.0, 1e5), t_a=st.floats(300.0, 900.0),
       t_b=st.floats(300.0, 900.0))
def test_slab_with_convection_is_exact(h_a, h_b, t_a, t_b):
    length = 0.02
    mesh = block_mesh(np.linspace(0, length, 6), np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3))
    model = BladeConduction(mesh, STEEL)
    convection = {"leading_edge": (h_a, t_a), "trailing_edge": (h_b, t_b)}
    temperature = model.solve_steady(convection, tol=1e-12)
    k = STEEL.thermal_conductivity
    flux = (t_a - t_b) / (1 / h_a + length / k + 1 / h_b)
    exact = t_a - flux / h_a - flux * mesh.points[:, 0] / k
    assert np.max(np.abs(temperature - exact)) <= 1e-6 * max(abs(t_a - t_b), 1.0) + 1e-8
    flows = model.heat_flows(temperature, convection)
    assert flows["leading_edge"] == pytest.approx(flux * 1e-4, rel=1e-6, abs=1e-9)
    assert flows["leading_edge"] + flows["trailing_edge"] == pytest.approx(0.0, abs=1e-8)


def test_uniform_ambient_gives_uniform_field():
    mesh = block_mesh(np.linspace(0, 0.03, 7), np.linspace(0, 0.01, 4), np.linspace(0, 0.02, 5))
    model = BladeConduction(mesh, STEEL)
    convection = {region: (100.0 * (i + 1), 750.0) for i, region in enumerate(REGIONS)}
    temperature = model.solve_steady(convection, tol=1e-12)
    np.testing.assert_allclose(temperature, 750.0, atol=1e-7)


def test_fin_converges_at_p1_rates():
    sizes, l2, h1 = [], [], []
    for n in (2, 4, 8):
        model = fin_model(n)
        errors = fin_errors(model, model.solve_steady(FIN.convection(model), tol=1e-12), FIN)
        sizes.append(0.005 / n)
        l2.append(errors["l2"])
        h1.append(errors["h1"])
    assert observed_order(sizes, l2) == pytest.approx(2.0, abs=0.15)
    assert observed_order(sizes, h1) == pytest.approx(1.0, abs=0.1)


def test_fin_energy_balance_and_heat_flow():
    model = fin_model(6)
    convection = FIN.convection(model)
    temperature = model.solve_steady(convection, tol=1e-12)
    flows = model.heat_flows(temperature, convection)
    total_in = sum(q for q in flows.values() if q > 0)
    assert abs(sum(flows.values())) <= 1e-9 * total_in
    # exact heat through the sides: 2·∫₀ᴸ k·A·m·cosh(mx)·sin(mb) dx·depth
    m, depth = FIN.wavenumber, 0.005
    exact_side = -2 * STEEL.thermal_conductivity * FIN.amplitude * math.sinh(m * FIN.length) * \
        math.sin(m * FIN.half_thickness) * depth
    side = flows["pressure_side"] + flows["suction_side"]
    assert side == pytest.approx(exact_side, rel=0.02)


def test_lumped_body_transient_first_order_in_time_and_conservative():
    mesh = block_mesh(np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3))
    model = BladeConduction(mesh, STEEL)
    h, ambient, start = 5.0, 500.0, 800.0  # Bi = h·V/(A·k) ≈ 2.5e-4
    convection = {region: (h, ambient) for region in REGIONS}
    tau = STEEL.density * STEEL.specific_heat * 0.01 / (6 * h)  # ρcV/(hA)
    errors = []
    for steps in (10, 20, 40):
        times = np.linspace(0.0, tau, steps + 1)
        history = model.solve_transient([convection] * (steps + 1), times,
                                        np.full(model.n_nodes, start), tol=1e-12)
        exact = ambient + (start - ambient) * math.exp(-1.0)
        errors.append(abs(history[-1].mean() - exact))
        # discrete energy balance of every step: stored heat rate = heat in
        for i in (1, steps):
            stored = (model.heat_content(history[i]) - model.heat_content(history[i - 1])) / (
                times[i] - times[i - 1])
            heat_in = sum(model.heat_flows(history[i], convection).values())
            assert stored == pytest.approx(heat_in, rel=1e-8)
    assert observed_order([1, 0.5, 0.25], errors) == pytest.approx(1.0, abs=0.1)


def test_richardson_recovers_fin_order():
    def build(size):
        model = fin_model(round(0.005 / size))
        return model, FIN.convection(model)

    def monitor(model, temperature, convection):
        return {"end_heat": model.heat_flows(temperature, convection)["trailing_edge"]}

    rows = mesh_convergence(build, [0.005 / 2, 0.005 / 4, 0.005 / 8], monitor)
    assert [row.nodes for row in rows] == sorted(row.nodes for row in rows)
    estimate = richardson(rows, "end_heat")
    assert 1.5 < estimate["order"] < 2.5
    fine_model = fin_model(8)
    assert abs(estimate["error_estimate"]) < 0.05 * abs(rows[-1].quantities["end_heat"])
    assert fine_model.n_nodes == rows[-1].nodes


def test_bad_inputs_are_refused():
    mesh = block_mesh(np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3), np.linspace(0, 0.01, 3))
    model = BladeConduction(mesh, STEEL)
    with pytest.raises(ValueError, match="not finite"):
        model.solve_steady({"tip": (np.nan, 500.0)})
    with pytest.raises(ValueError, match="≥ 0"):
        model.solve_steady({"tip": (-1.0, 500.0)})
    with pytest.raises(ValueError, match="needs convection"):
        model.solve_steady({"tip": (0.0, 500.0)})
    with pytest.raises(KeyError, match="not in the mesh"):
        model.solve_steady({"shroud": (10.0, 500.0)})
    broken = SolidMesh(mesh.points, mesh.tetrahedra, mesh.boundary_triangles,
                       np.full(mesh.boundary_regions.shape, 9))
    with pytest.raises(MeshError, match="REGIONS"):
        BladeConduction(broken, STEEL)
    with pytest.raises(MeshError, match="index a node"):
        BladeConduction(SolidMesh(mesh.points, mesh.tetrahedra + 1000,
                                  mesh.boundary_triangles, mesh.boundary_regions), STEEL)
