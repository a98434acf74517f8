"""Operating line and load profiles."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.model.operating import load_profile_inputs, operating_point, ramp_profile


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
