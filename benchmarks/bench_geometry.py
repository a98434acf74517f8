"""Full-size geometry benchmark: scan of hp1 (150k points; longer blades get the points
:func:`~steamtwin.geometry.scanner.planned_points` plans) -> preprocessing (8/15 kept) ->
fidelity; surface reconstruction -> STL -> fidelity and mesh of the measured blade; meshing;
scan-uncertainty study. Also: raw views -> STL wall time, statistical outlier removal against
open3d's on the raw points, recovered view poses against the scanner's true ones, reference spheres
found and removed. Prints timings and the measured figures as JSON.

Run: python benchmarks/bench_geometry.py [row] [seed] [--quick] [--spheres N]   (--quick: no
meshing and no uncertainty study; --spheres: reference spheres in the scan, default 4, 0 for
the scanner without them)
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

import numpy as np

from steamtwin.geometry.fidelity import align_to_nominal, surface_deviation
from steamtwin.geometry.filters import remove_statistical_outliers
from steamtwin.geometry.mesh_io import write_stl
from steamtwin.geometry.meshing import blade_volume_mesh, mesh_quality, mesh_stl
from steamtwin.geometry.preprocess import preprocess_views
from steamtwin.geometry.preprocess_settings import PreprocessSettings
from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.reconstruct import ReconstructionSettings, reconstruct_blade
from steamtwin.geometry.reconstruction_report import reconstruction_fidelity
from steamtwin.geometry.registration import pose_errors
from steamtwin.geometry.rigid import transform
from steamtwin.geometry.scanner import ScannerSettings, planned_points, scan_blade
from steamtwin.geometry.uncertainty import scan_uncertainty
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import load_spec


def settings_from(model_edges: bool | None, bridge_holes: bool | None
                  ) -> ReconstructionSettings:
    """The reconstruction's settings: the defaults, with ``model_edges`` and the guard's
    ``bridge_holes`` where given (None: the default)."""
    settings = ReconstructionSettings()
    if model_edges is not None:
        settings = replace(settings, model_edges=model_edges)
    if bridge_holes is not None and settings.guard is not None:
        settings = replace(settings, guard=replace(settings.guard, bridge_holes=bridge_holes))
    return settings


def main(row: str = "hp1", seed: int = 0, quick: bool = False, spheres: int = 4,
         settings: ReconstructionSettings | None = None) -> dict:
    spec = load_spec("reference")
    blade = make_blade(spec, row)
    figures: dict = {"row": row, "seed": seed, "reference_spheres": spheres}

    start = time.perf_counter()
    figures["scan_points"] = planned_points(blade)  # 150k for hp1, more for the others
    scan = scan_blade(blade, ScannerSettings(points=figures["scan_points"], views=8,
                                             reference_spheres=spheres), random_state=seed)
    figures["scan_s"] = time.perf_counter() - start
    figures["outlier_removal"] = _outlier_removal(np.concatenate([v.points for v in scan.views]))

    start = time.perf_counter()
    fused, poses, report = preprocess_views(
        [v.points for v in scan.views],
        PreprocessSettings(sphere_radius=scan.settings.sphere_radius if spheres else None),
        initial_poses=[v.tracked_pose for v in scan.views])
    figures["preprocess_s"] = time.perf_counter() - start  # fused: 8/15 of the points kept
    figures["steps"] = {"input": sum(report.input_points),
                        "outliers_injected": sum(int(v.is_outlier.sum()) for v in scan.views),
                        "outliers_removed": sum(report.outliers_removed),
                        "fused": report.fused_points, "downsampled": report.downsampled_points,
                        "pose_graph_edges": report.pose_graph_edges,
                        "sphere_points_injected": [int(np.sum(v.sphere_index >= 0))
                                                   for v in scan.views],
                        "sphere_points_removed": report.sphere_points_removed,
                        "spheres_found": report.spheres_found,
                        "spheres_matched": report.spheres_matched,
                        "sphere_centre_rms_mm": report.sphere_rms * 1e3}
    base = np.linalg.inv(scan.views[0].pose)
    blade_points = [v.points[v.sphere_index < 0] for v in scan.views]  # with the outliers
    figures["registration_error_max_mm"] = max(
        float(np.linalg.norm(transform(b, p) - transform(b, base @ v.pose), axis=1).max()) * 1e3
        for v, b, p in zip(scan.views, blade_points, poses, strict=True))
    figures["pose_recovery"] = _pose_recovery(scan, poses)
    figures["joint_icp"] = {"rms_mm": report.joint_rms * 1e3,
                            "weak_directions": report.joint_weak_directions}

    start = time.perf_counter()
    pose, fit_rms = align_to_nominal(fused, blade)
    figures["best_fit_s"] = time.perf_counter() - start
    deviation = surface_deviation(blade, transform(fused, pose))
    figures["fidelity_s"] = time.perf_counter() - start
    figures["fused_cloud_deviation_mm"] = {
        "mean": deviation.mean * 1e3, "rms": deviation.rms * 1e3, "max": deviation.max * 1e3,
        "hausdorff": deviation.hausdorff * 1e3, "p95": deviation.p95 * 1e3,
        "best_fit_rms": fit_rms * 1e3}
    truth_pose = np.linalg.inv(base)  # frame of view 0 -> blade frame (hidden truth)
    distance = np.linalg.norm(transform(fused[:1000], pose) - transform(fused[:1000], truth_pose),
                              axis=1)
    figures["best_fit_vs_truth_pose_max_mm"] = float(distance.max()) * 1e3

    figures["reconstruction"] = _reconstruction(blade, transform(fused, pose), quick, settings)
    figures["raw_views_to_stl_s"] = (figures["preprocess_s"] + figures["best_fit_s"]
                                     + figures["reconstruction"]["reconstruct_s"]
                                     + figures["reconstruction"]["write_stl_s"])
    if quick:
        return figures

    start = time.perf_counter()
    mesh = blade_volume_mesh(spec, row)
    figures["mesh_s"] = time.perf_counter() - start
    figures["mesh_quality"] = mesh_quality(mesh).as_dict()

    start = time.perf_counter()
    model = FullOrderModel(spec)
    _ = model.design_
    study = scan_uncertainty(blade, model, samples=20, sections=3, random_state=0)
    figures["uncertainty_s"] = time.perf_counter() - start
    figures["uncertainty"] = study.as_dict()
    return figures


def _outlier_removal(points: np.ndarray, repeats: int = 3) -> dict:
    """Ours against open3d's ``remove_statistical_outlier`` (50 neighbours besides the point,
    i.e. open3d's nb_neighbors = 51, std ratio 2) on the raw points: best of ``repeats`` wall
    times (s) and whether the kept points agree one for one."""
    import open3d as o3d

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    ours_s, open3d_s = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        _, mask = remove_statistical_outliers(points, 50, 2.0)
        ours_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        _, kept = cloud.remove_statistical_outlier(nb_neighbors=51, std_ratio=2.0)
        open3d_s.append(time.perf_counter() - start)
    reference = np.zeros(len(points), dtype=bool)
    reference[np.asarray(kept, dtype=np.int64)] = True
    return {"points": len(points), "ours_s": min(ours_s), "open3d_s": min(open3d_s),
            "ratio": min(ours_s) / min(open3d_s), "removed": int(np.sum(~mask)),
            "disagreeing_points": int(np.sum(mask != reference))}


def _pose_recovery(scan: object, poses: list[np.ndarray]) -> dict:
    """Recovered view poses against the scanner's true ones (:func:`pose_errors`; mm, deg):
    all views (one gauge fit), the views sharing a cap (cameras above / below), and the
    scanner's tracked poses for comparison. Per view, its blade points (no outliers, no
    reference spheres)."""
    views = [v.points[~v.is_outlier & (v.sphere_index < 0)] for v in scan.views]  # the blade
    truth = [v.pose for v in scan.views]

    def summary(estimated: list[np.ndarray], pick: list[int]) -> dict:
        errors = pose_errors([estimated[k] for k in pick], [truth[k] for k in pick],
                             [views[k] for k in pick])
        return {"translation_max_mm": float(errors["translation_m"].max() * 1e3),
                "across_span_max_mm": float(errors["across_span_m"].max() * 1e3),
                "span_max_mm": float(errors["span_m"].max() * 1e3),
                "rotation_max_deg": float(errors["rotation_deg"].max()),
                "point_max_mm": float(errors["max_point_m"].max() * 1e3)}

    every = list(range(len(views)))
    tracked = [v.tracked_pose for v in scan.views]
    return {"all_views": summary(poses, every), "tracked_all_views": summary(tracked, every),
            "tip_cap_views": summary(poses, every[0::2]),
            "root_cap_views": summary(poses, every[1::2])}


def _reconstruction(blade: Blade, cloud: np.ndarray, quick: bool = False,
                    settings: ReconstructionSettings | None = None) -> dict:
    """Surface reconstruction of the best-fitted fused cloud (``settings``: the
    reconstruction's, None for the defaults): patches, fit, deviation of the STL from the exact
    blade, row metrics and a volume mesh of the STL (mm, s)."""
    import tempfile
    from pathlib import Path

    figures: dict = {}
    start = time.perf_counter()
    result = reconstruct_blade(cloud, settings)
    figures["reconstruct_s"] = time.perf_counter() - start
    summary = result.summary()
    figures.update({key: summary[key] for key in (
        "points", "patch_points", "trimmed_by_fit", "side_fit_rms_mm", "side_fit_max_mm",
        "root_cap_rms_mm", "tip_cap_rms_mm", "breakpoints", "triangles")})
    figures["volume_error"] = result.volume / blade.volume - 1.0
    start = time.perf_counter()
    report = reconstruction_fidelity(blade, result.vertices, result.triangles)
    figures["fidelity_s"] = time.perf_counter() - start
    deviation = report.as_dict()["deviation_mm"]
    figures["deviation_mm"] = {k: deviation[k] for k in ("mean", "rms", "max", "hausdorff",
                                                          "p95")}
    figures["metric_errors"] = {
        section["section"]: {m["metric"]: m["error"] for m in section["metrics"]}
        for section in report.extra["sections"]}
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        path = write_stl(result, Path(folder) / "blade.stl")
        figures["write_stl_s"] = time.perf_counter() - start
        if quick:
            return figures
        start = time.perf_counter()
        mesh = mesh_stl(path)
        figures["mesh_stl_s"] = time.perf_counter() - start
    figures["mesh_stl_nodes"] = len(mesh.points)
    figures["mesh_stl_volume_error"] = mesh.volume() / blade.volume - 1.0
    return figures


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("row", nargs="?", default="hp1", help="blade row, e.g. hp1")
    parser.add_argument("seed", nargs="?", type=int, default=0, help="scan seed")
    parser.add_argument("--quick", action="store_true",
                        help="no meshing and no uncertainty study")
    parser.add_argument("--spheres", type=int, default=4,
                        help="reference spheres in the scan (0: the scanner without them)")
    options = parser.parse_args()
    print(json.dumps(main(options.row, options.seed, options.quick, options.spheres), indent=2,
                     default=float))
