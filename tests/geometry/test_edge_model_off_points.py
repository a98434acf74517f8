"""An edge whose span model stands off its points is left to the cloud (geometry/edge_model.py).

hp8 of the reference unit (192k points, seed 0, 2026-11-27): of the trailing edge's 81 slabs
only 5, all at 50–58 % span, had a circle of their own (elsewhere the arc's points scattered
more than the flanks'); the span model, started from those and continued straight by its
P-splines, was not brought back to the points near the caps by the robust fit: 0.5–0.7 mm off
the exact surface over the last 10 % of span at either end, the STL refused 1.91 mm off. The
model now stands in for the cloud only where the median distance of each slab's arc points from
it is within :data:`~steamtwin.geometry.edge_model.MODEL_BIAS`.

Synthetic here: a 0.3-mm trailing edge between straight flanks 4° apart (the Pritchard rows'
thin wedge), 30 mm of span bowed along the bisector by :data:`BOW` at either end (a parabola),
whose arc points scatter with σ = 0.05 mm (flanks 0.017 mm) outside a 6-mm band at mid-span: only
the slabs in that band have a circle of their own, as on hp8.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from steamtwin.geometry import edge_model, edge_span
from steamtwin.geometry.volume_mesh import REGIONS

RADIUS = 0.3e-3
HALF_WEDGE = math.radians(2.0)
HEIGHT = 30e-3
BAND = 6e-3  # the slabs with a circle of their own: this band at mid-span (m)
BOW = 0.5e-3  # the edge's shift along the bisector at either end (m)
SPACING = 0.16e-3
PERIMETER = 85e-3


def profile(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 2) and outward normals at arc length u (m) from the tip, at (r, 0); the
    flanks are straight beyond the tangent points."""
    theta = math.pi / 2 - HALF_WEDGE
    tangent_arc = RADIUS * theta
    angle = np.clip(u, -tangent_arc, tangent_arc) / RADIUS
    normal = np.column_stack([np.cos(angle), np.sin(angle)])
    point = RADIUS * normal
    for sign in (-1.0, 1.0):
        beyond = sign * u > tangent_arc
        along = sign * u[beyond] - tangent_arc
        point[beyond] += along[:, None] * np.array([-math.sin(theta), sign * math.cos(theta)])
    return point, normal


def bow(z: np.ndarray) -> np.ndarray:
    """The edge's shift along x (its bisector) at height z (m)."""
    return BOW * ((z - HEIGHT / 2) / (HEIGHT / 2)) ** 2


def modelled_error(monkeypatch: pytest.MonkeyPatch, bias: float | None) -> tuple:
    """The edge model of the synthetic cloud (``bias``: MODEL_BIAS in its place, None: as is)
    and the largest distance (m) of its points from the exact edge (0 when not modelled)."""
    if bias is not None:
        monkeypatch.setattr(edge_model, "MODEL_BIAS", bias)
    rng = np.random.default_rng(0)
    count = round(16e-3 * HEIGHT / SPACING**2)
    u = rng.uniform(-8e-3, 8e-3, count)
    z = rng.uniform(0.0, HEIGHT, count)
    xy, normal = profile(u)
    on_arc = np.abs(u) < RADIUS * (math.pi / 2 - HALF_WEDGE) + 0.3e-3
    sigma = np.where(on_arc & (np.abs(z - HEIGHT / 2) > BAND / 2), 0.05e-3, 0.017e-3)
    xy = xy + (rng.normal(0.0, 1.0, count) * sigma)[:, None] * normal
    xy[:, 0] += bow(z)
    labels = np.where(np.abs(u) < 1e-3, REGIONS.index("trailing_edge"),
                      np.where(u > 0.0, REGIONS.index("suction_side"),
                               REGIONS.index("pressure_side")))
    model = edge_model.model_sparse_edges(
        np.column_stack([xy, z]), np.mod(u / PERIMETER, 1.0), np.ones(count, dtype=bool),
        labels, np.full(count, PERIMETER), SPACING)
    if not len(model.points):
        return model, 0.0
    local = model.points[:, :2] - np.column_stack([bow(model.points[:, 2]),
                                                   np.zeros(len(model.points))])
    exact = profile(np.arange(-8e-3, 8e-3, 1e-6))[0]
    return model, float(cKDTree(exact).query(local)[0].max())


def test_a_span_model_off_its_points_does_not_replace_them(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A span model left at its start (no step of the robust fit: the mid-span band's circles
    continued straight by the P-splines) stands off the exact edge near the ends by more than
    0.3 mm (the mechanism is reproduced); with the check the edge is left to the cloud and says
    why. (scipy ``least_squares``, the fit before 2026-11-28, stopped at its evaluation limit
    0.87 mm off; the banded Levenberg–Marquardt fit converges, next test.)"""
    monkeypatch.setattr(edge_span, "MAX_EVALUATIONS", 1)
    _, unchecked = modelled_error(monkeypatch, math.inf)
    assert unchecked > 0.3e-3
    monkeypatch.undo()
    monkeypatch.setattr(edge_span, "MAX_EVALUATIONS", 1)
    model, error = modelled_error(monkeypatch, None)
    assert error == 0.0 and not model.replaced.any() and "trailing_edge" not in model.spans
    assert all(slab.reason.startswith("span model off the arc's points") for slab in model.slabs)


def test_the_robust_fit_brings_the_model_back_to_its_points(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """From the same start the span model's fit converges onto the bowed ends: the model
    stands in for the edge within 0.1 mm of the exact one (0.049 mm measured, 2026-11-28;
    0.87 mm from scipy ``least_squares``, which stopped at its evaluation limit)."""
    model, error = modelled_error(monkeypatch, None)
    assert model.replaced.any() and "trailing_edge" in model.spans
    assert 0.0 < error < 0.1e-3
