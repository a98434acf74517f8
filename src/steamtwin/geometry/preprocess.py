"""Point-cloud preprocessing: outliers, smoothing, registration, fusion, downsampling.

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


@dataclass(frozen=True)
class PreprocessSettings:
    """Hyper-parameters of :func:`preprocess_views` (lengths in m).

    ``voxel`` is the feature scale for FPFH/RANSAC; ``icp_distance`` the ICP correspondence
    cut-off; ``target_points`` the size of the fused, downsampled cloud.
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
    target_points: int = 80_000
    feature_share: float = 0.25  # share of the kept points reserved for high-curvature regions


@dataclass
class PreprocessReport:
    """What each step did (counts of points; lengths in m)."""

    input_points: list[int] = field(default_factory=list)
    outliers_removed: list[int] = field(default_factory=list)
    smoothing_mean_shift: list[float] = field(default_factory=list)
    pair_fitness: dict[str, float] = field(default_factory=dict)
    pair_rmse: dict[str, float] = field(default_factory=dict)
    pose_graph_edges: int = 0
    pose_graph_pruned: int = 0
    fused_points: int = 0
    downsampled_points: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def _cloud(points: np.ndarray) -> object:
    import open3d as o3d

    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, np.float64)))


def remove_statistical_outliers(points: np.ndarray, neighbours: int = 50,
                                std_ratio: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Drop points whose mean distance to their ``neighbours`` nearest is more than
    ``std_ratio`` standard deviations above the cloud's mean (Rusu et al. 2008).

    Returns ``(kept points, boolean mask of the kept points)``.
    """
    _, kept = _cloud(points).remove_statistical_outlier(nb_neighbors=neighbours,
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


@dataclass(frozen=True)
class PairRegistration:
    """Result of registering view ``source`` onto view ``target``."""

    source: int
    target: int
    transformation: np.ndarray  # 4×4, source frame -> target frame
    fitness: float
    rmse: float
    information: np.ndarray


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
                   progress: Callable[[float], None] | None = None) -> list[np.ndarray]:
    """Poses (4×4, view -> frame of view 0) of all views.

    1. Coarse: with ``initial_poses`` (the scanner's own tracking estimate, view -> any common
       frame) the relative poses start from them; without, each view is registered onto the
       model fused so far by FPFH + RANSAC (``settings.hypotheses`` seeds), rejecting poses that
       put points into the free space a registered camera saw through
       (:func:`visibility_violation`) or overlap less than ``settings.min_overlap`` and keeping
       the lowest point-to-plane RMS. On smooth, nearly symmetric blades with sparse views this
       fallback often slides a view along the surface (see docs/geometry.md).
    2. Fine: point-to-plane ICP of each view onto the model of the views before it, moving
       only along well-constrained directions (:func:`degeneracy_aware_icp`).
    3. Multi-view refinement: every overlapping pair is re-registered by ICP from the current
       poses and all pairs form an open3d pose graph optimised globally (Choi, Zhou & Koltun
       2015) with view 0 fixed.

    Raises ``ValueError`` naming the views that could not be registered.
    """
    import open3d as o3d

    settings = settings or PreprocessSettings()
    reg = o3d.pipelines.registration
    count = len(views)
    spacing = max(_spacing(v) for v in views)
    # correspondences must reach the next point of a sparse view: at least 3 point spacings
    distance = max(settings.icp_distance, 3.0 * spacing)
    radius = max(2.0 * spacing, settings.icp_distance)
    subsampled = [np.asarray(_cloud(v).voxel_down_sample(0.25 * settings.voxel).points)
                  for v in views]
    normals = [local_frames(v, 20, viewpoint=np.zeros(3))[1] for v in subsampled]
    if initial_poses is not None:
        if len(initial_poses) != count:
            raise ValueError(f"{len(initial_poses)} initial poses for {count} views")
        base = np.linalg.inv(np.asarray(initial_poses[0], dtype=np.float64))
        poses = {0: np.eye(4)}
        for j in range(1, count):
            model = np.concatenate([transform(subsampled[k], poses[k]) for k in poses])
            model_normals = np.concatenate([normals[k] @ poses[k][:3, :3].T for k in poses])
            guess = base @ np.asarray(initial_poses[j], dtype=np.float64)
            poses[j], _, _, _ = degeneracy_aware_icp(subsampled[j], model, model_normals, guess,
                                                     distance, stability=settings.stability,
                                                     source_normals=normals[j])
            if progress is not None:
                progress(0.6 * (j + 1) / count)
    else:
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
    if progress is not None:
        progress(1.0)
    return [np.asarray(graph.nodes[k].pose) for k in range(count)]


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


def transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4×4 rigid transformation to (n, 3) points."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


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
    """Outliers -> MLS smoothing -> registration -> fusion -> downsampling.

    ``initial_poses`` are the scanner's tracking estimates (see :func:`register_views`).
    Returns ``(fused cloud in the frame of view 0, per-view poses, report)``.
    """
    settings = settings or PreprocessSettings()
    report = PreprocessReport()
    cleaned = []
    for k, view in enumerate(views):
        view = check_point_cloud(view, f"view {k}")
        report.input_points.append(len(view))
        kept, mask = remove_statistical_outliers(view, settings.outlier_neighbours,
                                                 settings.outlier_std_ratio)
        report.outliers_removed.append(int((~mask).sum()))
        smooth = mls_smooth(kept, settings.mls_neighbours, settings.mls_max_shift)
        report.smoothing_mean_shift.append(float(np.linalg.norm(smooth - kept, axis=1).mean()))
        cleaned.append(smooth)
        if progress is not None:
            progress(0.2 * (k + 1) / len(views))
    poses = register_views(cleaned, settings, report, initial_poses,
                           None if progress is None else lambda f: progress(0.2 + 0.7 * f))
    fused = np.concatenate([transform(v, p) for v, p in zip(cleaned, poses, strict=True)])
    report.fused_points = len(fused)
    fused = feature_preserving_downsample(fused, settings.target_points, settings.feature_share)
    report.downsampled_points = len(fused)
    if progress is not None:
        progress(1.0)
    return fused, poses, report
