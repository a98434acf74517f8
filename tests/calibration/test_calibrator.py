"""The Calibrator: improvement, elitism, reproducibility, saving, arguments, failed runs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.calibration import CalibrationError, Calibrator, make_ga
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS

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


# -- arguments: one message per argument, naming it and its range, before any work ------------

BAD_ARGUMENTS = [
    ({"population": 0}, r"^population must be an integer ≥ 2 \(got 0\)$"),
    ({"population": 1, "tournament_size": 3}, r"^population must be an integer ≥ 2 \(got 1\)$"),
    ({"population": 2.5}, r"^population must be an integer ≥ 2 \(got 2\.5\)$"),
    ({"population": True}, r"^population must be an integer ≥ 2 \(got True\)$"),
    ({"generations": 0}, r"^generations must be an integer ≥ 1 \(got 0\)$"),
    ({"generations": "10"}, r"^generations must be an integer ≥ 1 \(got '10'\)$"),
    ({"tournament_size": 1}, r"^tournament_size must be an integer within \[2, 50\] \(got 1\)$"),
    ({"population": 4, "tournament_size": 5},
     r"^tournament_size must be an integer within \[2, 4\] \(got 5\)$"),
    ({"crossover_probability": 1.5},
     r"^crossover_probability must be a number within \[0, 1\] \(got 1\.5\)$"),
    ({"mutation_probability": -0.1},
     r"^mutation_probability must be a number within \[0, 1\] \(got -0\.1\)$"),
    ({"mutation_probability": float("nan")}, r"^mutation_probability must be a number within"),
    ({"crossover_eta": 0.0}, r"^crossover_eta must be a finite number > 0 \(got 0\.0\)$"),
    ({"mutation_eta": float("inf")}, r"^mutation_eta must be a finite number > 0 \(got inf\)$"),
    ({"seed": -1}, r"^seed must be an integer ≥ 0 \(got -1\)$"),
    ({"max_input_gap_s": -5.0}, r"^max_input_gap_s must be a number ≥ 0 s \(got -5\.0\)$"),
    ({"min_samples": 0}, r"^min_samples must be an integer ≥ 1 \(got 0\)$"),
]


@pytest.mark.parametrize(("arguments", "message"), BAD_ARGUMENTS)
def test_each_bad_argument_is_named_with_its_range(linear_simulator, arguments, message):
    # an empty window list would be refused too: the argument is checked first, before any work
    with pytest.raises(ValueError, match=message):
        Calibrator(linear_simulator, workers=1, **arguments).fit([])


@given(population=st.integers(-10**6, 1), tournament_size=st.integers(-10, 10**6))
def test_population_below_two_names_population_whatever_the_tournament(population,
                                                                       tournament_size):
    with pytest.raises(ValueError) as error:
        Calibrator(None, population=population, tournament_size=tournament_size).fit([])
    assert str(error.value) == f"population must be an integer ≥ 2 (got {population})"


@given(name=st.sampled_from(["crossover_probability", "mutation_probability"]),
       value=st.floats().filter(lambda v: not 0.0 <= v <= 1.0))
def test_probabilities_outside_zero_one_are_named(name, value):
    with pytest.raises(ValueError, match=f"^{name} must be a number within \\[0, 1\\]"):
        make_ga(3, **{name: value})


# -- a calibration in which no candidate gave a finite RMSE is an error, never a result -------

class _FarOff:
    """A model that runs, 5000 K away from every measurement (measurements in another unit)."""

    input_signals = INPUT_SIGNALS
    output_signals = ("control_stage_temperature", "hp_exhaust_temperature",
                      "hp_inner_casing_temperature")

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        t0 = inputs["main_steam_temperature"].to_numpy(dtype=float)
        value = t0 + 5000.0 * params.flow_coefficient
        return pd.DataFrame({name: value for name in self.output_signals}, index=inputs.index)


class _ReturnsNaN(_FarOff):
    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        return super().simulate(inputs, params) * np.nan


class _RejectsEverything(_FarOff):
    """A model that cannot run on these inputs (as the FOM with inputs in the wrong unit)."""

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        raise InputError("main_steam_pressure 167 MPa is above the model's range")


@pytest.mark.parametrize(("simulator", "message"), [
    (_RejectsEverything(), r"^no candidate gave a finite RMSE: the model rejected all 12 runs "
                           r"\(last reason: main_steam_pressure 167 MPa is above the model's "
                           r"range\)\. It may be unable to run on the windows' inputs"),
    (_ReturnsNaN(), r"^no candidate gave a finite RMSE: the model rejected all 12 runs \(last "
                    r"reason: the simulator returned non-finite temperatures\)"),
    (_FarOff(), r"^no candidate gave a finite RMSE better than the 1000 K penalty of a rejected"
                r" run \(best \d{4}\.?\d* K; 0 of 12 runs rejected\)\. The measured "
                r"temperatures may be in another unit"),
])
def test_no_finite_rmse_is_a_calibration_error(simulator, message, linear_window, tmp_path):
    calibrator = Calibrator(simulator, population=4, generations=3, workers=1,
                            checkpoint=tmp_path / "run.checkpoint")
    with pytest.raises(CalibrationError, match=message):
        calibrator.fit([linear_window])
    assert issubclass(CalibrationError, ValueError)
    assert not hasattr(calibrator, "params_")
    with pytest.raises(RuntimeError, match="not fitted"):
        calibrator.save(tmp_path / "params.json")
    # resuming the failed run's checkpoint fails the same way
    with pytest.raises(CalibrationError, match=message):
        Calibrator(simulator, population=4, generations=3, workers=1,
                   checkpoint=tmp_path / "run.checkpoint").fit([linear_window], resume=True)
