"""The cloud's side of the guard along an edge (issue 19: lean-sweep 40k seed 3, a fitted
nose flat across its apex, 0.20 mm inside it): the only evidence are the apex points the fit
trimmed, 0.11–0.20 mm off the surface in a strip one point across along the span, with 10–35 %
of their 20 nearest points far — short of a coverage gap's half. Counted along the span they
are a gap; the scan's outliers (1 %, 0.2–2 mm off, isolated) still are not."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from steamtwin.geometry.fit_guard import GuardSettings, coverage_gaps
from steamtwin.geometry.volume_mesh import REGIONS

RADIUS = 6e-3  # of the cylinder that stands for the blade (m)
HEIGHT = 20e-3  # its span (m)
DENSITY = 4e6  # points per m² (the 40k family clouds': 0.24-mm spacing)
LIMIT = 0.1e-3  # the guard's limit (m)
#: where the patches meet (s), as a reconstruction's ``boundaries``
BOUNDARIES = {"trailing_edge|suction_side": 0.02, "suction_side|leading_edge": 0.45,
              "leading_edge|pressure_side": 0.55, "pressure_side|trailing_edge": 0.98}


def _cylinder(seed: int) -> tuple[SimpleNamespace, np.ndarray, np.ndarray]:
    """A reconstruction-like cylinder (points spread uniformly at random, their parameters,
    patches by s, a grid of rings), the points' distances from the surface (m: within 0.01
    mm) and their parameters s."""
    rng = np.random.default_rng(seed)
    count = int(DENSITY * 2.0 * math.pi * RADIUS * HEIGHT)
    s = rng.uniform(0.0, 1.0, count)
    z = rng.uniform(0.0, HEIGHT, count)
    points = np.column_stack([RADIUS * np.cos(2 * math.pi * s),
                              RADIUS * np.sin(2 * math.pi * s), z])
    labels = np.where((s > 0.45) & (s < 0.55), REGIONS.index("leading_edge"),
                      np.where((s < 0.02) | (s > 0.98), REGIONS.index("trailing_edge"),
                               np.where(s < 0.5, REGIONS.index("suction_side"),
                                        REGIONS.index("pressure_side"))))
    ring_s = np.linspace(0.0, 1.0, 240, endpoint=False)
    rings = [np.column_stack([RADIUS * np.cos(2 * math.pi * ring_s),
                              RADIUS * np.sin(2 * math.pi * ring_s), np.full(len(ring_s), h)])
             for h in np.linspace(0.0, HEIGHT, 41)]
    spacing = float(np.median(np.sort(np.linalg.norm(points[:200, None] - points[None], axis=2),
                                      axis=1)[:, 1]))
    segmentation = SimpleNamespace(labels=labels, spacing=spacing,
                                   perimeter=np.full(count, 2.0 * math.pi * RADIUS))
    reconstruction = SimpleNamespace(points=points, segmentation=segmentation, parameters=s,
                                     vertices=np.concatenate(rings), ring_parameters=ring_s,
                                     boundaries=BOUNDARIES)
    distance = rng.uniform(0.0, 0.01e-3, count)
    outliers = rng.choice(count, count // 100, replace=False)
    distance[outliers] = rng.uniform(0.2e-3, 2e-3, len(outliers))
    return reconstruction, distance, s


def test_a_strip_one_point_across_along_an_edge_is_a_gap() -> None:
    """Points within 0.15 mm of the leading edge's apex line (s = 0.5) over 12 mm of span,
    0.15 mm off the surface: one gap there at 0.15 mm. Before the strips were counted, none
    (their 20 nearest points are mostly the apex's sides, on the surface)."""
    reconstruction, distance, s = _cylinder(3)
    across = np.abs(s - 0.5) * 2.0 * math.pi * RADIUS
    z = reconstruction.points[:, 2]
    strip = (across < 0.15e-3) & (z > 4e-3) & (z < 16e-3)
    distance[strip] = 0.15e-3
    assert 10 <= strip.sum() <= 20
    gaps = coverage_gaps(reconstruction, distance, LIMIT, GuardSettings())
    assert len(gaps) == 1
    assert gaps[0].region == "leading_edge"
    assert gaps[0].distance == 0.15e-3
    assert gaps[0].points >= 10
    assert 0.2 < gaps[0].span_from < gaps[0].span_to < 0.8


def test_outliers_alone_are_no_strip() -> None:
    """The same cloud with only its 1 % outliers far: no gap, over several seeds."""
    for seed in range(4):
        reconstruction, distance, _ = _cylinder(seed)
        assert coverage_gaps(reconstruction, distance, LIMIT, GuardSettings()) == []
