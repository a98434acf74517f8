"""The GA's scoring path (``Objective.evaluate``: per-sensor Σr, Σr² of each window, constants
cached per objective) against the residual path it replaced, which formed the residual arrays
and summed them per window (the formulas of the objective's module docstring, written out
below as they were)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem, Objective
from steamtwin.calibration.settings import THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowset import CalibrationWindow, WindowSet
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import DEFAULT_PRIORS

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")
# within the bounds, both corners of the default bounds, and one the model rejects
CANDIDATES = ([1.0, 1.0, 1.0], [1.02, 1.2, 0.8], [0.9, 0.5, 0.5], [1.1, 2.0, 2.0],
              [0.9, 2.0, 0.5])


def reference_evaluation(objective: Objective, x) -> tuple[float, float, str]:
    """RMSE, score and error of ``x`` as the objective computed them from whole residual
    arrays (before the summed path)."""
    try:
        parts = objective.residual_parts(objective.parameters(x))
    except ValueError as error:
        return PENALTY_RMSE, PENALTY_RMSE, str(error)
    sse = count = counted = chi2 = 0.0
    kelvin = objective.weights * objective.temperature_mask
    sums: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    for window, (residual, precision) in zip(objective.windows, parts, strict=True):
        valid = ~np.isnan(residual)
        filled = np.where(valid, residual, 0.0)
        squares = (filled**2).sum(axis=0)
        sse += window.weight * (kelvin * squares).sum()
        count += window.weight * (kelvin * valid.sum(axis=0)).sum()
        counted += window.weight * (objective.weights * valid.sum(axis=0)).sum()
        chi2 += (precision * squares).sum()
        a, b = precision * valid.sum(axis=0), precision * filled.sum(axis=0)
        spread = window.bias_spread if window.bias_spread is not None else np.zeros(a.size)
        inverse = np.full(a.size, np.inf)
        inverse[spread > 0] = 1.0 / (objective.tempering * spread[spread > 0] ** 2)
        if window.group in sums:
            a, b = a + sums[window.group][0], b + sums[window.group][1]
        sums[window.group] = (a, b, inverse)
    for a, b, inverse in sums.values():
        chi2 -= float((b**2 / (a + inverse)).sum())
    prior = (objective.prior_terms(x) ** 2).sum() / objective.tempering
    return (float(np.sqrt(sse / count)), float(np.sqrt((max(chi2, 0.0) + prior) / counted)),
            "")


def assert_same_as_reference(objective: Objective) -> None:
    for x in CANDIDATES:
        result = objective.evaluate(x)
        rmse, score, error = reference_evaluation(objective, x)
        assert result.error == error
        assert result.rmse == pytest.approx(rmse, rel=1e-12)
        assert result.value == pytest.approx(score, rel=1e-12)
        with_residuals, _ = objective.evaluate_with_residuals(x)
        assert with_residuals.error == error
        assert with_residuals.rmse == pytest.approx(rmse, rel=1e-12)
        assert with_residuals.value == pytest.approx(score, rel=1e-12)


def _objective(simulator, frames: list[pd.DataFrame], tempering: float) -> Objective:
    """Two instrument sets (sources), σ per sensor, class-1 biases, the default priors."""
    windows = WindowSet(tuple(
        CalibrationWindow(frame, "steady", 0.5, f"file {i % 2}", {s: 0.3 for s in SENSORS})
        for i, frame in enumerate(frames)))
    settings = ObjectiveSettings(sensors=SENSORS, sensor_bias=THERMOCOUPLE_BIAS,
                                 priors=DEFAULT_PRIORS)
    return replace(CalibrationProblem(simulator, windows, settings).objective,
                   tempering=tempering)


@pytest.mark.parametrize("tempering", [1.0, 0.01])
def test_summed_path_equals_the_residual_arrays_on_an_analytic_model(
        linear_simulator, linear_window, tempering):
    gappy = linear_window.copy()
    gappy.iloc[10:25, gappy.columns.get_loc("hp_exhaust_temperature")] = np.nan
    frames = [linear_window, gappy, linear_window.iloc[:60] + 0.0]
    assert_same_as_reference(_objective(linear_simulator, frames, tempering))


def test_summed_path_equals_the_residual_arrays_on_the_fom(reference_spec, low_load_window):
    """The full-order model read through lagging thermowells, on a plant window with a
    dropout of the casing sensor, one window per instrument set."""
    from steamtwin.model.fom import FullOrderModel

    sensed = FullOrderModel(reference_spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    gappy = low_load_window.copy()
    gappy.iloc[40:70, gappy.columns.get_loc(SENSORS[2])] = np.nan
    frames = [gappy.iloc[:150], gappy.iloc[150:]]
    assert_same_as_reference(_objective(sensed, frames, 0.05))


class _NaNSimulator:
    """Predicts NaN at the first sample of the exhaust temperature."""

    def __init__(self, inner) -> None:
        self.inner = inner
        self.input_signals, self.output_signals = inner.input_signals, inner.output_signals

    def simulate(self, inputs, params):
        out = self.inner.simulate(inputs, params)
        out.iloc[0, out.columns.get_loc("hp_exhaust_temperature")] = np.nan
        return out


def test_a_non_finite_prediction_is_penalised_only_where_measured(linear_simulator,
                                                                  linear_window):
    objective = _objective(_NaNSimulator(linear_simulator), [linear_window], 1.0)
    result = objective.evaluate(CANDIDATES[0])
    assert result.rmse == PENALTY_RMSE and "non-finite" in result.error
    unmeasured = linear_window.copy()
    unmeasured.iloc[0, unmeasured.columns.get_loc("hp_exhaust_temperature")] = np.nan
    objective = _objective(_NaNSimulator(linear_simulator), [unmeasured], 1.0)
    assert not objective.evaluate(CANDIDATES[0]).penalised
    assert_same_as_reference(objective)
