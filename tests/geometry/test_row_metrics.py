"""Row metrics on any blade: edge circles of exact sections built from two arcs and two edge
circles, and metrics of an extruded section without a nominal row."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.geometry.row_metrics import (
    blade_row_metrics,
    edge_circle,
    fit_circle,
    refine_circle,
    row_section,
)

pytestmark = pytest.mark.slow  # 7 s of the full suite (2026-11-27): not in the quick loop


def _arc(centre: np.ndarray, radius: float, start: float, stop: float, count: int
         ) -> np.ndarray:
    """Points of the anticlockwise arc from angle ``start`` to ``stop`` (end excluded)."""
    sweep = np.mod(stop - start, 2.0 * math.pi)
    angle = start + sweep * np.arange(count) / count
    return centre + radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _outer_centre(c1: np.ndarray, r1: float, c2: np.ndarray, r2: float, big: float,
                  side: float) -> np.ndarray:
    """Centre of the circle of radius ``big`` touching both edge circles from outside them
    (internally tangent), on the ``side`` (−1 below, +1 above) of the line c1-c2."""
    d1, d2 = big - r1, big - r2
    gap = float(np.linalg.norm(c2 - c1))
    along = (d1**2 - d2**2 + gap**2) / (2.0 * gap)
    height = math.sqrt(d1**2 - along**2)
    axis = (c2 - c1) / gap
    return c1 + along * axis + side * height * np.array([-axis[1], axis[0]])


def lens_section(le: float, te: float, upper: float, lower: float, length: float = 40e-3,
                 stagger: float = 0.0) -> np.ndarray:
    """Anticlockwise section (m): leading-edge circle radius ``le`` at the origin, trailing
    circle ``te`` at (``length``, 0), joined tangentially by arcs of radius ``upper`` and
    ``lower`` (biconvex); then turned by ``stagger`` (rad) about the origin."""
    c_le, c_te = np.zeros(2), np.array([length, 0.0])
    o_up = _outer_centre(c_le, le, c_te, te, upper, -1.0)
    o_lo = _outer_centre(c_le, le, c_te, te, lower, +1.0)

    def angle(c: np.ndarray, o: np.ndarray) -> float:  # direction of the tangent point from c
        d = c - o
        return math.atan2(d[1], d[0])

    te_lo, te_up = angle(c_te, o_lo), angle(c_te, o_up)
    le_up, le_lo = angle(c_le, o_up), angle(c_le, o_lo)
    polygon = np.vstack([
        _arc(c_te, te, te_lo, te_up, 600),
        _arc(o_up, upper, te_up, le_up, 4000),
        _arc(c_le, le, le_up, le_lo, 600),
        _arc(o_lo, lower, le_lo, te_lo, 4000)])
    turn = np.array([[math.cos(stagger), -math.sin(stagger)],
                     [math.sin(stagger), math.cos(stagger)]])
    return polygon @ turn.T


def test_circle_fits_are_exact_on_a_circle_arc() -> None:
    points = _arc(np.array([0.01, -0.02]), 0.7e-3, 1.0, 2.5, 50)
    start = np.array([0.0102, -0.0199])
    for centre, radius in (fit_circle(points), refine_circle(points, start, 1e-3)):
        assert radius == pytest.approx(0.7e-3, rel=1e-9)
        assert np.allclose(centre, [0.01, -0.02], atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(le=st.floats(0.2e-3, 2.0e-3), te=st.floats(0.1e-3, 1.0e-3),
       upper=st.floats(50e-3, 200e-3), lower=st.floats(80e-3, 400e-3),
       stagger=st.floats(-math.radians(70), math.radians(70)))
def test_edge_radii_of_exact_sections(le: float, te: float, upper: float, lower: float,
                                      stagger: float) -> None:
    polygon = lens_section(le, te, upper, lower, stagger=stagger)
    leading, trailing = edge_circle(polygon, "leading"), edge_circle(polygon, "trailing")
    # the polygon is exact (600 points round each edge): 0.3 % or 2 µm (the arc's overrun
    # past the tangent points, trimmed by an estimate, for a 5 µm RMS allowance)
    assert leading.radius == pytest.approx(le, rel=3e-3, abs=2e-6)
    assert trailing.radius == pytest.approx(te, rel=3e-3, abs=2e-6)
    assert np.linalg.norm(leading.centre) < max(3e-3 * le, 2e-6)
    far = 40e-3 * np.array([math.cos(stagger), math.sin(stagger)])
    assert np.linalg.norm(trailing.centre - far) < max(3e-3 * te, 2e-6)


def test_section_metrics_without_and_with_a_pitch() -> None:
    stagger = math.radians(55.0)
    polygon = lens_section(1.0e-3, 0.3e-3, 80e-3, 80e-3, stagger=stagger)
    alone = row_section(polygon)
    assert math.isnan(alone.throat) and math.isnan(alone.pitch)
    # symmetric lens: the farthest points lie on the axis of the edge centres
    assert alone.stagger == pytest.approx(stagger, abs=1e-5)
    assert alone.chord == pytest.approx(40e-3 + 1.0e-3 + 0.3e-3, rel=1e-6)
    assert alone.leading_edge.radius == pytest.approx(1.0e-3, rel=5e-3)
    pitched = row_section(polygon, pitch=30e-3)
    assert 0.0 < pitched.throat < 30e-3
    rows = {row["metric"]: row for row in pitched.rows()}
    assert rows["te_radius"]["unit"] == "mm"
    assert rows["te_radius"]["measured"] == pytest.approx(0.3, rel=5e-3)
    assert rows["stagger"]["measured"] == pytest.approx(55.0, abs=1e-3)


def test_blade_row_metrics_on_an_extruded_section() -> None:
    from steamtwin.geometry.profile import cap_triangles

    polygon = lens_section(1.0e-3, 0.3e-3, 80e-3, 120e-3, stagger=math.radians(40.0))
    polygon = polygon[::4]
    n = len(polygon)
    vertices = np.vstack([np.column_stack([polygon, np.full(n, z)]) for z in (0.50, 0.56)])
    k = np.arange(n)
    side = np.vstack([np.column_stack([k, (k + 1) % n, (k + 1) % n + n]),
                      np.column_stack([k, (k + 1) % n + n, k + n])])
    cap = cap_triangles(polygon)
    triangles = np.vstack([side, cap[:, ::-1], cap + n])
    sections = blade_row_metrics(vertices, triangles, blade_count=60)
    assert [s.name for s in sections] == ["hub", "mid", "tip"]
    assert sections[1].radius == pytest.approx(0.53)
    assert sections[1].pitch == pytest.approx(2.0 * math.pi * 0.53 / 60)
    for section in sections:
        assert section.leading_edge.radius == pytest.approx(1.0e-3, rel=1e-2)
        assert section.trailing_edge.radius == pytest.approx(0.3e-3, rel=1e-2)
        assert math.isfinite(section.throat)
    alone = blade_row_metrics(vertices, triangles)
    assert all(math.isnan(s.throat) for s in alone)
    with pytest.raises(ValueError, match="blade_count or pitch"):
        blade_row_metrics(vertices, triangles, blade_count=60, pitch=0.05)


def test_design_edge_radii_of_the_exact_hp1_blade(hp1_blade, tmp_path) -> None:
    """On the exact blade's own triangulation the measured edge radii equal the design's
    (Pritchard's radii scaled with the chord at each section), and the report gets them."""
    import csv
    import json

    from steamtwin.geometry.reconstruct import METRIC_SECTIONS
    from steamtwin.geometry.row_metrics import append_report_rows, design_edge_rows

    # 0.05 mm along the profile: chord sag 0.4 µm on the 0.82 mm trailing edge
    vertices, triangles, _ = hp1_blade.surface_mesh(0.05e-3, span_count=8)
    rows = {row["metric"]: row for row in design_edge_rows(hp1_blade, vertices, triangles)}
    params, design = hp1_blade.profile.params, hp1_blade.design
    for name, fraction in METRIC_SECTIONS:
        scale = float(design.chord_scale(design.hub_radius + fraction * design.span))
        le, te = rows[f"le_radius@{name}"], rows[f"te_radius@{name}"]
        assert le["truth"] == pytest.approx(params.leading_edge_radius * scale * 1e3, rel=2e-3)
        assert te["truth"] == pytest.approx(params.trailing_edge_radius * scale * 1e3, rel=2e-3)
        assert abs(le["error"]) < 1e-3 and abs(te["error"]) < 1e-3  # mm
    json_path, csv_path = tmp_path / "r.json", tmp_path / "r.csv"
    json_path.write_text("{}")
    csv_path.write_text("metric,unit,truth,measured,error\n")
    append_report_rows(json_path, csv_path, "edge_radii", list(rows.values()))
    assert len(json.loads(json_path.read_text())["edge_radii"]) == 6
    with csv_path.open() as handle:
        assert [r["metric"] for r in csv.DictReader(handle)][::6] == ["le_radius@hub"]
