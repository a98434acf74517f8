"""The spec format's one table: it is the loader's schema, sets its ranges and writes the docs."""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import re
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from toml_documents import toml_text

from steamtwin.spec import SpecError, load_spec, parse_spec
from steamtwin.spec.loader import OPTIONAL_KEYS, SPEC_KEYS
from steamtwin.spec.schema import (
    FIELD_BY_KEY,
    FIELDS,
    QUANTITY_PATTERN,
    Field,
    _value_schema,
    json_schema,
    json_schema_text,
    main,
    render_markdown,
)
from steamtwin.units import parse_quantity

REFERENCE_TEXT = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
    encoding="utf-8")
REFERENCE = tomllib.loads(REFERENCE_TEXT)
DOCS = Path(__file__).resolve().parents[2] / "docs"
#: Which entry of each array of tables the range tests change (0-based): the third stage, the
#: second valve and metal group, the only bleed — so messages must count from 1.
POSITIONS = {"stages": 2, "control_stage.valves": 1, "metal.groups": 1, "extractions": 0,
             "leakages": 0, "rotor.steam": 0}
#: The reference plus one leakage to the outside, so that every leakage field has a value.
WITH_LEAKAGE = {**REFERENCE, "leakages": [{"name": "HP-IP gland", "from_stage": 0,
                                            "to": "outside", "design_flow": "18 t/h",
                                            "sink_pressure": "3.5 MPa"}]}
NUMERIC = ("quantity", "number", "integer")
#: Valid contents of the optional tables whose arrays the reference leaves out: a test changing
#: one of their entries starts from them.
OPTIONAL_TABLES: dict[str, dict[str, Any]] = {
    "temperature_schedule": {"load_fraction": [0.3, 0.5, 1.0],
                             "main_steam_temperature": ["520 degC", "530 degC", "538 degC"],
                             "reheat_temperature": ["510 degC", "525 degC", "538 degC"]},
}


def _located(field: Field) -> tuple[list[str | int], str, str]:
    """Where ``field`` sits in the reference: key path, its TOML path (1-based) and the context
    the loader prefixes (``"stage 3: "``)."""
    keys: list[str | int] = []
    shown, context = [], ""
    for part in field.path.split("."):
        name = part.removesuffix("[]")
        keys.append(name)
        shown.append(name)
        if part.endswith("[]"):
            table = ".".join(str(key) for key in keys if isinstance(key, str))
            keys.append(POSITIONS[table])
            shown[-1] += f"[{POSITIONS[table] + 1}]"
            if table == "stages":
                context = f"stage {POSITIONS[table] + 1}: "
    return keys, ".".join(shown), context


def _with(document: dict[str, Any], keys: list[str | int], value: Any) -> dict[str, Any]:
    changed = copy.deepcopy(document)
    if keys[0] in OPTIONAL_TABLES and keys[0] not in changed:
        changed[keys[0]] = copy.deepcopy(OPTIONAL_TABLES[keys[0]])
    node: Any = changed
    for key in keys[:-1]:  # an optional table the reference leaves out is added
        node = node.setdefault(key, {}) if isinstance(key, str) else node[key]
    node[keys[-1]] = value
    return changed


def _out_of_range_cases() -> list[tuple[Field, str, float]]:
    """(field, "low"/"high", an SI value just beyond that bound) for every numeric field."""
    cases = []
    for field in FIELDS:
        if field.kind not in NUMERIC and field.items not in NUMERIC:
            continue
        if field.low is not None:
            step = 1 if "integer" in (field.kind, field.items) else max(abs(field.low), 1e-3) / 2
            cases.append((field, "low", field.low - step))
        if field.high is not None:
            step = 1 if "integer" in (field.kind, field.items) else max(abs(field.high), 1e-3) / 2
            cases.append((field, "high", field.high + step))
    return cases


def _written(field: Field, value: float) -> Any:
    """``value`` (SI) as a spec writes it."""
    if "integer" in (field.kind, field.items):
        return int(value)
    return f"{value!r} {field.unit}" if field.unit else value


OUT_OF_RANGE = _out_of_range_cases()


def test_the_schema_lists_exactly_the_keys_the_loader_accepts():
    accepted = {f"{table}.{key}" if table else key
                for table, keys in SPEC_KEYS.items() for key in keys}
    assert {field.key for field in FIELDS} == accepted
    assert len(FIELD_BY_KEY) == len(FIELDS)
    assert {field.key for field in FIELDS if field.kind in ("table", "tables")} == (
        set(SPEC_KEYS) - {""})
    assert {field.key for field in FIELDS if not field.required} == OPTIONAL_KEYS


