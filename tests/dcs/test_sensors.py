"""Measurement layer of the virtual plant (steamtwin.dcs.sensors)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.dcs.quality import check_quality
from steamtwin.dcs.sensors import (
    SECONDS_PER_YEAR,
    FaultConfig,
    SensorModel,
    default_sensor_models,
    first_order_lag,
    measure,
    pressure_transmitter,
    type_k_thermocouple,
)
from steamtwin.dcs.signals import SIGNALS

START = pd.Timestamp("2024-03-01 08:00", tz="Asia/Shanghai")
NO_FAULTS = FaultConfig.off()


def frame(columns: dict[str, np.ndarray], step: str = "1s") -> pd.DataFrame:
    n = len(next(iter(columns.values())))
    return pd.DataFrame(columns, index=pd.date_range(START, periods=n, freq=step))


def bare(model: SensorModel, **changes: float) -> SensorModel:
    """The model with every effect off except those given."""
    off = dict(tolerance_abs=0.0, tolerance_of_reading=0.0, tolerance_of_span=0.0,
               time_constant_s=0.0, noise_sigma=0.0, drift_per_year=0.0, resolution=0.0)
    return dataclasses.replace(model, **(off | changes))


PRESSURE = pressure_transmitter((0.0, 25.0e6))


# --------------------------------------------------------------------------------------------
# first-order lag


@pytest.mark.parametrize("hold", ["linear", "zero"])
@pytest.mark.parametrize("tau", [10.0, 20.0, 37.0])
def test_step_reaches_63_percent_at_tau(hold: str, tau: float) -> None:
    n, k0 = 400, 50
    x = np.zeros(n)
    x[k0:] = 1.0
    y = first_order_lag(x, 1.0, tau, hold=hold)  # type: ignore[arg-type]
    assert np.all(y[:k0] == 0.0)  # steady start: nothing moves before the step
    # zero-order hold: x[k0] is held from sample k0 on → y[k0 + n] = 1 − exp(−n/τ) exactly;
    # linear hold: the step is a ramp over (k0 − 1, k0], its midpoint is k0 − 1/2.
    onset = k0 if hold == "zero" else k0 - 0.5
    crossing = int(np.argmax(y >= 1.0 - math.exp(-1.0)))
    assert abs(crossing - (onset + tau)) <= 1.0
    if hold == "zero":
        k = np.arange(k0, n)
        np.testing.assert_allclose(y[k0:], 1.0 - np.exp(-(k - k0) / tau), atol=1e-12)
    assert y[-1] == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("hold", ["linear", "zero"])
def test_steady_state_unchanged(hold: str) -> None:
    x = np.full(1000, 811.15)
    np.testing.assert_allclose(first_order_lag(x, 1.0, 25.0, hold=hold), x,  # type: ignore[arg-type]
                               rtol=1e-14)


@pytest.mark.parametrize("tau", [0.4, 5.0, 30.0])
def test_ramp_lags_by_tau_exactly(tau: float) -> None:
    dt, rate = 1.0, 0.05  # K/s
    t = np.arange(0.0, 400.0, dt)
    x = np.where(t > 0.0, rate * t, 0.0)  # at rest, then a ramp from t = 0
    y = first_order_lag(x, dt, tau)
    # continuous solution for a ramp from rest: y = r·(t − τ·(1 − e^{−t/τ}))
    np.testing.assert_allclose(y, rate * (t - tau * (1.0 - np.exp(-t / tau))), atol=1e-12)
    late = t > 20 * tau
    np.testing.assert_allclose(x[late] - y[late], rate * tau, atol=1e-8)
    # zero-order hold: exact for held input; a ramp then lags by Δt/(1 − e^{−Δt/τ}) ≈ τ + Δt/2
    z = first_order_lag(x, dt, tau, hold="zero")
    np.testing.assert_allclose(x[late] - z[late], rate * dt / -math.expm1(-dt / tau), atol=1e-8)


def test_zero_time_constant_is_identity() -> None:
    x = np.linspace(0.0, 1.0, 11)
    np.testing.assert_array_equal(first_order_lag(x, 1.0, 0.0), x)


def test_measure_applies_the_lag() -> None:
    x = np.r_[np.full(50, 800.0), np.full(250, 810.0)]
    model = bare(type_k_thermocouple((0, 650), time_constant_s=20.0, noise_sigma=0.0),
                 time_constant_s=20.0)
    out = measure(frame({"main_steam_temperature": x}), {"main_steam_temperature": model},
                  np.random.default_rng(0), faults=NO_FAULTS).measured
    np.testing.assert_allclose(out["main_steam_temperature"], first_order_lag(x, 1.0, 20.0))


# --------------------------------------------------------------------------------------------
# noise, bias, drift, quantisation


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_noise_statistics(seed: int) -> None:
    n, sigma = 100_000, 5.0e3
    model = bare(PRESSURE, noise_sigma=sigma, tolerance_of_span=0.00065, time_constant_s=0.4)
    true = np.full(n, 16.7e6)
    result = measure(frame({"main_steam_pressure": true}), {"main_steam_pressure": model},
                     np.random.default_rng(seed), faults=NO_FAULTS)
    error = result.measured["main_steam_pressure"].to_numpy() - true
    bias = result.injected.sensors.loc["main_steam_pressure", "bias"]
    assert abs(bias) <= 0.00065 * 25.0e6
    assert np.std(error, ddof=1) == pytest.approx(sigma, rel=0.02)
    assert np.mean(error) == pytest.approx(bias, abs=4.0 * sigma / math.sqrt(n))


def iec_type_k_tolerance(t_degc: float, tolerance_class: int) -> float:
    """IEC 60584-1:2013, type K: class 1 ±1.5 °C or ±0.004·|t|, class 2 ±2.5 °C or ±0.0075·|t|."""
    absolute, relative = {1: (1.5, 0.004), 2: (2.5, 0.0075)}[tolerance_class]
    return max(absolute, relative * abs(t_degc))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), t_degc=st.floats(-40.0, 1000.0),
       tolerance_class=st.sampled_from([1, 2]))
def test_thermocouple_bias_within_iec_class(seed: int, t_degc: float,
                                            tolerance_class: int) -> None:
    model = bare(type_k_thermocouple((-50, 1050), tolerance_class=tolerance_class,
                                     time_constant_s=20.0, noise_sigma=0.2))
    model = dataclasses.replace(model, tolerance_abs=(1.5, 2.5)[tolerance_class - 1],
                                tolerance_of_reading=(0.004, 0.0075)[tolerance_class - 1])
    true = np.full(5, t_degc + 273.15)
    result = measure(frame({"hp_exhaust_temperature": true}), {"hp_exhaust_temperature": model},
                     np.random.default_rng(seed), faults=NO_FAULTS)
    offset = result.measured["hp_exhaust_temperature"].to_numpy() - true
    np.testing.assert_allclose(offset, offset[0], atol=1e-9)  # a fixed offset
    assert abs(offset[0]) <= iec_type_k_tolerance(t_degc, tolerance_class) + 1e-9
    assert offset[0] == pytest.approx(result.injected.sensors.loc["hp_exhaust_temperature",
                                                                  "bias"], abs=1e-9)


def test_default_thermocouple_bias_within_class_over_a_transient() -> None:
    t = np.arange(3600.0)
    true = 573.15 + 300.0 * t / t[-1]  # 300 → 600 °C
    models = default_sensor_models()
    model = bare(models["main_steam_temperature"], tolerance_abs=1.5, tolerance_of_reading=0.004)
    for seed in range(20):
        result = measure(frame({"main_steam_temperature": true}),
                         {"main_steam_temperature": model}, np.random.default_rng(seed),
                         faults=NO_FAULTS)
        offset = result.measured["main_steam_temperature"].to_numpy() - true
        limit = np.maximum(1.5, 0.004 * np.abs(true - 273.15))
        assert np.all(np.abs(offset) <= limit + 1e-9)


def test_quantisation_step_exact() -> None:
    q = 25.0e6 / 2**16
    model = bare(PRESSURE, noise_sigma=2.0e3, resolution=q)
    true = np.linspace(10.0e6, 10.1e6, 5000)
    out = measure(frame({"main_steam_pressure": true}), {"main_steam_pressure": model},
                  np.random.default_rng(4), faults=NO_FAULTS).measured["main_steam_pressure"]
    counts = out.to_numpy() / q  # grid anchored at the lower range value 0 Pa
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)
    steps = np.diff(np.unique(np.round(counts)))
    assert steps.min() == 1.0
    assert np.max(np.abs(out.to_numpy() - true)) <= 2.0e3 * 6 + q / 2


def test_quantisation_grid_of_a_thermocouple_is_in_degc() -> None:
    model = bare(type_k_thermocouple((0, 650), time_constant_s=0, noise_sigma=0.0),
                 resolution=0.1)
    true = np.linspace(800.0, 801.0, 101)
    out = measure(frame({"main_steam_temperature": true}), {"main_steam_temperature": model},
                  np.random.default_rng(0), faults=NO_FAULTS).measured["main_steam_temperature"]
    tenths = (out.to_numpy() - 273.15) / 0.1
    np.testing.assert_allclose(tenths, np.round(tenths), atol=1e-6)
    assert np.max(np.abs(out.to_numpy() - true)) <= 0.05 + 1e-9


@pytest.mark.parametrize("step", ["1s", "10s"])
def test_drift_rate_exact(step: str) -> None:
    limit = 0.01 * 25.0e6  # Pa per year, exaggerated to be visible
    model = bare(PRESSURE, drift_per_year=limit)
    n = 8640
    true = np.full(n, 16.0e6)
    data = frame({"main_steam_pressure": true}, step)
    for seed in range(5):
        result = measure(data, {"main_steam_pressure": model}, np.random.default_rng(seed),
                         faults=NO_FAULTS)
        rate = result.injected.sensors.loc["main_steam_pressure", "drift_rate"]
        assert 0.0 < abs(rate) <= limit / SECONDS_PER_YEAR
        assert result.injected.sensors.loc["main_steam_pressure", "drift_per_year"] == (
            pytest.approx(rate * SECONDS_PER_YEAR))
        elapsed = (data.index - data.index[0]).total_seconds().to_numpy()
        np.testing.assert_allclose(result.measured["main_steam_pressure"].to_numpy() - true,
                                   rate * elapsed, atol=1e-6)


# --------------------------------------------------------------------------------------------
# faults

HEAVY = FaultConfig(dropout_rate_per_h=2.0, spike_rate_per_h=3.0, stuck_rate_per_h=0.5,
                    stuck_median_s=900.0)


def plant_day(hours: float = 12.0) -> pd.DataFrame:
    n = int(hours * 3600)
    t = np.arange(n, dtype=float)
    load = 450e6 + 120e6 * np.sin(2 * np.pi * t / 43200.0)
    ratio = load / 600e6
    return frame({
        "main_steam_pressure": 8e6 + 8.7e6 * ratio,
        "main_steam_temperature": np.full(n, 811.15) - 5.0 * np.cos(t / 900.0),
        "main_steam_flow": 500.0 * ratio,
        "control_stage_pressure": 13e6 * ratio,
        "control_stage_temperature": 740.0 + 20.0 * ratio,
        "hp_exhaust_pressure": 3.9e6 * ratio,
        "hp_exhaust_temperature": 580.0 + 20.0 * ratio,
        "hp_inner_casing_temperature": 735.0 + 20.0 * ratio,
        "load": load,
        "hp_power": 0.295 * load,
    })


@pytest.fixture(scope="module")
def day() -> pd.DataFrame:
    return plant_day()


def test_faults_exactly_where_recorded(day: pd.DataFrame) -> None:
    models = default_sensor_models()
    faulty = measure(day, models, np.random.default_rng(11), faults=HEAVY)
    clean = measure(day, models, np.random.default_rng(11), faults=NO_FAULTS)
    faults = faulty.injected.faults
    assert set(faults["kind"]) == {"dropout", "spike", "stuck"}
    assert np.all(faults["n_samples"] == faults["end_row"] - faults["start_row"] + 1)
    assert np.all(faults["start"] == day.index[faults["start_row"]])
    assert np.all(faults["end"] == day.index[faults["end_row"]])
    for name in models:
        got = faulty.measured[name].to_numpy()
        ref = clean.measured[name].to_numpy()
        rows = faults[faults["signal"] == name]
        touched = np.zeros(len(day), dtype=bool)
        nan_expected = np.zeros(len(day), dtype=bool)
        for row in rows.itertuples():
            span = slice(row.start_row, row.end_row + 1)
            assert not touched[max(row.start_row - 1, 0):row.end_row + 2].any()  # apart
            touched[span] = True
            if row.kind == "dropout":
                nan_expected[span] = True
            elif row.kind == "spike":
                assert row.n_samples == 1
                assert got[row.start_row] == row.value != ref[row.start_row]
                assert row.value - ref[row.start_row] == pytest.approx(row.offset)
                assert abs(row.offset) >= 8 * models[name].noise_sigma
            else:
                assert np.all(got[span] == row.value)
                assert row.value == ref[row.start_row]
        np.testing.assert_array_equal(np.isnan(got), nan_expected)
        # everything not recorded as a fault is the fault-free measurement, bit for bit
        np.testing.assert_array_equal(got[~touched], ref[~touched])


def test_fault_counts_follow_rates(day: pd.DataFrame) -> None:
    models = default_sensor_models()
    hours = len(day) / 3600.0
    config = FaultConfig(dropout_rate_per_h=1.0, spike_rate_per_h=1.0, stuck_rate_per_h=0.0)
    counts = measure(day, models, np.random.default_rng(3), faults=config).injected.faults[
        "kind"].value_counts()
    expected = hours * len(models)  # 108 per kind, a few lost to overlaps
    for kind in ("dropout", "spike"):
        assert abs(counts[kind] - expected) < 4 * math.sqrt(expected)
    assert "stuck" not in counts


def test_faults_disabled_no_nan(day: pd.DataFrame) -> None:
    result = measure(day, default_sensor_models(), np.random.default_rng(5),
                     faults=dataclasses.replace(HEAVY, enabled=False))
    assert not result.measured.isna().any().any()
    assert result.injected.faults.empty
    assert list(result.injected.faults.columns)[:5] == ["signal", "kind", "start", "end",
                                                        "start_row"]


def test_quality_checker_finds_injected_faults(day: pd.DataFrame) -> None:
    config = FaultConfig(dropout_rate_per_h=0.5, spike_rate_per_h=0.5, stuck_rate_per_h=0.2,
                         stuck_median_s=1800.0)
    models = {"main_steam_pressure": default_sensor_models()["main_steam_pressure"]}
    result = measure(day[["main_steam_pressure"]], models, np.random.default_rng(8),
                     faults=config)
    report = check_quality(result.measured).counts()
    injected = result.injected.faults.groupby("kind")["n_samples"].sum()
    assert report.loc["main_steam_pressure", "nan"] == injected["dropout"]
    assert report.loc["main_steam_pressure", "stuck"] == injected["stuck"]
    spikes = result.injected.faults.query("kind == 'spike'")
    # a spike next to a dropout or stuck run may escape the spike test's window; most are found
    assert report.loc["main_steam_pressure", "spike"] >= 0.8 * len(spikes)


# --------------------------------------------------------------------------------------------
# reproducibility and API


def test_reproducible_and_seed_dependent(day: pd.DataFrame) -> None:
    models = default_sensor_models()
    a = measure(day, models, np.random.default_rng(42), faults=HEAVY)
    b = measure(day, models, np.random.default_rng(42), faults=HEAVY)
    c = measure(day, models, np.random.default_rng(43), faults=HEAVY)
    assert a.measured.index.equals(b.measured.index)
    np.testing.assert_array_equal(a.measured.to_numpy(), b.measured.to_numpy())
    pd.testing.assert_frame_equal(a.injected.faults, b.injected.faults)
    pd.testing.assert_frame_equal(a.injected.sensors, b.injected.sensors)
    for name in models:
        assert not np.array_equal(a.measured[name].to_numpy(), c.measured[name].to_numpy(),
                                  equal_nan=True)
    assert not a.injected.sensors["bias"].equals(c.injected.sensors["bias"])


def test_default_models_cover_measured_signals(day: pd.DataFrame) -> None:
    models = default_sensor_models()
    assert set(models) == set(SIGNALS) - {"hp_power"}
    result = measure(day, models, np.random.default_rng(0))
    np.testing.assert_array_equal(result.measured["hp_power"].to_numpy(),
                                  day["hp_power"].to_numpy())  # unmodelled: unchanged
    assert result.measured.index.equals(day.index)
    assert list(result.measured.columns) == list(day.columns)
    assert set(result.injected.sensors.index) == set(models)
    error = result.measured["main_steam_temperature"] - day["main_steam_temperature"]
    assert error.abs().median() < 3.0  # K: bias ≤ 2.2 K, noise 0.2 K, lag on a slow wave
    tc = models["main_steam_temperature"]
    assert tc.tolerance(538.0 + 273.15) == pytest.approx(0.004 * 538.0)
    assert models["main_steam_pressure"].tolerance(16.7e6) == pytest.approx(0.00065 * 25e6)


def test_default_faults_are_rare(day: pd.DataFrame) -> None:
    result = measure(day, default_sensor_models(), np.random.default_rng(2))
    assert len(result.injected.faults) < 15  # ~0.02/h × 9 signals × 12 h ≈ 2
    assert result.measured.isna().to_numpy().mean() < 1e-3


def test_index_unit_does_not_matter() -> None:
    true = np.r_[np.full(20, 800.0), np.full(80, 810.0)]
    model = bare(type_k_thermocouple((0, 650), time_constant_s=10.0, noise_sigma=0.0),
                 time_constant_s=10.0)
    outs = []
    for unit in ("ns", "us", "s"):
        data = frame({"main_steam_temperature": true})
        data.index = data.index.as_unit(unit)
        outs.append(measure(data, {"main_steam_temperature": model}, np.random.default_rng(0),
                            faults=NO_FAULTS).measured["main_steam_temperature"].to_numpy())
    np.testing.assert_array_equal(outs[0], outs[1])
    np.testing.assert_array_equal(outs[0], outs[2])


def test_rejects_bad_input() -> None:
    models = {"load": default_sensor_models()["load"]}
    data = frame({"load": np.full(10, 6e8)})
    with pytest.raises(ValueError, match="uniformly"):
        measure(data.iloc[[0, 1, 3, 4]], models, np.random.default_rng(0))
    bad = data.copy()
    bad.iloc[3, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        measure(bad, models, np.random.default_rng(0))
    with pytest.raises(TypeError):
        measure(data.reset_index(drop=True), models, np.random.default_rng(0))
    with pytest.raises(ValueError):
        SensorModel("x", (1.0, 0.0))
    with pytest.raises(ValueError):
        FaultConfig(spike_rate_per_h=-1.0)
