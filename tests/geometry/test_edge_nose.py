"""A round nose whose flanks curve is modelled over a window set by its radius
(geometry/edge_nose.py).

Issue 19's slender blade (NACA 65-series, leading-edge radius 0.3 → 0.15 mm, 80k points,
2026-11-27): the flanks of its nose have no straight part, so the edge model's circle between
straight lines fitted over 5 mm of flank stood 0.1–0.4 mm off the nose's points and the edge was
left to the cloud, whose side spline cut it 0.33 mm (0.44 mm missing) at 84 % span.

Synthetic here: a symmetric nose of half thickness t(x) = a·√x − b·x (leading-edge radius
r = a²/2 = 0.174 mm, slender's at 84 % span; t = 0.6 mm at 1.8 mm from the tip, a 65-series'
growth), extruded over 30 mm of span, sampled at slender's 80k density (4.4 points per mm²,
spacing 0.23 mm) with σ = 0.017 mm of noise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from steamtwin.geometry import edge_model, edge_nose
from steamtwin.geometry.volume_mesh import REGIONS

RADIUS = 0.174e-3
A = math.sqrt(2.0 * RADIUS)  # t ≈ √(2 r x) at the tip (m^½)
B = 0.1  # the flanks' flattening (dimensionless)
HEIGHT = 30e-3
DENSITY = 4.4e6  # points per m²
SPACING = 0.23e-3
PERIMETER = 75e-3
REACH = 7e-3  # arc length of flank sampled either side of the tip (m)


def exact_nose() -> tuple[np.ndarray, np.ndarray]:
    """The section (k, 2; m, tip at the origin, x into the blade) densely, and its signed arc
    length from the tip (m, positive on +y)."""
    x = np.linspace(0.0, 6.5e-3, 200_001) ** 2 / 6.5e-3  # dense at the tip
    upper = np.column_stack([x, A * np.sqrt(x) - B * x])
    step = np.linalg.norm(np.diff(upper, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(step)])
    curve = np.vstack([upper[::-1] * [1.0, -1.0], upper[1:]])
    return curve, np.concatenate([-arc[::-1], arc[1:]])


def nose_model(monkeypatch: pytest.MonkeyPatch, straight: bool, denser: float = 1.0) -> tuple:
    """The edge model of the synthetic cloud (``straight``: without the nose refit and with
    no check of the model against the points, the straight-flank model as it is; ``denser``:
    the density's factor) and the largest distance (m) of its points from the exact nose (NaN
    when not modelled)."""
    if straight:
        monkeypatch.setattr(edge_nose, "NOSE_ROUNDS", 0)
        monkeypatch.setattr(edge_model, "MODEL_BIAS", math.inf)
    curve, arc = exact_nose()
    rng = np.random.default_rng(0)
    count = round(denser * DENSITY * 2.0 * REACH * HEIGHT)
    u = rng.uniform(-REACH, REACH, count)
    xy = np.column_stack([np.interp(u, arc, curve[:, 0]), np.interp(u, arc, curve[:, 1])])
    tangent = np.column_stack([np.gradient(curve[:, 0]), np.gradient(curve[:, 1])])
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.column_stack([np.interp(u, arc, -tangent[:, 1]), np.interp(u, arc, tangent[:, 0])])
    xy += (rng.normal(0.0, 0.017e-3, count))[:, None] * normal
    z = rng.uniform(0.0, HEIGHT, count)
    labels = np.where(np.abs(u) < 1e-3, REGIONS.index("leading_edge"),
                      np.where(u > 0.0, REGIONS.index("pressure_side"),
                               REGIONS.index("suction_side")))
    model = edge_model.model_sparse_edges(
        np.column_stack([xy, z]), np.mod(0.5 + u / PERIMETER, 1.0), np.ones(count, dtype=bool),
        labels, np.full(count, PERIMETER), SPACING / math.sqrt(denser))
    if not len(model.points):
        return model, math.nan
    return model, float(cKDTree(curve).query(model.points[:, :2])[0].max())


def test_a_nose_with_curved_flanks_is_modelled_within_the_limits(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The straight-flank model over its 5-mm window stands more than 0.1 mm off the exact
    nose (measured: 0.15 mm); refitted over the nose window it replaces the cloud's points
    there and holds within 0.05 mm (measured: 0.026 mm)."""
    _, straight = nose_model(monkeypatch, straight=True)
    assert straight > 0.1e-3
    monkeypatch.undo()
    model, error = nose_model(monkeypatch, straight=False)
    assert "leading_edge" in model.spans and model.replaced.any()
    assert error < 0.05e-3


def test_a_resolved_edge_without_circles_of_its_own_is_not_pooled(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The pooled fit (edge_pooled) is for an edge too sparse for a slab's own circle. Taken
    for every edge here (``OWN_SHARE`` above 1), the nose at 4 × slender's density (its
    geometric start ~5 spacings across, ≥ ``POOLED_ACROSS``) is left to the cloud with the
    reason, as the reference unit's hp5 leading edge must be (pooled, it was refused 3.9 mm
    off)."""
    monkeypatch.setattr(edge_model, "OWN_SHARE", 1.01)
    model, _ = nose_model(monkeypatch, straight=False, denser=4.0)
    assert "leading_edge" not in model.spans and not model.replaced.any()
    assert all("spacings across: left to the cloud" in slab.reason for slab in model.slabs)