def test_array_markers_sit_exactly_after_arrays_of_tables():
    tables = {field.path for field in FIELDS if field.kind == "table"}
    arrays = {f"{field.path}[]" for field in FIELDS if field.kind == "tables"}
    assert {field.parent for field in FIELDS} == {""} | tables | arrays

    def kinds(node: Any, path: str) -> None:
        for key, value in node.items():
            field_path = f"{path}.{key}" if path else key
            field = FIELD_BY_KEY[field_path.replace("[]", "")]
            assert field.path == field_path
            if isinstance(value, dict):
                assert field.kind == "table"
                kinds(value, field_path)
            elif isinstance(value, list) and isinstance(value[0], dict):
                assert field.kind == "tables"
                for entry in value:
                    kinds(entry, f"{field_path}[]")
            else:
                assert field.kind not in ("table", "tables"), field_path

    kinds(REFERENCE, "")


@pytest.mark.parametrize("field", FIELDS, ids=lambda field: field.path)
def test_every_field_is_described_and_its_example_is_valid(field):
    assert field.meaning.strip() and field.source.strip()
    assert (field.example == "") == (field.kind in ("table", "tables"))
    if field.kind == "quantity" or field.items == "quantity":
        assert re.match(QUANTITY_PATTERN, field.example), field.example
        assert field.contains(parse_quantity(field.example, field.unit, field.path))
    elif field.kind in ("number", "integer") or field.items in ("number", "integer"):
        assert not isinstance(field.example, str)
        assert field.low is None or field.example >= field.low
        assert field.high is None or field.example <= field.high
    if field.items is not None:
        assert field.kind == "array"
        assert field.min_items >= 1


def test_the_reference_spec_passes_also_as_written_by_these_tests(reference_spec):
    """The reference loads; rewritten by :func:`_toml` it gives the same spec, so a refusal
    below is the changed value's doing."""
    assert load_spec("reference") == reference_spec
    assert parse_spec(toml_text(REFERENCE), "unit.toml") == reference_spec


@pytest.mark.parametrize(("field", "side", "value"), OUT_OF_RANGE,
                         ids=[f"{case[0].path}-{case[1]}" for case in OUT_OF_RANGE])
def test_a_value_beyond_the_schema_range_is_refused_naming_its_toml_path(field, side, value):
    keys, toml_path, context = _located(field)
    document = WITH_LEAKAGE
    if field.kind == "array":  # change the second entry of the array
        keys, toml_path = [*keys, 1], f"{toml_path}[2]"
        if field.parent == "control_stage.valve_characteristic":  # not in the reference: add one
            document = _with(WITH_LEAKAGE, ["control_stage", "valve_characteristic"],
                             {"lift": [0.0, 0.5, 1.0], "flow": [0.0, 0.5, 1.0]})
    text = toml_text(_with(document, keys, _written(field, value)))
    with pytest.raises(SpecError) as error:
        parse_spec(text, "unit.toml")
    message = str(error.value)
    if field.key == "sliding_pressure.load_fraction":
        assert message.startswith("unit.toml: sliding_pressure.load_fraction must increase within "
                                  f"{field.low:g}…{field.high:g}")
    elif field.key == "metal.groups.stages":
        assert message.startswith(f"unit.toml: {toml_path.removesuffix('[2]')} = ")
        assert f"within {field.low:g}…{len(REFERENCE['stages'])}" in message
    else:
        assert message.startswith(f"unit.toml: {context}{toml_path} = ")
        if field.kind == "integer":
            high = field.high if field.high is not None else len(REFERENCE["stages"]) - 1
            assert message.endswith(f"expected an integer in [{field.low:g}, {high:g}]")
        else:
            assert f"outside the valid range {field.range_text()}" in message


def test_the_loader_takes_its_ranges_from_the_schema(monkeypatch):
    """One source: narrowing a range in the table makes the loader refuse the reference."""
    field = FIELD_BY_KEY["stages.flow_capacity"]
    monkeypatch.setitem(FIELD_BY_KEY, field.key, dataclasses.replace(field, high=0.06))
    with pytest.raises(SpecError, match=re.escape(
            "unit.toml: stage 3: stages[3].flow_capacity = '0.06286 m^2' is outside the valid "
            "range [1e-05, 0.06] m^2")):
        parse_spec(REFERENCE_TEXT, "unit.toml")
    valves = FIELD_BY_KEY["control_stage.valves.opening_order"]
    monkeypatch.setitem(FIELD_BY_KEY, valves.key, dataclasses.replace(valves, high=2))
    with pytest.raises(SpecError, match=re.escape(
            "control_stage.valves[4].opening_order = 3: expected an integer in [1, 2]")):
        parse_spec(REFERENCE_TEXT, "unit.toml")


