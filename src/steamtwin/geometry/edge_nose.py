"""A round nose whose flanks curve: the span edge model refitted over a window set by its radius.

The edge model of :mod:`~steamtwin.geometry.edge_model` is a circle between two straight
flank lines (:mod:`~steamtwin.geometry.edge_span`), fitted to the points within a window of a
few millimetres (16 point spacings, ≥ 2 mm) beyond the edge. That is the shape of a wedge's
edge (a trailing edge, a double-circular-arc or a Pritchard profile), not of a nose whose
thickness grows as √x from the tip: near the leading edge of a NACA 4-digit or 65-series
section y ≈ √(2·r·x) (Abbott & von Doenhoff, "Theory of Wing Sections", 1959, §6.4: the
leading-edge radius is that of the parabola's vertex), so the flanks have no straight part and
their slope changes within a few radii. Straight lines through 5 mm of such flanks lean out,
the circle tangent to them is too large and its tip off the nose (issue 19's slender blade,
65-series, r 0.3 → 0.15 mm, 80k points: own circles r 0.45–0.51 mm, the span model 0.1–0.4 mm
off the leading edge's points, docs/benchmarks.md).

The nose is scale-free in r: a parabola y² = 2·r·x, x and y in units of r, is one curve
whatever the profile. Measured on the exact slender sections at 50 % and 84 % span
(2026-11-27), the circle-and-lines fit to the curve within u of arc length from the tip stands
off it within 0.6 mm of the tip by at most 0.007 / 0.014 / 0.027 / 0.065 mm for u = 0.5 / 1 /
2 / 5 mm (≈ 3, 6, 12, 29 radii). So the model is refitted (:func:`nose_refit`) to the points
within :data:`NOSE_RADII` radii of arc length from its tip — at least
:data:`MIN_BEYOND` point spacings beyond its tangent points, so each flank line still holds
points along the span —, the window set again from each refit's radius (the first model's
radius is too large, its window too long), as in the iterative closest point method (Besl &
McKay 1992, IEEE PAMI 14:239: correspondences reselected from the current fit). On the
synthetic nose of ``tests/geometry/test_edge_nose.py`` (slender's r 0.174 mm at 84 % span, its
80k density) the model's points stand within 0.026 / 0.063 mm of the exact nose for a window of
4 / 6 radii (radius 0.27 / 0.34 mm: a model of the nose's points, not its vertex radius), 0.15 mm
off with the straight-flank model over its 5-mm window; at 3 radii the floor of
:data:`MIN_BEYOND` spacings sets the window.

Beyond the window a nose's flanks leave the model's lines by more than the scan noise, so the
cloud's order is read against the model there from the points within
:data:`~steamtwin.geometry.edge_pooled.ORDER_DISTANCE` of it (``edge_model``), not within the
trim floor.
"""

from __future__ import annotations

import numpy as np

from steamtwin.geometry.edge_circle import arc_length_at, tip_and_half_angle
from steamtwin.geometry.edge_span import SpanEdgeModel, fit_span_edge

#: The nose window: arc length from the tip (either side) in radii of the current model
#: (module docstring: 4 radii 0.026 mm, 6 radii 0.063 mm off the synthetic nose).
NOSE_RADII = 4.0
#: Fewest point spacings of flank beyond the tangent points within the window.
MIN_BEYOND = 4.0
#: Refits, each with the window from the previous one's radius.
NOSE_ROUNDS = 3


def nose_window(points: np.ndarray, candidates: np.ndarray, model: SpanEdgeModel,
                spacing: float) -> np.ndarray:
    """Those of ``candidates`` (indices into ``points`` (n, 3; m)) within the nose window of
    ``model``: |u| ≤ max(:data:`NOSE_RADII`·r, r·(π − β)/2 + :data:`MIN_BEYOND`·``spacing``)
    (m) of arc length from its tip at their height."""
    centre, radius, normals = model.at(points[candidates, 2])
    u = arc_length_at(points[candidates, :2], centre, radius, normals)
    half = tip_and_half_angle(normals)[1]
    window = np.maximum(NOSE_RADII * radius, radius * half + MIN_BEYOND * spacing)
    return candidates[np.abs(u) <= window]


def nose_refit(points: np.ndarray, candidates: np.ndarray, model: SpanEdgeModel,
               spacing: float, radius_bounds: tuple[float, float]) -> SpanEdgeModel:
    """The span model ``model`` refitted :data:`NOSE_ROUNDS` times to the points of
    ``candidates`` (indices into ``points`` (n, 3; m), the edge's side points near it) in its
    nose window (:func:`nose_window`), radius within ``radius_bounds`` (m)."""
    for _ in range(NOSE_ROUNDS):
        window = nose_window(points, candidates, model, spacing)
        if len(window) == 0:
            break
        model, _ = fit_span_edge(points[window], model, radius_bounds)
    return model
