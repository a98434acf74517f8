"""The virtual plant's own physics: each feature the twin lacks, checked against a closed form
or an invariant, and shown to matter (the test fails when the feature is switched off)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.linalg import eigh
from scipy.optimize import brentq
from scipy.special import j0, j1, y0, y1

from steamtwin.dcs.plant import plant_sensor_models
from steamtwin.dcs.plant_model import (
    TWIN_EQUIVALENT_LOADS,
    PlantModel,
    PlantTruth,
    boiler_temperature,
    bored_rotor,
    plant_model,
    plant_steady_states,
    poppet_valve_characteristic,
    tip_leakage_fractions,
)
from steamtwin.model.operating import load_profile_inputs, operating_point, ramp_profile
from steamtwin.spec import TurbineSpec
from steamtwin.steam import if97

SIMPLE = PlantTruth.simple()


def _steady(model: PlantModel, load: float, stages: bool = False):
    frame = pd.DataFrame(operating_point(model.spec, np.array([load])),
                         index=pd.to_datetime(["2026-03-01"]))
    return model.simulate_detailed(frame, SIMPLE.parameters, stages=stages)


@pytest.fixture(scope="module")
def simple_model() -> PlantModel:
    return plant_model(SIMPLE)


def test_tip_leakage_fraction_closed_form(reference_spec: TurbineSpec) -> None:
    """First pressure stage of the reference: D 0.9434 m, ℓ 83.5 mm, α₁ 16°, r 0.3; δ 0.6 mm."""
    fractions = tip_leakage_fractions(reference_spec, (0.0006, 0.0008, 0.0009))
    expected = (0.7 * (0.9434 + 0.0835) * 0.0006 / (0.9434 * 0.0835 * math.sin(math.radians(16)))
                * math.sqrt(0.3 / (3 * 0.7)))
    assert fractions[0] == pytest.approx(expected, rel=1e-3)
    assert fractions.shape == (12,) and np.all((fractions > 0.005) & (fractions < 0.01))
    doubled = tip_leakage_fractions(reference_spec, (0.0012, 0.0016, 0.0018))
    np.testing.assert_allclose(doubled, 2.0 * fractions)  # λ ∝ δ
    assert not tip_leakage_fractions(reference_spec, (0.0,)).any()


def test_tip_leakage_lowers_hp_power_by_the_bypassed_work(simple_model: PlantModel) -> None:
    """At rated flow the power lost is Σ λ_i·m_i·Δh_i of the stages without tip leakage (to
    first order: the unused drop reheats the stages downstream, which recover a little)."""
    truth = replace(SIMPLE, tip_clearances=PlantTruth().tip_clearances)
    leaking = plant_model(truth)
    base = _steady(simple_model, 1.0, stages=True)
    pressures = base.stage_pressures.iloc[0].to_numpy()
    temperatures = base.stage_temperatures.iloc[0].to_numpy()
    enthalpy = np.array([float(if97.enthalpy_pt(p, t)) for p, t in zip(pressures, temperatures,
                                                                        strict=True)])
    constants = simple_model.design_.kernel
    flow = float(operating_point(simple_model.spec, 1.0)["main_steam_flow"])
    stage_flow = flow * (1.0 - np.concatenate(([0.0], np.cumsum(
        constants.extraction_fraction)[:-1])))
    fractions = tip_leakage_fractions(simple_model.spec, truth.tip_clearances)
    expected = float(np.sum(fractions * stage_flow * (enthalpy[:-1] - enthalpy[1:])))
    lost = (base.outputs["hp_power"].iloc[0]
            - _steady(leaking, 1.0).outputs["hp_power"].iloc[0])
    assert expected > 0.004 * base.outputs["hp_power"].iloc[0]
    assert lost == pytest.approx(expected, rel=0.15)


def test_valve_overlap_throttles_at_the_valve_point(simple_model: PlantModel) -> None:
    """Below ~80 % the sliding pressure holds the valves at a valve point; with overlap the
    last valve still throttles there, so the control stage expands less (hotter, less power).
    Between valve points with the last valve well short of full lift the overlap changes
    nothing (the previous valve is already full open)."""
    overlapping = plant_model(replace(SIMPLE, valve_overlap=0.1))
    for load in (0.3, 0.6):
        base, other = _steady(simple_model, load).outputs, _steady(overlapping, load).outputs
        rise = (other["control_stage_temperature"].iloc[0]
                - base["control_stage_temperature"].iloc[0])
        assert 0.5 < rise < 5.0, load
        assert other["hp_power"].iloc[0] < base["hp_power"].iloc[0]
    base, other = _steady(simple_model, 0.9).outputs, _steady(overlapping, 0.9).outputs
    assert other["control_stage_temperature"].iloc[0] == pytest.approx(
        base["control_stage_temperature"].iloc[0], abs=0.01)


def test_poppet_characteristic() -> None:
    """Effective area of curtain π·d·L and seat π·d²/4 in series: at half lift with L/d = 0.3
    the curtain is 0.6 seat areas, 0.6/sqrt(1.36) over the full lift's 1.2/sqrt(2.44)."""
    lift, flow = poppet_valve_characteristic(0.3)
    assert flow[0] == 0.0 and flow[-1] == 1.0 and np.all(np.diff(flow) > 0.0)
    half = flow[np.searchsorted(lift, 0.5)]
    assert half == pytest.approx((0.6 / math.sqrt(1.36)) / (1.2 / math.sqrt(2.44)))


