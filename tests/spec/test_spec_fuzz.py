"""Malformed turbine specs and parameter files: a clear error naming the file, never a crash.

The reference spec and a calibration's params.json are mutated — a key deleted, renamed to a
near miss, given a value of another type, garbage bytes inserted, the file truncated — and
loaded. Loading must raise :class:`SpecError` / :class:`ParameterError` (ValueError subclasses)
naming the file, or succeed only where the mutation kept the document valid: a deleted optional
key, or bytes that leave the same keys in place. Any other exception fails the test.
"""

from __future__ import annotations

import copy
import datetime
import json
import math
import re
import tomllib
from importlib import resources
from typing import Any

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from toml_documents import KeyPath, key_paths, toml_text

from steamtwin.model.parameters import (
    METADATA_KEYS,
    PARAMETER_BOUNDS,
    ModelParameters,
    ParameterError,
)
from steamtwin.spec import ControlStage, SpecError, load_spec, parse_spec
from steamtwin.spec.loader import OPTIONAL_KEYS, SPEC_KEYS

REFERENCE_TEXT = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
    encoding="utf-8")
REFERENCE = tomllib.loads(REFERENCE_TEXT)
SOURCE = "fuzz-unit.toml"
FUZZ = settings(max_examples=60, deadline=None)

def _table_paths(node: Any, prefix: KeyPath = ()) -> list[KeyPath]:
    """The path of every table under ``node`` (``()`` is the document)."""
    paths = [prefix] if isinstance(node, dict) else []
    children = node.items() if isinstance(node, dict) else (
        enumerate(node) if isinstance(node, list) else ())
    for key, value in children:
        paths += _table_paths(value, (*prefix, key))
    return paths


def _get(document: Any, path: KeyPath) -> Any:
    for part in path:
        document = document[part]
    return document


def _render(path: KeyPath) -> str:
    """A path as the loader writes it: ``stages[3].mean_diameter`` (positions from 1)."""
    text = ""
    for part in path:
        text += f"[{part + 1}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int | float):
        return "number"
    if isinstance(value, datetime.date):
        return "datetime"
    return type(value).__name__


REPLACEMENTS = ["text", 7, 2.5, True, [], [1, 2], {}, {"a": 1}, datetime.date(1979, 5, 27)]
SPEC_KEY_PATHS = key_paths(REFERENCE)


@st.composite
def near_misses(draw: st.DrawFn, key: str) -> str:
    """``key`` with one typing slip: letters swapped, dropped, doubled, replaced or added."""
    index = draw(st.integers(0, len(key) - 1))
    letter = draw(st.sampled_from("abcdefghijklmnopqrstuvwxyz_"))
    slip = draw(st.sampled_from(["swap", "drop", "double", "replace", "insert", "plural"]))
    return {
        "swap": key[:index] + key[index + 1:index + 2] + key[index] + key[index + 2:],
        "drop": key[:index] + key[index + 1:],
        "double": key[:index] + key[index] + key[index:],
        "replace": key[:index] + letter + key[index + 1:],
        "insert": key[:index] + letter + key[index:],
        "plural": key[:-1] if key.endswith("s") else key + "s",
    }[slip]


def _renamed(document: dict[str, Any], path: KeyPath, new_key: str) -> dict[str, Any]:
    mutated = copy.deepcopy(document)
    parent = _get(mutated, path[:-1])
    parent[new_key] = parent.pop(path[-1])
    return mutated


# -- the spec: deterministic sweeps ---------------------------------------------------------------


def test_reference_uses_every_known_key_and_no_other():
    """The shipped spec loads, and the schema is exactly the keys it uses (none unread)."""
    used: dict[str, set[str]] = {}
    for path in _table_paths(REFERENCE):
        schema = ".".join(part for part in path if isinstance(part, str))
        used.setdefault(schema, set()).update(_get(REFERENCE, path))
    # the optional [part_load] table is the design fit's: the reference unit keeps its defaults
    expected = {schema: set(keys) for schema, keys in SPEC_KEYS.items()
                if schema not in ("part_load", "leakages")}
    expected[""] -= {"part_load", "leakages"}  # the reference unit states no leakages
    expected["stages"] -= {"tip_leakage"}
    # the reference unit states its valve management (overlap and the valves' flow
    # characteristic), reaches rated load at a valve point, and the model sizes its nozzle throats
    expected["design"] -= {"valve_outlet_pressure"}
    expected["control_stage.valves"] -= {"throat_area"}
    # the reference unit's boiler holds the design main-steam temperature at every load
    del expected["temperature_schedule"]
    expected[""] -= {"temperature_schedule"}
    # the reference unit gives its metal as masses and areas and keeps the default thermocouple
    expected["metal"] -= {"casing_thermocouple_depth"}
    expected["metal.groups"] -= {"axial_length", "rotor_radius", "rotor_bore_radius",
                                 "casing_inner_radius", "casing_wall_thickness"}
    # the reference rotor is a solid 30CrMoNiV5-11 forging at the design speed: the defaults
    expected["rotor"] -= {"bore_radius", "material", "rotational_speed"}
    assert used == expected
    assert parse_spec(toml_text(REFERENCE), SOURCE) == load_spec("reference")


