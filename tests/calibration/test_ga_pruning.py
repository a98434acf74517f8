"""Pruning the GA's hopeless offspring: the windows run so far bound the score from below, and
an offspring pruned above the worst parent leaves the GA's course exactly as it was."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

import steamtwin.calibration.search as search_module
from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.objective import PRUNE_MARGIN, CalibrationProblem, Objective
from steamtwin.calibration.settings import THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowset import CalibrationWindow, WindowSet
from steamtwin.model.parameters import DEFAULT_PRIORS

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")


def _frames(window: pd.DataFrame) -> list[pd.DataFrame]:
    """Three windows: the fixture, one with a dropout, one warmer by 2 K (another bias)."""
    gappy = window.copy()
    gappy.iloc[10:25, gappy.columns.get_loc("hp_exhaust_temperature")] = np.nan
    warmer = window.iloc[:60].copy()
    warmer[list(SENSORS)] += 2.0
    return [window, gappy, warmer]


def _windows(frames: list[pd.DataFrame]) -> WindowSet:
    """Two instrument sets (sources), σ per sensor."""
    return WindowSet(tuple(
        CalibrationWindow(frame, "steady", 0.5, f"file {i % 2}", {s: 0.3 for s in SENSORS})
        for i, frame in enumerate(frames)))


def _objective(simulator, frames: list[pd.DataFrame], tempering: float) -> Objective:
    settings = ObjectiveSettings(sensors=SENSORS, sensor_bias=THERMOCOUPLE_BIAS,
                                 priors=DEFAULT_PRIORS)
    return replace(CalibrationProblem(simulator, _windows(frames), settings).objective,
                   tempering=tempering)


def _candidates(count: int) -> np.ndarray:
    random = np.random.default_rng(5)
    return np.column_stack([random.uniform(0.95, 1.1, count), random.uniform(0.5, 2.0, count),
                            random.uniform(0.5, 2.0, count)])


@pytest.mark.parametrize("tempering", [1.0, 0.01])
def test_the_windows_run_so_far_bound_the_score_from_below(linear_simulator, linear_window,
                                                          tempering):
    objective = _objective(linear_simulator, _frames(linear_window), tempering)
    for x in _candidates(30):
        params = objective.parameters(x)
        full = objective.evaluate(x)
        every = [_sums(objective, params, w) for w in objective.windows]
        for order in itertools.permutations(range(len(objective.windows))):
            sums = [None] * len(objective.windows)
            previous = objective._score_bound(x, sums)
            for index in order:
                sums[index] = every[index]
                bound = objective._score_bound(x, sums)
                assert previous <= bound * (1 + 1e-12)  # more windows, a higher bound
                assert bound <= full.value * (1 + 1e-12)
                previous = bound
            assert bound == pytest.approx(full.value, rel=1e-12)  # every window: the score


def _sums(objective: Objective, params, window) -> tuple[np.ndarray, np.ndarray]:
    from steamtwin.calibration.objective import _window_sums
    from steamtwin.calibration.windowprep import predict_window

    return _window_sums(predict_window(objective.simulator, window, params, objective.sensors),
                        window.measured)


def test_a_pruned_evaluation_is_marked_and_scores_above_the_threshold(linear_simulator,
                                                                     linear_window):
    objective = _objective(linear_simulator, _frames(linear_window), 1.0)
    pruned = 0
    for x in _candidates(30):
        full = objective.evaluate(x)
        for order in itertools.permutations(range(3)):
            ordered = replace(objective, run_order=order)
            # above the score: nothing pruned, the same numbers to the bit in any run order
            assert ordered.evaluate(x, prune_above=full.value * (1 + 2 * PRUNE_MARGIN)) == full
            first = objective._score_bound(x, [
                _sums(objective, objective.parameters(x), w) if k == order[0] else None
                for k, w in enumerate(objective.windows)])
            result = ordered.evaluate(x, prune_above=0.5 * first)
            assert result.pruned and not result.penalised and math.isnan(result.rmse)
            assert 0.5 * first < result.value <= full.value * (1 + 1e-12)
            pruned += 1
    assert pruned == 30 * 6
    # the priors alone can exceed a threshold: pruned before any window runs
    assert objective.evaluate([1.1, 2.0, 2.0], prune_above=1e-6).pruned


class _Counting:
    """The analytic simulator, counting its window-runs."""

    def __init__(self, inner) -> None:
        self.inner = inner
        self.input_signals, self.output_signals = inner.input_signals, inner.output_signals
        self.runs = 0

    def simulate(self, inputs, params):
        self.runs += 1
        return self.inner.simulate(inputs, params)


def test_pruning_leaves_the_ga_course_unchanged(linear_simulator, linear_window, monkeypatch):
    """The same populations (survivors and their scores) after every generation, the same
    history, result and posterior, with fewer window-runs."""
    populations: dict[bool, list[tuple[np.ndarray, np.ndarray]]] = {True: [], False: []}
    # a long first window (it bounds the score well) and a short second one; wide mutations
    frames = [linear_window, _frames(linear_window)[2]]
    original = search_module._history_row
    scored = CalibrationProblem.evaluate_candidates
    batches: list[tuple[float, np.ndarray, np.ndarray, Objective]] = []

    def scoring(problem, candidates):
        values = scored(problem, candidates)
        batches.append((problem.prune_above, np.array(candidates), values, problem.objective))
        return values

    fits, runs = {}, {}
    for prune in (False, True):
        def recording(algorithm, problem, repair, prune=prune):
            populations[prune].append((algorithm.pop.get("X").copy(),
                                       algorithm.pop.get("F").copy()))
            return original(algorithm, problem, repair)

        monkeypatch.setattr(search_module, "_history_row", recording)
        monkeypatch.setattr(CalibrationProblem, "evaluate_candidates", scoring)
        counting = _Counting(linear_simulator)
        fits[prune] = Calibrator(counting, objective=ObjectiveSettings(
            sensors=SENSORS, sensor_bias=THERMOCOUPLE_BIAS), search=GeneticSearch(
            population=12, generations=12, mutation_eta=2.0, prune=prune), random_state=4,
            workers=1).fit(_windows(frames))
        runs[prune] = counting.runs
    whole, pruned = fits[False], fits[True]
    # the pruned run's batches (the initial population, then one per generation): each
    # generation's offspring scored under its parents' worst score; a pruned offspring is
    # worse than every parent, an offspring not pruned has its exact score
    offspring = batches[len(batches) // 2 + 1:]
    assert batches[len(batches) // 2][0] == math.inf
    for (threshold, rows, values, objective), (_, parents) in zip(
            offspring, populations[True], strict=False):
        assert threshold == parents.max()
        for row, value in zip(rows, values, strict=True):
            exact = objective.evaluate(row).value
            assert exact > threshold if value > threshold else value == exact
    assert len(populations[True]) == len(populations[False]) == 12
    for (x_a, f_a), (x_b, f_b) in zip(populations[False], populations[True], strict=True):
        np.testing.assert_array_equal(x_a, x_b)
        np.testing.assert_array_equal(f_a, f_b)
    same = [c for c in whole.history_.columns if c not in ("pruned", "penalised")]
    pd.testing.assert_frame_equal(whole.history_[same], pruned.history_[same],
                                  check_exact=True)
    assert (whole.params_, whole.rmse_, whole.score_) == (pruned.params_, pruned.rmse_,
                                                          pruned.score_)
    np.testing.assert_array_equal(whole.posterior_.covariance, pruned.posterior_.covariance)
    assert whole.n_evaluations_ == pruned.n_evaluations_
    assert whole.n_pruned_ == 0 and (whole.history_["pruned"] == 0).all()
    assert pruned.n_pruned_ > 0 and pruned.history_["pruned"].iloc[-1] == pruned.n_pruned_
    # what was saved: at least one window per pruned candidate
    assert runs[True] <= runs[False] - pruned.n_pruned_
