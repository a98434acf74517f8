"""Point-cloud preprocessing: reference spheres, outliers, smoothing, registration, fusion,
downsampling.

Every step returns its result and what it removed or changed, so a report can account for each
point. open3d does the neighbour searches, features and registration; moving-least-squares
smoothing is a small numpy implementation (open3d has none).

View frames are the scanner's own (camera at the origin), as written by
:mod:`steamtwin.geometry.scanner` and by real handheld scanners; normals are oriented towards it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from steamtwin.geometry.pointcloud import check_point_cloud
from steamtwin.geometry.targets import (
    SphereFit,
    detect_spheres,
    fit_sphere,
    match_spheres,
    poses_from_spheres,
)

#: Share of the scanned blade points that the fused, downsampled cloud keeps by default: the
#: method's ~150k scanned points per blade → ~80k after feature-preserving downsampling.
KEPT_SHARE = 80_000 / 150_000


@dataclass(frozen=True)
class PreprocessSettings:
    """Hyper-parameters of :func:`preprocess_views` (lengths in m).

    ``voxel`` is the feature scale for FPFH/RANSAC; ``icp_distance`` the ICP correspondence
    cut-off; ``target_points`` the size of the fused, downsampled cloud (None:
    :data:`KEPT_SHARE` of the scanned blade points, i.e. of the input less the reference
    spheres' points — the method's ~150k → ~80k at any scan density). ``sphere_radius`` is
    the nominal radius of the reference spheres on the fixture (default 5 mm, the virtual
    scanner's spheres on hp1; a scan folder's ``scan.json`` records its own; None: no sphere
    detection), ``sphere_tolerance`` the shell half-width of a sphere's points
    (twice the scanner's ±0.05 mm bound), ``sphere_min_points`` the fewest points a sphere is
    accepted with and ``sphere_match_distance`` how close (in the frame of the starting poses)
    two views' centres of one sphere must land (see :mod:`steamtwin.geometry.targets`).
    """

    outlier_neighbours: int = 50
    outlier_std_ratio: float = 2.0
    mls_neighbours: int = 30
    mls_max_shift: float = 0.05e-3  # the scanner's error bound
    voxel: float = 1.0e-3
    icp_distance: float = 0.4e-3
    ransac_iterations: int = 200_000
    min_overlap: float = 0.3  # overlap share below which a pair of views is not linked
    hypotheses: int = 4  # RANSAC runs (seeds) per view
    stability: float = 0.1  # ICP moves only along directions this well constrained (share)
    max_violation: float = 0.10  # free-space violation share above which a pose is rejected
    target_points: int | None = None
    feature_share: float = 0.25  # share of the kept points reserved for high-curvature regions
    joint_iterations: int = 12  # Gauss-Newton steps of the joint multi-view ICP
    joint_stability: float = 1e-3  # joint ICP keeps directions weaker than this share fixed
    sphere_radius: float | None = 5e-3
    sphere_tolerance: float = 0.1e-3
    sphere_min_points: int = 30
    sphere_match_distance: float = 2e-3


@dataclass
class PreprocessReport:
    """What each step did (counts of points; lengths in m).

    ``spheres_found`` and ``sphere_points_removed`` are per view; ``spheres_matched`` counts the
    reference spheres found by two or more views (the registration's datums), ``spheres_single``
    those only one view found (removed, not datums), and ``sphere_rms`` is the RMS distance
    between two views' placements of one sphere's centre after registration (NaN without).
    """

    input_points: list[int] = field(default_factory=list)
    spheres_found: list[int] = field(default_factory=list)
    sphere_points_removed: list[int] = field(default_factory=list)
    spheres_matched: int = 0
    spheres_single: int = 0
    sphere_rms: float = float("nan")
    outliers_removed: list[int] = field(default_factory=list)
    smoothing_mean_shift: list[float] = field(default_factory=list)
    pair_fitness: dict[str, float] = field(default_factory=dict)
    pair_rmse: dict[str, float] = field(default_factory=dict)
    pose_graph_edges: int = 0
    pose_graph_pruned: int = 0
    joint_rms: float = float("nan")
    joint_weak_directions: int = 0
    fused_points: int = 0
    downsampled_points: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def _cloud(points: np.ndarray) -> object:
    import open3d as o3d

    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, np.float64)))


def neighbour_mean_distances(points: np.ndarray, neighbours: int = 50) -> np.ndarray:
    """Mean distance (m) of every point to its ``neighbours`` nearest *other* points (exact
    k-d tree search, scipy's ``cKDTree`` on all cores)."""
    from scipy.spatial import cKDTree

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
    _, kept = _cloud(points).remove_statistical_outlier(nb_neighbors=neighbours + 1,
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
    from scipy.spatial import cKDTree

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


def _features(points: np.ndarray, voxel: float, normals: np.ndarray | None = None
              ) -> tuple[object, object]:
    """Voxel-downsampled cloud and its FPFH features (Rusu, Blodow & Beetz 2009).

    Normals are estimated and turned towards the camera at the origin, unless given (a fused
    model carries each view's normals, oriented towards that view's camera).
    """
    import open3d as o3d

    cloud = _cloud(points)
    if normals is not None:
        cloud.normals = o3d.utility.Vector3dVector(normals)
    cloud = cloud.voxel_down_sample(voxel)
    if normals is None:
        cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2.5 * voxel,
                                                                    max_nn=30))
        cloud.orient_normals_towards_camera_location(np.zeros(3))
    else:
        cloud.normalize_normals()
    feature = o3d.pipelines.registration.compute_fpfh_feature(
        cloud, o3d.geometry.KDTreeSearchParamHybrid(radius=6.0 * voxel, max_nn=100))
    return cloud, feature


def coarse_registration(source: np.ndarray, target: np.ndarray, voxel: float,
                        iterations: int = 200_000, seed: int = 0,
                        target_normals: np.ndarray | None = None) -> np.ndarray:
    """FPFH features matched by RANSAC: a 4×4 source -> target guess.

    The source is a view in its scanner frame (camera at the origin); ``target_normals``
    gives the target's oriented normals when it is not (a fused model).
    """
    import open3d as o3d

    reg = o3d.pipelines.registration
    o3d.utility.random.seed(seed)
    src, src_f = _features(source, voxel)
    tgt, tgt_f = _features(target, voxel, target_normals)
    result = reg.registration_ransac_based_on_feature_matching(
        src, tgt, src_f, tgt_f, False, 1.5 * voxel,
        reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9),
         reg.CorrespondenceCheckerBasedOnDistance(1.5 * voxel)],
        reg.RANSACConvergenceCriteria(iterations, 0.999))
    return np.asarray(result.transformation)


