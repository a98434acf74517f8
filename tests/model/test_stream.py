"""The full-order model streamed block by block (issue 21, item 1): the same outputs as one
run over the whole series, a state that survives JSON, and clear refusals."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.stream_state import StreamState

PARAMS = ModelParameters(flow_coefficient=0.985, friction_coefficient=1.2,
                         heat_transfer_coefficient=1.3)


@pytest.fixture(scope="module")
def sensed(reference_spec) -> FullOrderModel:
    """The reference FOM read through thermocouple lags and an offset."""
    model = FullOrderModel(reference_spec, sensor_time_constants={
        "control_stage_temperature": 20.0, "hp_exhaust_temperature": 30.0,
        "hp_inner_casing_temperature": 5.0}, sensor_offsets={"hp_exhaust_temperature": 0.7})
    _ = model.design_
    return model


@pytest.fixture(scope="module")
def ramp(reference_spec) -> pd.DataFrame:
    """A 5 %/min ramp 100 → 60 % with holds, noisy inputs (no two samples equal)."""
    load = ramp_profile(1.0, 0.6, 0.05, 120.0, 300.0)
    inputs = load_profile_inputs(reference_spec, load)
    rng = np.random.default_rng(4)
    noisy = inputs * (1.0 + rng.normal(0.0, 2e-4, inputs.shape))
    noisy.iloc[200:260] = noisy.iloc[200]  # a run of repeated inputs too
    return noisy


def _streamed(model, inputs, cuts, params=PARAMS) -> pd.DataFrame:
    state, parts = None, []
    for start, stop in zip([0, *cuts], [*cuts, len(inputs)], strict=True):
        outputs, state = model.simulate_stream(inputs.iloc[start:stop], params, state)
        parts.append(outputs)
    return pd.concat(parts)


def test_streamed_blocks_equal_one_run(sensed, ramp):
    batch = sensed.simulate(ramp, PARAMS)
    streamed = _streamed(sensed, ramp, [1, 60, 61, 250, 600])
    assert streamed.index.equals(batch.index)
    assert np.abs(streamed.to_numpy() - batch.to_numpy()).max() <= 1e-9


@settings(max_examples=5, deadline=None)
@given(cuts=st.lists(st.integers(1, 899), min_size=1, max_size=6, unique=True))
def test_any_cut_gives_the_same_outputs(sensed, ramp, cuts):
    series = ramp.iloc[:900]
    batch = sensed.simulate(series, PARAMS)
    streamed = _streamed(sensed, series, sorted(cuts))
    assert np.abs(streamed.to_numpy() - batch.to_numpy()).max() <= 1e-9


def test_the_state_survives_json_exactly(sensed, ramp):
    _, state = sensed.simulate_stream(ramp.iloc[:300], PARAMS)
    restored = StreamState.from_dict(json.loads(json.dumps(state.to_dict())))
    direct, _ = sensed.simulate_stream(ramp.iloc[300:500], PARAMS, state)
    again, _ = sensed.simulate_stream(ramp.iloc[300:500], PARAMS, restored)
    pd.testing.assert_frame_equal(direct, again, check_exact=True)
    assert set(state.sensors) == {"control_stage_temperature", "hp_exhaust_temperature",
                                  "hp_inner_casing_temperature"}


def test_a_stream_refuses_the_past_and_a_foreign_state(sensed, ramp, reference_spec):
    _, state = sensed.simulate_stream(ramp.iloc[:100], PARAMS)
    with pytest.raises(InputError, match="not after the stream's last sample"):
        sensed.simulate_stream(ramp.iloc[50:150], PARAMS, state)
    broken = StreamState(state.time, {**state.arrays, "metal": state.arrays["metal"][:, :3]},
                         state.sensors)
    with pytest.raises(ValueError, match="shape"):
        sensed.simulate_stream(ramp.iloc[100:150], PARAMS, broken)
    with pytest.raises(ValueError, match="not a stream state"):
        StreamState.from_dict({"time": "2026-01-01T00:00:00Z"})
