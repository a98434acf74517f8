"""ObjectiveSettings (frozen, checked once) and the priors a calibration starts from."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration import GeneticSearch, ObjectiveSettings, SurrogateSearch
from steamtwin.calibration.report import write_trajectory
from steamtwin.calibration.settings import DEFAULT_SENSORS, load_priors
from steamtwin.model.parameters import DEFAULT_PRIORS, ParameterError, ParameterPrior


def test_settings_are_frozen_and_keep_their_defaults():
    settings = ObjectiveSettings(sensors=["hp_exhaust_temperature", "control_stage_temperature"])
    assert settings.sensors == ("hp_exhaust_temperature", "control_stage_temperature")
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.min_samples = 1  # type: ignore[misc]
    default = ObjectiveSettings()
    assert default.sensors == DEFAULT_SENSORS and default.priors == DEFAULT_PRIORS
    assert default.priors is not DEFAULT_PRIORS  # each instance owns its mapping
    assert default == ObjectiveSettings() and default != dataclasses.replace(default, priors=None)
    # the searches are hashable values: a Table-7 cache can key on them
    assert len({GeneticSearch(), GeneticSearch(), SurrogateSearch()}) == 2


def test_weights_and_sigma_in_sensor_order():
    settings = ObjectiveSettings(weights={"hp_exhaust_temperature": 2.0},
                                 sigma={"control_stage_temperature": 0.5})
    np.testing.assert_array_equal(settings.sensor_weights(), [1.0, 2.0, 1.0])
    np.testing.assert_array_equal(settings.sensor_sigma(None, "w"), [0.5, 1.0, 1.0])
    # a window's own σ wins over the settings'
    np.testing.assert_array_equal(
        settings.sensor_sigma({"hp_inner_casing_temperature": 2.0}, "w"), [1.0, 1.0, 2.0])
    assert ObjectiveSettings().sensor_sigma(None, "w") is None
    with pytest.raises(ValueError, match=r"^window 3: measurement errors σ must be"):
        ObjectiveSettings().sensor_sigma({"hp_exhaust_temperature": -1.0}, "window 3")


def test_priors_from_defaults_file_and_overrides(tmp_path):
    assert load_priors() == DEFAULT_PRIORS
    path = tmp_path / "params.json"
    path.write_text(json.dumps({"priors": {"flow_coefficient": {
        "distribution": "normal", "center": 0.97, "spread": 0.01}}}))
    priors = load_priors(path, ["friction_coefficient=lognormal:1.1:0.2"])
    def value(prior: ParameterPrior) -> tuple[str, float, float]:
        return prior.distribution, prior.center, prior.spread

    assert value(priors["flow_coefficient"]) == ("normal", 0.97, 0.01)
    assert value(priors["friction_coefficient"]) == ("lognormal", 1.1, 0.2)
    assert priors["heat_transfer_coefficient"] == DEFAULT_PRIORS["heat_transfer_coefficient"]
    (tmp_path / "bare.json").write_text("{}")
    with pytest.raises(ParameterError, match=r"bare\.json: expected a JSON object with a "
                                             r"'priors' section"):
        load_priors(tmp_path / "bare.json")
    with pytest.raises(ParameterError, match="--prior"):
        load_priors(None, ["flow_coefficient=normal:1.0"])


def test_trajectory_written_in_the_data_time_zone(tmp_path):
    index = pd.date_range("2026-03-01 06:00", periods=3, freq="30min", tz="UTC", name="time")
    trajectory = pd.DataFrame({"flow_coefficient": [1.0, 1.01, 1.02],
                               "friction_coefficient": 1.0, "heat_transfer_coefficient": 1.0,
                               "rmse": [2.0, 1.5, 1.4], "error": ""}, index=index)
    table, figure = write_trajectory(trajectory, tmp_path, "Europe/Berlin")
    written = pd.read_csv(table)
    assert written["time"].iloc[0].startswith("2026-03-01 07:00:00+01:00")
    assert figure == tmp_path / "trajectory.png" and figure.stat().st_size > 1000
