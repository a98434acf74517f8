"""Reference spheres as registration datums: detection in a view, matching across views.

Metrology scans link their views through artefacts every view sees: matte spheres on the
fixture (the sphere standards of VDI/VDE 2634-2/-3). A sphere's centre is a point fixed to the
part that a partial view of its surface determines to a few µm, so the centres seen by two views
tie their poses in every direction — also in the one a nearly extruded blade leaves free.

Detection (:func:`detect_spheres`) knows the nominal radius r (the user knows the artefact):
every point with its normal turned towards the camera proposes the centre p − r n (a minimal
set of one oriented point, as the sphere primitive of Schnabel, Wahl & Klein 2007, "Efficient
RANSAC for point-cloud shape detection", with the radius given); the densest cluster of
proposals seeds a least-squares fit of the centre with the radius fixed (geometric distances,
Gauss-Newton; Forbes 1989, NPL report DITC 140/89) on a shrinking shell of points. A fit is
accepted only when enough points lie within the shell and concentrate on the sphere, (almost)
none lies inside it (a solid sphere hides its inside; a surface through the ball does not),
they cover a cap in two directions (a cylinder of radius r matches only along a band) and a
fit with the radius free agrees with r.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations, permutations

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.rigid import kabsch, pose_matrix, transform


@dataclass(frozen=True)
class SphereFit:
    """A reference sphere found in one view (view frame, m).

    ``centre`` (3,), its ``covariance`` (3×3, m²) from the fit's residuals, ``radius`` the
    nominal radius the fit used, ``free_radius`` the radius of a fit with the radius free,
    ``rms`` the RMS distance of its points from the sphere and ``points`` the indices of the
    view's points on it (within the shell).
    """

    centre: np.ndarray
    covariance: np.ndarray
    radius: float
    free_radius: float
    rms: float
    points: np.ndarray


def fit_sphere(points: np.ndarray, radius: float, start: np.ndarray, iterations: int = 20
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares centre of a sphere of known ``radius`` through ``points`` (m), from
    ``start``: minimises Σ (|p − c| − r)² by Gauss-Newton.

    Returns ``(centre, covariance (3×3, m²: s² (JᵀJ)⁻¹ with s² the residual variance),
    residuals (m))``.
    """
    points = np.asarray(points, dtype=np.float64)
    if len(points) < 4:
        raise ValueError(f"a sphere fit needs at least 4 points (got {len(points)})")
    centre = np.asarray(start, dtype=np.float64).copy()
    for _ in range(iterations):
        offset = points - centre
        distance = np.linalg.norm(offset, axis=1)
        residual = distance - radius
        jacobian = -offset / distance[:, None]
        step = np.linalg.lstsq(jacobian, -residual, rcond=None)[0]
        centre += step
        if np.linalg.norm(step) < 1e-10:
            break
    offset = points - centre
    distance = np.linalg.norm(offset, axis=1)
    residual = distance - radius
    jacobian = offset / distance[:, None]
    variance = float(residual @ residual) / max(len(points) - 3, 1)
    return centre, variance * np.linalg.inv(jacobian.T @ jacobian), residual


def free_radius_fit(points: np.ndarray, start: np.ndarray, radius: float,
                    iterations: int = 20) -> tuple[np.ndarray, float]:
    """Least-squares centre and radius (m) of a sphere through ``points`` from ``start`` and
    ``radius`` (Gauss-Newton on the geometric distances)."""
    centre = np.asarray(start, dtype=np.float64).copy()
    for _ in range(iterations):
        offset = points - centre
        distance = np.linalg.norm(offset, axis=1)
        jacobian = np.column_stack([-offset / distance[:, None], -np.ones(len(points))])
        step = np.linalg.lstsq(jacobian, radius - distance, rcond=None)[0]
        centre += step[:3]
        radius += float(step[3])
        if np.linalg.norm(step) < 1e-10:
            break
    return centre, radius


def _oriented_normals(points: np.ndarray, neighbours: int = 15) -> np.ndarray:
    """Unit normals by local PCA, turned towards the camera at the origin."""
    _, index = cKDTree(points).query(points, k=neighbours, workers=-1)
    nbr = points[index] - points[index].mean(axis=1, keepdims=True)
    _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", nbr, nbr))
    normals = vectors[:, :, 0]
    flip = np.einsum("ij,ij->i", normals, points) > 0.0  # camera at the origin
    normals[flip] *= -1.0
    return normals


