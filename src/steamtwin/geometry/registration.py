"""Registration of scanner views: FPFH + RANSAC coarse poses, point-to-plane and
degeneracy-aware ICP, the pose graph, the joint multi-view ICP with reference-sphere datums, the
free-space (visibility) check, and pose errors against a known truth (lengths in m).

View frames are the scanner's own (camera at the origin), as written by
:mod:`steamtwin.geometry.scanner` and by real handheld scanners; normals are oriented towards it.
A pose is a 4×4 matrix, view -> frame of view 0 (:mod:`steamtwin.geometry.rigid`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.filters import local_frames, median_spacing, open3d_cloud
from steamtwin.geometry.multiview import multiview_icp
from steamtwin.geometry.preprocess_settings import PreprocessReport, PreprocessSettings
from steamtwin.geometry.rigid import (
    kabsch,
    pose_matrix,
    rotation_angle,
    rotation_from_vector,
    transform,
)
from steamtwin.geometry.targets import SphereFit, match_spheres, poses_from_spheres
from steamtwin.progress import ProgressCallback


def _features(points: np.ndarray, voxel: float, normals: np.ndarray | None = None
              ) -> tuple[object, object]:
    """Voxel-downsampled cloud and its FPFH features (Rusu, Blodow & Beetz 2009).

    Normals are estimated and turned towards the camera at the origin, unless given (a fused
    model carries each view's normals, oriented towards that view's camera).
    """
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    cloud = open3d_cloud(points)
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
                        iterations: int = 200_000, random_state: int = 0,
                        target_normals: np.ndarray | None = None) -> np.ndarray:
    """FPFH features matched by RANSAC: a 4×4 source -> target guess.

    The source is a view in its scanner frame (camera at the origin); ``target_normals``
    gives the target's oriented normals when it is not (a fused model). ``random_state`` seeds
    open3d's RANSAC sampler.
    """
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    reg = o3d.pipelines.registration
    o3d.utility.random.seed(random_state)
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
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    reg = o3d.pipelines.registration
    src, tgt = open3d_cloud(source), open3d_cloud(target)
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
        update[:3, :3] = rotation_from_vector(step[:3])
        update[:3, 3] = step[3:] + centre - update[:3, :3] @ centre
        transformation = update @ transformation
        overlap, rms = float(ok.mean()), float(np.sqrt(np.mean(residual**2)))
        if np.linalg.norm(step[3:]) < 1e-8 and np.linalg.norm(step[:3]) < 1e-7:
            break
    scale = np.diag([length] * 3 + [1.0] * 3)  # back to rad and m
    return transformation, overlap, rms, scale @ hessian @ scale


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
    d, idx = cKDTree(target).query(moved, distance_upper_bound=radius)
    ok = np.isfinite(d)
    if not np.any(ok):
        return 0.0, math.inf
    offset = np.einsum("ij,ij->i", moved[ok] - target[idx[ok]], target_normals[idx[ok]])
    return float(ok.mean()), float(np.sqrt(np.mean(offset**2)))


def register_views(views: Sequence[np.ndarray], settings: PreprocessSettings | None = None,
                   report: PreprocessReport | None = None,
                   initial_poses: Sequence[np.ndarray] | None = None,
                   progress: ProgressCallback | None = None,
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
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    settings = settings or PreprocessSettings()
    reg = o3d.pipelines.registration
    count = len(views)
    # every (n // 5000)-th point: the stride the registration's figures were measured with
    spacing = max(median_spacing(v, stride=max(1, len(v) // 5000)) for v in views)
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
    subsampled = [np.asarray(open3d_cloud(v).voxel_down_sample(0.25 * settings.voxel).points)
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
                        progress: ProgressCallback | None,
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
        progress(1.0, "joint multi-view ICP done")
    return poses


def _register_by_features(views: Sequence[np.ndarray], subsampled: list[np.ndarray],
                          normals: list[np.ndarray], settings: PreprocessSettings,
                          spacing: float, radius: float, distance: float,
                          progress: ProgressCallback | None) -> dict[int, np.ndarray]:
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
                                            settings.ransac_iterations, random_state=j + 7919 * h,
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
            progress(0.6 * len(poses) / count, f"{len(poses)}/{count} views registered")
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
    gauge = pose_matrix(*kabsch(source, target))
    out: dict[str, list[float]] = {"rotation_deg": [], "translation_m": [], "across_span_m": [],
                                   "span_m": [], "max_point_m": []}
    for t, e, p in zip(truth, estimated, placed, strict=True):
        error = gauge @ np.asarray(e) @ np.linalg.inv(np.asarray(t))
        centroid = p.mean(axis=0)
        shift = error[:3, :3] @ centroid + error[:3, 3] - centroid
        out["rotation_deg"].append(math.degrees(rotation_angle(error[:3, :3])))
        out["translation_m"].append(float(np.linalg.norm(shift)))
        out["across_span_m"].append(float(np.linalg.norm(shift[:2])))
        out["span_m"].append(float(abs(shift[2])))
        out["max_point_m"].append(float(np.linalg.norm(transform(p, error) - p, axis=1).max()))
    return {key: np.array(value) for key, value in out.items()}