def test_low_load_temperatures_follow_the_schedule() -> None:
    truth = PlantTruth()
    np.testing.assert_allclose(boiler_temperature(truth.main_steam_schedule,
                                                  np.array([0.3, 0.4, 0.5, 0.8, 1.0])) - 273.15,
                               [520.0, 529.0, 538.0, 538.0, 538.0])
    states = plant_steady_states((0.3, 0.8), truth)
    simple = plant_steady_states((0.3, 0.8), SIMPLE)
    assert states.loc[0.3, "main_steam_temperature"] == pytest.approx(793.15)
    assert simple.loc[0.3, "main_steam_temperature"] == pytest.approx(811.15)
    # reheat 515 °C at 30 %: HP-exhaust pressure lower by sqrt(788.15/811.15) (IP cone law)
    assert (states.loc[0.3, "hp_exhaust_pressure"] / simple.loc[0.3, "hp_exhaust_pressure"]
            == pytest.approx(math.sqrt(788.15 / 811.15)))
    assert states.loc[0.8, "hp_exhaust_pressure"] == simple.loc[0.8, "hp_exhaust_pressure"]
    # 18 K cooler steam leaves the HP section more than 10 K cooler
    cooler = simple.loc[0.3, "hp_exhaust_temperature"] - states.loc[0.3, "hp_exhaust_temperature"]
    assert 10.0 < cooler < 18.0


def test_deeper_thermocouple_lags_in_a_ramp(reference_spec: TurbineSpec) -> None:
    """Cooling from the bore, the wall is hotter the deeper: 20 mm reads above 14 mm during a
    ramp down (by K: the 3 %/min ramp cools the control-stage steam ~30 K in 17 min); at the
    steady start only the lagging loss's gradient remains (deeper a little cooler); the plant's
    sheath is its own."""
    frame = load_profile_inputs(reference_spec, ramp_profile(1.0, 0.5, 0.03, 60.0, 600.0))
    truth = PlantTruth()
    readings = {depth: plant_model(replace(truth, casing_thermocouple_depth=depth))
                .simulate(frame, truth.parameters)["hp_inner_casing_temperature"].to_numpy()
                for depth in (0.014, 0.020)}
    difference = readings[0.020] - readings[0.014]
    assert -0.2 < difference[0] < 0.0
    assert difference[300:1060].min() > 0.3 and difference.max() > 1.5  # ramp: 60…1060 s
    assert plant_sensor_models(truth)["hp_inner_casing_temperature"].time_constant_s == 8.0


