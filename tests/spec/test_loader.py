"""Turbine spec loading: the reference unit, SI conversion and errors that name the field."""

from __future__ import annotations

import re
from importlib import resources

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.spec import SpecError, load_spec, parse_spec
from steamtwin.spec.turbine import PartLoad, TemperatureSchedule

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
    with pytest.raises(SpecError, match=r"sensors\[9\] = 'vibration' is not a canonical signal"):
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
         r"sliding_pressure\.load_fraction\[1\]: '0 MPa' is not convertible"),
        ('"load",\n]', '"load", 3,\n]', r"sensors\[10\] = 3 is not a canonical signal"),
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


def test_misspelled_extractions_table_is_refused():
    """Finding 5: ``[[extraction]]`` used to drop the HP-heater bleed with exit 0."""
    text = REFERENCE_TEXT.replace("[[extractions]]", "[[extraction]]")
    with pytest.raises(SpecError, match=r"unit\.toml: extraction is not a turbine spec field "
                       r"\(did you mean 'extractions'\?\)"):
        parse_spec(text, "unit.toml")


def test_unknown_key_in_a_stage_names_the_stage_from_one():
    """Finding 5: an unknown key in the third [[stages]] table is named as stage 3."""
    text = REFERENCE_TEXT.replace('mean_diameter = "0.9539 m"', 'pitch_diameter = "0.9539 m"')
    with pytest.raises(SpecError, match=r"unit\.toml: stage 3: stages\[3\]\.pitch_diameter is not "
                       r"a turbine spec field \(did you mean 'mean_diameter'\?\); expected one "
                       r"of: blade_count, "):
        parse_spec(text, "unit.toml")


def test_misspelled_table_header_is_refused():
    text = REFERENCE_TEXT.replace("[metal.casing_material]", "[metal.casing_materail]")
    with pytest.raises(SpecError, match=r"metal\.casing_materail is not a turbine spec field "
                       r"\(did you mean 'casing_material'\?\)"):
        parse_spec(text, "unit.toml")


@pytest.mark.parametrize(("old", "new", "message"), [
    ('hp_power = "177.3 MW"', "hp_power = [177.3, 1]",
     r"design\.hp_power is an array: expected a string 'value unit' with a unit convertible "
     r"to W"),
    ('hp_power = "177.3 MW"', "hp_power = 1979-05-27", r"design\.hp_power is a date/time"),
    ('hp_power = "177.3 MW"', 'hp_power = "177.3 M)W"',
     r"design\.hp_power: cannot read the unit of .177\.3 M\)W.: expected .value unit. with a "
     r"unit convertible to W"),
    ("valve_pressure_drop = 0.03", "valve_pressure_drop = {value = 0.03}",
     r"design\.valve_pressure_drop is a table: expected a plain number"),
    ("load_fraction = [0.0, 0.27", "load_fraction = [0.0, nan",
     r"sliding_pressure\.load_fraction must increase within 0…1\.2"),
    ('pressure = ["6.0 MPa"', 'pressure = [[6.0]',
     r"sliding_pressure\.pressure\[1\] is an array"),
    ("[metal.rotor_material]", "[metal.rotor_material.extra]",
     r"metal\.rotor_material\.extra is not a turbine spec field"),
], ids=["array", "datetime", "unit-syntax", "table", "nan-load", "nested-array", "sub-table"])
def test_value_of_the_wrong_type_is_named(old, new, message):
    assert old in REFERENCE_TEXT
    with pytest.raises(SpecError, match=rf"unit\.toml: {message}"):
        parse_spec(REFERENCE_TEXT.replace(old, new, 1), "unit.toml")


@pytest.mark.parametrize(("content", "message"), [
    (bytes(range(256)) * 4, r"not UTF-8 text \(byte 0x80 at offset 128, line 2\)"),
    (REFERENCE_TEXT.replace("reference unit", "参考机组").encode("gbk"),
     r"not UTF-8 text \(byte 0xb2 at offset 21, line 1\); a turbine spec is a TOML file "
     "saved as UTF-8"),
    (b"", r"the file is empty"),
    (b"\n \n", r"the file is empty"),
    (b"\x00\x01 binary", r"not valid TOML"),
    (b"format_version = " + b"9" * 5000, r"not valid TOML: Exceeds the limit"),
    (b"a = " + b"[" * 5000, r"not valid TOML: maximum recursion depth"),
], ids=["binary", "gbk", "empty", "blank", "nul-bytes", "huge-integer", "deep-nesting"])
def test_unreadable_spec_file_is_a_spec_error_naming_it(tmp_path, content, message):
    """Finding 6: a binary or GBK file as spec used to end in a traceback."""
    path = tmp_path / "unit.toml"
    path.write_bytes(content)
    with pytest.raises(SpecError, match=rf"unit\.toml: {message}"):
        load_spec(path)


