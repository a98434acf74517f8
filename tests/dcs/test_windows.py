"""Time windows and steady-load search (steamtwin.dcs.windows)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.windows import SteadyWindow, find_steady_windows, select_window

RATED = 600e6  # W
START = pd.Timestamp("2024-03-01", tz="Asia/Shanghai")
MIN = 60.0


def synthetic_day(hold_s: float = 7200.0, step_s: float = 5.0, seed: int = 0,
                  n_nan: int = 50) -> tuple[pd.DataFrame, dict[str, float]]:
    """100 % for 1 h, ramp to 30 % at 1 %/min, hold, ramp to 50 %, hold, ramp to 100 %.

    Noise 0.3 % of rated (1.8 MW) and ``n_nan`` rejected samples. Returns the frame and the
    hold boundaries in s from midnight.
    """
    t = 3600.0 + 70 * MIN
    marks = {"hold30": t, "end30": t + hold_s}
    t += hold_s + 20 * MIN
    marks |= {"hold50": t, "end50": t + hold_s}
    t += hold_s + 50 * MIN
    marks["hold100"] = t
    knots = [(0.0, 1.0), (3600.0, 1.0), (marks["hold30"], 0.3), (marks["end30"], 0.3),
             (marks["hold50"], 0.5), (marks["end50"], 0.5), (t, 1.0), (86400.0, 1.0)]
    seconds = np.arange(0.0, 86400.0, step_s)
    fraction = np.interp(seconds, *zip(*knots, strict=True))
    rng = np.random.default_rng(seed)
    load = RATED * (fraction + 0.003 * rng.standard_normal(seconds.size))
    load[rng.choice(seconds.size, n_nan, replace=False)] = np.nan
    index = START + pd.to_timedelta(seconds, unit="s")
    return pd.DataFrame({"load": load}, index=index), marks


def at(seconds: float) -> pd.Timestamp:
    return START + pd.Timedelta(seconds=seconds)


# 1 %/min ramps leave or enter the ± 2 % band 2 min from a hold; allow 1 min of noise either way
def assert_hold(window: SteadyWindow, begin: float, end: float) -> None:
    assert at(begin - 3 * MIN) <= window.start <= at(begin - 1 * MIN)
    assert at(end + 1 * MIN) <= window.end <= at(end + 3 * MIN)


def test_steady_holds_found_exactly_on_synthetic_day() -> None:
    data, m = synthetic_day()
    windows = find_steady_windows(data, rated_load_w=RATED)
    assert len(windows) == 3
    assert [w.duration_s for w in windows] == sorted((w.duration_s for w in windows),
                                                     reverse=True)
    full, *holds = windows
    assert full.mean_load_fraction == pytest.approx(1.0, abs=0.002)
    assert full.start <= at(m["hold100"]) and full.end == at(86400.0)
    low, high = sorted(holds, key=lambda w: w.mean_load_fraction)
    assert_hold(low, m["hold30"], m["end30"])
    assert_hold(high, m["hold50"], m["end50"])
    assert low.mean_load_fraction == pytest.approx(0.30, abs=0.002)
    assert high.mean_load_fraction == pytest.approx(0.50, abs=0.002)
    for w in windows:
        assert w.duration_s == (w.end - w.start).total_seconds() >= 7200
        rows = select_window(data, w.start, w.end)
        assert len(rows) == w.n_samples == round(w.duration_s / 5.0)
        assert w.nan_fraction == pytest.approx(rows["load"].isna().mean())


def test_load_fraction_selects_one_hold() -> None:
    data, m = synthetic_day()
    (low,) = find_steady_windows(data, rated_load_w=RATED, load_fraction=0.30)
    assert_hold(low, m["hold30"], m["end30"])
    (high,) = find_steady_windows(data, rated_load_w=RATED, load_fraction=0.50)
    assert_hold(high, m["hold50"], m["end50"])
    assert find_steady_windows(data, rated_load_w=RATED, load_fraction=0.40) == []


def test_hold_shorter_than_duration_is_not_found() -> None:
    data, _ = synthetic_day(hold_s=100 * MIN)
    assert find_steady_windows(data, rated_load_w=RATED, load_fraction=0.30) == []
    assert find_steady_windows(data, rated_load_w=RATED, load_fraction=0.50) == []
    found = find_steady_windows(data, rated_load_w=RATED, load_fraction=0.30, duration_s=5400)
    assert len(found) == 1


def test_slow_drift_beyond_the_band_is_not_steady() -> None:
    seconds = np.arange(0.0, 6 * 3600.0, 10.0)
    load = RATED * (0.30 + 0.20 * seconds / seconds[-1])  # 3.3 %/h: 6.7 % in 2 h > 4 % band
    data = pd.DataFrame({"load": load}, index=START + pd.to_timedelta(seconds, unit="s"))
    assert find_steady_windows(data, rated_load_w=RATED) == []
    # within a wider band the same drift is steady over about 2 × 4 % / 3.3 %/h ≈ 2.4 h
    (w,) = find_steady_windows(data, rated_load_w=RATED, tolerance=0.04, duration_s=7200)
    assert 2.3 * 3600 <= w.duration_s <= 2.5 * 3600


def test_single_bad_sample_and_short_nan_run_do_not_split_a_hold() -> None:
    data, m = synthetic_day(n_nan=0)
    load = data["load"].to_numpy().copy()
    i = int((m["hold30"] + 3600) / 5.0)
    load[i] = 1.5 * RATED  # a spike that cleaning missed
    load[i + 100: i + 160] = np.nan  # 5 min without data
    data["load"] = load
    (low,) = find_steady_windows(data, rated_load_w=RATED, load_fraction=0.30)
    assert_hold(low, m["hold30"], m["end30"])
    assert low.nan_fraction == pytest.approx(60 / low.n_samples)


def test_long_stretch_without_data_splits_a_hold() -> None:
    data, m = synthetic_day(n_nan=0)
    middle = (m["hold30"] + m["end30"]) / 2
    data.loc[at(middle - 15 * MIN): at(middle + 15 * MIN), "load"] = np.nan
    assert find_steady_windows(data, rated_load_w=RATED, load_fraction=0.30) == []


def test_a_few_hundred_thousand_samples() -> None:
    data, _ = synthetic_day(step_s=0.3)  # 288 000 samples (~0.2 s: bench_window_run.py)
    windows = find_steady_windows(data, rated_load_w=RATED)
    assert len(windows) == 3


def test_select_window_inclusive_start_exclusive_end() -> None:
    data, _ = synthetic_day(n_nan=0)
    rows = select_window(data, at(600), at(1200))
    assert rows.index[0] == at(600) and rows.index[-1] == at(1195) and len(rows) == 120
    naive = select_window(data, "2024-03-01 00:10", "2024-03-01 00:20")  # index time zone
    assert naive.index.equals(rows.index)
    whole = select_window(data, data.index[0], data.index[-1] + pd.Timedelta(seconds=5))
    assert len(whole) == len(data)


def test_select_window_errors() -> None:
    data, _ = synthetic_day(n_nan=0)
    with pytest.raises(ValueError, match="outside the data"):
        select_window(data, at(-10), at(100))
    with pytest.raises(ValueError, match="outside the data"):
        select_window(data, at(600), at(86400 + 600))
    with pytest.raises(ValueError, match="before its end"):
        select_window(data, at(1200), at(600))
    gappy = data.drop(data.index[100:200])
    with pytest.raises(ValueError, match="no sample"):
        select_window(gappy, at(600), at(700))
    with pytest.raises(ValueError, match=r"quality\.clean"):
        select_window(data.iloc[::-1], at(600), at(700))


def test_find_steady_windows_errors() -> None:
    data, _ = synthetic_day(n_nan=0)
    with pytest.raises(ValueError, match="rated_load_w"):
        find_steady_windows(data, rated_load_w=0.0)
    with pytest.raises(ValueError, match="tolerance"):
        find_steady_windows(data, rated_load_w=RATED, tolerance=-0.1)
    with pytest.raises(KeyError, match="main_steam_flow"):
        find_steady_windows(data, rated_load_w=RATED, signal="main_steam_flow")
    with pytest.raises(ValueError, match=r"quality\.clean"):
        find_steady_windows(pd.concat([data, data.iloc[:5]]), rated_load_w=RATED)
