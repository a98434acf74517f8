"""Point-cloud filters: statistical outliers, moving-least-squares smoothing, local PCA frames
(and the plane basis normal to a direction), neighbour distances and feature-preserving voxel
downsampling (lengths in m).

Each returns its result and, where points go, which ones; open3d does the statistical outlier
search, scipy's k-d tree the rest; MLS smoothing is a small numpy implementation (open3d has none).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree


def open3d_cloud(points: np.ndarray) -> object:
    """An open3d ``PointCloud`` of (n, 3) points (m)."""
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, np.float64)))


def neighbour_mean_distances(points: np.ndarray, neighbours: int = 50) -> np.ndarray:
    """Mean distance (m) of every point to its ``neighbours`` nearest *other* points (exact
    k-d tree search, scipy's ``cKDTree`` on all cores)."""
    points = np.asarray(points, dtype=np.float64)
    distance = cKDTree(points).query(points, k=neighbours + 1, workers=-1)[0]
    return distance[:, 1:].mean(axis=1)  # column 0: the point itself (or a duplicate), at 0


def remove_statistical_outliers(points: np.ndarray, neighbours: int = 50,
                                std_ratio: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Statistical outlier removal (Rusu et al. 2008, PCL's ``StatisticalOutlierRemoval``):
    drop the points whose mean distance to their ``neighbours`` nearest other points
    (:func:`neighbour_mean_distances`) exceeds the mean of those distances over the cloud plus
    ``std_ratio`` sample standard deviations (n − 1).

    open3d's ``remove_statistical_outlier(nb_neighbors=k)`` counts the point itself among its k
    neighbours (its first, at distance 0), i.e. it averages over k − 1 other points and a zero.
    Every mean is then scaled by the same (k − 1)/k, which leaves the test unchanged, so
    ``nb_neighbors = neighbours + 1`` keeps exactly the points of this definition (open3d keeps
    strictly below the threshold, PCL at or below it; a tie has probability zero) — checked
    point for point against a brute-force reference in the tests. That call does the work here:
    its multi-threaded k-d tree is faster than scipy's.

    Returns ``(kept points, boolean mask of the kept points)``.
    """
    points = np.asarray(points)
    if len(points) <= neighbours:
        raise ValueError(f"statistical outlier removal needs more than {neighbours} points "
                         f"(got {len(points)})")
    _, kept = open3d_cloud(points).remove_statistical_outlier(nb_neighbors=neighbours + 1,
                                                        std_ratio=std_ratio)
    mask = np.zeros(len(points), dtype=bool)
    mask[np.asarray(kept, dtype=np.int64)] = True
    return points[mask], mask


def local_frames(points: np.ndarray, neighbours: int, viewpoint: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbour indices (n, k), unit normals (n, 3) and surface variation (n,) by local PCA.

    The surface variation λ0 / (λ0 + λ1 + λ2) (Pauly, Gross & Kobbelt 2002) is the curvature
    measure. Normals point towards ``viewpoint`` when given.
    """
    _, index = cKDTree(points).query(points, k=neighbours)
    nbr = points[index]
    centred = nbr - nbr.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", centred, centred) / neighbours
    values, vectors = np.linalg.eigh(cov)
    normals = vectors[:, :, 0]
    variation = values[:, 0] / np.maximum(values.sum(axis=1), 1e-300)
    if viewpoint is not None:
        flip = np.einsum("ij,ij->i", normals, viewpoint - points) < 0.0
        normals[flip] *= -1.0
    return index, normals, variation


def plane_basis(normal: np.ndarray) -> np.ndarray:
    """Two unit vectors (2, 3) spanning the plane normal to the unit ``normal`` (3,): with it,
    a right-handed orthonormal basis."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    first = np.cross(normal, helper)
    first /= np.linalg.norm(first)
    return np.array([first, np.cross(normal, first)])


def mls_smooth(points: np.ndarray, neighbours: int = 30, max_shift: float = 0.05e-3
               ) -> np.ndarray:
    """Moving-least-squares projection (Alexa et al. 2003; Levin 1998): each point moves onto
    the quadratic height field fitted, with Gaussian weights, to its ``neighbours`` nearest in
    their local PCA frame. Keeps the count and order of the points.

    Feature-preserving: a point whose projection would move it more than ``max_shift`` (m; the
    scanner's error bound) sits on a crease the quadratic cannot follow (cap rims, the trailing
    edge) and stays where it is.
    """
    index, normals, _ = local_frames(points, neighbours)
    nbr = points[index] - points[:, None, :]
    # tangent basis of each local frame
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(normals, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    u = np.einsum("nkj,nj->nk", nbr, t1)
    v = np.einsum("nkj,nj->nk", nbr, t2)
    w = np.einsum("nkj,nj->nk", nbr, normals)
    h2 = np.maximum(np.mean(u * u + v * v, axis=1, keepdims=True), 1e-30)
    weight = np.exp(-(u * u + v * v) / h2)
    basis = np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=2)
    bw = basis * weight[..., None]
    normal_matrix = np.einsum("nki,nkj->nij", bw, basis) + 1e-12 * np.eye(6)
    rhs = np.einsum("nki,nk->ni", bw, w)
    coef = np.linalg.solve(normal_matrix, rhs[..., None])[..., 0]
    shift = coef[:, 0]  # height of the fitted surface at u = v = 0
    shift = np.where(np.abs(shift) <= max_shift, shift, 0.0)
    return points + shift[:, None] * normals


def median_spacing(points: np.ndarray, tree: cKDTree | None = None, samples: int = 5000,
                   stride: int | None = None) -> float:
    """Median distance (m) to the nearest other point, over up to ``samples`` points (every
    ⌈n / samples⌉-th, or every ``stride``-th when given); ``tree`` a k-d tree of ``points``
    when one exists already."""
    tree = tree if tree is not None else cKDTree(points)
    step = stride if stride is not None else max(1, math.ceil(len(points) / samples))
    return float(np.median(tree.query(points[::step], k=2)[0][:, 1]))


def feature_preserving_downsample(points: np.ndarray, target: int, feature_share: float = 0.25,
                                  neighbours: int = 20) -> np.ndarray:
    """Thin ``points`` to about ``target`` points, keeping high-curvature regions dense.

    The ``feature_share`` of the budget goes to the points of highest surface variation
    (leading/trailing edges, cap rims), thinned on a fine voxel grid; the rest of the budget
    thins the remaining points on a coarser voxel grid sized by bisection to hit ``target``.
    Returns the kept points (a subset of the input, no new coordinates).
    """
    if target >= len(points):
        return points
    _, _, variation = local_frames(points, neighbours)
    order = np.argsort(-variation)
    feature = np.zeros(len(points), dtype=bool)
    feature[order[: int(0.2 * len(points))]] = True  # the most curved fifth of the cloud
    kept_feature = voxel_thin(points[feature], round(feature_share * target))
    kept_rest = voxel_thin(points[~feature], target - len(kept_feature))
    return np.concatenate([kept_feature, kept_rest])


def voxel_thin(points: np.ndarray, target: int) -> np.ndarray:
    """One point per voxel (the one nearest the voxel centre), voxel size bisected to ~target."""
    if target >= len(points):
        return points
    extent = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    lo, hi = extent * 1e-6, extent
    best = points
    for _ in range(40):
        size = np.sqrt(lo * hi)
        kept = voxel_pick(points, size)
        if len(kept) > target:
            lo = size
        else:
            hi = size
            best = kept
        if abs(len(kept) - target) <= 0.01 * target:
            return kept
    return best


def voxel_pick(points: np.ndarray, size: float) -> np.ndarray:
    """One point per cubic voxel of edge ``size`` (m): the one nearest the voxel centre."""
    cell = np.floor(points / size).astype(np.int64)
    offset = np.linalg.norm(points / size - cell - 0.5, axis=1)
    order = np.lexsort((offset, cell[:, 2], cell[:, 1], cell[:, 0]))
    sorted_cells = cell[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(sorted_cells[1:] != sorted_cells[:-1], axis=1)
    return points[order[first]]
