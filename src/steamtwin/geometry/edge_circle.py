"""Circles tangent to two lines: the edge of one section of a blade, fitted to its points.

The standard description of a blade profile closes each end with a circle tangent to the
pressure and suction sides (Dixon & Hall, "Fluid Mechanics and Thermodynamics of
Turbomachinery", 7th ed. 2014, §3.3; Pritchard 1985, ASME 85-GT-219). Near a thin edge the
sides are straight: the model is two lines nᵢ·p = dᵢ (inward unit normals) and the circle of
radius r inside their wedge tangent to both, whose centre solves nᵢ·c = dᵢ + r — a
one-parameter family in r. :func:`edge_distance` measures points against the arc between the
tangent points and the lines beyond them; :func:`fit_tangent_circle` fits r (geometric fit,
Chernov & Lesort 2005, "Least squares fitting of circles", J. Math. Imaging Vision 23:239, with
a robust loss); :func:`refine_edge` refits lines and radius together; :func:`flank_plane` fits
a flank as a plane; :func:`arc_length_at` is the arc length along the model. Used by
:mod:`~steamtwin.geometry.edge_model` slab by slab and :mod:`~steamtwin.geometry.edge_span`
along the span.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares, minimize_scalar

#: Scale δ (m) of the soft-L1 loss of the circle fit: about the scan noise.
SOFT_SCALE = 0.02e-3
#: Radii tried before the bounded search of the circle fit.
SEARCH_GRID = 40
#: Smallest residual (m) at which a point is left out of the circle fit: above the scan noise
#: (σ 0.017 mm, 3.5 σ), below the stray points of a fused scan (0.2–2 mm off).
TRIM_FLOOR = 0.06e-3
#: Fewest points of the arc's sector for a circle to be fitted.
MIN_ARC_POINTS = 4


def flank_plane(points: np.ndarray, rounds: int = 2) -> tuple[np.ndarray, float, float, np.ndarray]:
    """A flank as the total least-squares plane of ``points`` (n, 3; m), refitted ``rounds``
    times without the points beyond 3 robust standard deviations (floor 5 µm). Returns the
    in-plane unit normal n (2,), d0 and d1 of the line n·p = d0 + d1·(z − z̄) of each section
    z = const, and the kept-points mask."""
    keep = np.ones(len(points), dtype=bool)
    for _ in range(rounds + 1):
        mean = points[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(points[keep] - mean, full_matrices=False)
        normal3 = vt[-1]
        distance = (points - mean) @ normal3
        spread = 1.4826 * float(np.median(np.abs(distance[keep])))
        keep = np.abs(distance) <= 3.0 * max(spread, 5e-6)
    horizontal = float(np.hypot(normal3[0], normal3[1]))
    n = normal3[:2] / horizontal
    slope = float(-normal3[2] / horizontal)
    # the plane n3·(p − mean) = 0 in the section z: n·p = n·mean_xy + slope·(z − mean_z)
    return n, float(n @ mean[:2]) - slope * float(mean[2]), slope, keep


def tangent_centre(normals: np.ndarray, offsets: np.ndarray, radius: float) -> np.ndarray:
    """Centre (k, 2) of the circle of ``radius`` (m) tangent to the lines nᵢ·p = dᵢ with
    inward unit normals ``normals`` (2, 2) and offsets ``offsets`` (k, 2) per height:
    nᵢ·c = dᵢ + r."""
    return np.linalg.solve(normals, (offsets + radius).T).T


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products over the last axis, broadcast."""
    return np.sum(a * b, axis=-1)


def _away(normals: np.ndarray, tip: np.ndarray) -> np.ndarray:
    """Unit directions (…, 2) along the lines of inward ``normals`` (…, 2), away from
    ``tip``."""
    away = np.stack([normals[..., 1], -normals[..., 0]], axis=-1)
    return np.where((_dot(away, tip) > 0.0)[..., None], -away, away)


