"""One continuous run of the twin over a long file (:mod:`steamtwin.validation.replay`) and the
windows of ``monitor_windows`` taken from it (``replay_over``)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import steamtwin.validation.monitor as monitor
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.reconstruction import FLAG_INVALID
from steamtwin.validation.replay import ELAPSED, replay, replay_span

CASING = "hp_inner_casing_temperature"


@pytest.fixture(scope="module")
def ramp_then_hold(reference_spec) -> pd.DataFrame:
    """10 min at rated flow, a 4 %/min ramp to 50 % (12.5 min), 40 min at 50 %; 1-s samples,
    SI. Throttle (constant main-steam pressure) operation: the HP exhaust pressure follows
    the flow (Stodola's cone law with a low exhaust/inlet ratio: p ∝ ṁ; Cooke 1983)."""
    design = reference_spec.design
    seconds = np.arange(0.0, 600.0 + 750.0 + 2400.0)
    fraction = np.clip(1.0 - 0.04 / 60.0 * (seconds - 600.0), 0.5, 1.0)
    index = pd.date_range("2026-03-01", periods=seconds.size, freq="1s", tz="UTC")
    return pd.DataFrame({
        "main_steam_pressure": design.main_steam_pressure,
        "main_steam_temperature": design.main_steam_temperature,
        "main_steam_flow": design.main_steam_flow * fraction,
        "hp_exhaust_pressure": design.hp_exhaust_pressure * fraction,
    }, index=index)


def test_one_run_over_the_file_is_the_models_own_run(reference_model, ramp_then_hold):
    replayed = replay(reference_model, ramp_then_hold)
    direct = reference_model.simulate(ramp_then_hold, ModelParameters())
    pd.testing.assert_frame_equal(replayed.drop(columns=ELAPSED), direct)
    assert np.array_equal(replayed[ELAPSED].to_numpy(), np.arange(len(ramp_then_hold)))


def test_a_window_after_a_ramp_keeps_the_metals_state(reference_model, ramp_then_hold):
    """The hold's first sample, 50 s after the ramp: a fresh steady start puts the casing at
    its 50 % equilibrium, the continuous run still several K above it (the metal stored the
    full-load heat: lumped wall, τ = ρcV/(hA), Incropera & DeWitt §5.1); the start's error
    then decays monotonically, with the metal's time constant (≈ 30 min in this model: a
    third of it is left after 39 min)."""
    hold = ramp_then_hold.iloc[1400:]
    continuous = replay(reference_model, ramp_then_hold).loc[hold.index, CASING]
    fresh = reference_model.simulate(hold, ModelParameters())[CASING]
    difference = (continuous - fresh).to_numpy()[::60]  # each minute
    assert difference[0] > 5.0
    assert np.all(np.diff(difference) < 0.0)
    assert 0.15 * difference[0] < difference[-1] < 0.5 * difference[0]


def test_a_long_input_dropout_restarts_the_run_and_a_short_one_is_held(
        reference_model, ramp_then_hold):
    data = ramp_then_hold.copy()
    flow = data.columns.get_loc("main_steam_flow")
    data.iloc[300:330, flow] = np.nan  # 30 s: held, as a calibration window holds it
    data.iloc[2000:2200, flow] = np.nan  # 200 s: more than 60 s, the run is cut
    replayed = replay(reference_model, data)
    assert replayed.iloc[2000:2200].isna().all().all()
    assert replayed[ELAPSED].iloc[1999] == 1999.0  # one run through the short dropout
    assert replayed[ELAPSED].iloc[2200] == 0.0  # restarted at steady state
    tail = replay(reference_model, data.iloc[2200:])
    pd.testing.assert_frame_equal(replayed.iloc[2200:], tail)


def test_rows_before_the_first_complete_input_are_not_run(reference_model, ramp_then_hold):
    data = ramp_then_hold.copy()
    data.iloc[:5, data.columns.get_loc("hp_exhaust_pressure")] = np.nan
    replayed = replay(reference_model, data)
    assert replayed.iloc[:5].isna().all().all()
    assert replayed[ELAPSED].iloc[5] == 0.0


def test_bad_input_is_refused_with_its_name(reference_model, ramp_then_hold):
    with pytest.raises(ValueError, match=r"day-2: lacks the model's input column\(s\) "
                                         r"\['main_steam_flow'\]"):
        replay(reference_model, ramp_then_hold.drop(columns="main_steam_flow"), name="day-2")
    with pytest.raises(ValueError, match="non-empty DataFrame"):
        replay(reference_model, ramp_then_hold.iloc[:0])


def test_monitor_windows_takes_each_window_from_the_one_run(
        reference_model, ramp_then_hold, monkeypatch):
    """``replay_over``: the window's FOM signals are the continuous run's samples; without it,
    a fresh run from the window's start (the behaviour before). The ROM part is stubbed: this
    is about where the FOM's samples come from."""
    def rom_alone(bundle, frame):
        return SimpleNamespace(sensors=pd.DataFrame({FLAG_INVALID: False}, index=frame.index))

    monkeypatch.setattr(monitor, "predict_series", rom_alone)
    bundle = SimpleNamespace(rom=SimpleNamespace(input_names_=("main_steam_pressure",)),
                             provenance={"model_parameters": {
                                 "flow_coefficient": 1.0, "friction_coefficient": 1.0,
                                 "heat_transfer_coefficient": 1.0}})
    windows = {"hold": ramp_then_hold.iloc[1400:2000]}
    whole = monitor.monitor_windows(bundle, windows, reference_model,
                                    replay_over=ramp_then_hold)["hold"]
    fresh = monitor.monitor_windows(bundle, windows, reference_model)["hold"]
    expected = replay(reference_model, ramp_then_hold).loc[windows["hold"].index, CASING]
    np.testing.assert_array_equal(whole[CASING].to_numpy(), expected.to_numpy())
    assert whole[CASING].iloc[0] - fresh[CASING].iloc[0] > 2.0
    assert not whole[FLAG_INVALID].any()
    with pytest.raises(ValueError, match="replay_over needs a simulator"):
        monitor.monitor_windows(bundle, windows, replay_over=ramp_then_hold)


def test_replay_span_starts_the_warm_up_before_the_first_window_and_ends_with_the_last():
    index = pd.date_range("2026-03-01", periods=10 * 3600, freq="s", tz="UTC")
    data = pd.DataFrame({"x": np.arange(index.size, dtype=float)}, index=index)
    late, early = data.iloc[30000:30600], data.iloc[20000:20600]
    span = replay_span(data, [late, early], warm_up_s=3600.0)
    assert span.index[0] == early.index[0] - pd.Timedelta(hours=1)
    assert span.index[-1] == late.index[-1]
    # a warm-up longer than the file before the window starts at the file's first row
    assert replay_span(data, [early], warm_up_s=24 * 3600.0).index[0] == index[0]
    with pytest.raises(ValueError, match="at least one window"):
        replay_span(data, [])
