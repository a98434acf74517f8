"""The ROM's snapshot envelope: operating line, temperature schedule, valve points, calibrated
parameters and a historian's inputs; infeasible conditions replaced; errors naming the cause."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from steamtwin.model.design_check import valve_openings
from steamtwin.model.fom import InputError
from steamtwin.model.kernel import PRESSURE_TOLERANCE
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import ModelParameters, ParameterError
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.rom.build import build_rom, rom_envelope
from steamtwin.rom.envelope import (
    EnvelopeError,
    feasible_conditions,
    operating_line,
    parse_parameter_interval,
)
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.reconstruction import (
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
    predict_series,
)
from steamtwin.rom.snapshots import ROM_INPUTS, design_conditions
from steamtwin.spec import TemperatureSchedule

pytestmark = pytest.mark.slow  # 23 s of the full suite (2026-11-27): not in the quick loop

KELVIN = 273.15
CALIBRATED = ModelParameters(flow_coefficient=0.953)


@pytest.fixture(scope="module")
def scheduled_spec(reference_spec):
    """The reference with a boiler that runs 520 °C main steam at 30 % load."""
    schedule = TemperatureSchedule((0.3, 0.5, 1.0), (520.0 + KELVIN, 532.0 + KELVIN,
                                                     538.0 + KELVIN), None)
    return dataclasses.replace(reference_spec, temperature_schedule=schedule)


def _envelope(spec, model, params=None, **options):
    return rom_envelope(spec, params, model=model, **options)


def _rom_inputs(model, conditions, params):
    """(p0, T0, p1) of each condition: the model's steady control-stage pressure."""
    rows = []
    for i in range(len(conditions)):
        inputs = conditions.iloc[[i]][list(INPUT_SIGNALS)].set_index(pd.Index([0.0]))
        p1 = model.simulate_detailed(inputs, params, stages=False).diagnostics[
            "control_stage_pressure"].iloc[0]
        rows.append([conditions["main_steam_pressure"].iloc[i],
                     conditions["main_steam_temperature"].iloc[i], p1])
    return np.array(rows)


def _inside_hull(points, queries):
    """Whether each query lies in the convex hull of ``points`` (both scaled by the points'
    range, as the ROM's extrapolation check does)."""
    low, span = points.min(axis=0), np.ptp(points, axis=0)
    return Delaunay((points - low) / span).find_simplex((queries - low) / span) >= 0


def _planned(spec, model, params, envelope, n_snapshots=32, **options):
    conditions, replaced = feasible_conditions(
        spec, design_conditions(spec, n_snapshots, envelope=envelope, **options), params,
        model=model)
    return conditions, replaced, _rom_inputs(model, conditions, params)


def test_the_envelope_holds_the_operating_line_with_its_scheduled_temperature(
        scheduled_spec, reference_model):
    model = type(reference_model)(scheduled_spec)
    envelope = _envelope(scheduled_spec, model)
    _, replaced, inputs = _planned(scheduled_spec, model, None, envelope)
    assert replaced.empty  # the empirical model passes every planned condition
    line = operating_line(scheduled_spec, None, [0.3, 0.5, 1.0], model=model)
    on_line = line[["main_steam_pressure", "main_steam_temperature",
                    "control_stage_pressure"]].to_numpy()
    assert line["main_steam_temperature"].to_numpy() - KELVIN == pytest.approx(
        [520.0, 532.0, 538.0])
    assert np.all(_inside_hull(inputs, on_line))


def test_the_valve_points_are_where_a_group_reaches_full_lift(reference_spec, reference_model):
    envelope = _envelope(reference_spec, reference_model)
    assert envelope.valve_points  # GV1+2 and GV3 open fully within the sliding line
    line = operating_line(reference_spec, None, model=reference_model)
    for load in envelope.valve_points:
        before = line.loc[line.index < load - 1e-9, "active_admission_arc"].iloc[-1]
        after = line.loc[load, "active_admission_arc"]
        assert sum(v >= 1.0 - 1e-6 for v in valve_openings(reference_spec, after).values()) > \
            sum(v >= 1.0 - 1e-6 for v in valve_openings(reference_spec, before).values())
    plan = design_conditions(reference_spec, 32, envelope=envelope)
    assert len(plan) == 32
    for load in envelope.valve_points:  # one snapshot on the line at each valve point
        row = plan[plan["load_level"] == load].iloc[0]
        assert row["main_steam_flow"] == pytest.approx(
            load * reference_spec.design.main_steam_flow)