def tip_and_half_angle(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unit direction (…, 2) from the centre to the tip of an edge whose lines have the
    inward unit ``normals`` (…, 2, 2), along the wedge's bisector, and the angle (…; rad)
    from the tip to either tangent point, (π − β)/2 for a wedge angle β."""
    tip = -(normals[..., 0, :] + normals[..., 1, :])
    tip = tip / np.linalg.norm(tip, axis=-1, keepdims=True)
    return tip, np.arccos(np.clip(-_dot(normals[..., 0, :], tip), -1.0, 1.0))


def edge_distance_at(xy: np.ndarray, centre: np.ndarray, radius: np.ndarray | float,
                     normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance (m, positive outside) of ``xy`` (n, 2) from an edge model given per
    point or shared — circle ``centre`` (n, 2; m) and ``radius`` (n, or scalar; m), inward
    unit normals ``normals`` (n, 2, 2 or 2, 2) of the two lines tangent to it,
    n·p = n·c − r —: the arc between the tangent points c − r·nᵢ, then the lines beyond them.
    Returns the distance, the mask of the points in the arc's sector (past both tangent
    points, towards the edge) and the index of the line each other point is measured from
    (−1 in the sector)."""
    tip = tip_and_half_angle(normals)[0]
    r = np.asarray(radius)
    shape = np.broadcast_shapes(xy.shape[:-1], np.shape(centre)[:-1], r.shape)
    sector = np.ones(shape, dtype=bool)
    line = np.full(shape, np.inf)
    which = np.full(shape, -1)
    for i in range(2):
        n = normals[..., i, :]
        past = _dot(xy - (centre - r[..., None] * n), _away(n, tip)) < 0.0
        sector &= past
        distance = _dot(centre - xy, n) - r  # positive outside the line
        beside = ~past & (np.abs(distance) < np.abs(line))
        line[beside] = distance[beside]
        which[beside] = i
    circle = np.linalg.norm(xy - centre, axis=-1) - r
    which[sector] = -1
    return np.where(which < 0, circle, line), sector, which


def edge_distance(xy: np.ndarray, normals: np.ndarray, offsets: np.ndarray, radius: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (m, positive outside) of ``xy`` (n, 2) from the edge model — the arc
    of the circle of ``radius`` tangent to both lines nᵢ·p = dᵢ (``offsets`` (n, 2) at each
    point's height), then the lines beyond the tangent points c − r·nᵢ — and the mask of the
    points in the arc's sector (:func:`edge_distance_at` with the same lines at every point)."""
    distance, sector, _ = edge_distance_at(xy, tangent_centre(normals, offsets, radius),
                                           radius, normals)
    return distance, sector


def fit_tangent_circle(xy: np.ndarray, normals: np.ndarray, offsets: np.ndarray,
                       bounds: tuple[float, float]) -> tuple[float, np.ndarray]:
    """Radius (m) of the circle tangent to both flank lines whose edge model
    (:func:`edge_distance`) best fits ``xy`` (n, 2; m) in the geometric sense (Chernov &
    Lesort 2005) with the soft-L1 loss Σ(√(1 + (d/δ)²) − 1), δ = :data:`SOFT_SCALE` (quadratic
    within the noise, linear beyond: Triggs et al. 2000, "Bundle adjustment — a modern
    synthesis", §6.8 on robust cost functions), over ``bounds`` (m); ``offsets`` (n, 2) are
    the lines' offsets at each point's height. Points beyond 3 robust standard deviations,
    and at least :data:`TRIM_FLOOR`, are left out and the fit repeated: the few points round
    a sparse edge must not count as stray ones against the many on the flanks, whose spread is
    the noise alone. Returns the radius
    and the mask of the points kept."""
    keep = np.ones(len(xy), dtype=bool)
    radius = 0.5 * (bounds[0] + bounds[1])
    for _ in range(3):
        def cost(r: float, use: np.ndarray = keep) -> float:
            ratio = edge_distance(xy[use], normals, offsets[use], r)[0] / SOFT_SCALE
            return float(np.sum(np.sqrt(1.0 + ratio * ratio) - 1.0))

        # the cost is piecewise (points enter and leave the arc's sector): a grid first
        # (every radius at once), then Brent's method within the best grid cell
        grid = np.linspace(bounds[0], bounds[1], SEARCH_GRID)
        centres = np.linalg.solve(normals, offsets[keep].T[None] + grid[:, None, None])
        ratio = edge_distance_at(xy[keep], centres.transpose(0, 2, 1), grid[:, None],
                                 normals)[0] / SOFT_SCALE
        best = int(np.argmin(np.sum(np.sqrt(1.0 + ratio * ratio) - 1.0, axis=-1)))
        cell = (grid[max(best - 1, 0)], grid[min(best + 1, SEARCH_GRID - 1)])
        radius = float(minimize_scalar(cost, bounds=cell, method="bounded",
                                       options={"xatol": 1e-8}).x)
        residual = edge_distance(xy, normals, offsets, radius)[0]
        spread = 1.4826 * float(np.median(np.abs(residual[keep])))
        new = np.abs(residual) <= max(3.0 * spread, TRIM_FLOOR)
        if new.sum() < MIN_ARC_POINTS or np.array_equal(new, keep):
            break
        keep = new
    return radius, keep


def refine_edge(xy: np.ndarray, dz: np.ndarray, normals: np.ndarray, d0: np.ndarray,
                d1: np.ndarray, radius: float, keep: np.ndarray, bounds: tuple[float, float]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The flank lines and the radius fitted together to the kept points ``xy`` (n, 2; m) at
    heights ``dz`` (m from the slab's middle): the composite distance of :func:`edge_distance`
    over the lines' angles, offsets d0 and slopes d1 and the radius, soft-L1 loss of scale
    :data:`SOFT_SCALE` (scipy ``least_squares``, trust-region reflective; Branch, Coleman & Li
    1999). In a thin wedge the tip moves along the bisector by δd / sin(β/2) for an error δd
    of either line: lines fitted to the flanks alone, a little away from the edge, put it off
    by several times the noise; fitted with the edge points they agree with them."""
    angles = np.arctan2(normals[:, 1], normals[:, 0])

    def unpack(x: np.ndarray) -> tuple:
        n = np.column_stack([np.cos(x[:2]), np.sin(x[:2])])
        return n, x[2:4], x[4:6], x[6]

    def residual(x: np.ndarray) -> np.ndarray:
        n, e0, e1, r = unpack(x)
        offsets = e0[None, :] + dz[keep, None] * e1[None, :]
        return edge_distance(xy[keep], n, offsets, r)[0] / SOFT_SCALE

    start = np.concatenate([angles, d0, d1, [radius]])
    lower = np.concatenate([angles - 0.2, d0 - 0.2e-3, d1 - 0.5, [bounds[0]]])
    upper = np.concatenate([angles + 0.2, d0 + 0.2e-3, d1 + 0.5, [bounds[1]]])
    result = least_squares(residual, start, bounds=(lower, upper), loss="soft_l1",
                           x_scale=np.concatenate([[1e-2, 1e-2], [1e-5, 1e-5], [1e-2, 1e-2],
                                                   [1e-5]]), max_nfev=50)
    n, e0, e1, r = unpack(result.x)
    return n, e0, e1, float(r)


def arc_length_at(xy: np.ndarray, centre: np.ndarray, radius: np.ndarray,
                  normals: np.ndarray) -> np.ndarray:
    """Arc length u (m) of the points ``xy`` (n, 2) along the edge model of
    :func:`edge_distance_at` (per point: ``centre`` (n, 2), ``radius`` (n,), ``normals``
    (n, 2, 2)) from its tip, negative towards line 0: r × the angle from the tip on the arc's
    sector, r·(π − β)/2 plus the distance along the line beyond it."""
    tip, half = tip_and_half_angle(normals)
    perp = np.column_stack([-tip[:, 1], tip[:, 0]])
    sign = np.where(-np.einsum("ij,ij->i", normals[:, 0], perp) > 0, 1.0, -1.0)  # line 0's side
    v = xy - centre
    u = radius * np.arctan2(-sign * np.einsum("ij,ij->i", v, perp), np.einsum("ij,ij->i", v, tip))
    along, distance = np.zeros((2, len(xy))), np.zeros((2, len(xy)))
    for i in range(2):
        n = normals[:, i]
        along[i] = np.einsum("ij,ij->i", v + radius[:, None] * n, _away(n, tip))
        distance[i] = np.abs(np.einsum("ij,ij->i", v, n) + radius)
    beside = along.max(axis=0) >= 0.0  # not past both tangent points: on a flank
    line = np.where((along[1] < 0.0) | ((along[0] >= 0.0) & (distance[0] <= distance[1])), 0, 1)
    flank_u = (radius * half + along[line, np.arange(len(xy))]) * np.where(line == 0, -1.0, 1.0)
    return np.where(beside, flank_u, u)
