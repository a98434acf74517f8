"""The sensor offsets' class-1 prior keeps its weight when the likelihood is tempered.

A power likelihood tempers the data, not the priors (Grünwald & van Ommen 2017; Bissiri,
Holmes & Walker 2016): the offsets' N(0, β²) (IEC 60584-1 class 1, β = tolerance/√3) is a
prior like the coefficients'. When the data pin only a temperature's level — a parameter that
shifts it and the thermocouple's offset trade one for one (Kennedy & O'Hagan 2001, §4.3) — the
split between them is the two priors' alone, whatever κ; tempering the offsets' prior with the
likelihood hands the whole level to the offset (docs/benchmarks.md, "The offsets' class-1
prior").
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import minimize

from steamtwin.calibration.objective import CalibrationProblem
from steamtwin.calibration.posterior import fit_map, laplace_posterior
from steamtwin.calibration.settings import THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowprep import thermocouple_bias_spread
from steamtwin.calibration.windowset import CalibrationWindow, WindowSet
from steamtwin.model.parameters import DEFAULT_PRIORS, ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature")
SIGMA = {name: 0.05 for name in SENSORS}  # K: noise-free data, the level pinned
EXHAUST_LEVEL = 560.0  # K at ψ = 1: 287 °C, class-1 tolerance 1.5 K
FRICTION_SLOPE = 4.0  # K per unit of ψ
TRUE_FRICTION, TRUE_OFFSET = 1.5, 0.0


class LevelSimulator:
    """Control stage at a fixed 780 K (φ, h invisible); HP exhaust 560 K + 4 K·(ψ − 1): at one
    load the friction coefficient only moves the exhaust's level."""

    input_signals = INPUT_SIGNALS
    output_signals = SENSORS

    def check_inputs(self, inputs: pd.DataFrame) -> int:
        return len(inputs)

    def simulate_checked(self, n: int, params: ModelParameters, signals: tuple[str, ...]
                         ) -> np.ndarray:
        values = {"control_stage_temperature": 780.0 + 0.0 * params.flow_coefficient,
                  "hp_exhaust_temperature": EXHAUST_LEVEL
                  + FRICTION_SLOPE * (params.friction_coefficient - 1.0)}
        return np.column_stack([np.full(n, values[name]) for name in signals])


def _window_set() -> WindowSet:
    frames = []
    for day in range(4):
        index = pd.date_range(f"2026-01-0{day + 1}", periods=120, freq="10s", tz="UTC")
        frame = pd.DataFrame({"main_steam_pressure": 16.0e6, "main_steam_temperature": 810.0,
                              "main_steam_flow": 500.0, "hp_exhaust_pressure": 3.5e6,
                              "load": 600.0e6}, index=index)
        truth = ModelParameters(1.0, TRUE_FRICTION, 1.0)
        outputs = LevelSimulator().simulate_checked(len(frame), truth, SENSORS)
        frame[list(SENSORS)] = outputs
        frame["hp_exhaust_temperature"] += TRUE_OFFSET
        frames.append(CalibrationWindow(frame, "steady", 1.0, "synthetic", SIGMA))
    return WindowSet(tuple(frames))


def _objective(tempering: float):
    settings = ObjectiveSettings(sensors=SENSORS, min_samples=30,
                                 sensor_bias=THERMOCOUPLE_BIAS)
    objective = CalibrationProblem(LevelSimulator(), _window_set(), settings).objective
    return replace(objective, tempering=tempering)


def _two_prior_split() -> float:
    """The friction coefficient that splits the exhaust's measured level between ψ and the
    offset b as the priors alone say: min (ln ψ/s)² + (b/β)² with 4·(ψ − 1) + b fixed."""
    prior = DEFAULT_PRIORS["friction_coefficient"]
    beta = thermocouple_bias_spread(EXHAUST_LEVEL + FRICTION_SLOPE * (TRUE_FRICTION - 1.0))
    level = FRICTION_SLOPE * (TRUE_FRICTION - 1.0) + TRUE_OFFSET

    def cost(log_friction: np.ndarray) -> float:
        offset = level - FRICTION_SLOPE * (math.exp(log_friction[0]) - 1.0)
        return ((log_friction[0] - prior.mean_internal) / prior.spread) ** 2 + (
            offset / beta) ** 2

    return math.exp(minimize(cost, [0.0]).x[0])


@pytest.mark.parametrize("tempering", [1.0, 1.0e-2])
def test_the_level_splits_as_the_priors_say_whatever_the_tempering(tempering):
    expected = _two_prior_split()
    assert 1.05 < expected < 1.45  # both priors take a share
    objective = _objective(tempering)
    estimate = fit_map(objective)
    assert estimate.friction_coefficient == pytest.approx(expected, abs=0.01)
    offset = objective.sensor_offsets(estimate)["hp_exhaust_temperature"]
    level = FRICTION_SLOPE * (TRUE_FRICTION - 1.0) + TRUE_OFFSET
    assert offset + FRICTION_SLOPE * (estimate.friction_coefficient - 1.0) == pytest.approx(
        level, abs=0.02)


def test_score_counts_the_bias_prior_at_full_weight():
    objective = _objective(1.0e-2)
    params = ModelParameters(1.0, 1.2, 1.0)
    x = [params.flow_coefficient, params.friction_coefficient, params.heat_transfer_coefficient]
    residuals = objective.standardised_residuals(params)
    data = objective.data_rows()
    offsets = objective.sensor_offsets(params)
    betas = objective.windows[0].bias_spread
    # the bias rows are b/β (their prior, untempered), not √κ·b/β
    np.testing.assert_allclose(np.abs(residuals[data:]), [
        abs(offsets[s]) / b for s, b in zip(SENSORS, betas, strict=True)], rtol=1e-6)
    assert abs(residuals[-1]) > 0.1  # the exhaust's offset is far from zero at ψ = 1.2
    score = objective.evaluate(x).value
    assert score**2 * objective.tempering * objective.weighted_count() == pytest.approx(
        residuals @ residuals + (objective.prior_terms(x) ** 2).sum(), rel=1e-9)


def test_laplace_is_the_same_from_a_tempered_objective():
    """κ is taken out of the samples' rows and put back as 1/(τ S²); the bias rows stay."""
    plain, tempered = _objective(1.0), _objective(1.0e-2)
    params = fit_map(plain)
    first = laplace_posterior(plain, params, inflate=False).table()
    second = laplace_posterior(tempered, params, inflate=False).table()
    np.testing.assert_allclose(second["std"], first["std"], rtol=1e-3)
