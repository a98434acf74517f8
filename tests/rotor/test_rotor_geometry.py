"""The [rotor] spec section, the drawn section's checks and its graded (r, z) mesh."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.errors import RotorAreaError, SteamtwinError
from steamtwin.rotor.conduction import RotorConduction
from steamtwin.rotor.geometry import RotorGeometry, critical_nodes, rotor_geometry, rotor_mesh
from steamtwin.rotor.material import ConstantMaterial
from steamtwin.spec import load_spec, parse_spec
from steamtwin.spec.loader import SpecError

STEEL = ConstantMaterial("test", density_=7850.0, specific_heat_=460.0, conductivity_=40.0,
                         youngs_modulus_=2.1e11, poisson_ratio_=0.3, expansion_coefficient=1.2e-5)


@pytest.fixture(scope="module")
def reference():
    return rotor_geometry(load_spec("reference"))


@pytest.fixture(scope="module")
def mesh(reference):
    return rotor_mesh(reference, 0.03)


def test_reference_rotor_loads_with_its_defaults(reference):
    section = reference.section
    assert section.material == "30CrMoNiV5-11"
    assert section.rotational_speed == pytest.approx(2 * math.pi * 50.0)
    assert reference.solid and reference.groups == ("control stage", "HP stages 1-4")
    assert reference.groove_root == pytest.approx((0.36 - 0.025, 0.10))


def test_mesh_names_its_boundaries_and_has_nodes_at_the_critical_points(reference, mesh):
    assert set(mesh.boundaries) == {"ends", "axis", "steam:control stage", "steam:HP stages 1-4"}
    nodes = critical_nodes(mesh, reference)
    np.testing.assert_allclose(mesh.p[:, nodes["groove_root"]], reference.groove_root)
    np.testing.assert_allclose(mesh.p[:, nodes["bore"]], (0.0, 0.10))
    assert 500 < mesh.p.shape[1] < 3000  # small enough for a 24-h run at 1-s steps


def test_wetted_areas_are_the_drawn_surfaces_of_revolution(reference, mesh):
    """Σb = ∫2πr ds: a cylinder for the pressure stages; for the control stage the cylinder less
    the groove's mouth, the groove's two flanks (annuli) and semicircular root (Pappus: arc
    length times 2π times its centroid's radius, r_c − 2ρ/π), and the radius step's face."""
    system = RotorConduction(mesh, STEEL).system(600.0)
    areas = dict(zip(system.groups, (load.sum() for load in system.robin_load), strict=True))
    assert areas["HP stages 1-4"] == pytest.approx(2 * math.pi * 0.43 * 0.35, rel=1e-12)
    radius, rho, depth = 0.36, 0.008, 0.025
    centre = radius - depth + rho
    expected = (2 * math.pi * radius * (0.25 - 2 * rho) + 2 * math.pi * (radius**2 - centre**2)
                + 2 * math.pi * math.pi * rho * (centre - 2 * rho / math.pi)
                + math.pi * (0.43**2 - radius**2))
    assert areas["control stage"] == pytest.approx(expected, rel=1e-4)


def test_a_shallow_groove_is_a_circular_segment_and_a_bored_rotor_has_a_bore(reference):
    section = dataclasses.replace(reference.section, groove_depth=0.004, bore_radius=0.05)
    geometry = RotorGeometry(section)
    mesh = rotor_mesh(geometry, 0.04)
    assert "bore" in mesh.boundaries and "axis" not in mesh.boundaries
    assert section.groove_half_width == pytest.approx(math.sqrt(0.008**2 - 0.004**2))
    np.testing.assert_allclose(mesh.p[:, critical_nodes(mesh, geometry)["bore"]], (0.05, 0.10))


@pytest.mark.parametrize(("change", "message"), [
    ({"groove_depth": 0.36}, "rotor.groove_depth = 0.36 m leaves less than 0.01 m"),
    ({"bore_radius": 0.36}, "rotor.bore_radius = 0.36 m leaves less than"),
    ({"groove_position": 0.245}, "the groove .* must lie inside one constant-radius part"),
    ({"stage_start": 0.7}, "rotor.stage_start = 0.7 m must lie in"),
])
def test_an_undrawable_section_is_refused_naming_the_field(reference, change, message):
    with pytest.raises(RotorAreaError, match=message):
        RotorGeometry(dataclasses.replace(reference.section, **change))


REFERENCE_TEXT = (load_spec.__globals__["resources"].files("steamtwin.spec") / "data"
                  / "reference.toml").read_text(encoding="utf-8")


@pytest.mark.parametrize(("old", "new", "message"), [
    ('groove_depth = "25 mm"', 'groove_depth = "-25 mm"',
     r"rotor.groove_depth = '-25 mm' is outside the valid range \[0.001, 0.5\] m"),
    ('groove_depth = "25 mm"', 'groove_depth = "0.4 m"', "rotor.groove_depth = 0.4 m leaves"),
    ('group = "HP stages 1-4"', 'group = "HP stages 1-3"', r"rotor.steam\[2\].group = 'HP "
     r"stages 1-3' names no metal group"),
    ('end = "0.60 m"', 'end = "0.70 m"', r"rotor.steam\[2\] \('HP stages 1-4'\): start = "),
])
def test_a_bad_rotor_section_in_a_spec_is_refused_naming_the_field(old, new, message):
    assert old in REFERENCE_TEXT
    with pytest.raises(SpecError, match=message):
        parse_spec(REFERENCE_TEXT.replace(old, new, 1), "unit.toml")


def test_a_spec_without_rotor_loads_and_says_what_to_add():
    start = REFERENCE_TEXT.index("[rotor]")
    text = REFERENCE_TEXT[:start] + REFERENCE_TEXT[REFERENCE_TEXT.index("[sliding_pressure]"):]
    spec = parse_spec(text, "unit.toml")
    assert spec.rotor is None
    with pytest.raises(SteamtwinError, match=r"no \[rotor\] section: add one .*groove_radius"):
        rotor_geometry(spec)


def notch_volume(radius, rho, depth):
    """Volume (m³) the groove removes: its cross-section revolved (Pappus: area × 2π × the
    centroid's radius). A circular segment of height d ≤ ρ (central angle θ, centroid
    4ρ·sin³(θ/2)/(3(θ − sin θ)) from the circle's centre), else a rectangle down to the root
    circle's centre plus a semicircle (centroid 4ρ/(3π) below it)."""
    centre = radius - depth + rho
    if depth <= rho:
        theta = 2.0 * math.acos((rho - depth) / rho)
        area = 0.5 * rho**2 * (theta - math.sin(theta))
        centroid = centre - 4.0 * rho * math.sin(theta / 2) ** 3 / (3 * (theta - math.sin(theta)))
        return 2 * math.pi * area * centroid
    rectangle = 2 * rho * (radius - centre) * 2 * math.pi * (radius + centre) / 2
    semicircle = math.pi * rho**2 / 2 * 2 * math.pi * (centre - 4 * rho / (3 * math.pi))
    return rectangle + semicircle


@settings(max_examples=10, deadline=None)
@given(cs_radius=st.floats(0.2, 0.5), stage_radius=st.floats(0.2, 0.5),
       bore=st.sampled_from([0.0, 0.04, 0.08]), rho=st.floats(0.004, 0.02),
       depth_ratio=st.floats(0.2, 3.0), position=st.floats(0.05, 0.2),
       in_stages=st.booleans())
def test_any_drawable_section_meshes_to_its_volume_of_revolution(
        reference, cs_radius, stage_radius, bore, rho, depth_ratio, position, in_stages):
    """1ᵀ·M·1/(ρc) = ∫2πr dA, the volume of revolution: the outline (step, groove of either
    shape, bore) is drawn where the section says. Straight edges are exact; the groove's arcs
    are chords of at most ~1.5·h, each within its sagitta c²/(8ρ) of the arc, so the mesh holds
    more metal than the drawing by at most 2πR·(arc length)·(1.5h)²/(8ρ)."""
    section = dataclasses.replace(
        reference.section, control_stage_radius=cs_radius, stage_radius=stage_radius,
        bore_radius=bore, groove_radius=rho, groove_depth=depth_ratio * rho,
        groove_position=position + (0.25 if in_stages else 0.0))
    if section.problems(0.01):
        with pytest.raises(RotorAreaError):
            RotorGeometry(section)
        return
    geometry = RotorGeometry(section)
    size = rho / 3.0
    mesh = rotor_mesh(geometry, 0.05, size)
    volume = RotorConduction(mesh, STEEL).system(600.0).mass.sum() / (7850.0 * 460.0)
    radius, depth = section.outer_radius(section.groove_position), section.groove_depth
    expected = (math.pi * cs_radius**2 * 0.25 + math.pi * stage_radius**2 * 0.35
                - math.pi * bore**2 * 0.6 - notch_volume(radius, rho, depth))
    arc = (2.0 * rho * math.acos((rho - depth) / rho) if depth <= rho else math.pi * rho)
    assert 0.0 <= volume - expected < 2 * math.pi * radius * arc * (1.5 * size) ** 2 / (8 * rho)
    assert np.allclose(mesh.p[:, critical_nodes(mesh, geometry)["groove_root"]],
                       geometry.groove_root)
