"""Leakages past the pressure stages (spec [[leakages]], stages[].tip_leakage; model.kernel)."""

from __future__ import annotations

import dataclasses
import math
from functools import cache
from importlib import resources

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.model.design_check import design_line
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.kernel import labyrinth_flow
from steamtwin.spec import Leakage, SpecError, TurbineSpec, load_spec, parse_spec
from steamtwin.steam import if97


def _leaking(spec: TurbineSpec) -> TurbineSpec:
    """The reference with a 1 % HP–IP gland from the chamber and 0.5 % bypassing stages 4-12."""
    flow = spec.design.main_steam_flow
    return dataclasses.replace(spec, leakages=(
        Leakage("HP-IP gland", 0, "outside", 0.01 * flow, 0.9 * spec.design.hp_exhaust_pressure),
        Leakage("balance drum", 3, "hp_exhaust", 0.005 * flow)))


@cache
def _model(kind: str) -> FullOrderModel:
    spec = load_spec("reference")
    if kind == "tip":
        spec = dataclasses.replace(spec, stages=tuple(
            dataclasses.replace(stage, tip_leakage=0.01) for stage in spec.stages))
    return FullOrderModel(_leaking(spec))


def _energy_residual(diagnostics: pd.DataFrame) -> np.ndarray:
    out = (diagnostics["hp_power"] + diagnostics["heat_to_metal"]
           + diagnostics["extraction_energy_flow"] + diagnostics["exhaust_energy_flow"]
           + diagnostics["leakage_energy_flow"])
    return ((diagnostics["inlet_energy_flow"] - out) / diagnostics["inlet_energy_flow"]).to_numpy()


def test_zero_leakage_flow_is_no_leakage_bit_for_bit(reference_spec):
    """Zero design flows and zero tip leakage give the reference's design line exactly."""
    spec = dataclasses.replace(reference_spec, leakages=(
        Leakage("gland", 0, "outside", 0.0, 3.0e6), Leakage("drum", 5, "hp_exhaust", 0.0)),
        stages=tuple(dataclasses.replace(s, tip_leakage=0.0) for s in reference_spec.stages))
    line = design_line(spec, (1.0, 0.75, 0.5, 0.3))
    reference = design_line(reference_spec, (1.0, 0.75, 0.5, 0.3))
    for column in reference.columns:
        assert line[column].tolist() == reference[column].tolist(), column


def test_the_design_point_holds_with_leakages(reference_spec):
    model = _model("plain")
    diagnostics = model.simulate_detailed(model.design_inputs(), stages=False).diagnostics
    design = reference_spec.design
    assert diagnostics["leakage_flow"].iloc[0] == pytest.approx(
        0.015 * design.main_steam_flow, rel=1e-6)
    assert diagnostics["hp_exhaust_temperature"].iloc[0] == pytest.approx(
        design.hp_exhaust_temperature, abs=1e-5)
    # the seal's exhaust share mixes in, the gland's leaves: the energy flows say so
    assert diagnostics["leakage_energy_flow"].iloc[0] > 0.0
    # less steam through the stages: lower control-stage pressure and HP power than without
    assert diagnostics["control_stage_pressure"].iloc[0] < 0.995 * design.control_stage_pressure
    assert diagnostics["hp_power"].iloc[0] < design.hp_power


@pytest.mark.parametrize("kind", ["plain", "tip"])
def test_energy_balance_closes_with_leakages(kind, reference_spec):
    model = _model(kind)
    times = pd.date_range("2026-01-01", periods=40, freq="30s", tz="UTC")
    ramp = np.linspace(1.0, 0.45, times.size)
    design = reference_spec.design
    inputs = pd.DataFrame({
        "main_steam_pressure": design.main_steam_pressure * (0.6 + 0.4 * ramp),
        "main_steam_temperature": np.full(times.size, design.main_steam_temperature),
        "main_steam_flow": design.main_steam_flow * ramp,
        "hp_exhaust_pressure": design.hp_exhaust_pressure * ramp}, index=times)
    diagnostics = model.simulate_detailed(inputs, stages=False).diagnostics
    assert np.abs(_energy_residual(diagnostics)).max() < 1e-12
    assert (diagnostics["leakage_flow"] > 0.0).all()


def test_leakage_follows_the_seal_law_off_design(reference_spec):
    """At 60 % flow each seal passes C·sqrt((p² − p_sink²)/(p·v)) at the model's own state."""
    model = _model("plain")
    constants = model.design_.kernel
    inputs = model.design_inputs()
    inputs[["main_steam_flow", "hp_exhaust_pressure"]] *= 0.6
    run = model.simulate_detailed(inputs)
    assert run.stage_pressures is not None and run.stage_temperatures is not None
    expected = 0.0
    for j, origin in enumerate(constants.leak_origin):
        p = run.stage_pressures.iloc[0, origin]
        v = float(if97.specific_volume_pt(p, run.stage_temperatures.iloc[0, origin]))
        sink = constants.leak_sink_ratio[j] * inputs["hp_exhaust_pressure"].iloc[0]
        expected += constants.leak_capacity[j] * math.sqrt((p * p - sink * sink) / (p * v))
    leaked = run.diagnostics["leakage_flow"].iloc[0]
    assert leaked == pytest.approx(expected, rel=1e-4)  # tables vs IF97, sweep tolerance
    # about proportional to flow, as the control-stage pressure is
    assert leaked / (0.015 * reference_spec.design.main_steam_flow) == pytest.approx(0.6, abs=0.03)


