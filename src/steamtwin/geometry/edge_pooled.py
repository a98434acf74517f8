"""An edge too sparse for a circle per slab, started from its flanks found by geometry and
fitted pooled along the span.

Below about one point spacing across an edge's half circle π·r (issue 19's slender blade:
a 0.15-mm trailing edge at 0.23 mm spacing, 0.93 spacings across at 80k;
docs/benchmarks.md) a slab of
:mod:`~steamtwin.geometry.edge_model` holds two or three points on the arc and no slab passes
its own circle's checks; worse, the cloud's order ``s`` there is off by more than the flank
window's start (measured on slender 80k seed 0, random pose, 2026-11-27: of the points the
order puts 1.4–5 mm on one side of the trailing edge, 20–45 % lie on the other face), so
flanks picked by ``s`` mix both faces ("flanks not straight", RMS 0.13–0.19 mm, in 109 of
167 slabs). Two things still hold:

- *the flanks by geometry:* in a slab the side points near the edge lie along the chord; the
  edge is the end of their principal axis towards which the faces close, and a straight
  mid-line through the points 1.4–5 mm behind the tip (offset across the axis against
  distance behind the tip, a least-squares line) splits the two faces wherever the edge is
  thicker than the noise — the construction of :func:`~steamtwin.geometry.edge_thickness.
  wedge_radius`. Each face is then a flank plane (:func:`~steamtwin.geometry.edge_circle.
  flank_plane`), and the radius is that of the circle tangent to both whose tip lies at the
  outermost point;
- *the order per face:* 5–10 mm from the tip the order no longer mixes the faces (none of
  slender's points there); there the cloud's arc length is read against the model's on each
  face (:func:`face_order`), and every point within 10 mm of the tip gets its ``s`` from the
  model through it;
- *pooling along the span:* the span model (:mod:`~steamtwin.geometry.edge_span`) is fitted
  to the points of all slabs at once, so each of its knot spans (``KNOT_SPACING``) holds
  ρ·π·r·Δz points on the arc — ≈ 5 for the slender trailing edge at 80k (4.4 points per
  mm²), where a 1.5-mm slab holds 3. A circle with free centre from n arc points has
  sd(r) ≈ 2.3·σ/√n (Cramér–Rao; Chernov 2010, "Circular and linear regression", ch. 6), and
  the flanks fix the centre's other two degrees of freedom from thousands of points.

The per-slab values are only the start (median over ±:data:`START_SLABS` slabs, then the
P-spline start of :func:`~steamtwin.geometry.edge_span.initial_coefficients`); the fit is the
span model's.
"""

from __future__ import annotations

import math

import numpy as np

from steamtwin.geometry.edge_circle import (
    arc_length_at,
    edge_distance_at,
    flank_plane,
    tangent_centre,
    tip_and_half_angle,
)
from steamtwin.geometry.edge_span import SpanEdgeModel

#: Fewest points of each geometric flank in a slab.
MIN_FLANK_POINTS = 8
#: Wedge angles (rad) of a geometric start: the tangent-circle construction's range
#: (edge_model.WEDGE_RANGE).
WEDGE_RANGE = (math.radians(2.0), math.radians(120.0))
#: Slabs either side over which the geometric starts are smoothed (median): each comes from
#: two or three arc points, so its radius scatters by tens of per cent.
START_SLABS = 5


