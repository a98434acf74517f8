"""Turbine spec loading: the reference unit, SI conversion and errors that name the field."""

from __future__ import annotations

import re
from importlib import resources

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.spec import SpecError, load_spec, parse_spec

REFERENCE_TEXT = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text()


def _replace(key_line: str, new_line: str) -> str:
    pattern = re.compile(rf"^{re.escape(key_line)}.*$", re.MULTILINE)
    assert pattern.search(REFERENCE_TEXT), key_line
    return pattern.sub(new_line, REFERENCE_TEXT, count=1)


def test_reference_is_in_si_units(reference_spec):
    design = reference_spec.design
    assert design.main_steam_pressure == pytest.approx(16.7e6)
    assert design.main_steam_temperature == pytest.approx(811.15)
    assert design.main_steam_flow == pytest.approx(500.0)
    assert design.rotational_speed == pytest.approx(314.159, rel=1e-5)
    assert len(reference_spec.stages) == 12
    assert [v.name for v in reference_spec.control_stage.valves] == ["GV1", "GV2", "GV3", "GV4"]
    assert reference_spec.extractions[0].after_stage == 8


@pytest.mark.parametrize(
    ("line", "replacement", "message"),
    [
        ('main_steam_flow = "1800 t/h"', "", r"design\.main_steam_flow is missing"),
        ('main_steam_pressure = "16.7 MPa"', 'main_steam_pressure = "-16.7 MPa"',
         r"unit.toml: design\.main_steam_pressure .*outside"),
        ('main_steam_pressure = "16.7 MPa"', "main_steam_pressure = 16.7",
         r"main_steam_pressure: 16.7 has no unit"),
        ('main_steam_pressure = "16.7 MPa"', 'main_steam_pressure = "16.7 m"',
         r"not convertible to Pa"),
        ('hp_exhaust_pressure = "3.90 MPa"', 'hp_exhaust_pressure = "14 MPa"',
         r"design pressures must fall along the steam path"),
    ],
    ids=["missing", "negative", "no-unit", "wrong-unit", "pressures-rise"],
)
def test_bad_design_field_is_named(line, replacement, message):
    with pytest.raises(SpecError, match=message):
        parse_spec(_replace(line, replacement), "unit.toml")


def test_admission_arcs_cannot_exceed_the_circumference():
    text = REFERENCE_TEXT.replace("admission_arc = 0.20", "admission_arc = 0.40")
    with pytest.raises(SpecError, match=r"admission arcs add up to 1\.120"):
        parse_spec(text, "unit.toml")


def test_metal_groups_must_cover_every_stage():
    text = REFERENCE_TEXT.replace("stages = [9, 10, 11, 12]", "stages = [9, 10, 11]")
    with pytest.raises(SpecError, match=r"metal\.groups must cover stages 0…12 exactly once"):
        parse_spec(text, "unit.toml")


def test_unknown_sensor_is_named():
    text = REFERENCE_TEXT.replace('"load",\n]', '"vibration",\n]')
    with pytest.raises(SpecError, match=r"sensors\[8\] = 'vibration' is not a canonical signal"):
        parse_spec(text, "unit.toml")


def test_unknown_built_in_or_missing_file():
    with pytest.raises(SpecError, match=r"neither a built-in"):
        load_spec("no-such-unit")


@settings(max_examples=40, deadline=None)
@given(st.floats(min_value=-1e3, max_value=1e3, allow_nan=False).filter(
    lambda x: not 1.0 <= x <= 25.0))
def test_main_steam_pressure_outside_range_is_refused(value):
    text = _replace('main_steam_pressure = "16.7 MPa"', f'main_steam_pressure = "{value!r} MPa"')
    with pytest.raises(SpecError, match=r"design\.main_steam_pressure"):
        parse_spec(text, "unit.toml")


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('design_flow = "120 t/h"', 'design_flow = "1800 t/h"',
         r"extractions bleed 500\.0 kg/s in all, not less than the main-steam flow"),
        ('name = "HP stages 1-4"', 'name = "control stage"', r"metal\.groups names repeat"),
        ("stages = [0]\n", "stages = [0, 1]\n", r"the control stage \(stage 0\) must be a group"),
        ('hp_exhaust_temperature = "326.7 degC"', 'hp_exhaust_temperature = "240 degC"',
         r"hp_exhaust_temperature 240\.0 °C is not superheated at 3\.9 MPa"),
        ("load_fraction = [0.0, 0.27", 'load_fraction = ["0 MPa", 0.27',
         r"sliding_pressure\.load_fraction\[0\]: '0 MPa' is not convertible"),
        ('"load",\n]', '"load", 3,\n]', r"sensors\[9\] = 3 is not a canonical signal"),
    ],
    ids=["bleed-too-large", "group-names", "control-stage-group", "exhaust-wet", "load-unit",
         "sensor-type"],
)
def test_inconsistent_spec_is_refused(old, new, message):
    assert old in REFERENCE_TEXT
    text = REFERENCE_TEXT.replace(old, new, 1)
    if "stages = [0, 1]" in new:  # keep every stage covered once
        text = text.replace("stages = [1, 2, 3, 4]", "stages = [2, 3, 4]")
    with pytest.raises(SpecError, match=message):
        parse_spec(text, "unit.toml")
