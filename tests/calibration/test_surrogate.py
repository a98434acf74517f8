"""Surrogate-assisted calibration: near the full GA's optimum for a tenth of the model runs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration import (
    DEFAULT_SENSORS,
    CalibrationError,
    Calibrator,
    GeneticSearch,
    SurrogateSearch,
)
from steamtwin.calibration.posterior import fit_map
from steamtwin.calibration.settings import PARAMETER_NAMES
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS


@pytest.fixture(scope="module")
def full_ga(reference_model, low_load_window):
    return Calibrator(reference_model, search=GeneticSearch(population=30, generations=20),
                      random_state=2, workers=1).fit([low_load_window])


def test_surrogate_matches_the_full_ga_with_a_tenth_of_the_runs(reference_model,
                                                                 low_load_window, full_ga,
                                                                 tmp_path):
    budget = full_ga.n_evaluations_ // 10
    search = SurrogateSearch(initial_samples=20, infill_per_round=4, max_evaluations=budget,
                             generations=40)
    surrogate = Calibrator(reference_model, search=search, random_state=2,
                           workers=1).fit([low_load_window])
    assert surrogate.n_evaluations_ <= budget
    assert surrogate.rmse_ <= full_ga.rmse_ + 0.1
    # the result is a model-evaluated point, not a surrogate prediction
    assert surrogate.rmse_ == pytest.approx(
        full_ga.rmse([low_load_window], surrogate.params_), rel=1e-12)
    assert len(surrogate.samples_) == surrogate.n_evaluations_
    assert surrogate.samples_["score"].min() == surrogate.score_
    assert (np.diff(surrogate.history_["best_rmse"]) <= 0).all()
    for name in PARAMETER_NAMES:
        assert surrogate.samples_[name].between(*full_ga.problem([low_load_window])
                                                .parameter_bounds[name]).all()
    params_path, _ = surrogate.save(tmp_path / "p.json")
    assert ModelParameters.from_json(params_path) == surrogate.params_


def test_surrogate_has_no_checkpoint_to_resume(linear_simulator, linear_window):
    with pytest.raises(ValueError, match="the surrogate mode has no checkpoint"):
        Calibrator(linear_simulator, search=SurrogateSearch(), workers=1).fit(
            [linear_window], resume=True)


@pytest.mark.parametrize(("arguments", "message"), [
    ({"max_evaluations": 10}, r"^max_evaluations must be an integer ≥ initial_samples \+ "
                              r"infill_per_round = 34 \(got 10\)$"),
    ({"max_evaluations": True}, r"^max_evaluations must be an integer ≥"),
    ({"max_evaluations": 400.0}, r"^max_evaluations must be an integer ≥"),
    ({"initial_samples": 4}, r"^initial_samples must be an integer ≥ 5 \(got 4\)$"),
    ({"infill_per_round": 0}, r"^infill_per_round must be an integer ≥ 1 \(got 0\)$"),
    ({"patience": -1}, r"^patience must be an integer ≥ 1 \(got -1\)$"),
    ({"generations": 0}, r"^generations must be an integer ≥ 1 \(got 0\)$"),
    ({"population": 0}, r"^population must be an integer ≥ 2 \(got 0\)$"),
    ({"improvement_tolerance": -0.1},
     r"^improvement_tolerance must be a finite number ≥ 0 K \(got -0\.1\)$"),
    ({"improvement_tolerance": float("nan")}, r"^improvement_tolerance must be a finite"),
])
def test_each_bad_surrogate_argument_is_named_with_its_range(arguments, message):
    with pytest.raises(ValueError, match=message):
        SurrogateSearch(**arguments)


class _RejectsEverything:
    """A model that cannot run on these inputs (as the FOM with inputs in the wrong unit)."""

    input_signals = INPUT_SIGNALS
    output_signals = DEFAULT_SENSORS

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        raise InputError("main_steam_flow 1.2e4 kg/s exceeds what the valves pass")


def test_surrogate_with_no_finite_rmse_is_a_calibration_error(linear_window):
    search = SurrogateSearch(initial_samples=6, infill_per_round=2, max_evaluations=12,
                             population=6, generations=3)
    calibrator = Calibrator(_RejectsEverything(), search=search, workers=1)
    with pytest.raises(CalibrationError, match=r"^no candidate gave a finite RMSE: the model "
                       r"rejected all 12 runs \(last reason: main_steam_flow 1\.2e4 kg/s"):
        calibrator.fit([linear_window])
    assert not hasattr(calibrator, "params_")


def test_residual_vector_is_the_score_in_least_squares_form(linear_simulator, linear_window):
    problem = Calibrator(linear_simulator, workers=1).problem([linear_window])
    problem.objective = replace(problem.objective, tempering=0.01)
    x = np.array([1.01, 1.3, 0.7])
    result, residuals = problem.evaluate_with_residuals(x)
    objective = problem.objective
    # Σr² = κχ² + Σz² = score² · κ · n (objective module docstring)
    assert residuals @ residuals == pytest.approx(
        result.score**2 * objective.tempering * objective.weighted_count(), rel=1e-12)
    assert result == objective.evaluate(x)
    assert problem.n_evaluations == 1
    rejected, none = problem.evaluate_with_residuals(np.array([0.92, 1.0, 1.0]))
    assert none is None and rejected.penalised and problem.n_penalised == 1


def test_polish_lands_on_the_map_the_surrogate_alone_misses(linear_simulator, linear_window):
    search = SurrogateSearch(initial_samples=8, infill_per_round=2, max_evaluations=60,
                             patience=2, population=10, generations=10, polish_evaluations=30)
    polished = Calibrator(linear_simulator, search=search, random_state=3,
                          workers=1).fit([linear_window])
    problem = polished.problem([linear_window])
    problem.objective = replace(problem.objective, tempering=polished.tempering_)
    best = fit_map(problem.objective, ModelParameters(1.02, 1.2, 0.8))
    optimum = problem.objective.evaluate([getattr(best, n) for n in PARAMETER_NAMES]).value
    # the surrogate rounds stop short of the MAP (last round's best); the polish reaches it
    history = polished.history_["best_rmse"]
    assert history.iloc[-2] - optimum > 1e-4
    assert history.iloc[-1] == polished.score_ == pytest.approx(optimum, rel=1e-7)
    for name in PARAMETER_NAMES:
        assert getattr(polished.params_, name) == pytest.approx(getattr(best, name), abs=2e-3)
    polish_runs = polished.n_evaluations_ - int(polished.history_["evaluations"].iloc[-2])
    assert 0 < polish_runs <= 30
    assert len(polished.samples_) == polished.n_evaluations_
    assert polished.samples_["score"].min() == polished.score_
