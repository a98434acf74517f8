"""The Calibrator on plant data: improvement, elitism, reproducibility, saving."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration import Calibrator
from steamtwin.model.parameters import ModelParameters

SMALL = {"population": 8, "generations": 4, "workers": 1}


@pytest.fixture(scope="module")
def fitted(reference_model, low_load_window):
    messages = []
    calibrator = Calibrator(reference_model, seed=0, progress=lambda f, m: messages.append(f),
                            **SMALL)
    return calibrator.fit([low_load_window]), messages


def test_calibration_improves_on_default_parameters(fitted, low_load_window):
    calibrator, messages = fitted
    default = calibrator.rmse([low_load_window], ModelParameters())
    assert calibrator.rmse_ < default
    assert calibrator.rmse([low_load_window], calibrator.params_) == pytest.approx(
        calibrator.rmse_)
    assert calibrator.n_evaluations_ == 8 * 4
    assert messages[-1] == pytest.approx(1.0)
    excluded = int(low_load_window["hp_inner_casing_temperature"].isna().sum())
    assert calibrator.window_info_.loc[0, "excluded:hp_inner_casing_temperature"] == excluded


def test_history_best_never_increases(fitted):
    history = fitted[0].history_
    assert list(history.index) == [1, 2, 3, 4]
    assert (np.diff(history["best_rmse"]) <= 0).all()
    assert (history["mean_rmse"] >= history["best_rmse"]).all()
    assert (history["best_fitness"] > 0).all()
    assert history["evaluations"].iloc[-1] == fitted[0].n_evaluations_


def test_same_seed_same_history_different_seed_different(linear_simulator, low_load_window):
    def history(seed: int) -> pd.DataFrame:
        return Calibrator(linear_simulator, seed=seed, **SMALL).fit([low_load_window]).history_

    pd.testing.assert_frame_equal(history(1), history(1))
    assert not history(1).equals(history(2))


def test_save_round_trip(fitted, tmp_path):
    calibrator = fitted[0]
    json_path, csv_path = calibrator.save(tmp_path / "params.json")
    assert ModelParameters.from_json(json_path) == calibrator.params_
    pd.testing.assert_frame_equal(pd.read_csv(csv_path, index_col="generation"),
                                  calibrator.history_, check_exact=False)


def test_unfitted_save_and_bad_settings(linear_simulator, low_load_window, tmp_path):
    with pytest.raises(RuntimeError, match="not fitted"):
        Calibrator(linear_simulator).save(tmp_path / "p.json")
    with pytest.raises(ValueError, match="generations"):
        Calibrator(linear_simulator, generations=0).fit([low_load_window])
