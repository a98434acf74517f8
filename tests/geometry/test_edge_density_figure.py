"""The density a refused edge needs: its radius measured right below the point spacing, its
points per millimetre from the cloud's own spacing — against edges of known radius."""

from __future__ import annotations

import math

import numpy as np
import pytest
from foreign_blades import family_blade, laser_cloud

from steamtwin.geometry.edge_thickness import wedge_radius
from steamtwin.geometry.fit_guard import edge_radius, edge_sampling
from steamtwin.geometry.scanner import EDGE_SAMPLES
from steamtwin.geometry.segmentation import segment_blade


def wedge_section(radius: float, half_angle: float, length: float, step: float = 1e-6
                  ) -> np.ndarray:
    """Dense outline (m) of a thin edge: a circle of ``radius`` tangent to two lines at
    ``half_angle`` (rad) either side of the x axis, its tip at x = 0, the lines ``length``
    back; the blade lies at x < 0."""
    centre = -radius
    turn = np.arange(-(0.5 * math.pi - half_angle), 0.5 * math.pi - half_angle, step / radius)
    arc = np.column_stack([centre + radius * np.cos(turn), radius * np.sin(turn)])
    out = []
    for sign in (1.0, -1.0):
        start = np.array([centre + radius * math.sin(half_angle),
                          sign * radius * math.cos(half_angle)])
        along = np.arange(0.0, length, step)[:, None]
        out.append(start + along * np.array([-math.cos(half_angle), sign * math.sin(half_angle)]))
    return np.vstack([arc, *out])


@pytest.mark.parametrize("radius", [0.15e-3, 0.25e-3])
def test_a_thin_edge_between_points_reads_its_true_radius(radius: float) -> None:
    """A 0.15 / 0.25 mm edge, 5° wedge, sampled at random at 0.23 mm spacing (issue 19's slender
    blade at 80k points) with σ 0.017 mm noise, in slabs of six spacings: the flanks' radius
    is within 15 % of the truth, while the circle through the edge's points is ≥ 1.4 × it."""
    rng = np.random.default_rng(3)
    spacing, outline = 0.23e-3, wedge_section(radius, math.radians(2.5), 4e-3)
    density = math.log(2.0) / (math.pi * spacing**2)  # points per m², Clark & Evans 1954
    strip = 6.0 * spacing  # a slab's height: points over the outline's length × strip
    length = np.sum(np.linalg.norm(np.diff(outline, axis=0), axis=1))
    wedges, circles = [], []
    for _ in range(60):
        pick = outline[rng.integers(len(outline), size=rng.poisson(density * length * strip))]
        xy = pick + rng.normal(0.0, 0.017e-3, pick.shape)
        edge = xy[xy[:, 0] > -4.0 * spacing]
        if len(edge) >= 5:
            wedges.append(wedge_radius(xy, edge, spacing))
            circles.append(edge_radius(edge))
    assert np.nanmedian(wedges) == pytest.approx(radius, rel=0.15)
    assert np.median(circles) >= 1.4 * radius


@pytest.mark.slow  # 5–9 s: the family blade, its 40k cloud and segmentation
def test_the_refusal_figure_of_a_blade_with_known_edges() -> None:
    """compressor-dca at 40k points: 0.15 mm edges at 3.4 points per mm (√(N / area)). Each
    band reads 0.13–0.18 mm and 3.1–3.6 points per mm, and needs EDGE_SAMPLES / (π r) — about
    9 per mm, 7 × this scan's density — where the old circle fit read 0.5 mm and asked 3."""
    blade = family_blade("compressor-dca")
    cloud = laser_cloud(blade, points=40_000, seed=0)
    segmentation = segment_blade(cloud.points)
    true_per_mm = math.sqrt(40_000 / blade.mesh.area) * 1e-3
    for edge in ("leading_edge", "trailing_edge"):
        bands = edge_sampling(cloud.points, segmentation, edge)
        assert len(bands) == 5
        for band in bands:
            assert 0.13e-3 <= band.radius <= 0.18e-3
            assert band.per_mm == pytest.approx(true_per_mm, rel=0.08)
            assert band.needed == pytest.approx(EDGE_SAMPLES / (math.pi * band.radius * 1e3))
            assert 7.5 <= band.needed <= 11.0
            assert f"{(band.needed / band.per_mm) ** 2:.1f} × this scan's density" in (
                band.describe())
