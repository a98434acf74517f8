"""The model's own design point and off-design line, and the rated-flow consistency check."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.model.design_check import (
    DEFAULT_LOADS,
    LINE_COLUMNS,
    DesignError,
    check_design,
    checked_loads,
    consistency_problems,
    design_line,
    design_point,
    line_in_engineering_units,
    valve_openings,
)
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import TemperatureSchedule, TurbineSpec


def _all_valves_open(spec: TurbineSpec) -> TurbineSpec:
    valves = tuple(dataclasses.replace(valve, open_at_design=True)
                   for valve in spec.control_stage.valves)
    return dataclasses.replace(
        spec, control_stage=dataclasses.replace(spec.control_stage, valves=valves))


def test_reference_design_point_reproduces_the_heat_balance(reference_spec, reference_model):
    point = design_point(reference_spec, model=reference_model)
    relative = point["difference"] / point["spec"]
    # measured (with the reference's 10 % valve overlap): control-stage pressure 13.026 vs
    # 13.03 MPa (−0.03 %), HP power 177.36 vs 177.3 MW (+0.04 %); the exhaust temperature is
    # met by the design step (< 1e-8 K)
    assert abs(relative["control_stage_pressure"]) < 1e-3
    assert abs(relative["hp_power"]) < 1e-3
    assert abs(point.loc["hp_exhaust_temperature", "difference"]) < 1e-3
    design = reference_spec.design
    assert point.loc["control_stage_pressure", "spec"] == design.control_stage_pressure


def test_design_line_falls_with_load_and_opens_the_valves_in_order(sequential_spec,
                                                                    sequential_model):
    line = design_line(sequential_spec, model=sequential_model)
    assert list(line.index) == list(DEFAULT_LOADS)  # falling loads
    for name in ("main_steam_flow", "control_stage_pressure", "hp_exhaust_pressure",
                 "hp_power"):
        assert (np.diff(line[name].to_numpy()) < 0).all(), name
    assert (np.diff(line["main_steam_pressure"].to_numpy()) <= 0).all()  # sliding below 77 %
    rated = line.loc[1.0]
    point = design_point(sequential_spec, model=sequential_model)
    assert rated["control_stage_pressure"] == pytest.approx(
        point.loc["control_stage_pressure", "model"], rel=1e-9)
    # rated load is the GV1-3 valve point of the reference unit; GV4 is the overload reserve
    assert [rated[f"GV{i}_opening"] for i in (1, 2, 4)] == [1.0, 1.0, 0.0]
    assert rated["GV3_opening"] == pytest.approx(1.0, abs=1e-3)
    # below 77 % load only the first valve level (GV1+GV2) admits steam
    assert (line.loc[[0.75, 0.5, 0.4, 0.3], ["GV3_opening", "GV4_opening"]] == 0.0).all().all()
    arcs = np.array([v.admission_arc for v in sequential_spec.control_stage.valves])
    openings = line[[f"{v.name}_opening" for v in sequential_spec.control_stage.valves]]
    np.testing.assert_allclose(openings.to_numpy() @ arcs, line["admission_arc"], rtol=1e-12)


@given(fraction=st.floats(0.0, 1.0))
def test_valve_openings_fill_the_levels_in_opening_order(sequential_spec, fraction):
    valves = sequential_spec.control_stage.valves
    arc = fraction * sum(valve.admission_arc for valve in valves)
    openings = valve_openings(sequential_spec, arc)
    assert all(0.0 <= value <= 1.0 for value in openings.values())
    assert sum(openings[v.name] * v.admission_arc for v in valves) == pytest.approx(arc,
                                                                                   abs=1e-12)
    by_order = sorted(valves, key=lambda valve: valve.opening_order)
    for earlier, later in itertools.pairwise(by_order):
        if openings[later.name] > 0.0 and later.opening_order != earlier.opening_order:
            assert openings[earlier.name] == 1.0


@given(fraction=st.floats(0.0, 1.0), overlap=st.floats(0.0, 0.5))
def test_valve_openings_follow_the_overlap_of_opening(sequential_spec, fraction, overlap):
    spec = dataclasses.replace(sequential_spec, control_stage=dataclasses.replace(
        sequential_spec.control_stage, valve_overlap=overlap))
    valves = spec.control_stage.valves
    arc = fraction * sum(valve.admission_arc for valve in valves)
    openings = valve_openings(spec, arc)
    assert sum(openings[v.name] * v.admission_arc for v in valves) == pytest.approx(arc,
                                                                                   abs=1e-12)
    by_order = sorted(valves, key=lambda valve: valve.opening_order)
    for earlier, later in itertools.pairwise(by_order):
        if openings[later.name] > 0.0 and later.opening_order != earlier.opening_order:
            # the later level starts once the earlier is within the overlap of its full lift
            assert openings[earlier.name] >= 1.0 - overlap - 1e-9
            assert openings[earlier.name] - openings[later.name] == pytest.approx(
                1.0 - overlap, abs=1e-9) or openings[earlier.name] == 1.0


def test_reference_spec_is_consistent(reference_spec, reference_model):
    assert consistency_problems(reference_spec, reference_model) == []


def test_every_valve_open_at_design_is_refused_in_plant_terms(reference_spec):
    spec = _all_valves_open(reference_spec)
    problems = consistency_problems(spec)
    assert len(problems) == 1
    assert "every governing valve is open at rated load" in problems[0]
    assert "open_at_design = false on GV4 (opening_order 3)" in problems[0]
    assert "1800 t/h" in problems[0] and "13.03 MPa" in problems[0]
    with pytest.raises(DesignError, match="every governing valve is open"):
        design_line(spec)
    with pytest.raises(DesignError, match="every governing valve is open"):
        design_point(spec)


@pytest.mark.parametrize(
    ("change", "fields"),
    [
        (lambda s: dataclasses.replace(s, stages=tuple(
            dataclasses.replace(stage, flow_capacity=0.7 * stage.flow_capacity)
            for stage in s.stages)),
         "the pressure stages (stages[*].flow_capacity) are too small"),
        (lambda s: dataclasses.replace(s, stages=tuple(
            dataclasses.replace(stage, flow_capacity=0.9 * stage.flow_capacity)
            for stage in s.stages)),
         "the heat balance's control-stage pressure and the stages' flow capacities disagree"),
        (lambda s: dataclasses.replace(s, design=dataclasses.replace(
            s.design, hp_exhaust_temperature=573.15)),
         "cannot reproduce design.hp_exhaust_temperature"),
    ],
    ids=["stages-too-small", "control-stage-pressure-too-low", "exhaust-too-cold"],
)
def test_a_failing_design_step_names_the_spec_fields(reference_spec, change, fields):
    problems = consistency_problems(change(reference_spec))
    assert len(problems) == 1
    assert fields in problems[0] and "the model says" in problems[0]


@pytest.mark.parametrize(
    ("line", "message"),
    [(((0.0, 0.27, 0.77, 1.1), (6e6, 6e6, 16.0e6, 16.0e6)), "gives 16.00 MPa at rated load"),
     (((0.0, 0.27, 0.77, 0.95), (6e6, 6e6, 16.7e6, 16.7e6)), "ends at 0.95, below rated")],
)
def test_a_sliding_pressure_line_missing_the_design_point_is_a_problem(reference_spec, line,
                                                                       message):
    sliding = dataclasses.replace(reference_spec.sliding_pressure, load_fraction=line[0],
                                  pressure=line[1])
    problems = consistency_problems(dataclasses.replace(reference_spec,
                                                        sliding_pressure=sliding))
    assert len(problems) == 1 and message in problems[0]


@pytest.mark.parametrize(
    ("loads", "message"),
    [([1.0, 0.1], r"loads\[2\] \(1-based\).*0\.2…1\.1 \(got 0\.1\)"),
     ([1.2], r"loads\[1\]"), ([float("nan")], r"loads\[1\]"), ([], "non-empty"),
     ([0.5, 0.5], "repeat"), (["x"], "numbers")],
)
def test_bad_loads_are_refused(reference_spec, loads, message):
    with pytest.raises(DesignError, match=message):
        checked_loads(reference_spec, loads)


def test_a_model_of_another_spec_is_refused(reference_spec, reference_model):
    other = dataclasses.replace(reference_spec, name="other")
    with pytest.raises(ValueError, match="model is of turbine 'reference'"):
        design_line(other, model=reference_model)


def test_a_load_beyond_the_valves_capacity_names_the_load(reference_spec, reference_model):
    with pytest.raises(DesignError, match="cannot run 110% load: main_steam_flow exceeds"):
        design_line(reference_spec, loads=(1.1,), model=reference_model)


def test_a_fresh_model_gives_the_same_line(reference_spec, reference_model):
    shared = design_line(reference_spec, loads=(0.5,), model=reference_model)
    fresh = design_line(reference_spec, loads=(0.5,), model=FullOrderModel(reference_spec))
    np.testing.assert_allclose(fresh.to_numpy(), shared.to_numpy(), rtol=1e-12)


@pytest.mark.parametrize(("rated_c", "problems"), [(538.9, 0), (541.0, 1)])
def test_a_temperature_schedule_missing_the_design_temperature_is_a_problem(reference_spec,
                                                                            rated_c, problems):
    """The schedule at rated load must be design.main_steam_temperature (538 °C) within 1 K."""
    schedule = TemperatureSchedule((0.3, 1.0), (520.0 + 273.15, rated_c + 273.15))
    found = consistency_problems(dataclasses.replace(reference_spec,
                                                     temperature_schedule=schedule))
    assert len(found) == problems
    if problems:
        assert "temperature_schedule gives 541.0 °C at rated load" in found[0]
        assert "design.main_steam_temperature is 538.0 °C" in found[0]


def test_line_in_engineering_units_converts_every_column(reference_spec, reference_model):
    line = design_line(reference_spec, (1.0, 0.5), model=reference_model)
    shown = line_in_engineering_units(reference_spec, line)
    assert list(shown.index) == [100.0, 50.0] and shown.index.name == "load_pct"
    np.testing.assert_allclose(shown["main_steam_pressure_MPa"], line["main_steam_pressure"] / 1e6)
    np.testing.assert_allclose(shown["hp_exhaust_temperature_degC"],
                               line["hp_exhaust_temperature"] - 273.15)
    np.testing.assert_allclose(shown["main_steam_flow_t_per_h"], line["main_steam_flow"] * 3.6)
    np.testing.assert_allclose(shown["GV1_opening_pct"], line["GV1_opening"] * 100)
    assert len(shown.columns) == len(LINE_COLUMNS) + len(reference_spec.control_stage.valves)


def test_check_design_stops_at_the_consistency_problems(reference_spec):
    result = check_design(_all_valves_open(reference_spec))
    assert len(result.problems) == 1 and "every governing valve is open" in result.problems[0]
    assert result.point is None and result.line is None and result.residuals is None


def test_check_design_runs_the_point_and_the_line(reference_spec):
    result = check_design(reference_spec, (1.0, 0.5))
    assert result.problems == [] and result.residuals is None
    assert list(result.line.index) == [1.0, 0.5]
    assert abs(result.point.loc["hp_exhaust_temperature", "difference"]) < 1e-3