def refine_registration(source: np.ndarray, target: np.ndarray, initial: np.ndarray,
                        distance: float, target_normals: np.ndarray | None = None,
                        scales: Sequence[float] = (4.0, 2.0, 1.0)
                        ) -> tuple[np.ndarray, float, float, np.ndarray]:
    """Point-to-plane ICP (Chen & Medioni 1992) from ``initial``, with the correspondence
    distance shrinking through ``scales`` × ``distance``.

    Returns ``(transformation, fitness, inlier RMSE, 6×6 information matrix)``.
    """
    import open3d as o3d

    reg = o3d.pipelines.registration
    src, tgt = _cloud(source), _cloud(target)
    if target_normals is None:
        tgt.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(20))
    else:
        tgt.normals = o3d.utility.Vector3dVector(target_normals)
    transformation = np.asarray(initial, dtype=np.float64)
    for scale in scales:  # coarse-to-fine correspondence distance
        result = reg.registration_icp(src, tgt, scale * distance, transformation,
                                      reg.TransformationEstimationPointToPlane(),
                                      reg.ICPConvergenceCriteria(max_iteration=60))
        if result.fitness == 0.0:  # no correspondences: keep the last estimate
            break
        transformation = np.asarray(result.transformation)
    information = np.asarray(reg.get_information_matrix_from_point_clouds(
        src, tgt, distance, transformation))
    return transformation, float(result.fitness), float(result.inlier_rmse), information


