"""Windows at every steady load and on ramps, from one or several files."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration.windowset import (
    RAMP_BAND,
    WindowSet,
    WindowSource,
    find_calibration_windows,
    joint_window_set,
    measurement_sigma,
    split_at_input_dropouts,
)

RATED = 600.0e6  # W


def _day() -> pd.DataFrame:
    """1-min load: 2 h at 30 %, ramp to 50 % (10 min), 3 h at 50 %, ramp to 100 %, 1.5 h."""
    parts = [np.full(120, 0.3), np.linspace(0.3, 0.5, 10), np.full(180, 0.5),
             np.linspace(0.5, 1.0, 20), np.full(90, 1.0)]
    load = np.concatenate(parts)
    index = pd.date_range("2026-05-01T00:00+08:00", periods=load.size, freq="1min")
    return pd.DataFrame({"load": RATED * load}, index=index)


def test_steady_windows_at_every_load_and_the_ramps_between():
    windows = find_calibration_windows(_day(), RATED, source="day.csv")
    steady = [w for w in windows if w.kind == "steady"]
    ramps = [w for w in windows if w.kind == "ramp"]
    assert [round(w.load_fraction, 2) for w in steady] == [0.3, 0.5, 1.0]
    # the 3-h hold is cut to its last 2 h
    assert max((w.data.index[-1] - w.data.index[0]).total_seconds() for w in steady) <= 7200
    assert len(ramps) == 2
    first = ramps[0].data
    # the ramp window holds the ramp itself, 10 min before and 30 min after it
    assert first["load"].min() == pytest.approx(0.3 * RATED)
    assert first["load"].max() == pytest.approx(0.5 * RATED)
    assert (first["load"] == 0.5 * RATED).sum() >= 30
    assert all(w.source == "day.csv" and "day.csv" in w.name for w in windows)
    assert WindowSet(tuple(windows)).bands().count(RAMP_BAND) == 2


def test_band_weights_equalise_loads():
    windows = find_calibration_windows(_day(), RATED)
    window_set = WindowSet(tuple(windows))
    weights, n = window_set.sample_weights(), [len(w.data) for w in window_set]
    totals: dict[str, float] = {}
    for band, w, k in zip(window_set.bands(), weights, n, strict=True):
        totals[band] = totals.get(band, 0.0) + w * k
    assert np.allclose(list(totals.values()), np.mean(list(totals.values())))
    summary = window_set.summary()
    assert list(summary["weight"]) == pytest.approx(list(weights))


def test_joint_set_names_the_file_without_windows():
    day = WindowSource("a.csv", _day(), {"hp_exhaust_temperature": 0.5})
    flat = _day().iloc[:30]
    with pytest.raises(ValueError, match=r"b\.csv: no steady window"):
        joint_window_set([day, WindowSource("b.csv", flat)], RATED)
    joint = joint_window_set([day, WindowSource("c.csv", _day())], RATED)
    assert {w.source for w in joint} == {"a.csv", "c.csv"} and len(joint) == 10
    start, end = day.data.index[5], day.data.index[100]
    given = joint_window_set([day], RATED, given=[(start, end)])
    assert len(given) == 1 and given.windows[0].kind == "given"
    with pytest.raises(ValueError, match=r"lies in none of the files.*a\.csv"):
        joint_window_set([day], RATED, given=[(end + pd.Timedelta(days=3),
                                               end + pd.Timedelta(days=4))])
    with pytest.raises(ValueError, match=r"nodata\.csv: no .load. signal"):
        find_calibration_windows(_day().rename(columns={"load": "x"}), RATED,
                                 source="nodata.csv")


def test_measurement_sigma_adds_quantisation():
    sigma = measurement_sigma({"a": 0.3, "b": None, "c": None}, {"a": 0.4, "b": 1.2, "c": None})
    assert sigma["a"] == pytest.approx(np.sqrt(0.09 + 0.16 / 12))
    assert sigma["b"] == pytest.approx(1.2 / np.sqrt(12)) and "c" not in sigma


def test_windows_are_cut_around_input_dropouts_the_calibration_cannot_fill():
    """A 5-min main-steam-pressure dropout (an instrument fault the quality gate made NaN)
    inside a 2-h hold: the hold comes as two windows around it, neither holding a gap longer
    than the 60 s a calibration fills forward; a 30-s dropout stays inside (filled, counted)."""
    index = pd.date_range("2026-05-01T00:00+08:00", periods=3 * 3600, freq="1s")
    data = pd.DataFrame({"load": np.full(index.size, 0.5 * RATED),
                         "main_steam_pressure": 16.0e6, "main_steam_temperature": 810.0,
                         "main_steam_flow": 300.0, "hp_exhaust_pressure": 3.5e6}, index=index)
    data.iloc[7000:7300, data.columns.get_loc("main_steam_pressure")] = np.nan
    data.iloc[9000:9030, data.columns.get_loc("main_steam_flow")] = np.nan
    windows = find_calibration_windows(data, RATED, source="day.csv")
    assert [w.kind for w in windows] == ["steady", "steady"]
    first, second = (w.data for w in windows)
    assert first.index[-1] == index[6999] and second.index[0] == index[7300]
    assert second["main_steam_flow"].isna().sum() == 30
    assert len(first) + len(second) == 7200 - 300
    short = data.iloc[6990:7400]  # 10 valid rows before the dropout: too short to keep
    pieces = split_at_input_dropouts(short)
    assert [len(p) for p in pieces] == [100]
