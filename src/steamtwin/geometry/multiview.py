"""Joint multi-view registration: point-to-plane ICP of all views at once, with the scanner's
tracked poses as a prior and reference-sphere centres as datums (lengths in m, angles in rad).

Poses are 4×4 matrices, view -> frame of view 0 (:mod:`steamtwin.geometry.rigid`); the pairwise
steps that start it are in :mod:`steamtwin.geometry.registration`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.rigid import rotation_from_vector, rotation_vector, skew, transform


def multiview_icp(views: Sequence[np.ndarray], normals: Sequence[np.ndarray],
                  poses: Sequence[np.ndarray], distance: float, iterations: int = 30,
                  prior: Sequence[np.ndarray] | None = None, prior_angle: float = 5e-4,
                  prior_offset: float = 0.05e-3, min_pairs: int = 200,
                  tolerance: float = 1e-7, stability: float = 0.0,
                  centres: Sequence[Sequence[tuple[int, np.ndarray, np.ndarray]]] | None = None
                  ) -> tuple[list[np.ndarray], dict]:
    """Joint point-to-plane ICP of all views at once (simultaneous multi-view registration:
    Bergevin, Soucy, Gagnon & Laurendeau 1996, IEEE PAMI 18(5); Pulli 1999, 3DIM).

    Every ordered pair of overlapping views contributes the point-to-plane residuals of the
    first view's points against the second's tangent planes (``normals``, oriented towards
    each view's camera; pairs with normals more than 60° apart are dropped: on a thin blade the
    nearest point may lie on the opposite face); one Gauss-Newton step then moves all poses
    (6 (N − 1) unknowns, view 0 fixed: the gauge) together, so that a direction one pair cannot
    fix (the shift along the span of two views without a cap) is fixed by the others.
    Residuals are weighted by Huber's function (k = 1.345 robust σ) and correspondences farther
    than ``distance`` (m) or 3 robust σ are dropped. With ``prior`` (the scanner's own pose
    estimates, view -> the frame of view 0), each pose also carries a Gaussian prior of
    ``prior_angle`` (rad) and ``prior_offset`` (m) standard deviation about it: a maximum a
    posteriori estimate, which leaves the estimate at the prior only in directions the scans
    do not constrain. With ``stability`` > 0 the step is taken only along eigenvectors of the
    joint normal matrix whose eigenvalue exceeds ``stability`` × the largest (degeneracy-aware
    solving, Zhang, Kaess & Singh 2016); weaker directions keep their starting value.

    ``centres`` are datums seen by several views, e.g. reference spheres: per datum, the
    ``(view, centre (3,) in the view frame, covariance (3×3, m²))`` of every view that sees it.
    Each pair of those views adds the difference of the two placements of the centre, weighted
    by the inverse of the sum of the two covariances × 2/m (m views; for equal covariances
    exactly the cost of fitting one unknown centre to the m placements), so the datums tie the
    views also along directions the surfaces leave free. Returns ``(poses, figures)``, figures
    holding the linked view pairs, correspondences, the RMS residual (m), the iterations used,
    the number of weak directions and, with ``centres``, the RMS distance between two
    placements of a datum (``centre_rms``, m).
    """
    count = len(views)
    poses = [np.asarray(p, dtype=np.float64).copy() for p in poses]
    trees = [cKDTree(v) for v in views]
    centre = np.mean([transform(v, p).mean(axis=0) for v, p in zip(views, poses, strict=True)],
                     axis=0)
    length = float(np.sqrt(np.mean([np.sum((transform(v, p) - centre) ** 2, axis=1).mean()
                                    for v, p in zip(views, poses, strict=True)])))
    figures: dict = {"iterations": 0, "correspondences": 0, "rms": math.inf, "pairs": 0}
    sigma = distance / 3.0
    apart: set[tuple[int, int]] = set()
    for iteration in range(iterations):
        hessian = np.zeros((6 * count, 6 * count))
        gradient = np.zeros(6 * count)
        moved = [transform(v, p) for v, p in zip(views, poses, strict=True)]
        turned = [n @ p[:3, :3].T for n, p in zip(normals, poses, strict=True)]
        residuals = []
        linked = set()
        for i in range(count):
            for j in range(count):
                if i == j or (i, j) in apart:
                    continue
                local = transform(moved[i], np.linalg.inv(poses[j]))
                d, idx = trees[j].query(local, distance_upper_bound=distance, workers=-1)
                ok = np.flatnonzero(np.isfinite(d))
                if len(ok) < min_pairs:
                    if iteration == 0:  # views that do not overlap at the start never will
                        apart.add((i, j))
                    continue
                idx = idx[ok]
                n = turned[j][idx]
                ok_normal = np.einsum("ij,ij->i", turned[i][ok], n) > 0.5
                ok, idx, n = ok[ok_normal], idx[ok_normal], n[ok_normal]
                if len(ok) < min_pairs:
                    continue
                p_i, q_j = moved[i][ok] - centre, moved[j][idx] - centre
                r = np.einsum("ij,ij->i", p_i - q_j, n)
                keep = np.abs(r) <= 3.0 * sigma if iteration > 0 else np.ones(len(r), bool)
                p_i, q_j, n, r = p_i[keep], q_j[keep], n[keep], r[keep]
                residuals.append(r)
                linked.add((min(i, j), max(i, j)))
                a = np.column_stack([np.cross(p_i, n) / length, n])
                b = -np.column_stack([np.cross(q_j, n) / length, n])
                w = np.minimum(1.0, 1.345 * sigma / np.maximum(np.abs(r), 1e-300))
                si, sj = slice(6 * i, 6 * i + 6), slice(6 * j, 6 * j + 6)
                wa, wb = a * w[:, None], b * w[:, None]
                hessian[si, si] += a.T @ wa
                hessian[sj, sj] += b.T @ wb
                hessian[si, sj] += wa.T @ b
                hessian[sj, si] += wb.T @ a
                gradient[si] -= wa.T @ r
                gradient[sj] -= wb.T @ r
        if not residuals:
            raise ValueError("no two views overlap: the views cannot be registered jointly")
        all_r = np.concatenate(residuals)
        sigma = max(1.4826 * float(np.median(np.abs(all_r))), 1e-7)
        hessian /= sigma**2
        gradient /= sigma**2
        if centres:
            figures["centre_rms"] = _add_centre_links(hessian, gradient, centres, poses, centre,
                                                      length)
        if prior is not None:
            for k in range(1, count):
                error = _pose_difference(poses[k], np.asarray(prior[k], dtype=np.float64),
                                         centre, length)
                weight = np.array([1.0 / (prior_angle * length) ** 2] * 3
                                  + [1.0 / prior_offset**2] * 3)
                sk = slice(6 * k, 6 * k + 6)
                hessian[sk, sk] += np.diag(weight)
                gradient[sk] -= weight * error
        step = np.zeros(6 * count)
        values, vectors = np.linalg.eigh(hessian[6:, 6:])
        keep = values > stability * values[-1]
        step[6:] = vectors[:, keep] @ ((vectors[:, keep].T @ gradient[6:]) / values[keep])
        figures["weak_directions"] = int(np.sum(~keep))
        for k in range(1, count):
            delta = step[6 * k: 6 * k + 6]
            update = np.eye(4)
            update[:3, :3] = rotation_from_vector(delta[:3] / length)
            update[:3, 3] = delta[3:] + centre - update[:3, :3] @ centre
            poses[k] = update @ poses[k]
        figures.update({"iterations": iteration + 1, "correspondences": len(all_r),
                        "pairs": len(linked),
                        "rms": float(np.sqrt(np.mean(all_r**2)))})
        if np.abs(step).max() < tolerance:
            break
    return poses, figures


def _add_centre_links(hessian: np.ndarray, gradient: np.ndarray,
                      centres: Sequence[Sequence[tuple[int, np.ndarray, np.ndarray]]],
                      poses: Sequence[np.ndarray], centre: np.ndarray, length: float) -> float:
    """Add the datum terms of :func:`multiview_icp` to its normal equations (in place); returns
    the RMS distance (m) between two views' placements of a datum."""
    distances = []
    for datum in centres:
        weight_share = 2.0 / len(datum)
        placed = []
        for k, point, covariance in datum:
            rotation = poses[k][:3, :3]
            where = rotation @ point + poses[k][:3, 3]
            # a pose step (rotation vector × length, translation) moves the point by this
            jacobian = np.column_stack([-skew(where - centre) / length, np.eye(3)])
            placed.append((k, where, rotation @ covariance @ rotation.T, jacobian))
        for a, (i, p_i, cov_i, jac_i) in enumerate(placed):
            for j, p_j, cov_j, jac_j in placed[a + 1:]:
                residual = p_i - p_j
                weight = weight_share * np.linalg.inv(cov_i + cov_j)
                si, sj = slice(6 * i, 6 * i + 6), slice(6 * j, 6 * j + 6)
                hessian[si, si] += jac_i.T @ weight @ jac_i
                hessian[sj, sj] += jac_j.T @ weight @ jac_j
                hessian[si, sj] -= jac_i.T @ weight @ jac_j
                hessian[sj, si] -= jac_j.T @ weight @ jac_i
                gradient[si] -= jac_i.T @ weight @ residual
                gradient[sj] += jac_j.T @ weight @ residual
                distances.append(float(np.linalg.norm(residual)))
    return float(np.sqrt(np.mean(np.square(distances)))) if distances else math.nan



def _pose_difference(pose: np.ndarray, reference: np.ndarray, centre: np.ndarray,
                     length: float) -> np.ndarray:
    """The small motion (rotation vector × ``length``, translation at ``centre``; m) taking
    ``pose`` to ``reference``: reference ≈ exp(motion) · pose."""
    motion = reference @ np.linalg.inv(pose)
    vector = rotation_vector(motion[:3, :3])
    shift = motion[:3, :3] @ centre + motion[:3, 3] - centre
    return np.concatenate([vector * length, shift])
