"""Deviation and row metrics against exact ground truth."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from steamtwin.geometry.fidelity import (
    FidelityReport,
    align_to_nominal,
    chord_line,
    section_metrics,
    section_pitch,
    surface_deviation,
    surface_samples,
    truth_section,
    write_report,
)
from steamtwin.geometry.profile import make_blade, reference_surface
from steamtwin.geometry.rigid import transform

pytestmark = pytest.mark.slow  # 26 s of the full suite (2026-11-27): not in the quick loop


@pytest.mark.parametrize("row", ["hp1", "hp9", "ip3"])
def test_metrics_of_the_exact_section_reproduce_the_design(reference_spec, row: str) -> None:
    blade = make_blade(reference_spec, row)
    metrics = section_metrics(truth_section(blade), section_pitch(blade))
    params = blade.profile.params
    assert metrics.throat == pytest.approx(params.throat, abs=1e-6)
    assert 2 * params.leading_edge_radius < metrics.max_thickness < params.pitch


@pytest.mark.parametrize("row", ["hp1", "hp9", "ip3"])
def test_chord_line_is_the_pressure_side_bitangent_of_the_edge_circles(reference_spec,
                                                                        row: str) -> None:
    """The chord line touches the leading- and trailing-edge circles of the exact section on
    the pressure side; chord = projection of the section onto it; stagger = its direction."""
    blade = make_blade(reference_spec, row)
    radius = blade.design.mean_radius
    polygon = truth_section(blade, radius)
    lead, trail, concave = chord_line(polygon)
    assert concave
    direction = (trail - lead) / np.linalg.norm(trail - lead)
    normal = np.array([-direction[1], direction[0]])
    profile, params = blade.profile, blade.profile.params
    _, scale, _ = blade.section_transform(radius)
    centres = blade.place(np.array([profile.le_centre, profile.te_centre]), radius)[:, :2]
    radii = scale * np.array([params.leading_edge_radius, params.trailing_edge_radius])
    # both centres on the same side of the line, at their circle's radius (5 µm polyline)
    offsets = (centres - lead) @ normal
    np.testing.assert_allclose(np.abs(offsets), radii, atol=1e-7)
    assert np.sign(offsets[0]) == np.sign(offsets[1])
    # the line of the section bounds it: every section point on the circles' side of it
    assert np.all(np.sign(offsets[0]) * ((polygon - lead) @ normal) > -1e-9)
    metrics = section_metrics(polygon, section_pitch(blade, radius))
    assert metrics.stagger == pytest.approx(math.atan2(direction[1], direction[0]), abs=1e-12)
    # the extremes along the chord line: on the edge circles for the HP rows; the strongly
    # cambered IP stator's suction side bulges upstream of its leading-edge circle
    over_circles = (centres[1] - centres[0]) @ direction + radii.sum()
    if row.startswith("hp"):
        assert metrics.chord == pytest.approx(over_circles, abs=1e-7)
    else:
        assert metrics.chord > over_circles


def test_metrics_of_a_circle_and_a_slot() -> None:
    t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    circle = np.column_stack([0.01 * np.cos(t), 0.01 * np.sin(t)])
    m = section_metrics(circle, pitch=0.05)
    assert not chord_line(circle)[2]  # convex: no bitangent, the diameter stands in
    assert m.chord == pytest.approx(0.02, rel=1e-5)
    assert m.max_thickness == pytest.approx(0.02, rel=1e-4)
    # throat: from the neighbour's rear 6 % (x > 8.8 mm) to this circle
    rear = circle[circle[:, 0] > 0.01 - 0.06 * 0.02] + [0.0, 0.05]
    expected = np.min(np.linalg.norm(rear, axis=1)) - 0.01
    assert m.throat == pytest.approx(expected, abs=2e-6)  # 4000-gon vs its densified copy


def test_deviation_of_the_exact_surface_is_zero_and_of_a_shift_is_the_shift(
        reference_spec) -> None:
    blade = make_blade(reference_spec, "hp1")
    vertices, triangles, _ = reference_surface(blade)
    rng = np.random.default_rng(0)
    points = vertices[rng.choice(len(vertices), 20_000, replace=False)]
    exact = surface_deviation(blade, points, vertices, triangles, samples=20_000)
    assert exact.max < 1e-8
    # backwards, the reference's sliver cap triangles resolve to ~10 µm in single precision
    assert exact.hausdorff < 2e-5
    # inflate every point 0.1 mm along the outward normal of the section: deviation 0.1 mm
    grown = points.copy()
    centre = blade.place(blade.profile.centroid[None], blade.design.mean_radius)[0]
    side = (points[:, 2] > blade.design.hub_radius + 1e-3) & (
        points[:, 2] < blade.design.tip_radius - 1e-3)
    offset = points[side, :2] - centre[:2]
    grown = points[side]
    grown[:, :2] += 1e-4 * offset / np.linalg.norm(offset, axis=1, keepdims=True)
    shifted = surface_deviation(blade, grown, samples=5_000)
    assert shifted.max <= 1e-4 + 1e-8
    assert shifted.mean > 0.3e-4


def test_alignment_undoes_an_unknown_rigid_motion(reference_spec) -> None:
    blade = make_blade(reference_spec, "hp5")
    vertices, triangles, _ = reference_surface(blade)
    points = surface_samples(vertices, triangles, 30_000, np.random.default_rng(3))
    motion = np.eye(4)
    c, s = math.cos(0.7), math.sin(0.7)
    motion[:3, :3] = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    motion[:3, 3] = [0.1, -0.2, 0.05]
    moved = transform(points, motion)
    pose, rms = align_to_nominal(moved, blade)
    assert rms < 5e-6  # fit to 30k tangent planes of the nominal
    np.testing.assert_allclose(transform(moved, pose), points, atol=3e-5)


def test_report_files(reference_spec, tmp_path) -> None:
    blade = make_blade(reference_spec, "hp1")
    truth = section_metrics(truth_section(blade), section_pitch(blade))
    from dataclasses import replace

    from steamtwin.geometry.fidelity import Deviation

    measured = replace(truth, throat=truth.throat + 1e-5)
    report = FidelityReport("hp1", Deviation(1e-5, 2e-5, 5e-5, 6e-5, 10), truth, measured, {})
    json_path, csv_path = write_report(report, tmp_path / "fidelity")
    document = json.loads(json_path.read_text())
    throat = next(m for m in document["metrics"] if m["metric"] == "throat")
    assert throat["error"] == pytest.approx(0.01)  # mm
    assert document["deviation_mm"]["hausdorff"] == pytest.approx(0.06)
    assert "deviation_rms" in csv_path.read_text()