def _geometric_slab(points: np.ndarray, candidates: np.ndarray, axis: np.ndarray,
                    window: tuple[float, float], noise: float, z_mid: float,
                    bounds: tuple[float, float]) -> tuple | None:
    """One slab's start from its geometry with the edge towards ``axis`` (2,): (section
    values (cₓ, c_y, r, θ_left, θ_right), the left and right faces' points, the flanks' RMS
    (m)) or None. ``candidates`` the slab's side points near the edge, ``window`` (m) the
    flanks' distances behind the tip."""
    xy = points[candidates, :2]
    across = np.array([-axis[1], axis[0]])  # "left" looking towards the tip
    along = xy @ axis
    behind = float(np.percentile(along, 99.0)) - along  # robust to a stray point beyond
    offset = xy @ across
    flank = (behind >= window[0]) & (behind <= window[1])
    if flank.sum() < 2 * MIN_FLANK_POINTS:
        return None
    middle = np.polyval(np.polyfit(behind[flank], offset[flank], 1), behind)
    faces = [candidates[flank & (offset > middle)], candidates[flank & (offset <= middle)]]
    if min(len(f) for f in faces) < MIN_FLANK_POINTS:
        return None
    fits = [flank_plane(points[f] - [0.0, 0.0, z_mid]) for f in faces]
    normals = np.array([f[0] for f in fits])
    d0 = np.array([f[1] for f in fits])
    d1 = np.array([f[2] for f in fits])
    for i in range(2):  # inward: towards the other face's points
        if normals[i] @ points[faces[1 - i], :2].mean(axis=0) < d0[i]:
            normals[i], d0[i], d1[i] = -normals[i], -d0[i], -d1[i]
    rms = max(float(np.sqrt(np.mean(((points[f, :2] @ normals[i]) - d0[i]
                                     - (points[f, 2] - z_mid) * d1[i])[fits[i][3]] ** 2)))
              for i, f in enumerate(faces))
    wedge = math.pi - math.acos(float(np.clip(normals[0] @ normals[1], -1.0, 1.0)))
    bisector = tip_and_half_angle(normals)[0]  # towards the lines' apex
    if (rms > noise or not WEDGE_RANGE[0] <= wedge <= WEDGE_RANGE[1]
            or bisector @ axis <= 0.0):  # the faces must close towards the tip
        return None
    # the radius whose circle's tip lies at the outermost point round the edge: the tip
    # moves along the bisector b by r·(1 − 1/sin γ) as r grows (γ the half wedge angle), so
    # each point p at its height gives r = b·(p − c₀) / (1 + b·c₁), c(r) = c₀ + r·c₁; a
    # circle fit would trim these few points against the lines (a start 0.3–0.8 mm off)
    tip = candidates[behind <= window[0]]
    offsets = d0[None, :] + (points[tip, 2] - z_mid)[:, None] * d1[None, :]
    base = tangent_centre(normals, offsets, 0.0)
    step = tangent_centre(normals, np.zeros((1, 2)), 1.0)[0]
    radius = float(np.clip(np.min(((points[tip, :2] - base) @ bisector)
                                  / (1.0 + step @ bisector)), *bounds))
    centre = tangent_centre(normals, d0[None, :], radius)[0]
    return [float(centre[0]), float(centre[1]), radius,
            *np.arctan2(normals[:, 1], normals[:, 0]).tolist()], faces, rms


