"""Surrogate-assisted calibration: near the full GA's optimum for a tenth of the model runs."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.calibration import Calibrator
from steamtwin.calibration.objective import PARAMETER_NAMES
from steamtwin.calibration.surrogate import SurrogateCalibrator
from steamtwin.model.parameters import ModelParameters


@pytest.fixture(scope="module")
def full_ga(reference_model, low_load_window):
    return Calibrator(reference_model, population=30, generations=20, seed=2,
                      workers=1).fit([low_load_window])


def test_surrogate_matches_the_full_ga_with_a_tenth_of_the_runs(reference_model,
                                                                 low_load_window, full_ga,
                                                                 tmp_path):
    budget = full_ga.n_evaluations_ // 10
    surrogate = SurrogateCalibrator(reference_model, initial_samples=20, infill_per_round=4,
                                    max_evaluations=budget, seed=2, workers=1,
                                    generations=40).fit([low_load_window])
    assert surrogate.n_evaluations_ <= budget
    assert surrogate.rmse_ <= full_ga.rmse_ + 0.1
    # the result is a model-evaluated point, not a surrogate prediction
    assert surrogate.rmse_ == pytest.approx(
        full_ga.rmse([low_load_window], surrogate.params_), rel=1e-12)
    assert len(surrogate.samples_) == surrogate.n_evaluations_
    assert surrogate.samples_["rmse"].min() == surrogate.rmse_
    assert (np.diff(surrogate.history_["best_rmse"]) <= 0).all()
    for name in PARAMETER_NAMES:
        assert surrogate.samples_[name].between(*full_ga._problem([low_load_window])
                                                .parameter_bounds[name]).all()
    params_path, _ = surrogate.save(tmp_path / "p.json")
    assert ModelParameters.from_json(params_path) == surrogate.params_


def test_surrogate_settings_are_checked(reference_model, low_load_window):
    with pytest.raises(ValueError, match="max_evaluations"):
        SurrogateCalibrator(reference_model, max_evaluations=10, workers=1).fit(
            [low_load_window])
    with pytest.raises(ValueError, match="initial_samples"):
        SurrogateCalibrator(reference_model, initial_samples=3, workers=1).fit(
            [low_load_window])
