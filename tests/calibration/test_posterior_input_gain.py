"""The measured inputs' term of the posterior is the tempered MAP's own response to an input
error (implicit-function theorem on the objective the calibrators minimise; GUM JCGM
100:2008 §5.1), not the reported posterior's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration.objective import CalibrationProblem
from steamtwin.calibration.posterior import InputUncertainty, fit_map, laplace_posterior
from steamtwin.calibration.settings import PARAMETER_NAMES, THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowprep import thermocouple_bias_spread
from steamtwin.calibration.windowset import CalibrationWindow, WindowSet
from steamtwin.model.parameters import DEFAULT_PRIORS, ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")
RATED_FLOW = 500.0  # kg/s
TRUTH = ModelParameters(1.03, 1.25, 1.4)
SIGMA = {name: 0.5 for name in SENSORS}  # K
SETTINGS = ObjectiveSettings(sensors=SENSORS, min_samples=30, sensor_bias=THERMOCOUPLE_BIAS)
FLOW = {"main_steam_flow": InputUncertainty("relative", 0.01, "test: 1 % of reading")}


class SteadySimulator:
    """Algebraic toy, linear in the flow and friction coefficients: control stage
    T0 − 60 − 80·φ·(1.2 − f), exhaust T0 − 250 + 15·ψ·√f + 5·φ, casing metal = exhaust
    (f = flow / rated; h invisible, held by its prior)."""

    input_signals = INPUT_SIGNALS
    output_signals = SENSORS

    def check_inputs(self, inputs: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
        return (inputs["main_steam_temperature"].to_numpy(dtype=float),
                inputs["main_steam_flow"].to_numpy(dtype=float) / RATED_FLOW)

    def simulate_checked(self, checked: tuple[np.ndarray, np.ndarray],
                         params: ModelParameters, signals: tuple[str, ...]) -> np.ndarray:
        t0, f = checked
        control = t0 - 60.0 - 80.0 * params.flow_coefficient * (1.2 - f)
        exhaust = (t0 - 250.0 + 15.0 * params.friction_coefficient * np.sqrt(f)
                   + 5.0 * params.flow_coefficient)
        outputs = dict(zip(SENSORS, (control, exhaust, exhaust), strict=True))
        return np.column_stack([outputs[name] for name in signals])

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        values = self.simulate_checked(self.check_inputs(inputs), params, SENSORS)
        return pd.DataFrame(values, columns=list(SENSORS), index=inputs.index)


def _windows(flow_factor: float = 1.0, temperature_offset: float = 0.0,
             temperatures: tuple[float, ...] = (810.0,) * 4) -> WindowSet:
    """Four steady loads (60 samples of 10 s each) at main-steam ``temperatures`` (K), noisy
    readings of TRUTH; the recorded flow multiplied by ``flow_factor`` and the recorded
    main-steam temperature moved by ``temperature_offset`` (K; input calibration errors)."""
    random = np.random.default_rng(5)
    frames = []
    for day, (load, temperature) in enumerate(zip((0.3, 0.5, 0.75, 1.0), temperatures,
                                                  strict=True)):
        index = pd.date_range(f"2026-01-0{day + 1}", periods=60, freq="10s", tz="UTC")
        inputs = pd.DataFrame({"main_steam_pressure": 16.0e6 * load,
                               "main_steam_temperature": temperature,
                               "main_steam_flow": RATED_FLOW * load,
                               "hp_exhaust_pressure": 3.5e6, "load": 600.0e6 * load},
                              index=index)
        truth = SteadySimulator().simulate(inputs, TRUTH)
        measured = truth + random.normal(0.0, 0.5, truth.shape)
        recorded = inputs.assign(main_steam_flow=inputs["main_steam_flow"] * flow_factor,
                                 main_steam_temperature=temperature + temperature_offset)
        frames.append(CalibrationWindow(pd.concat([recorded, measured], axis=1), "steady",
                                        load, "synthetic", SIGMA))
    return WindowSet(tuple(frames))


def _objective(windows: WindowSet, kappa: float):
    objective = CalibrationProblem(SteadySimulator(), windows, SETTINGS).objective
    return replace(objective, tempering=kappa)


@pytest.mark.parametrize("kappa", [1.0, 1.0e-3])
def test_the_input_term_is_the_tempered_maps_shift_under_a_biased_input(kappa):
    """Refitting the κ-tempered objective on flows recorded 1 % high moves the MAP by
    g = H_κ⁻¹J_κᵀ(∂r_κ/∂u)u (exact for this near-linear toy), whatever κ is. At κ = 10⁻³ the
    flow coefficient leans on its prior (it moves by +0.004 in the refit, −0.010 at κ = 1),
    which a gain taken from the reported posterior's weighting (τ = S = 1 here, so 1, not
    κ) misses: that gain says 0.010."""
    objective = _objective(_windows(), kappa)
    estimate = fit_map(objective, start=TRUTH)
    posterior = laplace_posterior(objective, estimate, inflate=False, inputs=FLOW)
    spread = np.sqrt(np.diag(posterior.input_covariance))
    refit = fit_map(_objective(_windows(1.01), kappa), start=estimate)
    for i, name in enumerate(PARAMETER_NAMES[:2]):
        prior = DEFAULT_PRIORS[name]
        shift = prior.to_internal(getattr(refit, name)) - prior.to_internal(
            getattr(estimate, name))
        assert abs(shift) > 1e-3, name  # the flow error moves both (the test has teeth)
        assert abs(shift) == pytest.approx(spread[i], rel=0.05), name


def test_a_thermocouple_input_error_is_one_offset_over_every_window():
    """A thermocouple's calibration error is one offset over the record (IEC 60584-1 class 1
    at the readings' mean), not one per window's temperature. Here the main-steam temperature
    only shifts every output's level, which the output thermocouples' biases absorb: a refit
    on readings moved by that one offset barely moves the MAP, and the propagated term says
    the same — offsets of 0.99 K at the 700-K loads and 1.24 K at the 810-K ones would
    instead tilt the control stage's load trend: a term of 0.005 on the flow coefficient."""
    temperatures = (700.0, 700.0, 810.0, 810.0)
    thermocouple = {"main_steam_temperature": InputUncertainty(
        "thermocouple", 0.0, "test: IEC 60584-1 class 1")}
    offset = thermocouple_bias_spread(float(np.mean(temperatures)))
    objective = _objective(_windows(temperatures=temperatures), 1.0)
    estimate = fit_map(objective, start=TRUTH)
    posterior = laplace_posterior(objective, estimate, inflate=False, inputs=thermocouple)
    spread = np.sqrt(np.diag(posterior.input_covariance))
    refit = fit_map(_objective(_windows(temperature_offset=offset, temperatures=temperatures),
                               1.0), start=estimate)
    for i, name in enumerate(PARAMETER_NAMES[:2]):
        prior = DEFAULT_PRIORS[name]
        shift = prior.to_internal(getattr(refit, name)) - prior.to_internal(
            getattr(estimate, name))
        assert abs(shift) == pytest.approx(spread[i], rel=0.05, abs=2e-5), name
