"""Calibration result files: Table 6 against hand numbers, Table 7, Figures 7 and 8."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.objective import window_rmse
from steamtwin.calibration.report import (
    convergence_figure,
    ga_sensitivity_table,
    rmse_table,
    temperature_comparison_figure,
)
from steamtwin.model.parameters import ModelParameters


def test_rmse_table_pools_windows_per_condition(linear_simulator, low_load_window):
    calibrated = ModelParameters(1.02, 1.1, 1.3)
    a, b = low_load_window.iloc[:200], low_load_window.iloc[200:]
    table = rmse_table(linear_simulator, {"both": [a, b], "first": [a]}, calibrated)
    whole = window_rmse(linear_simulator, [low_load_window], calibrated)
    assert table.loc["both", "rmse_calibrated_K"] == pytest.approx(whole.loc[0, "rmse"])
    first = window_rmse(linear_simulator, [a], ModelParameters())
    assert table.loc["first", "rmse_empirical_K"] == pytest.approx(first.loc[0, "rmse"])
    row = table.loc["both"]
    assert row["reduction_pct"] == pytest.approx(
        100 * (1 - row["rmse_calibrated_K"] / row["rmse_empirical_K"]))
    assert table.loc["both", "samples"] == len(low_load_window)


class _OffsetSimulator:
    """The linear stand-in read with constant sensor offsets (K), as the delivered twin is."""

    def __init__(self, inner, offsets):
        self.inner, self.offsets = inner, offsets
        self.input_signals, self.output_signals = inner.input_signals, inner.output_signals

    def simulate(self, inputs, params):
        return self.inner.simulate(inputs, params) + pd.Series(self.offsets)


def test_rmse_table_scores_the_twin_as_delivered_beside_the_raw_readings(linear_simulator,
                                                                         linear_window):
    """With ``delivered`` (the calibrated model read with its sensor offsets), Table 6 adds
    the delivered RMSE and per-sensor columns; a bias the offsets carry leaves the raw figure
    and drops out of the delivered one."""
    fitted = ModelParameters(1.02, 1.2, 0.8)  # what linear_window was drawn at, ±0.5 K noise
    bias = {"control_stage_temperature": 1.5, "hp_exhaust_temperature": -1.0,
            "hp_inner_casing_temperature": 0.7, "hp_power": 0.0}
    window = linear_window.copy()
    for sensor in ("control_stage_temperature", "hp_exhaust_temperature",
                   "hp_inner_casing_temperature"):
        window[sensor] += bias[sensor]
    delivered = _OffsetSimulator(linear_simulator, bias)
    table = rmse_table(linear_simulator, {"hold": [window]}, fitted, delivered=delivered)
    expected = window_rmse(delivered, [window], fitted)
    assert table.loc["hold", "rmse_delivered_K"] == pytest.approx(expected.loc[0, "rmse"])
    assert table.loc["hold", "delivered:hp_exhaust_temperature"] == pytest.approx(
        expected.loc[0, "rmse:hp_exhaust_temperature"])
    assert table.loc["hold", "rmse_delivered_K"] < 0.6 < 1.0 < table.loc["hold",
                                                                         "rmse_calibrated_K"]
    assert "rmse_delivered_K" not in rmse_table(linear_simulator, {"hold": [window]},
                                                fitted).columns


def test_sensitivity_table_and_figures(linear_simulator, reference_model, low_load_window,
                                       tmp_path):
    base = {"population": 6, "generations": 2}

    def fit(settings):
        return Calibrator(linear_simulator, search=GeneticSearch(**settings), random_state=0,
                          workers=1).fit([low_load_window])

    table = ga_sensitivity_table(fit, base, {"population": (4, 8),
                                             "mutation_probability": (0.2,)})
    assert list(table["setting"]) == ["population", "population", "mutation_probability"]
    assert list(table["evaluations"][:2]) == [4 * 2, 8 * 2]
    assert np.isfinite(table["rmse_K"]).all()
    fitted = fit(base)
    figure7 = convergence_figure(fitted.history_, tmp_path / "figure7.png")
    figure8 = temperature_comparison_figure(reference_model, low_load_window,
                                            ModelParameters(0.98, 1.3, 1.4),
                                            tmp_path / "figure8.png")
    for path in (figure7, figure8):
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000
