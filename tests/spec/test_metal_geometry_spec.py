"""Metal groups given as drawn geometry: the loader's either/or rule, cross-checks and the casing
thermocouple depth, each refusal naming its TOML path."""

from __future__ import annotations

import copy
import math
import re
import tomllib
from importlib import resources
from typing import Any

import pytest
from toml_documents import toml_text

from steamtwin.spec import SpecError, parse_spec

REFERENCE = tomllib.loads((resources.files("steamtwin.spec") / "data" / "reference.toml")
                          .read_text(encoding="utf-8"))
MASS_AND_AREA = ("casing_mass", "casing_area", "rotor_mass", "rotor_area")
#: The second group (HP stages 1-4, mean radii 0.47-0.48 m) drawn.
DRAWN = {"axial_length": "0.6 m", "rotor_radius": "0.40 m", "rotor_bore_radius": "50 mm",
         "casing_inner_radius": "0.58 m", "casing_wall_thickness": "0.2 m"}


def _spec(group: dict[str, Any] | None = None, **metal: Any) -> str:
    """The reference's TOML with metal.groups[2] replaced by ``group`` and [metal] keys set."""
    document = copy.deepcopy(REFERENCE)
    if group is not None:
        document["metal"]["groups"][1] = {"name": "HP stages 1-4", "stages": [1, 2, 3, 4],
                                          "insulation_conductance": "0.6 W/(m^2*K)", **group}
    document["metal"].update(metal)
    return toml_text(document)


def _refused(text: str) -> str:
    with pytest.raises(SpecError) as error:
        parse_spec(text, "unit.toml")
    return str(error.value)


def test_a_drawn_group_gets_the_cylinders_masses_and_areas():
    spec = parse_spec(_spec(DRAWN), "unit.toml")
    group = spec.metal_groups[1]
    assert group.geometry is not None and group.geometry.rotor_bore_radius == 0.05
    assert group.casing_area == pytest.approx(2.0 * math.pi * 0.58 * 0.6, rel=1e-14)
    assert group.casing_mass == pytest.approx(7800.0 * math.pi * (0.78**2 - 0.58**2) * 0.6,
                                              rel=1e-14)
    assert group.rotor_area == pytest.approx(2.0 * math.pi * 0.40 * 0.6, rel=1e-14)
    assert group.rotor_mass == pytest.approx(7800.0 * math.pi * (0.40**2 - 0.05**2) * 0.6,
                                             rel=1e-14)
    assert spec.metal_groups[0].geometry is None  # the others keep their masses and areas
    solid = parse_spec(_spec({k: v for k, v in DRAWN.items() if k != "rotor_bore_radius"}))
    assert solid.metal_groups[1].geometry.rotor_bore_radius == 0.0


def test_mixing_masses_with_geometry_is_refused_naming_both():
    message = _refused(_spec({**DRAWN, "rotor_mass": "4680 kg"}))
    assert message.startswith("unit.toml: metal.groups[2] mixes masses/areas (rotor_mass) with "
                              "geometry (axial_length, rotor_radius, casing_inner_radius, "
                              "casing_wall_thickness, rotor_bore_radius)")


def test_a_partial_geometry_is_refused_naming_the_missing_fields():
    partial = {k: v for k, v in DRAWN.items() if k not in ("axial_length",
                                                           "casing_wall_thickness")}
    message = _refused(_spec(partial))
    assert message.startswith("unit.toml: metal.groups[2] gives the geometry fields "
                              "rotor_radius, casing_inner_radius, rotor_bore_radius but not "
                              "axial_length, casing_wall_thickness")
    assert "either casing_mass, casing_area, rotor_mass, rotor_area or" in message
    # a bore alone is a partial geometry too
    assert "but not axial_length, rotor_radius" in _refused(
        _spec({"rotor_bore_radius": "50 mm"}))


@pytest.mark.parametrize("key", MASS_AND_AREA)
def test_a_partial_set_of_masses_and_areas_names_the_missing_one(key):
    group = {k: v for k, v in REFERENCE["metal"]["groups"][1].items() if k != key}
    assert _refused(_spec(group)).startswith(f"unit.toml: metal.groups[2].{key} is missing")


@pytest.mark.parametrize(("change", "message"), [
    ({"rotor_bore_radius": "0.395 m"}, "metal.groups[2].rotor_bore_radius = 0.395 m leaves less "
     "than 0.01 m of metal under metal.groups[2].rotor_radius = 0.4 m"),
    ({"casing_inner_radius": "0.40 m"}, "metal.groups[2].casing_inner_radius = 0.4 m must "
     "exceed metal.groups[2].rotor_radius = 0.4 m"),
    ({"rotor_radius": "0.48 m", "casing_inner_radius": "0.6 m"},
     "metal.groups[2].rotor_radius = 0.48 m ('HP stages 1-4') must lie below the group's "
     "smallest blade mean radius 0.4717 m"),
    ({"casing_inner_radius": "0.45 m"}, "metal.groups[2].casing_inner_radius = 0.45 m ('HP "
     "stages 1-4') must lie above the group's largest blade mean radius 0.47995 m"),
])
def test_implausible_geometry_is_refused(change, message):
    assert message in _refused(_spec({**DRAWN, **change}))


def test_the_thermocouple_depth_is_read_and_checked_against_the_sensor_wall():
    assert parse_spec(_spec(casing_thermocouple_depth="30 mm")).casing_thermocouple_depth == (
        pytest.approx(0.03))
    assert parse_spec(_spec()).casing_thermocouple_depth == 0.014  # the default
    # the reference's HP stages 9-12 wall is 5990 kg / (7800 kg/m³ · 4.8 m²) = 0.16 m deep
    message = _refused(_spec(casing_thermocouple_depth="0.19 m", casing_sensor_group="HP "
                             "stages 9-12"))
    assert message.startswith("unit.toml: metal.casing_thermocouple_depth = 0.19 m lies "
                              "beyond the inner-casing wall of metal.groups[4] ('HP stages "
                              "9-12'), 0.159989 m deep")
    drawn = _spec({**DRAWN, "casing_wall_thickness": "0.05 m"}, casing_sensor_group="HP stages "
                  "1-4", casing_thermocouple_depth="60 mm")
    assert re.search(r"0\.06 m lies beyond .* 0\.05 m deep", _refused(drawn))
    assert "outside the valid range [0, 0.2] m" in _refused(
        _spec(casing_thermocouple_depth="-1 mm"))
