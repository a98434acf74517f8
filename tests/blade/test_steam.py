"""Steam-side boundary conditions of the control-stage blade from the FOM's state."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from steamtwin.blade.conduction import BladeConduction
from steamtwin.blade.mesh import block_mesh
from steamtwin.blade.steam import (
    ROOT_CONTACT_CONDUCTANCE,
    ControlStageState,
    SteamBoundary,
    admitting_stream,
    control_stage_states,
    flat_plate_htc,
    froessling_htc,
    idle_stream,
    velocity_triangles,
)
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.steam import if97

pytestmark = pytest.mark.slow  # 28 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def blade_mesh(reference_spec):
    return blade_volume_mesh(reference_spec, "hp1", element_size=0.006)


def state_at(model, spec, load: float) -> ControlStageState:
    point = operating_point(spec, load)
    inputs = pd.DataFrame({k: [float(v)] for k, v in point.items()},
                          index=pd.to_datetime(["2026-01-01T00:00:00Z"]))
    states, _ = control_stage_states(model, inputs)
    return states[0]


@pytest.mark.parametrize("load", [0.3, 0.5, 0.75, 1.0])
def test_velocity_triangles_close(reference_model, reference_spec, load):
    state = state_at(reference_model, reference_spec, load)
    tri = velocity_triangles(reference_spec, state)
    alpha = reference_spec.control_stage.blading.nozzle_exit_angle
    # law of cosines closes the triangle: w1² = c1² + u² − 2·u·c1·cos α1
    assert tri.inlet_relative_velocity**2 == pytest.approx(
        tri.nozzle_velocity**2 + tri.blade_speed**2
        - 2 * tri.blade_speed * tri.nozzle_velocity * math.cos(alpha), rel=1e-12)
    assert tri.blade_speed == pytest.approx(math.pi * 1.10 * 50.0, rel=1e-12)
    assert 0 < tri.inlet_relative_velocity < tri.nozzle_velocity
    # relative total enthalpy between nozzle-exit static and absolute total (h0)
    h0 = float(if97.enthalpy_pt(state.main_steam_pressure, state.main_steam_temperature))
    assert tri.static_enthalpy < tri.relative_total_enthalpy < h0
    stream = admitting_stream(reference_spec, state)
    assert stream.static_temperature < stream.recovery_temperature(
        stream.surface_velocity) < stream.relative_total_temperature
    assert stream.relative_total_temperature < state.main_steam_temperature


def test_correlations_match_textbook_values():
    # Frössling: Nu_D = 1.14 Re^0.5 Pr^0.4 at θ = 0; zero factor dependence 1 − (θ/90)³
    state = ControlStageState(16.7e6, 811.15, 500.0, 3.9e6, 13.0e6, 780.0, 0.7)
    from steamtwin.blade.steam import _stream

    stream = _stream(13e6, 770.0, 780.0, 200.0, 190.0)
    d = 0.004
    re = stream.density * 200.0 * d / stream.viscosity
    expected = 1.14 * re**0.5 * stream.prandtl**0.4 * stream.conductivity / d
    h = froessling_htc(stream, d, np.array([0.0, 60.0, 85.0]))
    assert h[0] == pytest.approx(expected, rel=1e-12)
    assert h[1] == pytest.approx(expected * (1 - (60 / 90) ** 3), rel=1e-12)
    assert h[2] == pytest.approx(expected * (1 - (80 / 90) ** 3), rel=1e-12)  # clipped at 80°
    x = np.array([0.01, 0.02])
    hx = flat_plate_htc(stream, x)
    assert hx[1] / hx[0] == pytest.approx(2 ** -0.2, rel=1e-12)  # h ∝ x^-0.2
    assert state.active_admission_arc == 0.7


def test_blade_energy_balance_and_bounds(reference_model, reference_spec, blade_mesh):
    conduction = BladeConduction(blade_mesh, reference_spec.rotor_material)
    boundary = SteamBoundary(conduction, reference_spec)
    assert 0.002 < boundary.leading_edge_diameter < 0.01
    for load in (0.3, 1.0):
        state = state_at(reference_model, reference_spec, load)
        convection = boundary.convection(state)
        field = conduction.solve_steady(convection)
        flows = conduction.heat_flows(field, convection)
        heat_in = sum(q for q in flows.values() if q > 0)
        assert abs(sum(flows.values())) < 1e-7 * heat_in
        assert flows["root"] < 0  # the hotter blade sheds heat into the rim
        fluid_max = max(float(np.max(t)) for _, t in convection.values())
        fluid_min = min(float(np.min(t)) for _, t in convection.values())
        # maximum principle: the field lies within the fluid temperatures (P1 on a general
        # tetrahedral mesh with a consistent Robin matrix keeps it only up to small overshoots)
        slack = 0.05 * (fluid_max - fluid_min)
        assert fluid_min - slack <= field.min() and field.max() <= fluid_max + slack


def test_heat_transfer_multiplier_scales_gas_side_only(reference_model, reference_spec):
    mesh = block_mesh(np.linspace(0, 0.04, 9), np.linspace(0, 0.006, 3),
                      0.534 + np.linspace(0, 0.032, 7))
    conduction = BladeConduction(mesh, reference_spec.rotor_material)
    boundary = SteamBoundary(conduction, reference_spec)
    state = state_at(reference_model, reference_spec, 0.5)
    base = boundary.convection(state)
    doubled = boundary.convection(state, ModelParameters(heat_transfer_coefficient=2.0))
    for region in ("leading_edge", "pressure_side", "tip"):
        np.testing.assert_allclose(doubled[region][0], 2 * base[region][0], rtol=1e-12)
        np.testing.assert_allclose(doubled[region][1], base[region][1], rtol=1e-12)
    assert doubled["root"][0] == base["root"][0] == ROOT_CONTACT_CONDUCTANCE


def test_partial_admission_limits(reference_model, reference_spec):
    mesh = block_mesh(np.linspace(0, 0.04, 9), np.linspace(0, 0.006, 3),
                      0.534 + np.linspace(0, 0.032, 7))
    conduction = BladeConduction(mesh, reference_spec.rotor_material)
    boundary = SteamBoundary(conduction, reference_spec)
    state = state_at(reference_model, reference_spec, 0.5)
    full = boundary.convection(ControlStageState(**{**state.__dict__, "active_admission_arc": 1.0}))
    idle = boundary.convection(ControlStageState(**{**state.__dict__, "active_admission_arc": 0.0}))
    active_stream = admitting_stream(reference_spec, state)
    idle_s = idle_stream(reference_spec, state)
    np.testing.assert_allclose(full["leading_edge"][1], active_stream.relative_total_temperature)
    np.testing.assert_allclose(idle["leading_edge"][1], idle_s.relative_total_temperature)
    mixed = boundary.convection(state)
    t = mixed["pressure_side"][1]
    assert np.all((t >= min(idle["pressure_side"][1].min(), full["pressure_side"][1].min()))
                  & (t <= max(idle["pressure_side"][1].max(), full["pressure_side"][1].max())))
