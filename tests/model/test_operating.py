"""Operating line and load profiles."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from steamtwin.model.operating import (
    hp_exhaust_pressure,
    load_profile_inputs,
    main_steam_temperature,
    operating_point,
    ramp_profile,
)
from steamtwin.spec import TemperatureSchedule, TurbineSpec

KELVIN = 273.15


def test_sliding_pressure_line_and_proportional_flows(reference_spec):
    point = operating_point(reference_spec, np.array([0.27, 0.52, 0.77, 1.0]))
    assert np.allclose(point["main_steam_pressure"] / 1e6, [6.0, 11.35, 16.7, 16.7])
    assert np.allclose(point["main_steam_flow"], [135.0, 260.0, 385.0, 500.0])
    assert np.allclose(point["hp_exhaust_pressure"] / point["main_steam_flow"], 3.9e6 / 500.0)
    with pytest.raises(ValueError, match="load_fraction must lie within"):
        operating_point(reference_spec, 0.1)


def test_ramp_profile_shape():
    load = ramp_profile(1.0, 0.3, 0.05, hold_before_s=60, hold_after_s=120)
    assert load.size == 60 + 840 + 120 + 1
    assert load[60] == 1.0 and load[-121] == pytest.approx(0.3)
    assert np.allclose(np.diff(load[60:900]), -0.05 / 60)
    hold = ramp_profile(0.5, 0.5, 0.05, hold_before_s=10, hold_after_s=10)
    assert hold.shape == (21,) and np.all(hold == 0.5)


def test_load_profile_inputs_is_a_timed_frame(reference_spec):
    frame = load_profile_inputs(reference_spec, [0.5, 0.5, 0.6], step_seconds=2.0)
    assert str(frame.index.tz) == "UTC"
    assert (frame.index[1] - frame.index[0]).total_seconds() == 2.0


def _scheduled(spec: TurbineSpec, loads: tuple[float, ...], main_c: tuple[float, ...],
               reheat_c: tuple[float, ...] | None = None) -> TurbineSpec:
    """``spec`` with a temperature schedule given in °C."""
    schedule = TemperatureSchedule(
        loads, tuple(t + KELVIN for t in main_c),
        None if reheat_c is None else tuple(t + KELVIN for t in reheat_c))
    return dataclasses.replace(spec, temperature_schedule=schedule)


def test_temperature_schedule_is_linear_between_its_points_and_flat_outside(reference_spec):
    spec = _scheduled(reference_spec, (0.3, 0.5, 1.0), (520.0, 530.0, 538.0))
    loads = np.array([0.2, 0.3, 0.4, 0.75, 1.0, 1.1])
    # by hand: 0.4 halfway 520→530; 0.75 halfway 530→538; flat below 0.3 and above 1.0
    expected_c = [520.0, 520.0, 525.0, 534.0, 538.0, 538.0]
    point = operating_point(spec, loads)
    assert point["main_steam_temperature"] - KELVIN == pytest.approx(expected_c, abs=1e-9)
    assert np.array_equal(main_steam_temperature(spec, loads), point["main_steam_temperature"])
    # no reheat axis: the HP-exhaust pressure still follows the flow alone, the pressure line too
    line = operating_point(reference_spec, loads)
    for name in ("main_steam_pressure", "main_steam_flow", "hp_exhaust_pressure"):
        assert np.array_equal(point[name], line[name]), name


def test_a_scheduled_reheat_temperature_scales_the_hp_exhaust_by_the_cone_law(reference_spec):
    spec = _scheduled(reference_spec, (0.3, 1.0), (520.0, 538.0), (500.0, 538.0))
    loads = np.array([0.25, 0.3, 0.65, 1.0])
    point = operating_point(spec, loads)
    # m·sqrt(T)/p constant at the IP inlet: p/m = (3.9 MPa / 500 kg/s)·sqrt(T_rh / 538 °C);
    # T_rh by hand: 500, 500, 519, 538 °C
    reheat = np.array([500.0, 500.0, 519.0, 538.0]) + KELVIN
    expected = 3.9e6 / 500.0 * np.sqrt(reheat / (538.0 + KELVIN))
    assert point["hp_exhaust_pressure"] / point["main_steam_flow"] == pytest.approx(expected,
                                                                                  rel=1e-12)
    assert float(hp_exhaust_pressure(spec, 500.0, 1.0)) == 3.9e6


def test_without_a_schedule_the_operating_line_is_todays_bit_for_bit(reference_spec):
    loads = np.linspace(0.2, 1.1, 91)
    design = reference_spec.design
    point = operating_point(reference_spec, loads)
    assert reference_spec.temperature_schedule is None
    assert np.array_equal(point["main_steam_temperature"],
                          np.full_like(loads, design.main_steam_temperature))
    assert np.array_equal(point["hp_exhaust_pressure"],
                          design.hp_exhaust_pressure * (loads * design.main_steam_flow)
                          / design.main_steam_flow)
    # a flat schedule at the design temperature without a reheat axis changes nothing either
    flat = operating_point(_scheduled(reference_spec, (0.2, 1.1), (538.0, 538.0)), loads)
    for name, values in point.items():
        assert np.array_equal(flat[name], values), name


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0.0, 1.2), min_size=2, max_size=6, unique=True),
       st.lists(st.floats(300.0, 650.0), min_size=6, max_size=6), st.floats(0.2, 1.1))
def test_the_scheduled_temperature_lies_between_its_neighbouring_points(reference_spec, loads,
                                                                          temperatures, load):
    loads = sorted(loads)
    assume(all(b - a > 1e-6 for a, b in itertools.pairwise(loads)))
    main_c = tuple(temperatures[: len(loads)])
    spec = _scheduled(reference_spec, tuple(loads), main_c)
    value = float(operating_point(spec, load)["main_steam_temperature"]) - KELVIN
    if load <= loads[0]:
        assert value == pytest.approx(main_c[0], abs=1e-9)
    elif load >= loads[-1]:
        assert value == pytest.approx(main_c[-1], abs=1e-9)
    else:
        upper = next(i for i, x in enumerate(loads) if x >= load)
        low, high = sorted((main_c[upper - 1], main_c[upper]))
        assert low - 1e-9 <= value <= high + 1e-9