def degeneracy_aware_icp(source: np.ndarray, target: np.ndarray, target_normals: np.ndarray,
                         initial: np.ndarray, distance: float, iterations: int = 30,
                         stability: float = 0.1, source_normals: np.ndarray | None = None
                         ) -> tuple[np.ndarray, float, float, np.ndarray]:
    """Point-to-plane ICP (Chen & Medioni 1992) that only moves along well-constrained
    directions.

    Each Gauss-Newton step solves the 6×6 normal equations H x = g and keeps the components of
    x along eigenvectors of H whose eigenvalue exceeds ``stability`` × the largest: a blade is
    close to an extruded surface, and a view pair that sees no cap cannot fix the shift along
    the span or the roll about it (Gelfand et al. 2003, "Geometrically stable sampling for the
    ICP algorithm"; Zhang, Kaess & Singh 2016, degeneracy-aware solving). Those directions keep
    the initial (tracked) estimate. With ``source_normals`` (oriented like the target's), pairs
    whose normals differ by more than 60° are dropped: on a thin blade the nearest target point
    may lie on the opposite face. Returns ``(transformation, overlap share, RMS
    point-to-plane distance (m), 6×6 information matrix H)``.
    """
    from scipy.spatial import cKDTree

    tree = cKDTree(target)
    transformation = np.asarray(initial, dtype=np.float64).copy()
    centre = target.mean(axis=0)  # linearise about the target centre: better conditioned
    # rotations scaled by the target's RMS radius so that all six directions are lengths
    length = float(np.sqrt(np.mean(np.sum((target - centre) ** 2, axis=1))))
    hessian = np.zeros((6, 6))
    overlap, rms = 0.0, math.inf
    for _ in range(iterations):
        moved = transform(source, transformation)
        d, idx = tree.query(moved, distance_upper_bound=distance)
        ok = np.isfinite(d)
        if source_normals is not None:
            turned = source_normals @ transformation[:3, :3].T
            ok[ok] &= np.einsum("ij,ij->i", turned[ok], target_normals[idx[ok]]) > 0.5
        if ok.sum() < 6:
            break
        p, q, n = moved[ok] - centre, target[idx[ok]] - centre, target_normals[idx[ok]]
        residual = np.einsum("ij,ij->i", p - q, n)
        jacobian = np.column_stack([np.cross(p, n) / length, n])
        hessian = jacobian.T @ jacobian
        gradient = -jacobian.T @ residual
        values, vectors = np.linalg.eigh(hessian)
        keep = values > stability * values[-1]
        step = vectors[:, keep] @ ((vectors[:, keep].T @ gradient) / values[keep])
        step[:3] /= length
        update = np.eye(4)
        update[:3, :3] = _rotation_from_vector(step[:3])
        update[:3, 3] = step[3:] + centre - update[:3, :3] @ centre
        transformation = update @ transformation
        overlap, rms = float(ok.mean()), float(np.sqrt(np.mean(residual**2)))
        if np.linalg.norm(step[3:]) < 1e-8 and np.linalg.norm(step[:3]) < 1e-7:
            break
    scale = np.diag([length] * 3 + [1.0] * 3)  # back to rad and m
    return transformation, overlap, rms, scale @ hessian @ scale


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
    from scipy.spatial import cKDTree

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
            update[:3, :3] = _rotation_from_vector(delta[:3] / length)
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
            jacobian = np.column_stack([-_skew(where - centre) / length, np.eye(3)])
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


def _skew(vector: np.ndarray) -> np.ndarray:
    """The matrix of the cross product: ``_skew(a) @ b == np.cross(a, b)``."""
    x, y, z = vector
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _pose_difference(pose: np.ndarray, reference: np.ndarray, centre: np.ndarray,
                     length: float) -> np.ndarray:
    """The small motion (rotation vector × ``length``, translation at ``centre``; m) taking
    ``pose`` to ``reference``: reference ≈ exp(motion) · pose."""
    motion = reference @ np.linalg.inv(pose)
    rotation = motion[:3, :3]
    angle = math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(rotation) - 1.0))))
    axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]])
    vector = axis * (0.5 * angle / math.sin(angle)) if angle > 1e-12 else 0.5 * axis
    shift = motion[:3, :3] @ centre + motion[:3, 3] - centre
    return np.concatenate([vector * length, shift])


def _rotation_from_vector(vector: np.ndarray) -> np.ndarray:
    """Rotation matrix of a rotation vector (Rodrigues)."""
    angle = float(np.linalg.norm(vector))
    if angle < 1e-15:
        return np.eye(3)
    axis = vector / angle
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