def detect_spheres(points: np.ndarray, radius: float, tolerance: float = 0.1e-3,
                   min_points: int = 30, min_spread: float = 0.02,
                   radius_tolerance: float = 0.02, attempts: int = 20) -> list[SphereFit]:
    """The reference spheres of known ``radius`` (m) in one view (points in the scanner's frame,
    camera at the origin).

    ``tolerance`` is the shell half-width (m) within which points belong to a sphere (twice the
    scanner's error bound); a fit is kept when at least ``min_points`` points lie within it with
    an RMS distance below ``tolerance``/3, fewer than 5 % as many lie inside the sphere, the
    variance of their directions from the centre, projected on the plane normal to their mean,
    is at least ``min_spread`` both ways (≈ a cap of 16° half-angle; a band round a cylinder
    spreads one way)
    and the free-radius fit lies within ``radius_tolerance`` (relative) of ``radius``. At most
    ``attempts`` candidate clusters are tried. Returns the fits, largest first.
    """
    points = np.asarray(points, dtype=np.float64)
    if radius <= 0.0 or tolerance <= 0.0:
        raise ValueError(f"sphere radius and tolerance must be positive (got {radius}, "
                         f"{tolerance} m)")
    if len(points) < max(min_points, 15):
        return []
    proposals = points - radius * _oriented_normals(points)
    cluster = 0.1 * radius  # proposals of one sphere scatter by r × the normals' error
    support = cKDTree(proposals).query_ball_point(proposals, cluster, return_length=True,
                                                  workers=-1)
    tree = cKDTree(points)
    free = np.ones(len(points), dtype=bool)
    fits: list[SphereFit] = []
    for _ in range(attempts):
        live = np.flatnonzero(free & (support >= min_points // 4))
        if len(live) == 0:
            break
        seed = proposals[live[np.argmax(support[live])]]
        fit = _fit_from(points, tree, free, seed, radius, tolerance, min_points, min_spread,
                        radius_tolerance)
        if fit is None:  # not a sphere: drop the proposals of this cluster
            support[np.linalg.norm(proposals - seed, axis=1) < 2.0 * cluster] = 0
            continue
        fits.append(fit)
        free[fit.points] = False
        support[np.linalg.norm(proposals - fit.centre, axis=1) < radius] = 0
    return sorted(fits, key=lambda f: -len(f.points))


def _fit_from(points: np.ndarray, tree: object, free: np.ndarray, seed: np.ndarray,
              radius: float, tolerance: float, min_points: int, min_spread: float,
              radius_tolerance: float) -> SphereFit | None:
    """Fit on a shell shrinking from 0.1 r to ``tolerance`` about ``seed``; None if the points
    fail the acceptance tests of :func:`detect_spheres`."""
    centre = seed
    chosen = np.empty(0, dtype=np.int64)
    for shell in (0.1 * radius, 0.03 * radius + tolerance, tolerance, tolerance):
        near = np.asarray(tree.query_ball_point(centre, radius + shell), dtype=np.int64)
        near = near[free[near]]
        distance = np.linalg.norm(points[near] - centre, axis=1)
        chosen = near[np.abs(distance - radius) <= shell]
        if len(chosen) < min_points:
            return None
        centre, covariance, residual = fit_sphere(points[chosen], radius, centre)
    if np.sqrt(np.mean(residual**2)) > tolerance / 3.0:
        return None  # points spread through the shell (RMS tolerance/√3), not on a sphere
    inside = np.asarray(tree.query_ball_point(centre, radius - tolerance), dtype=np.int64)
    if len(inside) > 0.05 * len(chosen):
        return None  # a solid sphere hides its inside: a surface passes through the ball
    directions = points[chosen] - centre
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    # spread in the plane normal to the mean direction: both ways for a cap, one for a band
    mean = directions.mean(axis=0)
    tangent = np.linalg.svd(np.eye(3) - np.outer(mean, mean) / (mean @ mean))[0][:, :2]
    if np.linalg.eigvalsh(np.cov((directions @ tangent).T))[0] < min_spread:
        return None
    _, free_radius = free_radius_fit(points[chosen], centre, radius)
    if abs(free_radius - radius) > radius_tolerance * radius:
        return None
    return SphereFit(centre=centre, covariance=covariance, radius=radius,
                     free_radius=free_radius, rms=float(np.sqrt(np.mean(residual**2))),
                     points=chosen)


def match_spheres(fits: Sequence[Sequence[SphereFit]], poses: Sequence[np.ndarray],
                  distance: float = 2e-3) -> list[list[tuple[int, int]]]:
    """Group the spheres found in the views into physical spheres.

    ``fits[k]`` are the spheres of view k, ``poses[k]`` (4×4) its pose estimate (view -> a
    common frame, e.g. the scanner's tracking); centres that land within ``distance`` (m) of
    each other there are one sphere. Returns, per sphere, its ``(view, fit index)`` pairs; a
    sphere only one view found has one pair.

    Raises ``ValueError`` when two spheres of one view, or two distinct groups, land together
    (spheres closer than ``distance`` or a wrong pose estimate).
    """
    if len(fits) != len(poses):
        raise ValueError(f"{len(fits)} views of spheres for {len(poses)} poses")
    groups: list[list[tuple[int, int, np.ndarray]]] = []
    for k, (view, pose) in enumerate(zip(fits, poses, strict=True)):
        pose = np.asarray(pose, dtype=np.float64)
        for i, fit in enumerate(view):
            centre = pose[:3, :3] @ fit.centre + pose[:3, 3]
            home = [g for g in groups
                    if min(np.linalg.norm(c - centre) for _, _, c in g) < distance]
            if len(home) > 1:
                raise ValueError(f"sphere {i} of view {k} lies within {distance * 1e3:.1f} mm "
                                 "of two distinct spheres: spheres too close or poses wrong")
            if home and any(j == k for j, _, _ in home[0]):
                raise ValueError(f"two spheres of view {k} lie within {distance * 1e3:.1f} mm "
                                 "of each other: not distinct reference spheres")
            if home:
                home[0].append((k, i, centre))
            else:
                groups.append([(k, i, centre)])
    return [[(k, i) for k, i, _ in group] for group in groups]


def poses_from_spheres(fits: Sequence[Sequence[SphereFit]], tolerance: float = 0.2e-3
                       ) -> dict[int, np.ndarray]:
    """Poses (4×4, view -> frame of view 0) from the reference spheres alone, for views
    without a pose estimate.

    Two views are matched by the distances between their sphere centres, which a rigid motion
    keeps: the largest assignment of at least 3 spheres whose distances agree within
    ``tolerance`` (m), refused when two assignments fit equally (a symmetric layout); the pair
    is posed by the least-squares fit of the matched centres (Kabsch). Views are chained from
    view 0 along the pairs that share the most spheres (a maximum spanning tree). Views not
    linked to view 0 this way are left out.
    """
    count = len(fits)
    centres = [np.array([f.centre for f in view]).reshape(-1, 3) for view in fits]
    links: dict[tuple[int, int], tuple[int, np.ndarray]] = {}
    for a in range(count):
        for b in range(a + 1, count):
            pose = _pair_from_centres(centres[b], centres[a], tolerance)
            if pose is not None:
                links[(a, b)] = pose
    poses = {0: np.eye(4)} if count else {}
    while True:
        best = None
        for (a, b), (shared, pose) in links.items():
            if (a in poses) != (b in poses) and (best is None or shared > best[0]):
                best = (shared, a, b, pose)
        if best is None:
            return poses
        _, a, b, pose = best  # pose: view b -> view a
        if a in poses:
            poses[b] = poses[a] @ pose
        else:
            poses[a] = poses[b] @ np.linalg.inv(pose)


def _pair_from_centres(source: np.ndarray, target: np.ndarray, tolerance: float
                       ) -> tuple[int, np.ndarray] | None:
    """(matched spheres, 4×4 source -> target) from sphere centres, or None."""
    d_source = np.linalg.norm(source[:, None] - source[None], axis=2)
    d_target = np.linalg.norm(target[:, None] - target[None], axis=2)
    for size in range(min(len(source), len(target)), 2, -1):
        found = []
        for picked in combinations(range(len(target)), size):
            sub_target = d_target[np.ix_(picked, picked)]
            for order in permutations(range(len(source)), size):
                if np.abs(d_source[np.ix_(order, order)] - sub_target).max() <= tolerance:
                    found.append((list(order), list(picked)))
        if len(found) > 1:
            return None  # two assignments fit: the layout does not fix the pose
        if found:
            order, picked = found[0]
            p, q = source[order], target[picked]
            pose = pose_matrix(*kabsch(p, q))
            if np.linalg.norm(transform(p, pose) - q, axis=1).max() > tolerance:
                return None  # the distances agree but only for a mirror image
            return size, pose
    return None
