"""Identifiability check: flags parameters the data cannot see, passes those it can."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.identifiability import (
    IdentifiabilityWarning,
    identifiability,
    integrated_time,
)
from steamtwin.calibration.objective import CalibrationProblem
from steamtwin.calibration.settings import ObjectiveSettings
from steamtwin.model.parameters import ModelParameters


def _noisy_window(simulator, params, n=600, seed=0):
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC")
    window = pd.DataFrame({"main_steam_pressure": 16.0e6,
                           "main_steam_temperature": 800.0 + np.linspace(0, 5, n),
                           "main_steam_flow": 400.0, "hp_exhaust_pressure": 3.5e6}, index=index)
    truth = simulator.simulate(window, params)
    noise = np.random.default_rng(seed).normal(0.0, 0.3, (n, 3))
    for j, sensor in enumerate(("control_stage_temperature", "hp_exhaust_temperature",
                                "hp_inner_casing_temperature")):
        window[sensor] = truth[sensor] + noise[:, j]
    return window


class BlindToHeatTransfer:
    """Like the linear simulator, but nothing depends on the heat-transfer coefficient."""

    def __init__(self, linear):
        self.linear = linear
        self.input_signals = linear.input_signals
        self.output_signals = linear.output_signals

    def simulate(self, inputs, params):
        return self.linear.simulate(inputs, ModelParameters(
            params.flow_coefficient, params.friction_coefficient, 1.0))


def test_linear_model_is_identifiable_and_standard_errors_are_right(linear_simulator):
    truth = ModelParameters(1.0, 1.2, 1.4)
    window = _noisy_window(linear_simulator, truth)
    problem = CalibrationProblem(linear_simulator, [window], ObjectiveSettings(priors=None))
    table = identifiability(problem.objective, truth, problem.parameter_bounds)
    assert table["identifiable"].all()
    # white noise σ = 0.3 K on a sensor with slope a K per unit: standard error σ/(a·√n)
    slopes = {"flow_coefficient": 100.0, "friction_coefficient": 10.0,
              "heat_transfer_coefficient": 5.0}
    for name, slope in slopes.items():
        assert table.loc[name, "std_error"] == pytest.approx(0.3 / slope / np.sqrt(600), rel=0.25)
    assert table.attrs["autocorrelation_time_samples"] < 2.0  # white noise


def test_a_parameter_without_effect_is_flagged_with_a_warning(linear_simulator):
    blind = BlindToHeatTransfer(linear_simulator)
    window = _noisy_window(blind, ModelParameters(1.0, 1.2, 1.0))
    with pytest.warns(IdentifiabilityWarning, match="heat_transfer_coefficient is not identif"):
        fitted = Calibrator(blind, search=GeneticSearch(population=8, generations=3),
                            workers=1).fit([window])
    table = fitted.identifiability_
    assert not table.loc["heat_transfer_coefficient", "identifiable"]
    assert table.loc["heat_transfer_coefficient", "rmse_rise"] == pytest.approx(0.0, abs=1e-9)
    assert table.loc["heat_transfer_coefficient", "std_error"] == np.inf
    assert table.loc["flow_coefficient", "identifiable"]


def test_plant_hold_cannot_identify_heat_transfer(reference_model, plant_run):
    hold = plant_run.measured.iloc[-600:]
    problem = CalibrationProblem(reference_model, [hold], ObjectiveSettings(priors=None))
    table = identifiability(problem.objective, plant_run.truth.twin_equivalent,
                            problem.parameter_bounds)
    assert table.loc["flow_coefficient", "identifiable"]
    assert not table.loc["heat_transfer_coefficient", "identifiable"]


def test_integrated_time_of_known_processes():
    random = np.random.default_rng(1)
    assert integrated_time(random.normal(size=20000)) == pytest.approx(1.0, abs=0.15)
    phi = 0.9  # AR(1): τ = (1 + φ)/(1 − φ) = 19
    x = np.zeros(200000)
    shocks = random.normal(size=x.size)
    for i in range(1, x.size):
        x[i] = phi * x[i - 1] + shocks[i]
    assert integrated_time(x) == pytest.approx(19.0, rel=0.1)


def test_with_instrument_errors_the_figures_are_in_sigma_whatever_the_sensors_units(
        linear_simulator):
    """A joint calibration's windows carry each sensor's σ (K, or Pa for a pressure): the
    check weighs residuals as the objective does, r/σ, so its RMSE is in instrument errors (a
    pressure in Pa no longer swamps the temperatures: the demo's "RMSE's own uncertainty
    723.770 K"); with one σ for every sensor the figures are the plain ones over σ."""
    truth = ModelParameters(1.0, 1.2, 1.4)
    window = _noisy_window(linear_simulator, truth)
    sigma = {"control_stage_temperature": 0.3, "hp_exhaust_temperature": 0.3,
             "hp_inner_casing_temperature": 0.3}
    problem = CalibrationProblem(linear_simulator, [window],
                                 ObjectiveSettings(priors=None, sigma=sigma))
    table = identifiability(problem.objective, truth, problem.parameter_bounds)
    assert table.attrs["unit"] == "σ"
    assert table.attrs["rmse"] == pytest.approx(1.0, rel=0.1)  # white noise of σ: RMSE 1 σ
    plain = CalibrationProblem(linear_simulator, [window], ObjectiveSettings(priors=None))
    in_kelvin = identifiability(plain.objective, truth, plain.parameter_bounds)
    assert in_kelvin.attrs["unit"] == "K"
    np.testing.assert_allclose(table["rmse_rise"] * 0.3, in_kelvin["rmse_rise"], rtol=1e-6)
    assert (table["identifiable"] == in_kelvin["identifiable"]).all()