def _spacing(points: np.ndarray) -> float:
    """Median nearest-neighbour distance of a cloud (m)."""
    from scipy.spatial import cKDTree

    sample = points[:: max(1, len(points) // 5000)]
    return float(np.median(cKDTree(points).query(sample, k=2)[0][:, 1]))


def visibility_violation(target: np.ndarray, moved: np.ndarray, spacing: float,
                         tolerance: float) -> float:
    """Share of ``moved`` points lying in the free space the target's camera saw through.

    The target view was taken from its origin; a moved point that projects onto a pixel of the
    target's depth image but lies more than ``tolerance`` in front of the observed surface would
    have hidden it — a sign of a wrong alignment (the free-space test of Huber & Hebert 2003).
    """
    distance = float(np.median(np.linalg.norm(target, axis=1)))
    pixel = 2.0 * spacing / distance

    def keys(p: np.ndarray) -> np.ndarray:
        u = np.floor(p[:, 0] / p[:, 2] / pixel).astype(np.int64)
        v = np.floor(p[:, 1] / p[:, 2] / pixel).astype(np.int64)
        return u * 2_000_003 + v

    key = keys(target)
    order = np.argsort(key)
    unique, start = np.unique(key[order], return_index=True)
    nearest = np.minimum.reduceat(np.linalg.norm(target, axis=1)[order], start)
    front = moved[moved[:, 2] > 0.0]
    if len(front) == 0:
        return 0.0
    k = keys(front)
    pos = np.clip(np.searchsorted(unique, k), 0, len(unique) - 1)
    seen = unique[pos] == k
    closer = seen & (np.linalg.norm(front, axis=1) < nearest[pos] - tolerance)
    return float(closer.sum() / max(int(seen.sum()), 1))


def plane_residual(target: np.ndarray, target_normals: np.ndarray, moved: np.ndarray,
                   radius: float) -> tuple[float, float]:
    """Overlap share and RMS point-to-plane distance (m) of ``moved`` points within
    ``radius`` of the target."""
    from scipy.spatial import cKDTree

    d, idx = cKDTree(target).query(moved, distance_upper_bound=radius)
    ok = np.isfinite(d)
    if not np.any(ok):
        return 0.0, math.inf
    offset = np.einsum("ij,ij->i", moved[ok] - target[idx[ok]], target_normals[idx[ok]])
    return float(ok.mean()), float(np.sqrt(np.mean(offset**2)))


def register_views(views: Sequence[np.ndarray], settings: PreprocessSettings | None = None,
                   report: PreprocessReport | None = None,
                   initial_poses: Sequence[np.ndarray] | None = None,
                   progress: Callable[[float], None] | None = None,
                   spheres: Sequence[Sequence[SphereFit]] | None = None) -> list[np.ndarray]:
    """Poses (4×4, view -> frame of view 0) of all views.

    1. Coarse: with ``initial_poses`` (the scanner's own tracking estimate, view -> any common
       frame) the relative poses start from them; without, from the reference spheres when
       they link every view (:func:`poses_from_spheres`: at least 3 spheres shared along a
       chain of view pairs); otherwise each view is registered onto the model fused so far
       by FPFH + RANSAC (``settings.hypotheses`` seeds), rejecting poses that put points into
       the free space a registered camera saw through (:func:`visibility_violation`) or
       overlap less than ``settings.min_overlap`` and keeping the lowest point-to-plane RMS.
       On smooth, nearly symmetric blades with sparse views this fallback often slides a view
       along the surface (see docs/geometry.md).
    2. With the FPFH fallback only — fine: point-to-plane ICP of each view onto the model
       of the views before it, moving only along well-constrained directions
       (:func:`degeneracy_aware_icp`); then every overlapping pair is re-registered by ICP from
       the current poses and all pairs form an open3d pose graph optimised globally (Choi, Zhou
       & Koltun 2015) with view 0 fixed.
    3. Joint multi-view point-to-plane ICP of all full-resolution views at once
       (:func:`multiview_icp`), degeneracy-aware: the one direction a nearly extruded blade
       leaves free — the shift along the span, with the matching turn of the twist, between the
       views that see only the tip cap and those that see only the root cap — keeps its
       starting (tracked) value; every other direction is fixed by the scans to µm. With
       ``spheres`` (the reference spheres found in each view, :func:`detect_spheres`), the
       spheres are matched across views by the starting poses (:func:`match_spheres`) and
       their centres join the joint ICP as datums (``centres`` of :func:`multiview_icp`),
       which fix that direction too.

    Raises ``ValueError`` naming the views that could not be registered, or when spheres were
    found but none matches across views (:func:`match_spheres` for ambiguous matches).
    """
    import open3d as o3d

    settings = settings or PreprocessSettings()
    reg = o3d.pipelines.registration
    count = len(views)
    spacing = max(_spacing(v) for v in views)
    # correspondences must reach the next point of a sparse view: at least 3 point spacings
    distance = max(settings.icp_distance, 3.0 * spacing)
    radius = max(2.0 * spacing, settings.icp_distance)
    if initial_poses is not None:
        if len(initial_poses) != count:
            raise ValueError(f"{len(initial_poses)} initial poses for {count} views")
        base = np.linalg.inv(np.asarray(initial_poses[0], dtype=np.float64))
        tracked = [base @ np.asarray(p, dtype=np.float64) for p in initial_poses]
        return _joint_registration(views, tracked, distance, settings, report, progress,
                                   spheres)
    if spheres is not None and any(spheres):
        linked = poses_from_spheres(spheres)
        if len(linked) == count:  # every view posed by the sphere centres
            return _joint_registration(views, [linked[k] for k in range(count)], distance,
                                       settings, report, progress, spheres)
    subsampled = [np.asarray(_cloud(v).voxel_down_sample(0.25 * settings.voxel).points)
                  for v in views]
    normals = [local_frames(v, 20, viewpoint=np.zeros(3))[1] for v in subsampled]
    poses = _register_by_features(views, subsampled, normals, settings, spacing, radius,
                                  distance, progress)
    graph = reg.PoseGraph()
    for k in range(count):
        graph.nodes.append(reg.PoseGraphNode(poses[k]))
    for i in range(count):
        for j in range(i + 1, count):
            relative = np.linalg.inv(poses[i]) @ poses[j]  # view j -> view i
            transformation, overlap, rmse, information = degeneracy_aware_icp(
                subsampled[j], subsampled[i], normals[i], relative, distance,
                stability=settings.stability, source_normals=normals[j])
            if overlap < settings.min_overlap:
                continue
            graph.edges.append(reg.PoseGraphEdge(j, i, transformation, information,
                                                 uncertain=True))
            if report is not None:
                report.pair_fitness[f"{j}->{i}"] = overlap
                report.pair_rmse[f"{j}->{i}"] = rmse
    edges = len(graph.edges)
    option = reg.GlobalOptimizationOption(max_correspondence_distance=distance,
                                          edge_prune_threshold=0.25, reference_node=0)
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        reg.global_optimization(graph, reg.GlobalOptimizationLevenbergMarquardt(),
                                reg.GlobalOptimizationConvergenceCriteria(), option)
    if report is not None:
        report.pose_graph_edges = len(graph.edges)
        report.pose_graph_pruned = edges - len(graph.edges)
    optimised = [np.asarray(graph.nodes[k].pose) for k in range(count)]
    return _joint_registration(views, optimised, distance, settings, report, progress, spheres)


def _joint_registration(views: Sequence[np.ndarray], poses: list[np.ndarray], distance: float,
                        settings: PreprocessSettings, report: PreprocessReport | None,
                        progress: Callable[[float], None] | None,
                        spheres: Sequence[Sequence[SphereFit]] | None = None
                        ) -> list[np.ndarray]:
    """Final joint multi-view ICP (:func:`multiview_icp`) of the full-resolution views from
    ``poses`` (view -> frame of view 0), degeneracy-aware with ``settings.joint_stability``,
    the reference spheres matched by ``poses`` as datums."""
    centres = None
    if spheres is not None and any(len(found) for found in spheres):
        groups = match_spheres(spheres, poses, settings.sphere_match_distance)
        centres = [[(k, spheres[k][i].centre, spheres[k][i].covariance) for k, i in group]
                   for group in groups if len(group) > 1]
        if not centres:
            seen = [k for k, found in enumerate(spheres) if found]
            raise ValueError(
                f"reference spheres were found in views {seen} but none matches a sphere of "
                f"another view within {settings.sphere_match_distance * 1e3:.1f} mm: check the "
                "starting poses and the sphere radius (sphere_radius=None if the scan holds no "
                "reference spheres)")
        if report is not None:
            report.spheres_single = len(groups) - len(centres)
    normals = [local_frames(v, 20, viewpoint=np.zeros(3))[1] for v in views]
    poses, figures = multiview_icp(views, normals, poses, distance,
                                   iterations=settings.joint_iterations,
                                   stability=settings.joint_stability, centres=centres)
    if report is not None and centres is not None:
        report.spheres_matched = len(centres)
        report.sphere_rms = figures["centre_rms"]
    if report is not None:
        report.joint_rms = figures["rms"]
        report.joint_weak_directions = figures.get("weak_directions", 0)
        report.pose_graph_edges = max(report.pose_graph_edges, figures["pairs"])
    if progress is not None:
        progress(1.0)
    return poses


def _register_by_features(views: Sequence[np.ndarray], subsampled: list[np.ndarray],
                          normals: list[np.ndarray], settings: PreprocessSettings,
                          spacing: float, radius: float, distance: float,
                          progress: Callable[[float], None] | None) -> dict[int, np.ndarray]:
    """Coarse + fine registration of every view onto the growing model (FPFH + RANSAC, ICP)."""
    count = len(views)
    tolerance = 4.0 * distance
    poses: dict[int, np.ndarray] = {0: np.eye(4)}
    pending = list(range(1, count))
    while pending:
        model = np.concatenate([transform(subsampled[k], poses[k]) for k in poses])
        model_normals = np.concatenate([normals[k] @ poses[k][:3, :3].T for k in poses])
        registered = None
        for j in pending:
            best = None
            for h in range(settings.hypotheses):
                guess = coarse_registration(subsampled[j], model, settings.voxel,
                                            settings.ransac_iterations, seed=j + 7919 * h,
                                            target_normals=model_normals)
                pose, _, _, _ = refine_registration(subsampled[j], model, guess, distance,
                                                    model_normals)
                moved = transform(subsampled[j], pose)
                overlap, rms = plane_residual(model, model_normals, moved, radius)
                if overlap < settings.min_overlap:
                    continue
                violation = max(max(
                    visibility_violation(subsampled[k],
                                         transform(moved, np.linalg.inv(poses[k])),
                                         spacing, tolerance),
                    visibility_violation(subsampled[j], transform(
                        transform(subsampled[k], poses[k]), np.linalg.inv(pose)),
                        spacing, tolerance)) for k in poses)
                if violation <= settings.max_violation and (best is None or rms < best[0]):
                    best = (rms, pose)
            if best is not None:
                registered = (j, best[1])
                break  # rebuild the model with the new view
        if registered is None:
            raise ValueError(f"views {pending} could not be registered: no hypothesis passed "
                             "the overlap and free-space checks")
        poses[registered[0]] = registered[1]
        pending.remove(registered[0])
        if progress is not None:
            progress(0.6 * len(poses) / count)
    return poses


def pose_errors(estimated: Sequence[np.ndarray], truth: Sequence[np.ndarray],
                views: Sequence[np.ndarray]) -> dict[str, np.ndarray]:
    """Errors of recovered view poses against the true ones (4×4, view -> any common frame).

    Only relative poses are recoverable: the estimate lives in the frame of view 0 (a free
    gauge). One rigid transformation G — the least-squares fit (Kabsch) of all view points as
    placed by the estimate onto the same points as placed by the truth — takes the estimated
    pose set to the true one; each view's error is then E_k = G T̂_k T_k⁻¹, a motion of the
    truth frame. Per view (arrays of length N): ``rotation_deg`` its angle (degrees),
    ``translation_m`` the displacement of the view's point centroid (m; at the part, not at the
    camera 0.1 m away), split into ``across_span_m`` (x-y) and ``span_m`` (z of the truth
    frame, the blade's span for blade-frame truth), and ``max_point_m``, the largest
    displacement of any of the view's ``views`` points (view frame, m).
    """
    placed = [transform(v, t) for v, t in zip(views, truth, strict=True)]
    moved = [transform(v, e) for v, e in zip(views, estimated, strict=True)]
    step = max(1, sum(len(v) for v in views) // 200_000)
    source = np.concatenate(moved)[::step]
    target = np.concatenate(placed)[::step]
    gauge = np.eye(4)
    gauge[:3, :3], gauge[:3, 3] = _kabsch(source, target)
    out: dict[str, list[float]] = {"rotation_deg": [], "translation_m": [], "across_span_m": [],
                                   "span_m": [], "max_point_m": []}
    for t, e, p in zip(truth, estimated, placed, strict=True):
        error = gauge @ np.asarray(e) @ np.linalg.inv(np.asarray(t))
        cosine = 0.5 * (np.trace(error[:3, :3]) - 1.0)
        centroid = p.mean(axis=0)
        shift = error[:3, :3] @ centroid + error[:3, 3] - centroid
        out["rotation_deg"].append(math.degrees(math.acos(max(-1.0, min(1.0, cosine)))))
        out["translation_m"].append(float(np.linalg.norm(shift)))
        out["across_span_m"].append(float(np.linalg.norm(shift[:2])))
        out["span_m"].append(float(abs(shift[2])))
        out["max_point_m"].append(float(np.linalg.norm(transform(p, error) - p, axis=1).max()))
    return {key: np.array(value) for key, value in out.items()}


def _kabsch(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation of the least-squares rigid fit of ``source`` onto ``target``
    (Kabsch 1976)."""
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rotation, ct - rotation @ cs


def transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4×4 rigid transformation to (n, 3) points."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def _remove_sphere_remnants(views: list[np.ndarray], spheres: Sequence[Sequence[SphereFit]],
                            poses: Sequence[np.ndarray], settings: PreprocessSettings,
                            report: PreprocessReport, widen: float) -> list[np.ndarray]:
    """Remove from each view the points of the reference spheres it did not find (too few
    points, e.g. mostly hidden by the blade), counted in ``report.sphere_points_removed``.

    A sphere's centre is the mean of its placements by ``poses`` (view -> a common frame),
    carried into the view; the view's points within 0.5 mm of that sphere's surface (the poses
    may be off by the tracking error) refit the centre with the known radius (kept if it moves
    less than 0.5 mm), and the points on the shell (``sphere_tolerance`` + ``widen``, m) or
    inside it are removed.
    """
    groups = match_spheres(spheres, poses, settings.sphere_match_distance)
    radius = settings.sphere_radius
    band = 0.5e-3
    kept = []
    for k, (view, pose) in enumerate(zip(views, poses, strict=True)):
        remnant = np.zeros(len(view), dtype=bool)
        for group in groups:
            if any(j == k for j, _ in group):
                continue  # found in this view: its points are gone already
            placed = np.mean([transform(spheres[j][i].centre[None], np.asarray(poses[j]))[0]
                              for j, i in group], axis=0)
            centre = transform(placed[None], np.linalg.inv(np.asarray(pose)))[0]
            distance = np.linalg.norm(view - centre, axis=1)
            candidates = np.abs(distance - radius) <= band
            if candidates.sum() >= 4:
                refit = fit_sphere(view[candidates], radius, centre)[0]
                if np.linalg.norm(refit - centre) < band:
                    distance = np.linalg.norm(view - refit, axis=1)
            remnant |= distance <= radius + settings.sphere_tolerance + widen
        report.sphere_points_removed[k] += int(remnant.sum())
        kept.append(view[~remnant])
    return kept


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
    kept_feature = _voxel_thin(points[feature], round(feature_share * target))
    kept_rest = _voxel_thin(points[~feature], target - len(kept_feature))
    return np.concatenate([kept_feature, kept_rest])


def _voxel_thin(points: np.ndarray, target: int) -> np.ndarray:
    """One point per voxel (the one nearest the voxel centre), voxel size bisected to ~target."""
    if target >= len(points):
        return points
    extent = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    lo, hi = extent * 1e-6, extent
    best = points
    for _ in range(40):
        size = np.sqrt(lo * hi)
        kept = _voxel_pick(points, size)
        if len(kept) > target:
            lo = size
        else:
            hi = size
            best = kept
        if abs(len(kept) - target) <= 0.01 * target:
            return kept
    return best


def _voxel_pick(points: np.ndarray, size: float) -> np.ndarray:
    cell = np.floor(points / size).astype(np.int64)
    offset = np.linalg.norm(points / size - cell - 0.5, axis=1)
    order = np.lexsort((offset, cell[:, 2], cell[:, 1], cell[:, 0]))
    sorted_cells = cell[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(sorted_cells[1:] != sorted_cells[:-1], axis=1)
    return points[order[first]]


def preprocess_views(views: Sequence[np.ndarray], settings: PreprocessSettings | None = None,
                     initial_poses: Sequence[np.ndarray] | None = None,
                     progress: Callable[[float], None] | None = None
                     ) -> tuple[np.ndarray, list[np.ndarray], PreprocessReport]:
    """Reference spheres -> outliers -> MLS smoothing -> registration -> fusion ->
    downsampling.

    With ``settings.sphere_radius``, the reference spheres of that radius are found in each
    view (:func:`detect_spheres`) and their points removed before anything else, so that the
    fused cloud holds the blade only; their centres link the views in the registration. The
    few points of a sphere that a view saw too little of to find it are removed as well
    (:func:`_remove_sphere_remnants`): before the outlier removal when ``initial_poses`` place
    the spheres, else after the registration.
    ``initial_poses`` are the scanner's tracking estimates (see :func:`register_views`).
    Returns ``(fused cloud in the frame of view 0, per-view poses, report)``.
    """
    settings = settings or PreprocessSettings()
    if settings.target_points is not None and settings.target_points < 1:
        raise ValueError(f"target_points = {settings.target_points} (expected a count >= 1, "
                         "or None for 8/15 of the scanned blade points)")
    report = PreprocessReport()
    blade_views, spheres = [], []
    for k, view in enumerate(views):
        view = check_point_cloud(view, f"view {k}")
        report.input_points.append(len(view))
        found = [] if settings.sphere_radius is None else detect_spheres(
            view, settings.sphere_radius, settings.sphere_tolerance, settings.sphere_min_points)
        on_sphere = np.zeros(len(view), dtype=bool)
        for fit in found:
            on_sphere[fit.points] = True
        spheres.append(found)
        report.spheres_found.append(len(found))
        report.sphere_points_removed.append(int(on_sphere.sum()))
        blade_views.append(view[~on_sphere])
    if any(spheres) and initial_poses is not None:
        if len(initial_poses) != len(views):
            raise ValueError(f"{len(initial_poses)} initial poses for {len(views)} views")
        blade_views = _remove_sphere_remnants(blade_views, spheres, initial_poses, settings,
                                              report, 0.0)
    cleaned = []
    for k, view in enumerate(blade_views):
        kept, mask = remove_statistical_outliers(view, settings.outlier_neighbours,
                                                 settings.outlier_std_ratio)
        report.outliers_removed.append(int((~mask).sum()))
        smooth = mls_smooth(kept, settings.mls_neighbours, settings.mls_max_shift)
        report.smoothing_mean_shift.append(float(np.linalg.norm(smooth - kept, axis=1).mean()))
        cleaned.append(smooth)
        if progress is not None:
            progress(0.2 * (k + 1) / len(views))
    poses = register_views(cleaned, settings, report, initial_poses,
                           None if progress is None else lambda f: progress(0.2 + 0.7 * f),
                           spheres)
    if any(spheres) and initial_poses is None:
        cleaned = _remove_sphere_remnants(cleaned, spheres, poses, settings, report,
                                          settings.mls_max_shift)
    fused = np.concatenate([transform(v, p) for v, p in zip(cleaned, poses, strict=True)])
    report.fused_points = len(fused)
    target = settings.target_points
    if target is None:
        target = round(KEPT_SHARE * (sum(report.input_points) - sum(report.sphere_points_removed)))
    fused = feature_preserving_downsample(fused, target, settings.feature_share)
    report.downsampled_points = len(fused)
    if progress is not None:
        progress(1.0)
    return fused, poses, report
