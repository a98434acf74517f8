"""Thermocouple lag: exact against the virtual plant's discretisation, limits, in the FOM."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.dcs.sensors import first_order_lag
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S, lag
from steamtwin.model.operating import load_profile_inputs, ramp_profile


@settings(max_examples=30, deadline=None)
@given(dt=st.floats(0.1, 30.0), tau=st.floats(0.5, 100.0), seed=st.integers(0, 1000))
def test_equals_the_plant_instruments_lag_on_uniform_steps(dt, tau, seed):
    x = np.random.default_rng(seed).normal(500.0, 5.0, 300)
    steps = np.full(x.size, dt)
    np.testing.assert_allclose(lag(x, steps, tau), first_order_lag(x, dt, tau), rtol=0,
                               atol=1e-9)


def test_ramp_lags_by_tau_and_steady_start_and_zero_tau():
    t = np.concatenate([np.arange(0.0, 100.0, 1.0), 100.0 + np.arange(1, 401) * 2.5])
    steps = np.diff(t, prepend=-np.inf)
    x = 800.0 + 0.1 * t  # K, ramp at 0.1 K/s; uneven spacing
    y = lag(x, steps, 20.0)
    assert y[0] == x[0]
    late = t > 300.0  # transient gone: y = x(t − τ) exactly for a linear input
    np.testing.assert_allclose(y[late], 800.0 + 0.1 * (t[late] - 20.0), atol=1e-9)
    np.testing.assert_array_equal(lag(x, steps, 0.0), x)


def test_fom_reports_readings_and_keeps_the_computed_values(reference_spec, reference_model):
    inputs = load_profile_inputs(reference_spec, ramp_profile(1.0, 0.6, 0.05, 60.0, 300.0))
    lagged = FullOrderModel(reference_spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    plain = reference_model.simulate_detailed(inputs, stages=False)
    read = lagged.simulate_detailed(inputs, stages=False)
    for name, tau in TYPICAL_TIME_CONSTANTS_S.items():
        expected = lag(plain.outputs[name].to_numpy(), np.ones(len(inputs)), tau)
        np.testing.assert_allclose(read.outputs[name], expected, rtol=0, atol=1e-9)
    assert read.outputs["hp_exhaust_temperature"].iloc[0] == pytest.approx(
        plain.outputs["hp_exhaust_temperature"].iloc[0])  # steady start
    np.testing.assert_array_equal(read.diagnostics, plain.diagnostics)
    np.testing.assert_array_equal(read.outputs["control_stage_pressure"],
                                  plain.outputs["control_stage_pressure"])
    with pytest.raises(ValueError, match="not an output"):
        FullOrderModel(reference_spec, sensor_time_constants={"load": 1.0}).simulate(inputs)
    with pytest.raises(ValueError, match="≥ 0"):
        FullOrderModel(reference_spec, sensor_time_constants={
            "hp_exhaust_temperature": -1.0}).simulate(inputs)
