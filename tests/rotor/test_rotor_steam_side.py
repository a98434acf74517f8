"""Steam-side conditions of the rotor FEM: the FOM's group states and its rotor htc."""

import math

import numpy as np
import pytest

from steamtwin.errors import RotorAreaError
from steamtwin.model.operating import load_profile_inputs
from steamtwin.model.parameters import ModelParameters
from steamtwin.rotor.conduction import (
    cooling_factor_column,
    htc_column,
    steam_temperature_column,
)
from steamtwin.rotor.steam_side import group_flows, steam_side
from steamtwin.steam import if97


@pytest.fixture(scope="module")
def design_run(reference_model, reference_spec):
    inputs = load_profile_inputs(reference_spec, np.array([1.0, 1.0, 0.5]), step_seconds=60.0)
    return inputs, reference_model.simulate_detailed(inputs, ModelParameters(), stages=True)


def test_control_stage_htc_is_dittus_boelter_at_the_kernels_relative_velocity(
        reference_model, design_run):
    """By hand: Nu = 0.023·Re^0.8·Pr^0.3 with the velocity √(c_ax² + (u/2)²) (module docstring
    of steamtwin.model.metal) at the FOM's control-stage state and the kernel's annulus."""
    inputs, run = design_run
    frame = steam_side(reference_model, inputs, groups=["control stage"], run=run)
    p = run.stage_pressures["control_stage"].iloc[0]
    t = run.stage_temperatures["control_stage"].iloc[0]
    assert frame[steam_temperature_column("control stage")].iloc[0] == t
    metal = reference_model.design_.kernel.metal
    v, mu = float(if97.specific_volume_pt(p, t)), float(if97.viscosity_pt(p, t))
    k, cp = float(if97.thermal_conductivity_pt(p, t)), float(if97.isobaric_heat_capacity_pt(p, t))
    axial = inputs["main_steam_flow"].iloc[0] * v / metal.flow_area[0]
    velocity = math.hypot(axial, 0.5 * metal.rotor_speed[0])
    diameter = metal.hydraulic_diameter[0]
    reynolds, prandtl = velocity * diameter / (v * mu), cp * mu / k
    expected = 0.023 * reynolds**0.8 * prandtl**0.3 * k / diameter
    assert frame[htc_column("control stage")].iloc[0] == pytest.approx(expected, rel=1e-10)
    # the rotor heating the steam: Pr^0.4 instead of Pr^0.3
    assert frame[cooling_factor_column("control stage")].iloc[0] == pytest.approx(
        prandtl**0.1, rel=1e-12)
    assert 1e3 < expected < 2e4  # W/(m²·K): 12.7 kW at the reference design point


def test_the_calibrated_multiplier_scales_the_htc_and_part_load_lowers_it(
        reference_model, reference_spec, design_run):
    inputs, run = design_run
    base = steam_side(reference_model, inputs, run=run)
    params = ModelParameters(heat_transfer_coefficient=1.5)
    scaled = steam_side(reference_model, inputs, params, run=run)
    for group in reference_spec.metal_groups:
        np.testing.assert_allclose(scaled[htc_column(group.name)],
                                   1.5 * base[htc_column(group.name)], rtol=1e-12)
        assert base[htc_column(group.name)].iloc[2] < base[htc_column(group.name)].iloc[0]


def test_a_stage_groups_steam_lies_between_its_inlet_and_outlet(reference_model, design_run):
    inputs, run = design_run
    frame = steam_side(reference_model, inputs, groups=["HP stages 5-8"], run=run)
    temperature = frame[steam_temperature_column("HP stages 5-8")].to_numpy()
    assert np.all(temperature < run.stage_temperatures["stage_4"].to_numpy())
    assert np.all(temperature > run.stage_temperatures["stage_8"].to_numpy())
    flows = group_flows(reference_model, inputs, run)
    # the HP heater bleed (after stage 8) leaves after the last group's first stage: only the
    # group ending after it (stages 9-12) passes less than the throttle flow
    np.testing.assert_array_equal(flows[:, :3], np.repeat(inputs[["main_steam_flow"]].to_numpy(),
                                                          3, axis=1))
    assert np.all(flows[:, 3] < inputs["main_steam_flow"].to_numpy())


def test_an_unknown_group_is_refused(reference_model, design_run):
    inputs, run = design_run
    with pytest.raises(RotorAreaError, match=r"metal groups \['HP stages 1-3'\] are not"):
        steam_side(reference_model, inputs, groups=["HP stages 1-3"], run=run)


def test_a_fom_driven_ramp_moves_the_groove_root_before_the_axis(reference_model,
                                                                 reference_spec):
    """FOM → steam side → rotor FEM on a 10-min ramp 100 → 50 % load (10-s steps): the surface
    at the groove follows the control-stage steam, the axis lags (a rotor's time constant a²/κ
    is hours), and the heat the steam gives equals the rotor's stored energy change."""
    from steamtwin.rotor.conduction import RotorConduction
    from steamtwin.rotor.geometry import critical_nodes, rotor_geometry, rotor_mesh
    from steamtwin.rotor.material import ConstantMaterial

    loads = np.clip(1.0 - 0.05 / 6.0 * np.arange(61), 0.5, 1.0)
    inputs = load_profile_inputs(reference_spec, loads, step_seconds=10.0)
    geometry = rotor_geometry(reference_spec)
    frame = steam_side(reference_model, inputs, groups=list(geometry.groups))
    mesh = rotor_mesh(geometry, 0.04)
    steel = ConstantMaterial("CrMoV", 7850.0, 540.0, 34.0, 2.1e11, 0.3, 1.25e-5)
    conduction = RotorConduction(mesh, steel, geometry.groups)
    first = frame.iloc[0]
    initial = conduction.steady([first[htc_column(g)] for g in geometry.groups],
                                [first[steam_temperature_column(g)] for g in geometry.groups])
    run = conduction.transient_frame(initial, frame, probes=critical_nodes(mesh, geometry))
    change = run.probes.iloc[-1] - run.probes.iloc[0]
    steam_change = (frame[steam_temperature_column("control stage")].iloc[-1]
                    - first[steam_temperature_column("control stage")])
    assert abs(steam_change) > 5.0
    assert np.sign(change["groove_root"]) == np.sign(steam_change)
    assert abs(change["groove_root"]) > 5.0 * abs(change["bore"])
    supplied = run.heat_in[1:] * np.diff(run.times)
    np.testing.assert_allclose(supplied.sum(), run.stored.sum(), rtol=1e-9)
