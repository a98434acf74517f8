"""Residual monitoring (issue 21, item 5): CUSUM thresholds from the wanted false-alarm rate,
a drifting sensor told from a degrading turbine, no alarm on healthy data."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.live.residuals import (
    MonitorSettings,
    ResidualMonitor,
    _long_run_factor,
    block_means,
    model_sensitivity,
    siegmund_threshold,
)

SENSORS = ("control_stage_pressure", "control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")
SIGMA = {"control_stage_pressure": 1.0e4, "control_stage_temperature": 0.1,
         "hp_exhaust_temperature": 0.1, "hp_inner_casing_temperature": 0.1}
# sensitivity to the flow coefficient (per unit): p1 ∝ 1/φ at 9.5 MPa, temperatures mildly
J = pd.DataFrame({"flow_coefficient": [-9.5e6, 25.0, 8.0, 20.0]}, index=list(SENSORS))


def _healthy(blocks: int, rng: np.random.Generator) -> pd.DataFrame:
    index = pd.date_range("2026-03-01", periods=blocks, freq="60s", tz="UTC")
    return pd.DataFrame({s: rng.normal(0.0, SIGMA[s], blocks) for s in SENSORS}, index=index)


def _monitor(seed: int = 0) -> ResidualMonitor:
    rng = np.random.default_rng(seed)
    return ResidualMonitor(SENSORS, {s: 0.5 * v for s, v in SIGMA.items()}).fit(
        _healthy(600, rng))


def test_siegmund_threshold_matches_the_tabulated_cusum():
    """Montgomery (7th ed.) Table 9.3: two-sided k = 0.5, h = 4 → ARL₀ 168, h = 5 → 465; a
    one-sided CUSUM has twice that."""
    assert siegmund_threshold(2 * 168.0, 0.5) == pytest.approx(4.0, abs=0.05)
    assert siegmund_threshold(2 * 465.0, 0.5) == pytest.approx(5.0, abs=0.05)
    with pytest.raises(ValueError):
        siegmund_threshold(0.5, 0.5)


def test_the_threshold_gives_the_wanted_run_length_monte_carlo():
    rng = np.random.default_rng(3)
    k, arl0 = 0.5, 200.0
    h = siegmund_threshold(arl0, k)
    lengths = []
    for _ in range(400):
        g, n = 0.0, 0
        while g <= h:
            g = max(0.0, g + rng.normal() - k)
            n += 1
        lengths.append(n)
    assert np.mean(lengths) == pytest.approx(arl0, rel=0.2)


def test_healthy_days_raise_no_alarm():
    for seed in range(3):
        monitor = _monitor(seed)
        day = _healthy(1440, np.random.default_rng(100 + seed))
        events = [e for t, row in day.iterrows() for e in monitor.update(t, row, J)]
        assert events == []


def test_a_drifting_thermocouple_is_a_sensor_fault():
    monitor = _monitor()
    day = _healthy(120, np.random.default_rng(7))
    minutes = np.arange(120, dtype=float)
    day["hp_exhaust_temperature"] += np.clip(minutes - 30.0, 0.0, None) * 2.0 / 60.0  # 2 K/h
    events = [e for t, row in day.iterrows() for e in monitor.update(t, row, J)]
    assert events, "the drift was not flagged"
    first = events[0]
    assert (first.kind, first.signal) == ("sensor_fault", "hp_exhaust_temperature")
    assert first.time - day.index[30] <= pd.Timedelta(minutes=15)
    assert not any(e.kind == "degradation" for e in events)


def test_a_flow_coefficient_step_is_degradation():
    monitor = _monitor()
    day = _healthy(120, np.random.default_rng(8))
    step = np.where(np.arange(120) >= 60, -0.02, 0.0)
    for sensor in SENSORS:
        day[sensor] += J.loc[sensor, "flow_coefficient"] * step
    events = [e for t, row in day.iterrows() for e in monitor.update(t, row, J)]
    assert events and (events[0].kind, events[0].signal) == ("degradation", "flow_coefficient")
    assert events[0].time - day.index[60] <= pd.Timedelta(minutes=10)
    assert not any(e.kind == "sensor_fault" for e in events)


def test_an_alarm_ends_and_the_state_restores_exactly():
    monitor = _monitor()
    day = _healthy(200, np.random.default_rng(9))
    day.iloc[20:40, 2] += 2.0  # a 20-min bias step on the exhaust
    events, copied = [], []
    copy = None
    for k, (t, row) in enumerate(day.iterrows()):
        if k == 30:  # mid-alarm: a restart from the saved state
            copy = ResidualMonitor(SENSORS, {s: 0.5 * v for s, v in SIGMA.items()}).set_state(
                monitor.get_state())
        events += monitor.update(t, row, J)
        if copy is not None:
            copied += copy.update(t, row, J)
    starts = [e for e in events if not e.ended]
    ends = [e for e in events if e.ended]
    assert [(e.kind, e.signal) for e in starts] == [("sensor_fault", "hp_exhaust_temperature")]
    assert len(ends) == 1 and ends[0].signal == "hp_exhaust_temperature"
    assert day.index[20] <= starts[0].time <= day.index[23]
    assert day.index[40] <= ends[0].time <= day.index[45]
    assert copied == [e for e in events if e.time >= day.index[30]]
    assert copy.get_state() == monitor.get_state()


@settings(max_examples=25, deadline=None)
@given(scale=st.floats(1e-3, 1e3), shift=st.floats(-5.0, 5.0))
def test_the_statistics_do_not_depend_on_the_units(scale, shift):
    """Invariant: rescaling a sensor (units) and its σ together leaves every statistic as it is."""
    rng = np.random.default_rng(11)
    healthy = _healthy(200, rng)
    block = healthy.iloc[-1] + shift * pd.Series(SIGMA)
    a = ResidualMonitor(SENSORS, SIGMA).fit(healthy)
    scaled = {**SIGMA, "hp_exhaust_temperature": SIGMA["hp_exhaust_temperature"] * scale}
    b = ResidualMonitor(SENSORS, scaled, MonitorSettings(sensor_shift={
        "hp_exhaust_temperature": 2.0 * a.sigma_["hp_exhaust_temperature"] * scale}))
    b.fit(healthy.assign(hp_exhaust_temperature=healthy["hp_exhaust_temperature"] * scale))
    t = healthy.index[-1]
    scaled_block = block.copy()
    scaled_block["hp_exhaust_temperature"] *= scale
    a.update(t, block, None)
    b.update(t, scaled_block, None)
    assert a.statistics_.keys() == b.statistics_.keys()
    for key in a.statistics_:
        assert b.statistics_[key] == pytest.approx(a.statistics_[key], rel=1e-9, abs=1e-12)


def test_block_means_count_samples():
    index = pd.date_range("2026-03-01", periods=180, freq="1s", tz="UTC")
    frame = pd.DataFrame({"x": np.arange(180.0)}, index=index)
    frame.iloc[5, 0] = np.nan
    means = block_means(frame, 60.0)
    assert list(means["n_x"]) == [59, 60, 60]
    assert means["x"].iloc[1] == pytest.approx(np.arange(60.0, 120.0).mean())


def test_model_sensitivity_of_the_full_order_model(reference_model):
    from steamtwin.model.operating import operating_point
    from steamtwin.model.parameters import ModelParameters

    point = operating_point(reference_model.spec, 0.5)
    index = pd.date_range("2026-03-01", periods=30, freq="1s", tz="UTC")
    inputs = pd.DataFrame({name: np.full(30, point[name]) for name in
                           reference_model.input_signals}, index=index)
    sensitivity = model_sensitivity(reference_model, inputs, ModelParameters(),
                                    ["control_stage_pressure"])
    p1 = reference_model.simulate(inputs, ModelParameters())["control_stage_pressure"].mean()
    # Stodola's cone law through the first pressure stage: p1 roughly ∝ 1/φ
    assert sensitivity.loc["control_stage_pressure", "flow_coefficient"] == pytest.approx(
        -p1, rel=0.35)


def _load_day(rng: np.random.Generator, blocks: int = 720) -> tuple[pd.DataFrame, pd.Series]:
    """Healthy residuals whose mean follows the load (a curve) and the lag of a 20-min
    first-order metal behind it (ramps of 2 %/min between holds), plus AR(1) noise."""
    index = pd.date_range("2026-03-01", periods=blocks, freq="60s", tz="UTC")
    targets = [0.5, 0.9, 0.4, 0.8, 0.6, 1.0]
    load, level = np.empty(blocks), 0.5
    for k in range(blocks):
        target = targets[(k // 120) % len(targets)]
        level += float(np.clip(target - level, -0.02, 0.02))
        load[k] = level
    lagged = np.empty(blocks)
    lagged[0] = load[0]
    for k in range(1, blocks):
        lagged[k] = lagged[k - 1] + (1.0 - np.exp(-60.0 / 1200.0)) * (load[k] - lagged[k - 1])
    noise = np.zeros((blocks, len(SENSORS)))
    for k in range(1, blocks):
        noise[k] = 0.5 * noise[k - 1] + rng.normal(0.0, 1.0, len(SENSORS))
    scale = np.array([SIGMA[s] for s in SENSORS])
    shape = np.column_stack([3.0 * load**2, -2.0 * load, np.sin(3.0 * load), load])
    transient = np.outer(load - lagged, [20.0, 10.0, 30.0, -5.0])
    frame = pd.DataFrame((shape + transient + 0.5 * noise) * scale, index=index,
                         columns=list(SENSORS))
    return frame, pd.Series(load, index=index)


def test_an_operating_point_baseline_holds_where_one_offset_alarms():
    """Fitted on a healthy day with ramps, the load baseline and transient σ raise no alarm
    on another such day (one offset raises many) and still catch a 2 K/h drift."""
    healthy, load = _load_day(np.random.default_rng(20))
    plain = ResidualMonitor(SENSORS, {s: 0.5 * v for s, v in SIGMA.items()}).fit(healthy)
    fitted = ResidualMonitor(SENSORS, {s: 0.5 * v for s, v in SIGMA.items()}).fit(
        healthy, load=load)
    day, day_load = _load_day(np.random.default_rng(21))
    assert sum(len(plain.update(t, row, J)) for t, row in day.iterrows()) > 0
    assert [e for t, row in day.iterrows()
            for e in fitted.update(t, row, J, load=day_load[t])] == []
    fitted.set_state(fitted.get_state() | {"statistics": {}, "active": {},
                                           "filtered_load": None, "last_time": None})
    drifted = day.copy()
    minutes = np.arange(len(day), dtype=float)
    drifted["hp_exhaust_temperature"] += np.clip(minutes - 360.0, 0.0, None) * 2.0 / 60.0
    events = [e for t, row in drifted.iterrows()
              for e in fitted.update(t, row, J, load=day_load[t])]
    assert events and (events[0].kind, events[0].signal) == ("sensor_fault",
                                                             "hp_exhaust_temperature")
    assert events[0].time - day.index[360] <= pd.Timedelta(minutes=30)


def test_the_load_state_restores_exactly():
    healthy, load = _load_day(np.random.default_rng(22), 240)
    monitor = ResidualMonitor(SENSORS, SIGMA).fit(healthy, load=load)
    day, day_load = _load_day(np.random.default_rng(23), 240)
    day.iloc[100:, 1] += 5.0 * SIGMA["control_stage_temperature"]
    copy, a, b = None, [], []
    for k, (t, row) in enumerate(day.iterrows()):
        if k == 50:
            state = json.loads(json.dumps(monitor.get_state()))
            copy = ResidualMonitor(SENSORS, SIGMA).set_state(state)
        a += monitor.update(t, row, J, load=day_load[t])
        if copy is not None:
            b += copy.update(t, row, J, load=day_load[t])
    assert a and b == [e for e in a if e.time >= day.index[50]]
    assert copy.get_state() == monitor.get_state()


def test_the_long_run_factor_of_an_ar1_series():
    """√((1+ρ)/(1−ρ)) for AR(1): ρ = 0.6 → 2 (Box, Jenkins & Reinsel §3.2)."""
    rng = np.random.default_rng(5)
    x = np.zeros(20000)
    for k in range(1, x.size):
        x[k] = 0.6 * x[k - 1] + rng.normal()
    assert _long_run_factor(x) == pytest.approx(2.0, rel=0.05)
    assert _long_run_factor(rng.normal(size=5000)) == pytest.approx(1.0, abs=0.05)


def _after_a_degradation_swap(rebase: bool, seed: int = 12) -> tuple[list, list]:
    """A flow step flagged as degradation; the twin's coefficient then swapped in (the J
    pattern gone) but a plant response the twin lacks leaves the casing thermocouple 0.35 K
    (≈ 3.5 σ) off; 100 min later a real 0.35-K bias on the exhaust thermocouple. Returns
    (events before the swap, events after it)."""
    monitor = _monitor()
    day = _healthy(300, np.random.default_rng(seed))
    step = np.where(np.arange(300) >= 30, -0.02, 0.0)
    for sensor in SENSORS:
        day[sensor] += J.loc[sensor, "flow_coefficient"] * step
    before = [e for t, row in day.iloc[:50].iterrows() for e in monitor.update(t, row, J)]
    after_swap = day.iloc[50:].copy()
    for sensor in SENSORS:  # the swapped coefficient explains the pattern ...
        after_swap[sensor] -= J.loc[sensor, "flow_coefficient"] * -0.02
    after_swap["hp_inner_casing_temperature"] += 0.35  # ... but not the casing's answer
    after_swap.iloc[100:, 2] += 0.35  # a real exhaust bias, 100 min after the swap
    monitor.restart(day.index[49] if rebase else None)  # blocks after the 50th re-based
    after = []
    for k, (t, row) in enumerate(after_swap.iterrows()):
        if k == 5:  # a restart from the saved state mid-window
            monitor = ResidualMonitor(SENSORS, {s: 0.5 * v for s, v in SIGMA.items()}
                                      ).set_state(json.loads(json.dumps(monitor.get_state())))
        after += monitor.update(t, row, J)
    return before, after


def test_a_degradation_swap_re_bases_the_residuals():
    """The rule of steamtwin.live.rebaseline with one band (a monitor without loads; control
    chart revised after an assignable cause, CUSUM restarted: Montgomery §5.3/§6.2; Page
    1954): without it the casing's leftover
    offset is a 'sensor fault' for as long as the data last; with it, none — and a real
    sensor bias after the window is still flagged as one."""
    before, stale = _after_a_degradation_swap(rebase=False)
    assert [(e.kind, e.signal) for e in before if not e.ended] == [
        ("degradation", "flow_coefficient")]
    assert ("sensor_fault", "hp_inner_casing_temperature") in [
        (e.kind, e.signal) for e in stale if not e.ended]
    _, rebased = _after_a_degradation_swap(rebase=True)
    starts = [e for e in rebased if not e.ended]
    assert [(e.kind, e.signal) for e in starts] == [("sensor_fault", "hp_exhaust_temperature")]
    swap = pd.Timestamp("2026-03-01", tz="UTC") + pd.Timedelta(minutes=50)
    bias = swap + pd.Timedelta(minutes=100)
    assert bias < starts[0].time <= bias + pd.Timedelta(minutes=15)
    # the degradation alarm ended once the re-based residuals were healthy
    assert [(e.kind, e.signal) for e in rebased if e.ended] == [
        ("degradation", "flow_coefficient")]
    with pytest.raises(ValueError, match="rebase_blocks"):
        MonitorSettings(rebase_blocks=0)
