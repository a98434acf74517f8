"""The twin-equivalent heat-transfer coefficient (steamtwin.dcs.twin_equivalent): the plant's
noise-free readings are its recording less noise and calibration error, and the fit recovers a
coefficient the readings were made with, whatever constant offsets the sensors carry."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from steamtwin.dcs.plant import run_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.dcs.twin_equivalent import best_heat_transfer, centred_rms, noise_free_readings
from steamtwin.model.parameters import ModelParameters

THERMOCOUPLES = ("control_stage_temperature", "hp_exhaust_temperature",
                 "hp_inner_casing_temperature")


@pytest.fixture(scope="module")
def ramp_run():
    """10 min at 100 % then the ramp down at 3 %/min into a short 50 % hold, no faults."""
    return run_plant("deep-peak-50", hours=0.1, random_state=5,
                     truth=PlantTruth(faults=FaultConfig(enabled=False)))


def test_recording_less_noise_free_readings_is_bias_and_noise(ramp_run):
    readings = noise_free_readings(ramp_run, THERMOCOUPLES)
    sensors = ramp_run.injected.sensors
    for name in THERMOCOUPLES:
        difference = (ramp_run.measured[name] - readings[name]).to_numpy()
        row = sensors.loc[name]
        n = difference.size
        # constant class-1 tolerance at these levels: the bias is the same at every reading;
        # quantisation (resolution) adds a uniform error of width `resolution` at most
        allowance = 4.0 * row["noise_sigma"] / np.sqrt(n) + row["resolution"]
        assert abs(difference.mean() - row["bias"]) < allowance + 0.05 * abs(row["bias"])
        assert difference.std() == pytest.approx(np.hypot(row["noise_sigma"],
                                                          row["resolution"] / np.sqrt(12.0)),
                                                 rel=0.15)


def test_noise_free_readings_name_a_missing_instrument(ramp_run):
    with pytest.raises(KeyError, match="no_such_sensor"):
        noise_free_readings(ramp_run, ("no_such_sensor",))


def test_centred_rms_ignores_constant_offsets():
    rng = np.random.default_rng(0)
    readings = rng.normal(700.0, 5.0, size=(200, 3))
    assert centred_rms(readings + np.array([0.7, -1.2, 2.0]), readings) == pytest.approx(0.0,
                                                                                         abs=1e-12)
    wiggle = np.sin(np.linspace(0.0, 6.0, 200))[:, None] * np.ones(3)
    assert centred_rms(readings + wiggle, readings) == pytest.approx(
        np.sqrt(np.mean((wiggle - wiggle.mean()) ** 2)), rel=1e-12)


@pytest.mark.parametrize("coefficient", [0.7, 1.3])
def test_fit_recovers_the_coefficient_the_readings_were_made_with(coefficient, ramp_run,
                                                                  reference_model):
    inputs = ramp_run.true_inputs[list(reference_model.input_signals)]
    params = ModelParameters(flow_coefficient=0.98, friction_coefficient=1.2)
    made = reference_model.simulate(inputs, replace(params,
                                                    heat_transfer_coefficient=coefficient))
    readings = made[list(THERMOCOUPLES)] + np.array([0.8, -0.5, 1.4])  # the sensors' offsets
    assert best_heat_transfer(reference_model, inputs, readings, params) == pytest.approx(
        coefficient, abs=0.01)