def test_a_calibrated_flow_coefficient_no_longer_breaks_the_plan(reference_spec,
                                                                 reference_model):
    """At 0.953 the old plan's rated corners at −5 % pressure exceed the valves' capacity;
    they are replaced by the highest flow the valves pass, and the planned p1 cover the
    calibrated model's line and a plant anywhere in 0.94…0.97."""
    old = design_conditions(reference_spec, 32, layout="corners")
    with pytest.raises(InputError, match="wide-open governing valves"):
        reference_model.simulate_detailed(old[list(INPUT_SIGNALS)], CALIBRATED, stages=False)
    envelope = _envelope(reference_spec, reference_model, CALIBRATED,
                         parameter_intervals={"flow_coefficient": (0.94, 0.97)})
    conditions, replaced, inputs = _planned(reference_spec, reference_model, CALIBRATED,
                                            envelope, 35, layout="corners")
    assert len(envelope.valve_points) == 2  # 32 corners + 2 valve points + the rated point
    assert len(replaced) >= 1
    assert replaced["reason"].str.contains("wide-open governing valves").all()
    in_place, added = replaced[replaced["row"] < 35], replaced[replaced["row"] >= 35]
    assert len(conditions) == 35 + len(added) and len(added) == len(in_place) >= 1
    # in place: the same (p0, T0) just below the flow the valves pass; added: the same flow
    # at the lowest throttle pressure that passes it — both on the capacity limit
    assert np.all(in_place["flow_after"] < in_place["flow_before"])
    assert np.all(in_place["pressure_after"] == in_place["pressure_before"])
    assert np.all(added["flow_after"] == added["flow_before"])
    assert np.all(added["pressure_after"] > added["pressure_before"])
    assert np.all(replaced["temperature_after"] == replaced["temperature_before"])
    for row in replaced.itertuples():
        beyond = conditions.iloc[[row.row]].copy()
        if row.row < 35:
            beyond["main_steam_flow"] *= 1.01
        else:
            beyond["main_steam_pressure"] *= 0.99
        with pytest.raises(InputError, match="wide-open"):
            reference_model.simulate_detailed(beyond[list(INPUT_SIGNALS)], CALIBRATED,
                                              stages=False)
    loads = [0.3, 0.5, 0.75, 1.0]
    for flow_coefficient in (0.94, 0.953, 0.97):
        line = operating_line(reference_spec, ModelParameters(flow_coefficient=flow_coefficient),
                              loads, model=reference_model)
        p1 = line["control_stage_pressure"].to_numpy()
        assert inputs[:, 2].min() <= p1.min() and p1.max() <= inputs[:, 2].max()
        # and inside the design's hull, not just its range: the plant states at each load
        on_line = line[["main_steam_pressure", "main_steam_temperature",
                        "control_stage_pressure"]].to_numpy()
        assert np.all(_inside_hull(inputs, on_line)), flow_coefficient


def test_build_with_the_calibrated_flow_coefficient(reference_spec, reference_model,
                                                    coarse_blade):
    bundle, built = build_rom(reference_spec, coarse_blade, CALIBRATED, n_snapshots=35,
                              layout="corners", max_workers=1,
                              parameter_intervals={"flow_coefficient": (0.94, 0.97)})
    envelope = bundle.provenance["envelope"]
    assert envelope["replaced"] == len(envelope["replacements"]) >= 1
    assert "parameter intervals flow_coefficient 0.94…0.97" in envelope["sources"]
    line = operating_line(reference_spec, CALIBRATED, [0.3, 0.5, 1.0], model=reference_model)
    distance = bundle.rom.extrapolation_distance(
        line[list(ROM_INPUTS)].to_numpy())
    assert np.all(distance == 0.0)
    assert built.conditions["main_steam_flow"].max() > reference_spec.design.main_steam_flow


def test_the_historian_widens_the_envelope_to_its_samples(reference_spec, reference_model,
                                                          coarse_blade):
    """A unit that runs 505 °C and 4 % below the sliding line at 30 %, a 62 % and a full-load
    hold: without --data its 30 % samples lie beyond the ROM's domain (the spec has no
    temperature schedule: snapshots at 528–548 °C), with it every sample is inside the
    snapshots' hull."""
    model = reference_model
    rng = np.random.default_rng(5)
    rows = []
    for load, temperature, pressure in ((0.30, 505.0, 0.96), (0.62, 528.0, 1.0),
                                        (1.0, 536.0, 1.0)):
        point = {k: float(v) for k, v in operating_point(reference_spec, load).items()}
        for _ in range(40):
            rows.append(dict(point, main_steam_temperature=temperature + KELVIN
                             + rng.normal(0.0, 0.4),
                             main_steam_pressure=point["main_steam_pressure"] * pressure
                             * (1.0 + rng.normal(0.0, 0.002)),
                             main_steam_flow=point["main_steam_flow"]
                             * (1.0 + rng.normal(0.0, 0.003))))
    observed = pd.DataFrame(_rom_inputs(model, pd.DataFrame(rows), None),
                            columns=list(ROM_INPUTS))
    widened = _envelope(reference_spec, model, observed=observed)
    assert "observed inputs (120 samples)" in widened.sources
    low = [box for box in widened.levels if box.load <= 0.3]
    assert min(box.temperature_offset[0] for box in low) <= 505.0 - 538.0 - 1.0
    flags = {}
    for label, data in (("before", None), ("after", observed)):
        bundle, _ = build_rom(reference_spec, coarse_blade, n_snapshots=16, max_workers=1,
                              observed=data)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)
            flags[label] = predict_series(bundle, observed).sensors
    assert flags["before"][FLAG_OUT_OF_DOMAIN].iloc[:40].all()
    assert not flags["after"][FLAG_OUT_OF_DOMAIN].any()
    assert not flags["after"][FLAG_INVALID].any()
    coverage = bundle.provenance["envelope"]["observed"]
    # and inside the snapshots' hull, not only their range: the anchors about the samples
    assert coverage == {"samples": 120, "outside_hull": 0, "beyond_limit": 0,
                        "max_distance": 0.0}
    assert not flags["after"][FLAG_EXTRAPOLATED].any()
    anchors = bundle.provenance["envelope"]["observed_anchors"]
    assert anchors % 4 == 0 and len(bundle.conditions) == 16 + anchors + len(
        [r for r in bundle.provenance["envelope"]["replacements"] if r["row"] >= 16])