def test_tip_leakage_lowers_the_stage_work():
    """Efficiency × (1 − share): the design step makes up 1 % tip leakage by a ~1 % larger
    efficiency scale (the control stage, without tip leakage, carries part of the scale)."""
    plain, tip = _model("plain").design_, _model("tip").design_
    assert 1.005 < tip.efficiency_scale / plain.efficiency_scale < 1.0125
    assert (tip.kernel.stage_tip_passing == 0.99).all()


@settings(max_examples=60, deadline=None)
@given(st.floats(1e5, 2e7), st.floats(0.0, 0.95), st.floats(2e4, 4e5), st.floats(1e-4, 1e-1),
       st.floats(1.1, 4.0))
def test_seal_law_scaling(upstream, ratio, pv, capacity, factor):
    """m = C·sqrt((p_up² − p_down²)/(p_up·v_up)): at a fixed pressure ratio and v ~ 1/p (p·v
    fixed, isothermal ideal gas) the flow grows with the upstream pressure; with the capacity."""
    flow = labyrinth_flow(capacity, upstream, pv, ratio * upstream)
    assert flow == pytest.approx(capacity * upstream * math.sqrt((1 - ratio**2) / pv),
                                 rel=1e-12)
    assert labyrinth_flow(capacity, factor * upstream, pv, factor * ratio * upstream) == (
        pytest.approx(factor * flow, rel=1e-12))
    assert labyrinth_flow(factor * capacity, upstream, pv, ratio * upstream) == pytest.approx(
        factor * flow, rel=1e-12)
    # p·v fourfold (hotter steam, same pressures): half the flow
    assert labyrinth_flow(capacity, upstream, 4.0 * pv, ratio * upstream) == pytest.approx(
        flow / 2.0, rel=1e-12)
    assert labyrinth_flow(capacity, upstream, pv, upstream / max(ratio, 1e-3)) == 0.0


# --- loader ---------------------------------------------------------------------------------

REFERENCE_TEXT = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
    encoding="utf-8")


def _block(entry: dict[str, object]) -> str:
    """A [[leakages]] table; strings are written quoted, numbers as they are."""
    lines = ["[[leakages]]"]
    lines += [f'{key} = "{value}"' if isinstance(value, str) else f"{key} = {value}"
              for key, value in entry.items() if value is not None]
    return "\n".join(lines) + "\n"


def _spec_with(**leakage: object) -> str:
    entry = {"name": "HP-IP gland", "from_stage": 0, "to": "outside", "design_flow": "18 t/h",
             "sink_pressure": "3.5 MPa", **leakage}
    return f"{REFERENCE_TEXT}\n{_block(entry)}"


def test_a_leakage_loads():
    spec = parse_spec(_spec_with(), "unit.toml")
    assert spec.leakages == (Leakage("HP-IP gland", 0, "outside", 5.0, 3.5e6),)
    exhaust = parse_spec(_spec_with(to="hp_exhaust", sink_pressure=None, from_stage=11),
                         "unit.toml")
    assert exhaust.leakages[0].sink_pressure is None


@pytest.mark.parametrize(("change", "message"), [
    ({"sink_pressure": None}, "unit.toml: leakages[1].sink_pressure is missing: a leakage to "
                              "the outside needs"),
    ({"to": "hp_exhaust"}, "unit.toml: leakages[1].sink_pressure: a leakage to the hp_exhaust"),
    ({"to": "ip"}, "unit.toml: leakages[1].to = 'ip': expected one of ['hp_exhaust', "
                   "'outside']"),
    ({"from_stage": 12}, "unit.toml: leakages[1].from_stage = 12: expected an integer in "
                         "[0, 11]"),
    ({"sink_pressure": "14 MPa"}, "unit.toml: leakages[1].sink_pressure = 14 MPa must lie "
                                  "below design.control_stage_pressure"),
    ({"design_flow": "-1 t/h"}, "unit.toml: leakages[1].design_flow = '-1 t/h' is outside"),
    ({"design_flow": 5.0}, "unit.toml: leakages[1].design_flow: 5.0 has no unit"),
    ({"velocity": 1.0}, "velocity"),
])
def test_bad_leakages_are_refused_naming_the_field(change, message):
    with pytest.raises(SpecError) as error:
        parse_spec(_spec_with(**change), "unit.toml")
    assert message in str(error.value)


def test_leakages_and_bleeds_must_leave_steam_for_the_stages():
    text = REFERENCE_TEXT + "".join(
        _block({"name": f"seal {k}", "from_stage": 0, "to": "hp_exhaust",
                "design_flow": "100 kg/s"}) for k in range(5))
    with pytest.raises(SpecError, match=r"leakages .* and extractions .* take together"):
        parse_spec(text, "unit.toml")
    text = REFERENCE_TEXT + "".join(
        _block({"name": "a", "from_stage": stage, "to": "hp_exhaust", "design_flow": "1 kg/s"})
        for stage in (0, 1))
    with pytest.raises(SpecError, match=r"leakages names repeat"):
        parse_spec(text, "unit.toml")
