"""One sensor setup for every mode (issue 18, item 3): tag map first, else τ estimated from the
data's ramps, else typical; the metal thermocouple's depth from the tag map."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.dcs.tagmap import TagMapError, parse_tag_map
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S, lag
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.sensor_setup import (
    TIME_CONSTANT_SEARCH_S,
    estimate_time_constant,
    sensor_setup,
)

# the plant's own thermowells: slower than the typical values the twin assumes
TRUE_TAU = {"control_stage_temperature": 35.0, "hp_exhaust_temperature": 60.0}
NOISE_K = 0.2


def _tag_map(extra: str = "") -> str:
    return ("[historian]\nlayout = 'wide'\ntime_column = 't'\ntime_zone = 'UTC'\n"
            "[signals.hp_exhaust_temperature]\ncolumn = 'a'\nunit = 'degC'\n" + extra)


@pytest.fixture(scope="module")
def ramp_windows(reference_spec):
    """Two windows of the model's own temperatures read through slower sensors, with a bias
    and noise: a 3 %/min ramp down and one up (plus holds)."""
    model = FullOrderModel(reference_spec)
    rng = np.random.default_rng(7)
    windows = []
    for start, end in ((0.9, 0.6), (0.55, 0.85)):
        loads = ramp_profile(start, end, 0.03, 300.0, 600.0, step_seconds=2.0)
        inputs = load_profile_inputs(reference_spec, loads, step_seconds=2.0)
        outputs = model.simulate(inputs)
        window = inputs.copy()
        steps = np.full(len(inputs), 2.0)
        for name in model.output_signals:
            reading = outputs[name].to_numpy()
            if name in TRUE_TAU:
                reading = lag(reading, steps, TRUE_TAU[name]) + 0.7
                reading = reading + rng.normal(0.0, NOISE_K, reading.size)
            window[name] = reading
        windows.append(window)
    return windows


def test_time_constants_are_estimated_from_ramps(reference_spec, ramp_windows):
    setup = sensor_setup(reference_spec, None, ramp_windows)
    for name, tau in TRUE_TAU.items():
        assert setup.time_constants[name] == pytest.approx(tau, rel=0.15), name
        assert setup.sources[name].startswith("estimated from the data's ramps")
        low, high = (float(x) for x in setup.sources[name].rsplit("interval ", 1)[1]
                     .removesuffix(" s").split("–"))
        assert low <= tau <= high
    # the casing thermocouple has no lag in these data: its τ cannot go below the search range,
    # so it stays at the typical value, said so
    casing = "hp_inner_casing_temperature"
    assert setup.time_constants[casing] == TYPICAL_TIME_CONSTANTS_S[casing]
    assert setup.sources[casing].startswith("typical value")


def test_a_steady_window_cannot_tell_the_time_constant(reference_spec, ramp_windows):
    steady = ramp_windows[0].iloc[:140]  # the hold before the ramp
    setup = sensor_setup(reference_spec, None, [steady])
    name = "hp_exhaust_temperature"
    assert setup.time_constants[name] == TYPICAL_TIME_CONSTANTS_S[name]
    assert "not identified by the data" in setup.sources[name]


def test_the_tag_map_wins_and_no_data_means_typical(reference_spec, ramp_windows):
    tag_map = parse_tag_map(_tag_map("time_constant = 12.5\n"))
    setup = sensor_setup(reference_spec, tag_map, ramp_windows)
    assert setup.time_constants["hp_exhaust_temperature"] == 12.5
    assert setup.sources["hp_exhaust_temperature"] == "tag map"
    assert setup.time_constants["control_stage_temperature"] == pytest.approx(35.0, rel=0.15)
    bare = sensor_setup(reference_spec, tag_map)
    assert bare.time_constants["control_stage_temperature"] == TYPICAL_TIME_CONSTANTS_S[
        "control_stage_temperature"]
    assert bare.sources["control_stage_temperature"].startswith("typical value (no data")
    assert bare.model(reference_spec).sensor_time_constants == bare.time_constants


def test_the_thermocouple_depth_comes_from_the_tag_map(reference_spec, ramp_windows):
    """A metal thermocouple 40 mm deep follows the bore's transient later and less than one
    at the spec's 14 mm: on the ramp its reading differs; at steady state it does not."""
    inputs = ramp_windows[0][list(FullOrderModel.input_signals)]
    readings = {}
    for depth in ("14 mm", "40 mm"):
        text = _tag_map().replace("hp_exhaust_temperature", "hp_inner_casing_temperature")
        setup = sensor_setup(reference_spec, parse_tag_map(text + f"depth = '{depth}'\n"))
        assert setup.spec_for(reference_spec).casing_thermocouple_depth == pytest.approx(
            float(depth.split()[0]) / 1e3)
        assert setup.depth_source == "tag map depth"
        readings[depth] = setup.model(reference_spec).simulate(inputs)[
            "hp_inner_casing_temperature"].to_numpy()
    difference = readings["40 mm"] - readings["14 mm"]
    assert -0.5 < difference[0] < 0.0  # steady: the lagging's small heat loss cools the depth
    # the ramp's cooling wave reaches the deeper point later: it reads warmer while it passes
    assert np.max(difference - difference[0]) > 0.5
    assert sensor_setup(reference_spec).casing_thermocouple_depth is None


@pytest.mark.parametrize(("depth", "message"), [
    ("'20 kg'", "not convertible to m"),
    ("20", r'expected a length such as "20 mm" in \[0, 200\] mm'),
    ("'0.3 m'", r" = '0.3 m': expected a length"),
])
def test_a_bad_depth_is_refused_naming_the_field(depth, message):
    text = _tag_map().replace("hp_exhaust_temperature", "hp_inner_casing_temperature")
    with pytest.raises(TagMapError, match=r"signals.hp_inner_casing_temperature.depth.*" + message):
        parse_tag_map(text + f"depth = {depth}\n")


def test_only_the_metal_thermocouple_has_a_depth():
    with pytest.raises(TagMapError, match="only the metal thermocouple"):
        parse_tag_map(_tag_map("depth = '20 mm'\n"))


def test_the_estimate_recovers_a_pure_lag_and_flags_flat_data():
    """A first-order reading of a clean ramp: τ recovered to 1e-2 relative; constant data
    leave τ unidentified across the whole search range."""
    steps = np.ones(3000)
    x = np.concatenate([np.full(500, 500.0), 500.0 - 0.05 * np.arange(2000), np.full(500, 400.0)])
    y = lag(x, steps, 80.0) + np.random.default_rng(1).normal(0.0, 0.05, x.size)
    estimate = estimate_time_constant([(y, x, steps)])
    assert estimate.identified and estimate.value == pytest.approx(80.0, rel=1e-2)
    assert estimate.low < 80.0 < estimate.high
    flat = estimate_time_constant([(np.full(600, 3.0), np.full(600, 2.0), np.ones(600))])
    assert not flat.identified
    assert (flat.low, flat.high) == pytest.approx(TIME_CONSTANT_SEARCH_S)


def test_offsets_are_described_in_their_signals_units():
    """A thermocouple's offset in K, a pressure witness's (SI Pa inside) in kPa."""
    from steamtwin.model.sensor_setup import SensorSetup

    setup = SensorSetup({}, {}, offsets={"hp_exhaust_temperature": -1.25,
                                         "control_stage_pressure": 2149.0})
    assert setup.describe() == [
        "hp_exhaust_temperature: offset -1.25 K (the calibration's estimate of its bias)",
        "control_stage_pressure: offset +2.15 kPa (the calibration's estimate of its bias)"]