def test_a_byte_order_mark_is_accepted(tmp_path, reference_spec):
    path = tmp_path / "unit.toml"
    path.write_bytes(b"\xef\xbb\xbf" + REFERENCE_TEXT.encode("utf-8"))
    assert load_spec(path) == reference_spec


def test_an_unreadable_spec_file_is_named(tmp_path, monkeypatch):
    path = tmp_path / "unit.toml"
    path.write_text(REFERENCE_TEXT)

    def refuse(self):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(type(path), "read_bytes", refuse)
    with pytest.raises(SpecError, match=r"unit\.toml: cannot read the turbine spec: Permission"):
        load_spec(path)


def test_part_load_table_is_optional_and_each_field_defaults(reference_spec):
    text = REFERENCE_TEXT
    assert reference_spec.part_load == PartLoad()
    spec = parse_spec(text + "\n[part_load]\nreynolds_exponent = 0.2\n", "unit.toml")
    assert spec.part_load == PartLoad(reynolds_exponent=0.2)
    with pytest.raises(SpecError, match=r"unit\.toml: part_load\.flow_capacity_multiplier = 2\.0 "
                                        r"is outside the valid range \[0\.8, 1\.25\]"):
        parse_spec(text + "\n[part_load]\nflow_capacity_multiplier = 2.0\n", "unit.toml")


def _with_schedule(body: str) -> str:
    return REFERENCE_TEXT + "\n[temperature_schedule]\n" + body + "\n"


def test_temperature_schedule_is_optional_and_read_in_kelvin(reference_spec):
    assert reference_spec.temperature_schedule is None
    spec = parse_spec(_with_schedule(
        'load_fraction = [0.3, 0.5, 1.0]\n'
        'main_steam_temperature = ["520 degC", "530 degC", "538 degC"]\n'
        'reheat_temperature = ["500 degC", "520 degC", "811.15 K"]'), "unit.toml")
    assert spec.temperature_schedule == TemperatureSchedule(
        (0.3, 0.5, 1.0), pytest.approx((793.15, 803.15, 811.15)),
        pytest.approx((773.15, 793.15, 811.15)))
    no_reheat = parse_spec(_with_schedule(
        'load_fraction = [0.3, 1.0]\nmain_steam_temperature = ["520 degC", "538 degC"]'), "u")
    assert no_reheat.temperature_schedule is not None
    assert no_reheat.temperature_schedule.reheat_temperature is None


@pytest.mark.parametrize(("body", "message"), [
    ('load_fraction = [0.3, 0.5, 0.5]\nmain_steam_temperature = ["520 degC", "530 degC", '
     '"538 degC"]',
     r"temperature_schedule\.load_fraction\[3\] = 0\.5 is not above load_fraction\[2\] = 0\.5"),
    ('load_fraction = [0.3, 1.3]\nmain_steam_temperature = ["520 degC", "538 degC"]',
     r"temperature_schedule\.load_fraction\[2\] = 1\.3 is outside the valid range \[0, 1\.2\]"),
    ('load_fraction = [0.3, 1.0]\nmain_steam_temperature = ["520 degC", "680 degC"]',
     r"temperature_schedule\.main_steam_temperature\[2\] = '680 degC' is outside the valid range "
     r"\[573\.15, 923\.15\] K = \[300, 650\] degC"),
    ('load_fraction = [0.3, 1.0]\nmain_steam_temperature = ["520 degC", "538 degC"]\n'
     'reheat_temperature = ["515 degC", 538]',
     r"temperature_schedule\.reheat_temperature\[2\]: 538 has no unit"),
    ('load_fraction = [0.3, 1.0]\nmain_steam_temperature = ["520 degC", "530 degC", "538 degC"]',
     r"temperature_schedule\.main_steam_temperature has 3 values but load_fraction has 2"),
    ('load_fraction = [0.3, 1.0]\nmain_steam_temperature = ["520 degC", "538 degC"]\n'
     'reheat_temperature = ["515 degC"]',
     r"temperature_schedule\.reheat_temperature has 1 value: expected an array of ≥ 2 values"),
    ('load_fraction = 0.3\nmain_steam_temperature = ["520 degC", "538 degC"]',
     r"temperature_schedule\.load_fraction is a float: expected an array of ≥ 2 values"),
    ('load_fraction = [0.3, 1.0]',
     r"temperature_schedule\.main_steam_temperature is missing"),
    ('load_fraction = [0.3, 1.0]\nmain_steam_temperatures = ["520 degC", "538 degC"]',
     r"temperature_schedule\.main_steam_temperatures is not a turbine spec field \(did you mean "
     r"'main_steam_temperature'\?\)"),
], ids=["not-increasing", "load-range", "temperature-range", "no-unit", "length", "too-short",
        "not-an-array", "missing", "misspelled"])
def test_a_bad_temperature_schedule_names_the_entry(body, message):
    with pytest.raises(SpecError, match=rf"^unit\.toml: {message}"):
        parse_spec(_with_schedule(body), "unit.toml")