def test_every_key_but_the_optional_ones_is_required():
    for path in SPEC_KEY_PATHS:
        mutated = copy.deepcopy(REFERENCE)
        del _get(mutated, path[:-1])[path[-1]]
        if len(path) == 1 and path[0] in OPTIONAL_KEYS:
            assert getattr(parse_spec(toml_text(mutated), SOURCE), path[0]) in ((), None)
            continue
        if path[0] == "control_stage" and len(path) == 2 and ".".join(path) in OPTIONAL_KEYS:
            # the reference's valve management: without it, the documented default
            default = getattr(ControlStage, path[-1])
            assert getattr(parse_spec(toml_text(mutated), SOURCE).control_stage,
                           path[-1]) == default
            continue
        with pytest.raises(SpecError, match=r"fuzz-unit\.toml: ") as error:
            parse_spec(toml_text(mutated), SOURCE)
        assert f"{_render(path)} is missing" in str(error.value), path


def test_an_unknown_key_in_any_table_is_refused():
    for path in _table_paths(REFERENCE):
        mutated = copy.deepcopy(REFERENCE)
        _get(mutated, path)["unexpected"] = 1
        with pytest.raises(SpecError, match=r"fuzz-unit\.toml: ") as error:
            parse_spec(toml_text(mutated), SOURCE)
        field = _render((*path, "unexpected"))
        assert f"{field} is not a turbine spec field" in str(error.value), path


# -- the spec: hypothesis -------------------------------------------------------------------------


@FUZZ
@given(st.data())
def test_spec_with_a_key_renamed_to_a_near_miss_is_refused(data):
    path = data.draw(st.sampled_from(SPEC_KEY_PATHS))
    new_key = data.draw(near_misses(path[-1]))
    assume(new_key and new_key not in _get(REFERENCE, path[:-1]))
    with pytest.raises(SpecError, match=r"fuzz-unit\.toml: ") as error:
        parse_spec(toml_text(_renamed(REFERENCE, path, new_key)), SOURCE)
    assert f"{_render((*path[:-1], new_key))} is not a turbine spec field" in str(error.value)


@FUZZ
@given(st.sampled_from(SPEC_KEY_PATHS), st.sampled_from(REPLACEMENTS))
def test_spec_with_a_value_of_another_type_is_refused(path, replacement):
    assume(_kind(replacement) != _kind(_get(REFERENCE, path)))
    mutated = copy.deepcopy(REFERENCE)
    _get(mutated, path[:-1])[path[-1]] = replacement
    with pytest.raises(SpecError, match=r"fuzz-unit\.toml: "):
        parse_spec(toml_text(mutated), SOURCE)


def _load_spec_bytes(folder, content: bytes) -> None:
    """Load ``content`` as a spec file: a SpecError naming it, or the reference's keys intact."""
    path = folder / "mutated.toml"
    path.write_bytes(content)
    try:
        load_spec(path)
    except SpecError as error:
        assert str(error).startswith(f"{path}: "), error
        return
    kept = tomllib.loads(content.decode("utf-8-sig"))
    assert key_paths(kept) == SPEC_KEY_PATHS


REFERENCE_BYTES = REFERENCE_TEXT.encode("utf-8")


@settings(max_examples=100, deadline=None)
@given(st.integers(0, len(REFERENCE_BYTES)), st.binary(min_size=1, max_size=8))
def test_spec_with_garbage_bytes_is_refused_or_intact(tmp_path_factory, position, garbage):
    content = REFERENCE_BYTES[:position] + garbage + REFERENCE_BYTES[position:]
    _load_spec_bytes(tmp_path_factory.mktemp("spec"), content)


@FUZZ
@given(st.integers(0, len(REFERENCE_BYTES) - 1))
def test_truncated_spec_is_refused_or_intact(tmp_path_factory, length):
    _load_spec_bytes(tmp_path_factory.mktemp("spec"), REFERENCE_BYTES[:length])


# Positions inside the quoted values ("16.7 MPa", "W/(m^2*K)", names): garbage there reaches
# the unit parser instead of failing as TOML.
QUOTED_POSITIONS = [match.start(1) + offset
                    for match in re.finditer(r'"([^"\n]*)"', REFERENCE_TEXT)
                    for offset in range(len(match.group(1)) + 1)]


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(QUOTED_POSITIONS),
       st.text(st.characters(codec="utf-8", exclude_categories=("Cc", "Cs"),
                             exclude_characters='"\\'), min_size=1, max_size=4))
