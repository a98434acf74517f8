"""Derive writes the metal as the drawn geometry it assumes; the kit's optional rotor bore and
casing wall thickness ([machine]) reach every metal group."""

from __future__ import annotations

import math
from importlib.resources import files

import pytest

from steamtwin.spec import (
    DeriveError,
    HeatBalanceError,
    derive_spec,
    parse_heat_balance,
    parse_spec,
)
from steamtwin.spec.derive import BORE_CLEARANCE, CASING_ALLOWABLE_STRESS

KIT = files("steamtwin.spec").joinpath("data/example-600mw-heat-balance.toml").read_text(
    encoding="utf-8")
RATED = 'rated_load = "600 MW"'


def _derived(machine_lines: str = ""):
    text = KIT.replace(RATED, f"{RATED}\n{machine_lines}", 1)
    return parse_spec(derive_spec(parse_heat_balance(text, "kit.toml")).toml, "derived.toml")


@pytest.fixture(scope="module")
def plain():
    return _derived()


def test_without_drawings_the_casing_is_the_hoop_thickness_beyond_the_tips(plain):
    group = plain.metal_groups[0]  # the control stage at its design pressure
    blading = plain.control_stage.blading
    tip = (blading.mean_diameter + blading.blade_height) / 2.0
    assert group.geometry.casing_inner_radius == pytest.approx(tip + BORE_CLEARANCE, abs=1e-4)
    assert group.geometry.casing_wall_thickness == pytest.approx(
        plain.design.control_stage_pressure * group.geometry.casing_inner_radius
        / CASING_ALLOWABLE_STRESS, rel=2e-3)
    assert plain.casing_thermocouple_depth == pytest.approx(0.014)
    # the cylinders' masses: more casing than the plane wall of the same bore area
    assert group.casing_mass > 7800.0 * group.casing_area * group.geometry.casing_wall_thickness


def test_the_kits_bore_and_wall_reach_every_group(plain):
    spec = _derived('rotor_bore_diameter = "120 mm"\ncasing_wall_thickness = "0.16 m"')
    for group, solid in zip(spec.metal_groups, plain.metal_groups, strict=True):
        assert group.geometry.rotor_bore_radius == pytest.approx(0.06)
        assert group.geometry.casing_wall_thickness == pytest.approx(0.16)
        assert group.geometry.rotor_radius == solid.geometry.rotor_radius
        assert solid.rotor_mass - group.rotor_mass == pytest.approx(
            7800.0 * math.pi * 0.06**2 * group.geometry.axial_length, rel=1e-9)


def test_a_bore_through_the_blading_root_is_refused():
    with pytest.raises(DeriveError, match=r"kit\.toml: machine\.rotor_bore_diameter = 0\.95 m "
                                          r"leaves less than 0\.01 m of metal"):
        _derived('rotor_bore_diameter = "0.95 m"')


@pytest.mark.parametrize(("line", "message"), [
    ('rotor_bore_diameter = "3 m"', r"machine: rotor_bore_diameter = '3 m' is outside the "
     r"plausible range \[0 m, 2 m\]"),
    ('casing_wall_thickness = "5 mm"', r"machine: casing_wall_thickness = '5 mm' is outside "
     r"the plausible range \[0\.01 m, 1 m\]"),
])
def test_the_machine_fields_are_range_checked(line, message):
    with pytest.raises(HeatBalanceError, match=message):
        _derived(line)