def test_observed_loads_below_the_levels_add_a_level(reference_spec, reference_model):
    point = operating_line(reference_spec, None, [0.24], model=reference_model)
    observed = point[list(ROM_INPUTS)].reset_index(drop=True)
    envelope = _envelope(reference_spec, reference_model, observed=observed)
    assert envelope.levels[0].load == pytest.approx(0.23, abs=0.002)


def test_the_error_names_the_parameter_when_the_line_cannot_be_run(reference_spec,
                                                                   reference_model):
    """At its lower bound 0.90 the flow coefficient leaves the valves short of rated flow."""
    with pytest.raises(EnvelopeError) as caught:
        _envelope(reference_spec, reference_model, ModelParameters(flow_coefficient=0.9),
                  params_source="params.json")
    message = str(caught.value)
    assert message.startswith("flow_coefficient 0.9 from params.json: at 100% load")
    assert "wide-open governing valves pass only" in message
    needed = float(message.split("flow_coefficient ≥ ")[1].split(" ")[0])
    # the named coefficient does pass the rated flow, a little less does not
    for value, passes in ((needed + 0.002, True), (needed - 0.01, False)):
        line = operating_line(reference_spec, ModelParameters(flow_coefficient=value), [1.0],
                              model=reference_model)
        assert (line["failure"].iloc[0] == "") is passes


def test_bad_parameter_intervals_are_refused(reference_spec, reference_model):
    assert parse_parameter_interval("flow_coefficient=0.94:0.97") == (
        "flow_coefficient", (0.94, 0.97))
    for text in ("flow=0.9:1", "flow_coefficient=0.97:0.94", "flow_coefficient=0.9"):
        with pytest.raises(ValueError, match="NAME=LOW:HIGH"):
            parse_parameter_interval(text)
    with pytest.raises(ParameterError, match=r"does not contain flow_coefficient 0\.953"):
        _envelope(reference_spec, reference_model, CALIBRATED,
                  parameter_intervals={"flow_coefficient": (0.96, 0.98)})
    with pytest.raises(ParameterError, match="outside its physical bounds"):
        _envelope(reference_spec, reference_model, CALIBRATED,
                  parameter_intervals={"flow_coefficient": (0.85, 0.98)})


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(flow_coefficient=st.floats(0.925, 1.1), seed=st.integers(0, 50),
       layout=st.sampled_from(["lhs", "corners", "bands"]))
def test_every_planned_condition_runs_and_spans_the_line(reference_spec, reference_model,
                                                         flow_coefficient, seed, layout):
    """For any flow coefficient that passes rated flow, the repaired plan runs in the model
    as a whole and its p1 span the line's at 30…100 %."""
    params = ModelParameters(flow_coefficient=flow_coefficient)
    envelope = _envelope(reference_spec, reference_model, params)
    conditions, _ = feasible_conditions(
        reference_spec, design_conditions(reference_spec, 32, random_state=seed, layout=layout,
                                          envelope=envelope), params, model=reference_model)
    steady = conditions[list(INPUT_SIGNALS)].set_index(pd.Index(np.arange(len(conditions))
                                                                * 1e12))
    p1 = reference_model.simulate_detailed(steady, params, stages=False).diagnostics[
        "control_stage_pressure"].to_numpy()
    line = operating_line(reference_spec, params, [0.3, 0.5, 0.75, 1.0],
                          model=reference_model)["control_stage_pressure"].to_numpy()
    # to the model's own convergence: a sample that keeps the last sweep's state is within
    # 1.5 × the kernel's relative pressure tolerance of a converged solve (kernel.py; seen
    # here: 2e-5 between the plan's rated line point and the line's solve of the same inputs)
    slack = 1.5 * PRESSURE_TOLERANCE * line
    assert p1.min() <= line.min() + slack[0] and line.max() - slack[-1] <= p1.max()
