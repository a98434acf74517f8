"""The spec's content hash: stable over formatting and re-loading, sensitive to every value."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from importlib import resources

from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.spec import load_spec, parse_spec
from steamtwin.spec.fingerprint import (
    builtin_spec_text,
    canonical_spec_json,
    load_spec_and_text,
    spec_hash,
)

REFERENCE_TEXT = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
    encoding="utf-8")
REFERENCE_HASH = spec_hash(load_spec("reference"))


def _reformatted(text: str) -> str:
    """The same spec written otherwise: no comments, other spacing, MPa as kPa, degC as K."""
    lines = []
    for line in text.splitlines():
        stripped = re.sub(r"\s+#.*$", "", line) if not line.lstrip().startswith("#") else ""
        stripped = re.sub(r"^(\w+) = ", r"\1   =   ", stripped)
        lines.append(stripped)
    body = "\n\n".join(lines)
    body = body.replace('"16.7 MPa"', '"16700 kPa"').replace('"538 degC"', '"811.15 K"')
    return body


def test_hash_is_stable_over_reloading_and_formatting(tmp_path):
    assert spec_hash(load_spec("reference")) == REFERENCE_HASH
    assert len(REFERENCE_HASH) == 64 and int(REFERENCE_HASH, 16) >= 0
    other = _reformatted(REFERENCE_TEXT)
    assert other != REFERENCE_TEXT and "#" not in other and "16700 kPa" in other
    reparsed = parse_spec(other, "reformatted")
    assert reparsed == load_spec("reference")
    assert spec_hash(reparsed) == REFERENCE_HASH
    path = tmp_path / "copy.toml"
    path.write_text(other, encoding="utf-8")
    spec, text = load_spec_and_text(path)
    assert text == other and spec_hash(spec) == REFERENCE_HASH
    assert builtin_spec_text(spec) == REFERENCE_TEXT


def test_canonical_form_is_sorted_json_with_exact_numbers():
    spec = load_spec("reference")
    document = json.loads(canonical_spec_json(spec))
    assert document["canonical_form"] == 1
    design = document["spec"]["design"]
    assert float(design["main_steam_pressure"]) == spec.design.main_steam_pressure
    assert design["main_steam_pressure"] == repr(spec.design.main_steam_pressure)
    assert canonical_spec_json(spec) == json.dumps(document, sort_keys=True,
                                                   separators=(",", ":"))
    # fields at their default are left out: a new optional field keeps old hashes
    assert all("tip_leakage" not in stage for stage in document["spec"]["stages"])
    assert spec_hash(_replace(spec, "stages", tuple(
        dataclasses.replace(stage, tip_leakage=0.0) for stage in spec.stages))) == REFERENCE_HASH


def _replace(spec, path: str, value):
    head, _, rest = path.partition(".")
    if not rest:
        return dataclasses.replace(spec, **{head: value})
    return dataclasses.replace(spec, **{head: _replace(getattr(spec, head), rest, value)})


def _get(spec, path: str):
    for part in path.split("."):
        spec = getattr(spec, part)
    return spec


FIELDS = ("design.main_steam_pressure", "design.hp_exhaust_temperature", "ambient_temperature",
          "control_stage.valve_overlap", "design.valve_pressure_drop")


@settings(max_examples=60, deadline=None)
@given(field=st.sampled_from(FIELDS),
       factor=st.floats(min_value=0.5, max_value=1.5, allow_nan=False))
def test_hash_changes_with_any_value(field, factor):
    spec = load_spec("reference")
    original = _get(spec, field)
    value = original * factor if original else factor * 0.1
    changed = _replace(spec, field, value)
    assert (spec_hash(changed) == REFERENCE_HASH) == (value == original)


@settings(max_examples=20, deadline=None)
@given(name=st.text(min_size=1, max_size=20))
def test_hash_changes_with_the_name(name):
    spec = load_spec("reference")
    assert (spec_hash(dataclasses.replace(spec, name=name)) == REFERENCE_HASH) == (
        name == spec.name)


def test_a_one_ulp_change_is_seen():
    spec = load_spec("reference")
    nudged = _replace(spec, "design.main_steam_pressure",
                      math.nextafter(spec.design.main_steam_pressure, math.inf))
    assert spec_hash(nudged) != REFERENCE_HASH
