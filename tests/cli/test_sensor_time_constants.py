"""Per-sensor time constants from the tag map reach the models of validate and calibrate
(issue 17, item 1: "per-sensor time constants in the tag map")."""

from __future__ import annotations

import dataclasses

import pytest

from steamtwin.cli.validate import _monitoring_model
from steamtwin.dcs.plant import plant_tag_map
from steamtwin.dcs.tagmap import TagMapError, parse_tag_map, write_tag_map
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.sensor_setup import sensor_setup

TAGS = """
[historian]
layout = "wide"
time_column = "time"

[signals.hp_exhaust_temperature]
column = "TE1"
unit = "degC"
time_constant = 45.5

[signals.main_steam_pressure]
column = "PT1"
unit = "MPa"
time_constant = 2.0
"""


def test_time_constant_is_read_written_and_checked(tmp_path):
    tag_map = parse_tag_map(TAGS, "tags.toml")
    assert tag_map.time_constants == {"hp_exhaust_temperature": 45.5, "main_steam_pressure": 2.0}
    write_tag_map(tag_map, tmp_path / "back.toml")
    assert parse_tag_map((tmp_path / "back.toml").read_text(), "back.toml").time_constants == (
        tag_map.time_constants)
    for bad in ("-1.0", "601.0", "true", '"20 s"'):
        with pytest.raises(TagMapError, match=r"tags\.toml: signals\.hp_exhaust_temperature"
                                              r"\.time_constant = .*time constant in s"):
            parse_tag_map(TAGS.replace("45.5", bad), "tags.toml")


def test_the_plants_own_time_constants_replace_the_typical_ones(reference_spec):
    setup = sensor_setup(reference_spec, parse_tag_map(TAGS, "tags.toml"))
    assert setup.time_constants == {  # inputs are not lagged
        "control_stage_temperature": TYPICAL_TIME_CONSTANTS_S["control_stage_temperature"],
        "hp_exhaust_temperature": 45.5,
        "hp_inner_casing_temperature": TYPICAL_TIME_CONSTANTS_S["hp_inner_casing_temperature"]}
    assert setup.sources["hp_exhaust_temperature"] == "tag map"


def test_validate_lags_the_model_by_the_tag_maps_time_constants(reference_spec):
    tag_map = plant_tag_map("wide")
    signals = dict(tag_map.signals)
    signals["hp_exhaust_temperature"] = dataclasses.replace(
        signals["hp_exhaust_temperature"], time_constant_s=45.5)
    tag_map = dataclasses.replace(tag_map, signals=signals)
    model = _monitoring_model(reference_spec, "fom", True, tag_map, {})
    assert model.sensor_time_constants["hp_exhaust_temperature"] == 45.5
    assert model.sensor_time_constants["control_stage_temperature"] == (
        TYPICAL_TIME_CONSTANTS_S["control_stage_temperature"])
    unlagged = _monitoring_model(reference_spec, "fom", False, tag_map, {})
    assert unlagged.sensor_time_constants is None and unlagged.sensor_offsets is None
    offsets = {"hp_exhaust_temperature": -1.2}
    assert _monitoring_model(reference_spec, "fom", True, tag_map, offsets).sensor_offsets == (
        offsets)