def test_exclusive_bounds_are_honoured_and_shown():
    field = Field("x", "number", "m", "s", low=0.0, high=1.0, low_inclusive=False)
    assert not field.contains(0.0) and field.contains(1e-12) and field.contains(1.0)
    assert not field.contains(math.nan) and not field.contains(1.0 + 1e-12)
    assert field.range_text() == "(0, 1] (dimensionless)"
    assert dataclasses.replace(field, low=None).range_text() == "(−∞, 1] (dimensionless)"
    assert _value_schema(field, "number") == {"type": "number", "exclusiveMinimum": 0.0,
                                              "maximum": 1.0}


def test_ranges_are_shown_in_the_examples_unit():
    assert FIELD_BY_KEY["design.main_steam_pressure"].range_text(display=True) == "[1, 25] MPa"
    assert FIELD_BY_KEY["design.main_steam_temperature"].range_text(display=True) == (
        "[300, 650] degC")
    assert FIELD_BY_KEY["stages.nozzle_exit_angle"].range_text(display=True) == "[5, 40] deg"
    assert FIELD_BY_KEY["design.main_steam_pressure"].range_text() == "[1e+06, 2.5e+07] Pa"


EXAMPLE_UNITS = {field.display_unit: field.unit for field in FIELDS if field.display_unit}


@settings(max_examples=60, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False), st.sampled_from(sorted(EXAMPLE_UNITS)),
       st.sampled_from(["", " ", "  "]))
def test_the_quantity_pattern_accepts_what_the_loader_reads(value, unit, gap):
    """Editors must not flag a value the loader accepts: 'value unit' in every example unit."""
    text = f"{value!r}{gap}{unit}"
    parse_quantity(text, EXAMPLE_UNITS[unit], "x")
    assert re.match(QUANTITY_PATTERN, text)


@pytest.mark.parametrize("text", ["16.7", "MPa", "", "16.7 ", "1.2.3"])
def test_the_quantity_pattern_refuses_a_value_without_a_unit(text):
    assert not re.match(QUANTITY_PATTERN, text)


def test_docs_spec_md_is_generated_from_the_schema():
    """Regenerate with: python -m steamtwin.spec.schema --markdown > docs/spec.md"""
    markdown = render_markdown()
    assert (DOCS / "spec.md").read_text(encoding="utf-8") == markdown
    for field in FIELDS:
        assert markdown.count(f"| `{field.path}` |") == 1, field.path


def test_docs_spec_schema_json_is_generated_from_the_schema():
    """Regenerate with: python -m steamtwin.spec.schema --json-schema > docs/spec.schema.json"""
    assert (DOCS / "spec.schema.json").read_text(encoding="utf-8") == json_schema_text()
    assert json.loads(json_schema_text()) == json_schema()


def test_the_module_writes_either_document(capsys):
    main(["--markdown"])
    assert capsys.readouterr().out == render_markdown()
    main(["--json-schema"])
    assert json.loads(capsys.readouterr().out) == json_schema()
    with pytest.raises(SystemExit):
        main([])


def _validator() -> Any:
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.Draft202012Validator.check_schema(json_schema())
    return jsonschema.Draft202012Validator(json_schema())


def test_the_reference_validates_against_the_json_schema():
    assert list(_validator().iter_errors(REFERENCE)) == []


@pytest.mark.parametrize(("keys", "value"), [
    (["design", "hp_powr"], "177.3 MW"),
    (["design", "hp_power"], 177.3),
    (["design", "hp_power"], "177.3"),
    (["stages", 2, "blade_count"], 9.5),
    (["control_stage", "valves", 0, "open_at_design"], "yes"),
    (["sensors", 0], "vibration"),
    (["name"], " "),
], ids=["unknown-key", "no-unit", "no-unit-string", "float-count", "flag-string", "sensor",
        "blank-name"])
def test_the_json_schema_flags_what_the_loader_refuses(keys, value):
    document = _with(REFERENCE, keys, value)
    with pytest.raises(SpecError):
        parse_spec(toml_text(document), "unit.toml")
    assert list(_validator().iter_errors(document))


def test_the_json_schema_flags_a_missing_field_and_an_out_of_range_number():
    validator = _validator()
    missing = copy.deepcopy(REFERENCE)
    del missing["design"]["main_steam_flow"]
    assert list(validator.iter_errors(missing))
    for field, _, value in OUT_OF_RANGE:
        if field.kind in ("number", "integer") and field.high is not None:
            keys, _, _ = _located(field)
            assert list(validator.iter_errors(_with(REFERENCE, keys, _written(field, value))))


def test_the_error_quoted_in_the_rules_is_the_loaders():
    quoted = re.search(r"`(unit\.toml: stage 3: [^`]*?) \.\.\.`", render_markdown())
    assert quoted is not None
    text = REFERENCE_TEXT.replace('flow_capacity = "0.06286 m^2"', 'flow_capacity = "0 m^2"')
    with pytest.raises(SpecError) as error:
        parse_spec(text, "unit.toml")
    assert str(error.value).startswith(quoted.group(1))
