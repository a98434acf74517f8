"""The heat-transfer coefficient with which the twin best follows the virtual plant's transients.

:attr:`~steamtwin.dcs.plant_model.PlantTruth.twin_equivalent` fits the twin's flow and friction
coefficients to the plant's steady states and carries the heat-transfer coefficient over: steady
states do not see it, and the plant's metal (a rotor with a bore, graded walls, a deeper casing
thermocouple) has no exact counterpart in the twin. The carried-over value is the plant's, not
the twin's: the twin's lumped metal reaches the plant's transients with another coefficient. A
calibration's interval for it is judged against the value a *perfect* calibration would find —
the plant's noise-free readings (its true signals through its thermowells' lags, no noise, no
calibration error) and its true inputs, the twin run over the same hours with the steady-state
twin-equivalent flow and friction coefficients, the heat-transfer coefficient varied alone.

Each sensor's constant difference is removed before scoring, as the calibration's sensor-offset
terms absorb a constant (Kennedy & O'Hagan 2001, "Bayesian calibration of computer models",
J. R. Stat. Soc. B 63, §4.2: a model-discrepancy term that is constant per output is not
separable from a bias). The one-dimensional minimum is found by Brent's method on the bounded
interval (Brent 1973, "Algorithms for Minimization without Derivatives", ch. 5; scipy's
``minimize_scalar(method="bounded")``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy.optimize import minimize_scalar

from steamtwin.dcs.plant import PlantRun, plant_sensor_models
from steamtwin.dcs.sensors import first_order_lag
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters
from steamtwin.model.simulator import Simulator

#: Tolerance (–) of the fitted coefficient: a tenth of the smallest interval width a
#: calibration reports for it on the virtual plant's day (~0.05 half-width).
COEFFICIENT_TOLERANCE = 1e-3


def noise_free_readings(run: PlantRun, sensors: Sequence[str]) -> pd.DataFrame:
    """What the plant's instruments on ``sensors`` would read without noise, drift, calibration
    error or quantisation (SI; the run's index): the true signals through each instrument's
    first-order lag, discretised as :func:`~steamtwin.dcs.sensors.measure` does."""
    models = plant_sensor_models(run.truth)
    missing = [s for s in sensors if s not in run.true_outputs.columns or s not in models]
    if missing:
        raise KeyError(f"the plant run has no instrument on {missing}")
    index = run.true_outputs.index
    dt_s = float((index[1] - index[0]) / pd.Timedelta(seconds=1)) if len(index) > 1 else 1.0
    return pd.DataFrame({s: first_order_lag(run.true_outputs[s].to_numpy(dtype=float), dt_s,
                                            models[s].time_constant_s) for s in sensors},
                        index=index)


def centred_rms(predicted: np.ndarray, readings: np.ndarray) -> float:
    """RMS (K) of ``predicted − readings`` after each column's mean difference is removed."""
    error = np.asarray(predicted, dtype=float) - np.asarray(readings, dtype=float)
    error = error - np.nanmean(error, axis=0)
    return float(np.sqrt(np.nanmean(error**2)))


def best_heat_transfer(model: Simulator, inputs: pd.DataFrame, readings: pd.DataFrame,
                       params: ModelParameters,
                       bounds: tuple[float, float] = PARAMETER_BOUNDS[
                           "heat_transfer_coefficient"]) -> float:
    """The heat-transfer coefficient (–) within ``bounds`` that minimises :func:`centred_rms`
    of ``model``'s predictions on ``inputs`` (SI) against ``readings`` (SI, its columns the
    sensors), the other parameters as in ``params``."""
    sensors = list(readings.columns)

    def score(coefficient: float) -> float:
        simulated = model.simulate(inputs, replace(params, heat_transfer_coefficient=coefficient))
        return centred_rms(simulated[sensors].to_numpy(dtype=float),
                           readings.loc[simulated.index, sensors].to_numpy(dtype=float))

    found = minimize_scalar(score, bounds=bounds, method="bounded",
                            options={"xatol": COEFFICIENT_TOLERANCE})
    return float(found.x)


def twin_equivalent_heat_transfer(run: PlantRun, model: Simulator,
                                  sensors: Sequence[str]) -> float:
    """The twin's heat-transfer coefficient (–) that best follows ``run``'s noise-free readings
    of ``sensors`` over the whole run (see the module docstring); ``model`` is the twin as it is
    calibrated (with its sensor models), flow and friction at the run's steady-state
    twin-equivalent values."""
    inputs = run.true_inputs[list(model.input_signals)]
    return best_heat_transfer(model, inputs, noise_free_readings(run, sensors),
                              run.truth.twin_equivalent)
