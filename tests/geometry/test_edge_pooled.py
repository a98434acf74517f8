"""A thin edge below one point spacing across its half circle, fitted pooled along the span
(geometry/edge_pooled.py through edge_model.py).

test_edge_model.py's wedge (a trailing-edge circle tangent to two straight flanks, Dixon &
Hall §3.3) with issue 19's slender trailing edge: r = 0.15 mm, 6° half wedge, 4.4 points per
mm² (slender 80k), so √ρ·π·r ≈ 1 point across the half circle and two or three on the arc of a
1.5-mm slab — no slab gets a circle of its own. The cloud's order mixes the faces next to the
edge as slender's does (a third of the points within 4 mm of the tip on the other face).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from test_edge_model import WedgeSection

from steamtwin.geometry.edge_circle import tip_and_half_angle
from steamtwin.geometry.edge_model import model_sparse_edges
from steamtwin.geometry.volume_mesh import REGIONS

RADIUS = 0.15e-3  # m
HALF_WEDGE = math.radians(6.0)
HEIGHT = 40e-3  # m of span
DENSITY = 4.4e6  # points per m²
SPACING = 0.5 / math.sqrt(DENSITY)  # m: the mean nearest-neighbour distance (Clark & Evans)


def sparse_scan(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points (n, 3), the cloud's (face-mixed) s, labels and perimeters."""
    rng = np.random.default_rng(seed)
    section = WedgeSection(RADIUS, HALF_WEDGE)
    pieces = []
    for lo, hi in itertools.pairwise(np.linspace(0.0, HEIGHT, 81)):
        count = rng.poisson(section.perimeter * (hi - lo) * DENSITY)
        u = rng.uniform(0.0, section.perimeter, count)
        xy, normal = section.at(u)
        xy = xy + rng.normal(0.0, 0.017e-3, count)[:, None] * normal
        distance = np.minimum(u, section.perimeter - u)
        mixed = (distance < 4e-3) & (rng.uniform(size=count) < 1 / 3)
        order = np.where(mixed, section.perimeter - u, u) / section.perimeter
        labels = np.where(distance < 1e-3, REGIONS.index("trailing_edge"),
                          np.where(np.abs(u - section.perimeter / 2) < 3e-3,
                                   REGIONS.index("leading_edge"),
                                   REGIONS.index("suction_side")))
        pieces.append((np.column_stack([xy, rng.uniform(lo, hi, count)]), order, labels,
                       np.full(count, section.perimeter)))
    return tuple(np.concatenate(column) for column in zip(*pieces, strict=True))


def exact_distance(xy: np.ndarray) -> np.ndarray:
    """Signed distance (m) from the wedge's trailing edge: the arc, then the flanks."""
    theta = math.pi / 2 - HALF_WEDGE
    angle = np.arctan2(xy[:, 1], xy[:, 0])
    lines = [xy @ np.array([math.cos(a), math.sin(a)]) - RADIUS for a in (theta, -theta)]
    return np.where(np.abs(angle) <= theta, np.linalg.norm(xy, axis=1) - RADIUS,
                    np.where(angle > 0, lines[0], lines[1]))


@pytest.fixture(scope="module")
def pooled():
    points, s, labels, perimeter = sparse_scan()
    return model_sparse_edges(points, s, np.ones(len(points), dtype=bool), labels, perimeter,
                              SPACING)


def test_no_slab_has_a_circle_of_its_own(pooled) -> None:
    slabs = [slab for slab in pooled.slabs if slab.edge == "trailing_edge"]
    assert slabs and not any(slab.reason == "" for slab in slabs)


def test_pooled_model_holds_the_edge_at_every_z(pooled) -> None:
    span = pooled.spans["trailing_edge"]  # no model at all before edge_pooled
    z = np.linspace(2e-3, HEIGHT - 2e-3, 77)
    centre, radius, normals = span.at(z)
    tip = centre + radius[:, None] * tip_and_half_angle(normals)[0]
    assert np.abs(tip - [RADIUS, 0.0]).max() < 0.03e-3
    assert np.abs(radius - RADIUS).max() < 0.03e-3


def test_model_points_lie_on_the_exact_surface(pooled) -> None:
    inside = (pooled.points[:, 2] > 2e-3) & (pooled.points[:, 2] < HEIGHT - 2e-3)
    assert inside.sum() > 1000
    assert np.abs(exact_distance(pooled.points[inside, :2])).max() < 0.05e-3


def test_model_order_is_monotone_across_the_edge(pooled) -> None:
    """Round the edge the model's parameter runs one way on both faces (the cloud's order
    mixes them): s increases with the anticlockwise angle at every height."""
    xy, s = pooled.points[:, :2], np.mod(pooled.s + 0.5, 1.0) - 0.5
    angle = np.arctan2(xy[:, 1], xy[:, 0])
    for lo in np.arange(2e-3, HEIGHT - 2e-3, 1.5e-3):
        ring = (pooled.points[:, 2] >= lo) & (pooled.points[:, 2] < lo + 0.3e-3)
        assert ring.sum() > 5
        order = np.argsort(angle[ring])
        assert np.all(np.diff(s[ring][order]) >= -1e-5)
