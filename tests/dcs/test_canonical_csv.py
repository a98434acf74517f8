"""Canonical CSV files: wire units out and back, time kept exactly, errors that name the line."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.canonical_csv import CsvFormatError, read_canonical_csv, write_canonical_csv


def _frame(index):
    return pd.DataFrame({
        "main_steam_pressure": np.linspace(16.7e6, 16.6e6, len(index)),
        "main_steam_temperature": np.full(len(index), 811.15),
        "hp_power": np.full(len(index), 1.7e8),
    }, index=index)


@pytest.mark.parametrize("index", [
    pd.Index([1234567.0, 1234568.0, 1234569.5]),
    pd.date_range("2026-03-01T10:00:00Z", periods=3, freq="1s"),
])
def test_round_trip_keeps_time_and_converts_units(tmp_path, index):
    frame = _frame(index)
    path = tmp_path / "signals.csv"
    write_canonical_csv(frame, path)
    raw = pd.read_csv(path)
    assert raw["main_steam_pressure"].iloc[0] == pytest.approx(16.7)  # MPa on the wire
    assert raw["main_steam_temperature"].iloc[0] == pytest.approx(538.0)  # °C
    back = read_canonical_csv(path)
    assert list(back.index) == list(index)
    assert np.allclose(back["main_steam_pressure"], frame["main_steam_pressure"], rtol=1e-6)
    assert np.allclose(back["hp_power"], frame["hp_power"], rtol=1e-6)


def test_missing_column_and_bad_time_are_named(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time,main_steam_pressure\nyesterday,16.7\n")
    with pytest.raises(CsvFormatError, match=r"column .time. data row 1 \(line 2\): .yesterday."):
        read_canonical_csv(path)
    with pytest.raises(CsvFormatError, match=r"missing column\(s\) \['main_steam_flow'\]"):
        read_canonical_csv(path, required=("main_steam_flow",))
