"""The edge model of thin, sparse blade edges (geometry/edge_model.py, edge_circle.py).

Synthetic sections made here: a wedge closed by a trailing-edge circle of radius r tangent to
both straight flanks and by a large leading-edge circle (the edge-circle profile of Dixon & Hall
§3.3 / Pritchard 1985), stacked along z with a lean, sampled at random with noise along the
normal. Exact geometry is known, so the fitted circles and model points are checked against it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from steamtwin.geometry.edge_circle import edge_distance, tangent_centre
from steamtwin.geometry.edge_model import model_sparse_edges
from steamtwin.geometry.volume_mesh import REGIONS

LEAN = 0.02  # m of y per m of z: the edge drifts along the span


class WedgeSection:
    """Trailing-edge circle (centre (0, LEAN·z), radius ``r``), flanks at ±``half_wedge``
    about the −x axis, leading-edge circle of radius ``r + length·sin(half_wedge)`` at
    ``length`` behind; arc length ``s`` anticlockwise from the trailing edge's tip."""

    def __init__(self, r: float, half_wedge: float, length: float = 20e-3) -> None:
        self.r, self.alpha, self.length = r, half_wedge, length
        self.big = r + length * math.sin(half_wedge)
        self.theta = math.pi / 2 - half_wedge  # tangent points' angle from +x
        self.flank = length * math.cos(half_wedge)
        self.pieces = np.array([self.r * self.theta, self.flank,
                                self.big * (2 * math.pi - 2 * self.theta), self.flank,
                                self.r * self.theta])
        self.perimeter = float(self.pieces.sum())

    def at(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Points (n, 2) and outward normals at arc length u ∈ [0, perimeter) (z = 0)."""
        u = np.mod(u, self.perimeter)
        ends = np.cumsum(self.pieces)
        point, normal = np.zeros((len(u), 2)), np.zeros((len(u), 2))
        lead = np.array([-self.length, 0.0])
        for k in range(5):
            on = (u >= (ends[k - 1] if k else 0.0)) & (u < ends[k])
            v = u[on] - (ends[k - 1] if k else 0.0)
            if k in (0, 4):  # trailing-edge arc, through the tip at angle 0
                angle = v / self.r - (self.theta if k == 4 else 0.0)
                normal[on] = np.column_stack([np.cos(angle), np.sin(angle)])
                point[on] = self.r * normal[on]
            elif k == 2:  # leading-edge arc
                angle = self.theta + v / self.big
                normal[on] = np.column_stack([np.cos(angle), np.sin(angle)])
                point[on] = lead + self.big * normal[on]
            else:  # upper (k = 1, towards the front) or lower flank (k = 3, towards the rear)
                a = self.theta if k == 1 else -self.theta
                n = np.array([math.cos(a), math.sin(a)])
                start, stop = self.r * n, lead + self.big * n
                direction = (stop - start) / np.linalg.norm(stop - start)
                direction = direction if k == 1 else -direction
                origin = start if k == 1 else stop
                point[on] = origin + v[:, None] * direction
                normal[on] = n
        return point, normal


def scan(section: WedgeSection, spacing: float, height: float = 12e-3, noise: float = 0.017e-3,
         seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (n, 3) at a mean spacing, their arc-length fraction s and labels."""
    rng = np.random.default_rng(seed)
    count = round(section.perimeter * height / spacing**2)
    u = rng.uniform(0.0, section.perimeter, count)
    z = rng.uniform(0.0, height, count)
    xy, normal = section.at(u)
    xy = xy + rng.normal(0.0, noise, count)[:, None] * normal + np.column_stack(
        [np.zeros(count), LEAN * z])
    s = u / section.perimeter
    distance = np.minimum(u, section.perimeter - u)
    labels = np.where(distance < 1e-3, REGIONS.index("trailing_edge"),
                      np.where(np.abs(u - section.perimeter / 2) < 3e-3,
                               REGIONS.index("leading_edge"), REGIONS.index("suction_side")))
    return np.column_stack([xy, z]), s, labels


def _model(section: WedgeSection, spacing: float, seed: int = 0):
    points, s, labels = scan(section, spacing, seed=seed)
    perimeter = np.full(len(points), section.perimeter)
    return points, model_sparse_edges(points, s, np.ones(len(points), dtype=bool), labels,
                                      perimeter, spacing)


def test_tangent_centre_is_at_the_radius_from_both_lines() -> None:
    normals = np.array([[0.1, -1.0], [0.1, 1.0]]) / math.hypot(0.1, 1.0)
    offsets = np.array([[-0.3e-3, -0.3e-3]])
    centre = tangent_centre(normals, offsets, 0.2e-3)
    assert normals @ centre[0] - offsets[0] == pytest.approx([0.2e-3, 0.2e-3], abs=1e-12)


@pytest.mark.parametrize(("radius", "half_wedge_deg"), [(0.2e-3, 7.0), (0.15e-3, 5.0),
                                                        (0.3e-3, 12.0)])
def test_sparse_trailing_edge_circle_is_recovered(radius: float, half_wedge_deg: float) -> None:
    """About four points across the half circle, σ 0.017 mm: every modelled slab's radius
    within 0.03 mm and centre within 0.1 mm of the truth, and most slabs modelled."""
    section = WedgeSection(radius, math.radians(half_wedge_deg))
    _, model = _model(section, spacing=0.14e-3)
    slabs = [slab for slab in model.slabs if slab.edge == "trailing_edge"]
    used = [slab for slab in slabs if slab.used]
    assert len(used) >= 0.6 * len(slabs)
    radii = np.array([slab.radius for slab in used])
    centres = np.array([slab.centre for slab in used])
    truth = np.column_stack([np.zeros(len(used)), LEAN * np.array([slab.z for slab in used])])
    assert np.abs(radii - radius).max() < 0.03e-3
    assert np.linalg.norm(centres - truth, axis=1).max() < 0.1e-3
    assert np.median(np.abs(radii - radius)) < 0.01e-3


def test_model_points_lie_on_the_true_edge_and_no_beak() -> None:
    """The model points stay within 0.04 mm of the exact profile, none beyond the true tip
    by more than 0.04 mm (a "beak"), and their s follows the arc length round the edge."""
    section = WedgeSection(0.2e-3, math.radians(7.0))
    points, model = _model(section, spacing=0.14e-3)
    assert len(model.points) > 0
    local = model.points[:, :2] - np.column_stack([np.zeros(len(model.points)),
                                                   LEAN * model.points[:, 2]])
    # the exact profile near the edge, densely sampled (1 µm steps)
    u = np.arange(-3e-3, 3e-3, 1e-6)
    exact, _ = section.at(u)
    distance, nearest = cKDTree(exact).query(local)
    assert distance.max() < 0.04e-3
    assert local[:, 0].max() < 0.2e-3 + 0.04e-3
    # s follows the exact arc length round the edge
    error = np.abs(np.mod(model.s - u[nearest] / section.perimeter + 0.5, 1.0) - 0.5)
    assert np.median(error) * section.perimeter < 0.05e-3
    # the points replaced are the cloud's edge points only
    replaced = points[model.replaced]
    assert np.all(replaced[:, 0] > -1e-3)


def test_a_well_sampled_edge_keeps_its_own_points() -> None:
    """The 2.6 mm leading-edge circle holds far more than MODEL_SAMPLES spacings: never
    modelled; nor is a 1.5 mm trailing edge."""
    section = WedgeSection(1.5e-3, math.radians(7.0))
    _, model = _model(section, spacing=0.14e-3)
    assert not any(slab.used for slab in model.slabs)
    assert not model.replaced.any()


def test_stray_points_do_not_make_a_beak() -> None:
    """A fused scan's stray points (here 5 % of the trailing edge's, 0.2–2 mm outward, five
    times the whole cloud's 1 %) are left out of the fit: the radius stays within 0.03 mm and
    no model point lies beyond the true tip."""
    section = WedgeSection(0.2e-3, math.radians(7.0))
    points, s, labels = scan(section, 0.14e-3, seed=4)
    rng = np.random.default_rng(5)
    edge = np.flatnonzero(labels == REGIONS.index("trailing_edge"))
    stray = rng.choice(edge, len(edge) // 20, replace=False)
    _, normal = section.at(s[stray] * section.perimeter)
    points[stray, :2] += rng.uniform(0.2e-3, 2e-3, len(stray))[:, None] * normal
    model = model_sparse_edges(points, s, np.ones(len(points), dtype=bool), labels,
                               np.full(len(points), section.perimeter), 0.14e-3)
    used = [slab for slab in model.slabs if slab.used]
    assert len(used) >= 4
    assert max(abs(slab.radius - 0.2e-3) for slab in used) < 0.03e-3
    local = model.points[:, :2] - np.column_stack([np.zeros(len(model.points)),
                                                   LEAN * model.points[:, 2]])
    assert local[:, 0].max() < 0.2e-3 + 0.04e-3
    assert model.replaced[stray].sum() > 0  # stray points at the edge are not fitted


def test_edge_distance_is_signed_outward_on_arc_and_flanks() -> None:
    """Points 0.05 mm outside the arc and the flanks are at +0.05 mm; the centre is inside."""
    normals = np.array([[-math.sin(0.12), -math.cos(0.12)], [-math.sin(0.12), math.cos(0.12)]])
    offsets = np.full((1, 2), -0.2e-3)
    centre = tangent_centre(normals, offsets, 0.2e-3)[0]
    flank = np.array([normals[0][1], -normals[0][0]])
    flank = -flank if flank[0] > 0 else flank  # along the flank, away from the tip (+x)
    probes = np.array([centre + np.array([0.25e-3, 0.0]),  # beyond the tip
                       centre - 0.2e-3 * normals[0] + 2e-3 * flank - 0.05e-3 * normals[0]])
    distance, sector = edge_distance(probes, normals, np.repeat(offsets, 2, axis=0), 0.2e-3)
    assert distance == pytest.approx([0.05e-3, 0.05e-3], abs=1e-9)
    assert sector.tolist() == [True, False]
    assert edge_distance(centre[None], normals, offsets, 0.2e-3)[0][0] == pytest.approx(-0.2e-3)
