"""Table 5 (operating conditions) and Table 8 (deviations) against hand-computed values."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.blade.mesh import block_mesh
from steamtwin.rom.estimator import PodRbfRom
from steamtwin.rom.reconstruction import FLAG_EXTRAPOLATED, FLAG_INVALID
from steamtwin.rom.romfile import FORMAT_VERSION, BladeRom, probe_nodes
from steamtwin.validation.tables import (
    deviation_table,
    operating_table,
    rom_provenance_table,
    series_frame,
)

T = "hp_exhaust_temperature"


def _index(n: int, start: str = "2026-03-01T00:00:00Z") -> pd.DatetimeIndex:
    return pd.date_range(start, periods=n, freq="1s", name="time")


def _pair() -> tuple[pd.DataFrame, pd.DataFrame]:
    index = _index(6)
    measured = pd.DataFrame({T: [500.0, 501.0, np.nan, 503.0, 504.0, 505.0]}, index=index)
    monitored = pd.DataFrame({
        T: [501.0, 500.0, 502.0, 503.0, 506.0, 505.5],  # row 3: a value, but flagged invalid
        FLAG_INVALID: [False, False, False, True, False, False],
        FLAG_EXTRAPOLATED: [False, True, False, False, False, True],
    }, index=index)
    return measured, monitored


def test_deviation_table_matches_hand_computed_values():
    measured, monitored = _pair()
    table = deviation_table({"50 % load": (measured, monitored)}, [T])
    row = table.iloc[0]
    assert (row.signal, row.window, row.unit, row.measured_unit) == (T, "50 % load", "K",
                                                                     "degC")
    # used rows 0, 1, 4, 5: d = +1, −1, +2, +0.5 K; row 2 NaN measured, row 3 ROM-invalid
    assert (row.n_samples, row.n_used, row.n_skipped_missing, row.n_skipped_rom_invalid,
            row.n_extrapolated) == (6, 4, 1, 1, 2)
    assert row.mean_deviation == pytest.approx(2.5 / 4)
    assert row.mean_abs_deviation == pytest.approx(4.5 / 4)
    assert row.max_abs_deviation == pytest.approx(2.0)
    assert row.rmse == pytest.approx(np.sqrt((1 + 1 + 4 + 0.25) / 4))
    mean_degc = (500 + 501 + 504 + 505) / 4 - 273.15
    assert row.mean_measured == pytest.approx(mean_degc)
    assert row.relative_error_pct == pytest.approx(100 * 1.125 / mean_degc)
    assert row.max_relative_error_pct == pytest.approx(100 * 2.0 / (504.0 - 273.15))
    assert row.mean_deviation_pct == pytest.approx(100 * 0.625 / mean_degc)
    assert row.rmse_pct == pytest.approx(100 * np.sqrt(6.25 / 4) / mean_degc)


def test_pressure_rows_are_in_mpa_with_percentages():
    measured, monitored = _pair()
    p1 = "control_stage_pressure"
    measured[p1] = [10.0e6, 10.2e6, 10.4e6, np.nan, 10.0e6, 9.8e6]
    monitored[p1] = [10.1e6, 10.0e6, 10.4e6, 10.0e6, np.nan, 9.9e6]
    table = deviation_table({"w": (measured, monitored)}, [T, p1])
    assert list(table.signal) == [T, p1]
    row = table.iloc[1]
    assert (row.unit, row.measured_unit) == ("MPa", "MPa")
    # used rows 0, 1, 2, 5 (3 ROM-invalid, 4 twin missing): d = +0.1, −0.2, 0, +0.1 MPa
    assert (row.n_used, row.n_skipped_missing, row.n_skipped_rom_invalid) == (4, 1, 1)
    d = np.array([0.1, -0.2, 0.0, 0.1])
    truth = np.array([10.0, 10.2, 10.4, 9.8])
    assert row.mean_deviation == pytest.approx(d.mean(), abs=1e-12)
    assert row.mean_abs_deviation == pytest.approx(0.1)
    assert row.max_abs_deviation == pytest.approx(0.2)
    assert row.rmse == pytest.approx(np.sqrt(np.mean(d**2)))
    assert row.mean_measured == pytest.approx(truth.mean())
    assert row.relative_error_pct == pytest.approx(100 * 0.1 / truth.mean())
    assert row.rmse_pct == pytest.approx(100 * np.sqrt(np.mean(d**2)) / truth.mean())
    assert row.max_relative_error_pct == pytest.approx(100 * 0.2 / 10.2)
    assert row.mean_deviation_pct == pytest.approx(100 * d.mean() / truth.mean(), abs=1e-12)


def test_series_frame_holds_measured_twin_and_residual_per_sample():
    measured, monitored = _pair()
    p1 = "control_stage_pressure"
    measured[p1] = np.linspace(10e6, 10.5e6, 6)
    monitored[p1] = measured[p1] + 0.05e6
    zone = measured.set_axis(measured.index.tz_convert("Asia/Shanghai"))
    twin = monitored.set_axis(zone.index)
    series = series_frame(zone, twin, [T, p1], "w")
    assert str(series.index.tz) == "Asia/Shanghai"
    assert series.index[0].isoformat() == "2026-03-01T08:00:00+08:00"
    np.testing.assert_allclose(series[f"{T}_measured_degC"], measured[T] - 273.15)
    np.testing.assert_allclose(series[f"{T}_twin_degC"], monitored[T] - 273.15)
    np.testing.assert_allclose(series[f"{T}_residual_K"].dropna(),
                               (monitored[T] - measured[T]).dropna(), atol=1e-9)
    np.testing.assert_allclose(series[f"{p1}_residual_MPa"], 0.05, atol=1e-12)
    assert series[f"{T}_used"].tolist() == [True, True, False, False, True, True]
    assert series.attrs["units"] == {f"{T}_measured_degC": "degC", f"{T}_twin_degC": "degC",
                                     f"{T}_residual_K": "K", f"{p1}_measured_MPa": "MPa",
                                     f"{p1}_twin_MPa": "MPa", f"{p1}_residual_MPa": "MPa"}


def test_deviation_table_counts_everything_and_orders_signal_then_window():
    measured, monitored = _pair()
    other = "hp_inner_casing_temperature"
    measured[other] = measured[T] + 10.0
    monitored[other] = monitored[T] + 10.0
    empty_measured = measured.assign(**{T: np.nan, other: np.nan})
    table = deviation_table({"30 % load": (empty_measured, monitored),
                             "50 % load": (measured, monitored)}, [T, other])
    assert list(zip(table.signal, table.window, strict=True)) == [
        (T, "30 % load"), (T, "50 % load"), (other, "30 % load"), (other, "50 % load")]
    counts = table[["n_used", "n_skipped_missing", "n_skipped_rom_invalid"]].sum(axis=1)
    assert (counts == table["n_samples"]).all()
    nothing = table.iloc[0]
    assert (nothing.n_used, nothing.n_skipped_missing, nothing.n_skipped_rom_invalid) == (0, 5, 1)
    assert np.isnan(nothing.rmse) and np.isnan(nothing.relative_error_pct)
    assert table.iloc[3].rmse == pytest.approx(table.iloc[1].rmse)


def test_deviation_table_refuses_bad_input():
    measured, monitored = _pair()
    with pytest.raises(ValueError, match=r"temperature .* or pressure"):
        deviation_table({"w": (measured, monitored)}, ["main_steam_flow"])
    with pytest.raises(ValueError, match="lack 'control_stage_temperature'"):
        deviation_table({"w": (measured, monitored)}, ["control_stage_temperature"])
    shifted = monitored.set_axis(_index(6, "2026-03-02T00:00:00Z"))
    with pytest.raises(ValueError, match="same time index"):
        deviation_table({"w": (measured, shifted)}, [T])


def test_operating_table_converts_to_wire_units():
    first = pd.DataFrame({
        "main_steam_pressure": [16.6e6, 16.7e6, 16.8e6],
        "main_steam_temperature": [811.15, 811.15, np.nan],
        "main_steam_flow": [500.0, 500.0, 500.0],
        "load": [600e6, 600e6, 600e6],
    }, index=_index(3))
    second = first.drop(columns="load").iloc[:2]
    table = operating_table({"100 % load": first, "no load signal": second})
    row = table.loc["100 % load"]
    assert row["main_steam_pressure_MPa_mean"] == pytest.approx(16.7)
    assert row["main_steam_pressure_MPa_min"] == pytest.approx(16.6)
    assert row["main_steam_pressure_MPa_max"] == pytest.approx(16.8)
    assert row["main_steam_temperature_degC_mean"] == pytest.approx(538.0)  # NaN ignored
    assert row["main_steam_flow_t_per_h_mean"] == pytest.approx(1800.0)
    assert row["load_MW_max"] == pytest.approx(600.0)
    assert row["samples"] == 3
    assert row["start"] == first.index[0] and row["end"] == first.index[-1]
    assert np.isnan(table.loc["no load signal", "load_MW_mean"])
    assert "hp_exhaust_pressure_MPa_mean" not in table.columns  # in no window
    with pytest.raises(ValueError, match="holds no sample"):
        operating_table({"empty": first.iloc[:0]})


def test_rom_provenance_table_names_format_snapshots_modes_and_parameters():
    mesh = block_mesh(np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 3), np.linspace(0, 0.05, 4))
    rng = np.random.default_rng(0)
    conditions = rng.uniform(size=(8, 3))
    fields = 700.0 + conditions @ rng.uniform(1, 5, size=(3, mesh.points.shape[0]))
    rom = PodRbfRom(energy=0.9999).fit(fields, conditions)
    bundle = BladeRom(rom, mesh, probe_nodes(mesh), pd.DataFrame(conditions),
                      provenance={"turbine": "reference",
                                  "model_parameters": {"flow_coefficient": 0.98},
                                  "design": {"load_levels": [0.3, 0.5]}})
    items = rom_provenance_table(bundle).set_index("item")["value"]
    assert items["format_version"] == FORMAT_VERSION
    assert items["snapshots"] == 8 and items["modes"] == rom.n_modes_
    assert items["provenance.model_parameters.flow_coefficient"] == 0.98
    assert items["provenance.design.load_levels"] == "0.3, 0.5"
