"""Pritchard sections and stacked blades against their defining conditions."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.geometry.pritchard import (
    SEGMENTS,
    GeometryError,
    PritchardParameters,
    pritchard_profile,
)
from steamtwin.geometry.profile import make_blade, row_design
from steamtwin.geometry.row_sizing import HP_ROWS
from steamtwin.geometry.volume_mesh import REGIONS

REFERENCE = PritchardParameters(
    radius=0.5, axial_chord=0.040, tangential_chord=0.008, unguided_turning=math.radians(7.0),
    inlet_angle=math.radians(40.0), inlet_half_wedge=math.radians(12.0),
    leading_edge_radius=0.0024, outlet_angle=math.radians(-65.0),
    trailing_edge_radius=0.0006, blade_count=90, throat=2 * math.pi * 0.5 / 90 * math.cos(
        math.radians(65.0)))


def _direction(points: np.ndarray, at_start: bool) -> float:
    d = points[1] - points[0] if at_start else points[-1] - points[-2]
    return math.atan2(d[1], d[0])


def test_segments_join_with_continuous_position_and_tangent() -> None:
    profile = pritchard_profile(REFERENCE)
    segments = [profile.segment(i, 20001) for i in range(len(SEGMENTS))]
    for k in range(len(segments)):
        a, b = segments[k], segments[(k + 1) % len(segments)]
        assert np.linalg.norm(a[-1] - b[0]) < 1e-12
        turn = (_direction(b, True) - _direction(a, False) + math.pi) % (2 * math.pi) - math.pi
        assert abs(turn) < 2e-3  # tangent continuity (G1), within the sampling step


def test_throat_is_distance_from_neighbour_trailing_edge() -> None:
    profile = pritchard_profile(REFERENCE)
    p = REFERENCE
    suction = np.concatenate([profile.segment(0, 20001), profile.segment(1, 20001)])
    neighbour_te = profile.te_centre + np.array([0.0, p.pitch])
    distance = np.linalg.norm(suction - neighbour_te, axis=1).min() - p.trailing_edge_radius
    assert distance == pytest.approx(p.throat, abs=2e-7)


def test_leading_and_trailing_edges_sit_at_the_chord_ends() -> None:
    profile = pritchard_profile(REFERENCE)
    pts, _ = profile.dense
    assert pts[:, 0].min() == pytest.approx(0.0, abs=1e-8)  # 5 µm polyline sag
    assert pts[:, 0].max() == pytest.approx(REFERENCE.axial_chord, abs=1e-8)
    # key-point blade angles are the inlet/outlet angle ± the half-wedge angles
    assert profile.angles[3] - profile.angles[4] == pytest.approx(2 * REFERENCE.inlet_half_wedge)
    assert profile.angles[5] - profile.angles[1] == pytest.approx(2 * profile.outlet_half_wedge)


@given(
    inlet=st.floats(25.0, 50.0), outlet=st.floats(-72.0, -55.0), wedge=st.floats(6.0, 14.0),
    turning=st.floats(4.0, 10.0),
)
def test_valid_parameters_give_a_closed_simple_profile(inlet: float, outlet: float, wedge: float,
                                                       turning: float) -> None:
    params = dataclasses.replace(
        REFERENCE, inlet_angle=math.radians(inlet), outlet_angle=math.radians(outlet),
        inlet_half_wedge=math.radians(wedge), unguided_turning=math.radians(turning),
        throat=REFERENCE.pitch * math.cos(math.radians(outlet)))
    try:
        profile = pritchard_profile(params)
    except GeometryError as error:  # only the documented refusals
        assert "passage" in str(error) or "half-wedge" in str(error)
        return
    assert profile.area > 0.0
    assert 0.0 < profile.outlet_half_wedge < math.radians(30.0)


def test_bad_parameters_are_refused_by_name() -> None:
    with pytest.raises(GeometryError, match="throat"):
        pritchard_profile(dataclasses.replace(REFERENCE, throat=1.0))
    with pytest.raises(GeometryError, match="outlet_angle"):
        pritchard_profile(dataclasses.replace(REFERENCE, outlet_angle=0.3))


def test_rows_follow_the_spec(reference_spec) -> None:
    for k, row in enumerate(HP_ROWS):
        design = row_design(reference_spec, row)
        blading = (reference_spec.control_stage.blading if k == 0
                   else reference_spec.stages[k - 1].blading)
        assert design.mean_radius == pytest.approx(blading.mean_diameter / 2)
        assert design.span == pytest.approx(blading.blade_height)
        assert design.mean_section.blade_count == blading.blade_count
        # zero exit swirl: the relative exit flow angle is -atan(u / c_a)
        _, outlet = design.blade_angles(design.mean_radius)
        u = reference_spec.design.rotational_speed * design.mean_radius
        assert float(outlet) == pytest.approx(-math.atan(u / design.axial_velocity))
        # the stage reaction Λ = 1 - c_θ1 / (2u) of the velocity triangle equals the spec's
        c_theta1 = design.inlet_swirl_radius / design.mean_radius
        assert 1.0 - c_theta1 / (2.0 * u) == pytest.approx(blading.reaction)
    with pytest.raises(GeometryError, match="unknown blade row"):
        row_design(reference_spec, "lp3")


@pytest.mark.parametrize("row", ["hp1", "hp7", "hp13"])
def test_blade_surface_is_closed_and_has_the_exact_volume(reference_spec, row: str) -> None:
    blade = make_blade(reference_spec, row)
    vertices, triangles, regions = blade.surface_mesh(4e-4)
    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(blade.volume, rel=5e-4)  # chord sag of the polyline
    assert set(np.unique(regions)) == set(range(len(REGIONS)))
    assert vertices[:, 2].min() == pytest.approx(blade.design.hub_radius)
    assert vertices[:, 2].max() == pytest.approx(blade.design.tip_radius)


def test_section_transform_round_trips(hp1_blade) -> None:
    pts, _ = hp1_blade.profile.sample(1e-3)
    placed = hp1_blade.place(pts, hp1_blade.design.tip_radius)
    np.testing.assert_allclose(hp1_blade.to_section(placed), pts, atol=1e-12)


def test_ip_rows_are_a_consistent_estimate(reference_spec) -> None:
    from steamtwin.geometry.ip_rows import IP_REACTION, ip_expansion
    from steamtwin.geometry.row_sizing import IP_ROWS

    designs = [row_design(reference_spec, row) for row in IP_ROWS]
    assert all(d.kind == "stator" and d.angular_speed == 0.0 for d in designs)
    # constant root radius, heights growing with the specific volume down the expansion
    np.testing.assert_allclose([d.hub_radius for d in designs], designs[0].hub_radius)
    assert np.all(np.diff([d.span for d in designs]) > 0.0)
    expansion = ip_expansion(reference_spec)
    assert expansion["pressure"][0] == pytest.approx(
        0.9 * reference_spec.design.hp_exhaust_pressure)
    assert expansion["pressure"][-1] == pytest.approx(0.9e6, rel=0.05)
    # continuity at the first stator exit: m v = 2π r_m h c_a
    from steamtwin.steam import if97

    d = designs[0]
    p_in, p_out = expansion["pressure"][:2]
    h_exit = expansion["enthalpy"][0] - (1 - IP_REACTION) * 0.9 * expansion["stage_drop"]
    v = float(if97.specific_volume_ph(p_out * (p_in / p_out) ** IP_REACTION, h_exit))
    assert expansion["flow"] * v == pytest.approx(
        2 * math.pi * d.mean_radius * d.span * d.axial_velocity, rel=1e-9)
    # axial inlet, 16° exit from the wheel plane
    inlet, outlet = d.blade_angles(d.mean_radius)
    assert float(inlet) == pytest.approx(0.0)
    assert float(outlet) == pytest.approx(-math.radians(74.0))
    blade = make_blade(reference_spec, "ip9")
    assert blade.volume > 0.0