def _hollow_cylinder_root(inner: float, outer: float) -> float:
    """Smallest λ with J1(λb)·Y0(λR) − Y1(λb)·J0(λR) = 0: adiabatic bore b, fixed surface R
    (Carslaw & Jaeger, *Conduction of Heat in Solids*, 1959, §7.7)."""
    def f(x: float) -> float:
        return j1(x * inner) * y0(x * outer) - y1(x * inner) * j0(x * outer)

    grid = np.linspace(0.1, 6.0, 600) / outer
    values = np.array([f(x) for x in grid])
    k = int(np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0])
    return brentq(f, grid[k], grid[k + 1])


def test_bored_rotor_conserves_mass_and_has_the_exact_slowest_mode(
        reference_spec: TurbineSpec) -> None:
    """The graded hollow chain keeps mass and area and its slowest decay (surface held, bore
    adiabatic) matches the Bessel solution of the hollow cylinder within 2 % (the
    discretisation error of 16 graded volumes: 1.4 %)."""
    group = reference_spec.metal_groups[1]
    material = reference_spec.rotor_material
    capacity, conductance, half_cell, outer, radius = bored_rotor(
        group.rotor_mass, group.rotor_area, material, 16, 0.05)
    assert capacity.sum() == pytest.approx(group.rotor_mass * material.specific_heat)
    assert outer == 0.0
    solid = 2.0 * group.rotor_mass / (material.density * group.rotor_area)
    assert radius**2 - solid * radius - 0.05**2 == pytest.approx(0.0, abs=1e-12)
    stiffness = np.diag(np.concatenate((conductance, [0.0])) + np.concatenate(([0.0],
                                                                              conductance)))
    stiffness -= np.diag(conductance, 1) + np.diag(conductance, -1)
    stiffness[0, 0] += group.rotor_area / half_cell  # surface held at the steam temperature
    slowest = eigh(stiffness, np.diag(capacity), eigvals_only=True)[0]
    diffusivity = material.thermal_conductivity / (material.density * material.specific_heat)
    exact = diffusivity * _hollow_cylinder_root(0.05, radius) ** 2
    assert slowest == pytest.approx(exact, rel=0.02)


def test_plant_energy_balance_closes_in_a_ramp(reference_spec: TurbineSpec) -> None:
    """Steam energy in = power + heat to metal + bleed + exhaust, and the metal stores exactly
    the heat it takes minus the lagging loss (implicit Euler, 1-s steps)."""
    frame = load_profile_inputs(reference_spec, ramp_profile(1.0, 0.4, 0.05, 60.0, 300.0))
    diagnostics = plant_model().simulate_detailed(frame, PlantTruth().parameters,
                                                  stages=False).diagnostics
    out = (diagnostics["hp_power"] + diagnostics["heat_to_metal"]
           + diagnostics["extraction_energy_flow"] + diagnostics["exhaust_energy_flow"])
    residual = (diagnostics["inlet_energy_flow"] - out) / diagnostics["inlet_energy_flow"]
    assert np.abs(residual.to_numpy()).max() < 1e-12
    stored = np.diff(diagnostics["metal_heat_content"].to_numpy())
    taken = (diagnostics["heat_to_metal"] - diagnostics["lagging_loss"]).to_numpy()[1:]
    np.testing.assert_allclose(stored, taken, rtol=1e-6, atol=1e-3 * np.abs(taken).max())


def test_twin_equivalent_is_the_closed_form_on_the_simple_plant() -> None:
    """Without tip leakage and overlap the fit finds φ/(1 − λ) (gland leakage only) and the
    true friction; with them the friction it needs rises (the clearances cost efficiency)."""
    simple = SIMPLE.twin_equivalent
    assert simple.flow_coefficient == pytest.approx(0.965 / (1.0 - 0.015), abs=5e-4)
    assert simple.friction_coefficient == pytest.approx(1.3, abs=0.02)
    assert simple.heat_transfer_coefficient == 1.4
    full = PlantTruth().twin_equivalent
    assert full.friction_coefficient > simple.friction_coefficient + 0.1
    assert TWIN_EQUIVALENT_LOADS == (0.3, 0.5, 0.75, 1.0)
