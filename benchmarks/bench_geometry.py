"""Full-size geometry benchmark: 150k-point scan of hp1 -> preprocessing -> fidelity; surface
reconstruction -> STL -> fidelity and mesh of the measured blade; meshing; scan-uncertainty
study. Prints timings and the measured figures.

Run: python benchmarks/bench_geometry.py [row]
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from steamtwin.geometry.fidelity import align_to_nominal, surface_deviation
from steamtwin.geometry.meshing import blade_volume_mesh, mesh_quality, mesh_stl
from steamtwin.geometry.preprocess import PreprocessSettings, preprocess_views, transform
from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.reconstruct import reconstruct_blade, reconstruction_fidelity, write_stl
from steamtwin.geometry.scanner import ScannerSettings, scan_blade
from steamtwin.geometry.uncertainty import scan_uncertainty
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import load_spec


def main(row: str = "hp1") -> dict:
    spec = load_spec("reference")
    blade = make_blade(spec, row)
    figures: dict = {"row": row}

    start = time.perf_counter()
    scan = scan_blade(blade, ScannerSettings(points=150_000, views=8), rng=0)
    figures["scan_s"] = time.perf_counter() - start

    start = time.perf_counter()
    fused, poses, report = preprocess_views(
        [v.points for v in scan.views], PreprocessSettings(target_points=80_000),
        initial_poses=[v.tracked_pose for v in scan.views])
    figures["preprocess_s"] = time.perf_counter() - start
    figures["steps"] = {"input": sum(report.input_points),
                        "outliers_injected": sum(int(v.is_outlier.sum()) for v in scan.views),
                        "outliers_removed": sum(report.outliers_removed),
                        "fused": report.fused_points, "downsampled": report.downsampled_points,
                        "pose_graph_edges": report.pose_graph_edges}
    base = np.linalg.inv(scan.views[0].pose)
    figures["registration_error_max_mm"] = max(
        float(np.linalg.norm(transform(v.points, p) - transform(v.points, base @ v.pose),
                             axis=1).max()) * 1e3
        for v, p in zip(scan.views, poses, strict=True))

    start = time.perf_counter()
    pose, fit_rms = align_to_nominal(fused, blade)
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

    figures["reconstruction"] = _reconstruction(blade, transform(fused, pose))

    start = time.perf_counter()
    mesh = blade_volume_mesh(spec, row)
    figures["mesh_s"] = time.perf_counter() - start
    figures["mesh_quality"] = mesh_quality(mesh).as_dict()

    start = time.perf_counter()
    model = FullOrderModel(spec)
    _ = model.design_
    study = scan_uncertainty(blade, model, samples=20, sections=3, rng=0)
    figures["uncertainty_s"] = time.perf_counter() - start
    figures["uncertainty"] = study.as_dict()
    return figures


def _reconstruction(blade: Blade, cloud: np.ndarray) -> dict:
    """Surface reconstruction of the best-fitted fused cloud: patches, fit, deviation of the
    STL from the exact blade, row metrics and a volume mesh of the STL (mm, s)."""
    import tempfile
    from pathlib import Path

    figures: dict = {}
    start = time.perf_counter()
    result = reconstruct_blade(cloud)
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
        path = write_stl(result, Path(folder) / "blade.stl")
        start = time.perf_counter()
        mesh = mesh_stl(path)
        figures["mesh_stl_s"] = time.perf_counter() - start
    figures["mesh_stl_nodes"] = len(mesh.points)
    figures["mesh_stl_volume_error"] = mesh.volume() / blade.volume - 1.0
    return figures


if __name__ == "__main__":
    print(json.dumps(main(*sys.argv[1:2]), indent=2, default=float))