def geometric_start(points: np.ndarray, arc: np.ndarray, edges_z: np.ndarray, noise: float,
                    window: tuple[float, float], bounds: tuple[float, float]
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Start values of the span model from each slab's geometry: heights (k,; m) and values
    (k, 5: centre x, y, radius (m), angles of the inward normals of the lines at negative
    and positive cloud arc length (rad), unwrapped along the span), smoothed over
    ±:data:`START_SLABS` slabs. ``arc`` (m) the side points' signed arc length from the edge
    by the cloud's order (inf off the side), ``edges_z`` (m) the slabs' bounds, ``window``
    (m) the flanks' distances behind the tip, ``bounds`` (m) the radius's search range."""
    candidates = np.flatnonzero(np.abs(arc) <= 2.0 * window[1])
    z = points[candidates, 2]
    heights, values, faces = [], [], []
    for k in range(len(edges_z) - 1):
        members = candidates[(z >= edges_z[k]) & (z <= edges_z[k + 1])]
        if len(members) < 4 * MIN_FLANK_POINTS:
            continue
        z_mid = 0.5 * (edges_z[k] + edges_z[k + 1])
        # the edge lies at the end of the principal axis of the points near it towards which
        # the faces close (the cloud's order, which put the points near the edge, can be off
        # by millimetres on one face; where both ends close, the straighter flanks)
        xy = points[members, :2]
        axis = np.linalg.svd(xy - xy.mean(axis=0), full_matrices=False)[2][0]
        tried = [_geometric_slab(points, members, sign * axis, window, noise, z_mid, bounds)
                 for sign in (1.0, -1.0)]
        found = min((f for f in tried if f is not None), key=lambda f: f[2], default=None)
        if found is not None:
            heights.append(z_mid)
            values.append(found[0])
            faces.append(found[1])
    if not heights:
        return np.empty(0), np.empty((0, 5))
    values = np.array(values)
    # which geometric face is the line at negative cloud arc length (line 0 of the span
    # model): one vote over all slabs — the order is wrong for a share of the points, not
    # for most of them
    negative = sum(int(np.sum(arc[left] < 0.0)) - int(np.sum(arc[right] < 0.0))
                   for left, right in faces)
    if negative < 0:
        values[:, 3:] = values[:, 4:2:-1]
    values[:, 3:] = np.unwrap(values[:, 3:], axis=0)
    smooth = np.array([np.median(values[max(0, k - START_SLABS): k + START_SLABS + 1], axis=0)
                       for k in range(len(values))])
    return np.array(heights), smooth


#: Where the cloud's order is read against the model in the pooled case: its arc length u
#: from the tip between these multiples of the flank window's reach (the order mixes the
#: faces within ~5 mm of slender's trailing edge, none of its points 5–10 mm away).
ORDER_BAND = (1.5, 2.0)
#: Largest distance (m) from the model's lines of a point in that band: the flanks leave the
#: lines by < 0.1 mm within 10 mm of slender's trailing edge; stray points lie 0.2–2 mm out.
ORDER_DISTANCE = 0.2e-3


def pooled_members(points: np.ndarray, arc: np.ndarray, model: SpanEdgeModel, reach: float,
                   edges_z: np.ndarray) -> list[np.ndarray]:
    """Per slab (bounds ``edges_z``, m) the side points within ``ORDER_BAND[1]`` × ``reach``
    (m) of arc length along ``model`` from its tip and within ``ORDER_DISTANCE`` × 5 of its
    lines, taken from those within twice that of the cloud's own arc length ``arc`` (m): the
    points whose order the model sets."""
    outer = ORDER_BAND[1] * reach
    candidates = np.flatnonzero(np.abs(arc) <= 2.0 * outer)
    section = model.at(points[candidates, 2])
    u = arc_length_at(points[candidates, :2], *section)
    distance = edge_distance_at(points[candidates, :2], *section)[0]
    chosen = candidates[(np.abs(u) <= outer) & (np.abs(distance) <= 5.0 * ORDER_DISTANCE)]
    z = points[chosen, 2]
    return [chosen[(z >= edges_z[k]) & (z <= edges_z[k + 1])] for k in range(len(edges_z) - 1)]


def face_order(points: np.ndarray, arc: np.ndarray, members: np.ndarray,
               model: SpanEdgeModel, reach: float) -> tuple[float, float, float]:
    """The cloud's arc length (m) against the model's u on either face, arc = c + bᵢ·u (b₀
    for u < 0, b₁ beyond; one c, so the order stays continuous at the tip), least squares
    over the slab's ``members`` in :data:`ORDER_BAND` × ``reach`` (m) that the cloud's order
    puts on the model's face: (c, b₀, b₁), NaN when a face has fewer than
    :data:`MIN_FLANK_POINTS` there or a slope is off by more than a factor two."""
    if len(members) == 0:
        return math.nan, math.nan, math.nan
    section = model.at(points[members, 2])
    u = arc_length_at(points[members, :2], *section)
    distance = edge_distance_at(points[members, :2], *section)[0]
    band = ((np.abs(u) >= ORDER_BAND[0] * reach) & (np.abs(distance) <= ORDER_DISTANCE)
            & (np.sign(u) == np.sign(arc[members])))
    if min(np.sum(band & (u < 0.0)), np.sum(band & (u > 0.0))) < MIN_FLANK_POINTS:
        return math.nan, math.nan, math.nan
    design = np.column_stack([np.ones(band.sum()), np.minimum(u[band], 0.0),
                              np.maximum(u[band], 0.0)])
    c, b0, b1 = np.linalg.lstsq(design, arc[members[band]], rcond=None)[0]
    return (float(c), float(b0), float(b1)) if min(b0, b1) > 0.5 and max(b0, b1) < 2.0 else (
        math.nan, math.nan, math.nan)


def order_arc(order: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The cloud's arc length (m) at the model's ``u`` (m) through ``order`` (c, b₀, b₁)."""
    return order[0] + np.where(u < 0.0, order[1], order[2]) * u