def test_spec_with_garbage_in_a_quoted_value_is_refused_or_read(position, garbage):
    """Whatever the text in a quoted value, the loader answers with a SpecError or a spec."""
    try:
        parse_spec(REFERENCE_TEXT[:position] + garbage + REFERENCE_TEXT[position:], SOURCE)
    except SpecError as error:
        assert str(error).startswith(f"{SOURCE}: "), error


# -- parameter files ------------------------------------------------------------------------------

CALIBRATED = {
    "parameters": {"flow_coefficient": 0.98, "friction_coefficient": 1.2,
                   "heat_transfer_coefficient": 1.4},
    "bounds": {name: list(bounds) for name, bounds in PARAMETER_BOUNDS.items()},
    "calibration": {"rmse_K": 1.5, "sensors": ["hp_exhaust_temperature"], "evaluations": 12,
                    "mode": "ga", "population": 6, "generations": 2, "seed": 0},
}
HAND_WRITTEN = dict(CALIBRATED["parameters"])
EXPECTED = ModelParameters(0.98, 1.2, 1.4)
PARAMETER_DOCUMENTS = {"calibrated": CALIBRATED, "hand-written": HAND_WRITTEN}


def _informational(path: KeyPath) -> bool:
    """A key inside the metadata, whose content the reader does not use."""
    return len(path) > 1 and path[0] in METADATA_KEYS


def _load_parameters(folder, content: bytes) -> ModelParameters | None:
    """from_json of ``content``; None after a ParameterError that names the file."""
    path = folder / "params.json"
    path.write_bytes(content)
    try:
        return ModelParameters.from_json(path)
    except ParameterError as error:
        assert str(error).startswith(f"{path}: "), error
        return None


@FUZZ
@given(st.data())
def test_parameter_file_with_a_key_deleted(tmp_path_factory, data):
    document = data.draw(st.sampled_from(list(PARAMETER_DOCUMENTS.values())))
    path = data.draw(st.sampled_from(key_paths(document)))
    mutated = copy.deepcopy(document)
    del _get(mutated, path[:-1])[path[-1]]
    loaded = _load_parameters(tmp_path_factory.mktemp("params"), json.dumps(mutated).encode())
    assert loaded == (EXPECTED if path[0] in METADATA_KEYS else None), path


@FUZZ
@given(st.data())
def test_parameter_file_with_a_key_renamed_to_a_near_miss(tmp_path_factory, data):
    document = data.draw(st.sampled_from(list(PARAMETER_DOCUMENTS.values())))
    path = data.draw(st.sampled_from(key_paths(document)))
    new_key = data.draw(near_misses(path[-1]))
    assume(new_key and new_key not in _get(document, path[:-1]))
    content = json.dumps(_renamed(document, path, new_key)).encode()
    loaded = _load_parameters(tmp_path_factory.mktemp("params"), content)
    assert loaded == (EXPECTED if _informational(path) else None), (path, new_key)


@FUZZ
@given(st.data(), st.sampled_from([*REPLACEMENTS[:-1], float("nan"), float("inf"), None]))
def test_parameter_file_with_a_value_of_another_type(tmp_path_factory, data, replacement):
    document = data.draw(st.sampled_from(list(PARAMETER_DOCUMENTS.values())))
    path = data.draw(st.sampled_from(key_paths(document)))
    original = _get(document, path)
    non_finite = isinstance(replacement, float) and not math.isfinite(replacement)
    assume(_kind(replacement) != _kind(original) or non_finite)
    mutated = copy.deepcopy(document)
    _get(mutated, path[:-1])[path[-1]] = replacement
    loaded = _load_parameters(tmp_path_factory.mktemp("params"), json.dumps(mutated).encode())
    assert loaded == (EXPECTED if _informational(path) else None), (path, replacement)


def _refused_or_intact(folder, content: bytes, document: dict[str, Any]) -> None:
    """A ParameterError naming the file, or the same keys with the file's own values."""
    loaded = _load_parameters(folder, content)
    if loaded is not None:
        kept = json.loads(content.decode("utf-8-sig"))
        schema_keys = [path for path in key_paths(kept) if not _informational(path)]
        assert schema_keys == [path for path in key_paths(document) if not _informational(path)]
        assert loaded == ModelParameters(**kept.get("parameters", kept))


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(list(PARAMETER_DOCUMENTS.values())), st.data(),
       st.binary(min_size=1, max_size=8))
def test_parameter_file_with_garbage_bytes(tmp_path_factory, document, data, garbage):
    text = json.dumps(document, indent=2).encode()
    position = data.draw(st.integers(0, len(text)))
    _refused_or_intact(tmp_path_factory.mktemp("params"),
                       text[:position] + garbage + text[position:], document)


@FUZZ
@given(st.sampled_from(list(PARAMETER_DOCUMENTS.values())), st.data())
def test_truncated_parameter_file(tmp_path_factory, document, data):
    text = json.dumps(document, indent=2).encode()
    length = data.draw(st.integers(0, len(text) - 1))
    _refused_or_intact(tmp_path_factory.mktemp("params"), text[:length], document)
