"""The Calibrator: improvement, elitism, reproducibility, saving, arguments, failed runs, and
the numbers of the calibrators before they became one (pinned bit for bit)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.calibration import (
    CalibrationError,
    Calibrator,
    GeneticSearch,
    ObjectiveSettings,
    SurrogateSearch,
    make_ga,
)
from steamtwin.calibration.online import OnlineCalibrator
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS

SMALL = GeneticSearch(population=8, generations=4)


@pytest.fixture(scope="module")
def fitted(reference_model, low_load_window):
    messages = []
    calibrator = Calibrator(reference_model, search=SMALL, random_state=0, workers=1,
                            progress=lambda f, m: messages.append(f))
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
        return Calibrator(linear_simulator, search=SMALL, random_state=seed,
                          workers=1).fit([low_load_window]).history_

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
        GeneticSearch(generations=0)
    with pytest.raises(TypeError, match="search must be"):
        Calibrator(linear_simulator, search={"generations": 10}).fit([low_load_window])


# -- arguments: one message per argument, naming it and its range, before any work ------------

BAD_SEARCH = [
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
]

BAD_OBJECTIVE = [
    ({"max_input_gap_s": -5.0}, r"^max_input_gap_s must be a number ≥ 0 s \(got -5\.0\)$"),
    ({"min_samples": 0}, r"^min_samples must be an integer ≥ 1 \(got 0\)$"),
    ({"sensors": ()}, r"^sensors must be a non-empty list of distinct signal names$"),
    ({"sensors": "hp_exhaust_temperature"}, r"^sensors must be a list of signal names"),
    ({"weights": (1.0, -1.0, 1.0)}, r"^weights must be finite, ≥ 0 and not all zero$"),
    ({"weights": {"load": 1.0}}, r"^weights for unselected sensor\(s\) \['load'\]$"),
    ({"bounds": {"flow_coefficient": (1.2, 1.1)}}, r"^bounds\['flow_coefficient'\]"),
    ({"priors": {"flow_coefficient": None}}, r"^priors: give one per parameter"),
    ({"sigma": {"hp_exhaust_temperature": 0.0}}, r"^sigma: measurement errors σ must be"),
    ({"sensor_bias": "typeK"}, r"^sensor_bias must be None, 'thermocouple' or a mapping"),
    ({"sensor_bias": {"load": 1.0}}, r"^sensor_bias: expected β ≥ 0 K for selected sensors"),
    ({"tempering": 0.0}, r"^tempering must be a number in \(0, 1\] or 'auto' \(got 0\.0\)$"),
]


@pytest.mark.parametrize(("arguments", "message"), BAD_SEARCH)
def test_each_bad_search_argument_is_named_with_its_range(arguments, message):
    with pytest.raises(ValueError, match=message):
        GeneticSearch(**arguments)


@pytest.mark.parametrize(("arguments", "message"), BAD_OBJECTIVE)
def test_each_bad_objective_setting_is_named_with_its_range(arguments, message):
    with pytest.raises(ValueError, match=message):
        ObjectiveSettings(**arguments)


@pytest.mark.parametrize("random_state", [-1, 1.5, True, None])
def test_bad_random_state_is_named_before_any_work(linear_simulator, random_state):
    # an empty window list would be refused too: the argument is checked first, before any work
    with pytest.raises(ValueError, match=r"^random_state must be an integer ≥ 0 \(got "):
        Calibrator(linear_simulator, workers=1, random_state=random_state).fit([])


@given(population=st.integers(-10**6, 1), tournament_size=st.integers(-10, 10**6))
def test_population_below_two_names_population_whatever_the_tournament(population,
                                                                       tournament_size):
    with pytest.raises(ValueError) as error:
        GeneticSearch(population=population, tournament_size=tournament_size)
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
    search = GeneticSearch(population=4, generations=3, checkpoint=tmp_path / "run.checkpoint")
    calibrator = Calibrator(simulator, search=search, workers=1)
    with pytest.raises(CalibrationError, match=message):
        calibrator.fit([linear_window])
    assert issubclass(CalibrationError, ValueError)
    assert not hasattr(calibrator, "params_")
    with pytest.raises(RuntimeError, match="not fitted"):
        calibrator.save(tmp_path / "params.json")
    # resuming the failed run's checkpoint fails the same way
    with pytest.raises(CalibrationError, match=message):
        Calibrator(simulator, search=search, workers=1).fit([linear_window], resume=True)


# -- one calibrator, same numbers: pinned against the three calibrators it replaced ------------
# Recorded on 2026-11-27 with the separate Calibrator, SurrogateCalibrator and OnlineCalibrator
# (commit cb06cd0), same settings and seeds: float.hex of the results, so bit for bit.

def _hex(params: ModelParameters) -> list[str]:
    return [float(v).hex() for v in (params.flow_coefficient, params.friction_coefficient,
                                      params.heat_transfer_coefficient)]


def test_ga_gives_todays_numbers_bit_for_bit(linear_simulator, linear_window):
    ga = Calibrator(linear_simulator, search=GeneticSearch(population=8, generations=5),
                    random_state=3, workers=1).fit([linear_window])
    assert _hex(ga.params_) == ["0x1.0577266cd222bp+0", "0x1.05867f718fc93p+0",
                                "0x1.224cc7a206252p-1"]
    assert (ga.rmse_.hex(), ga.score_.hex()) == ("0x1.472bff4cb3e07p+0",
                                                 "0x1.4a0128b5007e5p+0")
    assert ga.n_evaluations_ == 40
    plain = Calibrator(linear_simulator, objective=ObjectiveSettings(priors=None),
                       search=GeneticSearch(population=8, generations=5,
                                            mutation_probability=0.5, crossover_eta=10.0,
                                            tournament_size=3),
                       random_state=3, workers=1).fit([linear_window])
    assert (plain.params_.flow_coefficient.hex(), plain.rmse_.hex()) == (
        "0x1.06e5e28ff3db2p+0", "0x1.3bf47cdab36e4p+0")
    assert plain.samples_ is None and plain.population_.shape == (8, 3)


def test_surrogate_gives_todays_numbers_bit_for_bit(linear_simulator, linear_window):
    search = SurrogateSearch(initial_samples=12, infill_per_round=3, max_evaluations=24,
                             population=10, generations=10)
    surrogate = Calibrator(linear_simulator, search=search, random_state=1,
                           workers=1).fit([linear_window])
    assert _hex(surrogate.params_) == ["0x1.07c9539f15626p+0", "0x1.24ef5c6d2b234p+0",
                                       "0x1.2238dd4d02dc8p+0"]
    assert (surrogate.rmse_.hex(), surrogate.score_.hex()) == ("0x1.3ca0e7e8200bep+0",
                                                               "0x1.3d4bfb9381fe7p+0")
    assert surrogate.n_evaluations_ == 24 and len(surrogate.samples_) == 24
    assert surrogate.population_ is None


FLOW_TRAJECTORY = ["0x1.080e33614b25bp+0", "0x1.07ae57725934ap+0"]
RMSE_TRAJECTORY = ["0x1.315edfd666602p+0", "0x1.26cba7179ebdcp+0"]


def test_online_calibrator_gives_todays_trajectory(linear_simulator, linear_window):
    data = pd.concat([linear_window.set_axis(linear_window.index + pd.Timedelta(seconds=120 * k))
                      for k in range(6)])
    online = OnlineCalibrator(linear_simulator, window_s=240.0, every_s=240.0, population=6,
                              generations=2, first_generations=3, random_state=2
                              ).run(data, chunk_s=60.0)
    trajectory = online.trajectory_
    assert online.n_evaluations_ == 32 and len(trajectory) == 2
    assert (trajectory["error"] == "").all()
    assert [v.hex() for v in trajectory["flow_coefficient"]] == FLOW_TRAJECTORY
    assert [v.hex() for v in trajectory["rmse"]] == RMSE_TRAJECTORY
