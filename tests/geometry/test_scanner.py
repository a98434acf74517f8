"""Virtual scanner: noise bound, outlier share, self-occlusion, frames, files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from steamtwin.geometry.fidelity import blade_distance
from steamtwin.geometry.pointcloud import read_point_cloud
from steamtwin.geometry.scanner import ScannerSettings, scan_blade, write_scan

pytestmark = pytest.mark.slow  # 37 s of the full suite (2026-11-27): not in the quick loop

SETTINGS = ScannerSettings(views=6, points=24_000, outlier_share=0.02)


@pytest.fixture(scope="module")
def hp1_scan(hp1_blade):
    return scan_blade(hp1_blade, SETTINGS, random_state=7)


def _in_blade_frame(view) -> np.ndarray:
    return view.points @ view.pose[:3, :3].T + view.pose[:3, 3]


def test_inliers_lie_within_the_scanner_accuracy(hp1_scan, hp1_blade) -> None:
    for view in hp1_scan.views:  # the blade's points (the reference spheres: their own test)
        inliers = _in_blade_frame(view)[~view.is_outlier & (view.sphere_index < 0)]
        distance = blade_distance(hp1_blade, inliers)
        # the range error is cut at ±0.05 mm; along an oblique ray the normal distance is less
        assert distance.max() <= SETTINGS.noise_bound + 1e-6
        rms = float(np.sqrt(np.mean(distance**2)))  # ≈ σ·cos(incidence), truncation lowers it
        assert 0.4 * SETTINGS.noise_sigma < rms < 1.0 * SETTINGS.noise_sigma


def test_counts_outliers_and_reproducibility(hp1_scan, hp1_blade) -> None:
    assert len(hp1_scan.views) == 6
    total = sum(int(np.sum(v.sphere_index < 0)) for v in hp1_scan.views)  # spheres on top
    assert total == SETTINGS.points
    share = sum(int(v.is_outlier.sum()) for v in hp1_scan.views) / total
    assert share == pytest.approx(0.02, abs=0.002)
    again = scan_blade(hp1_blade, SETTINGS, random_state=7)
    np.testing.assert_array_equal(again.views[3].points, hp1_scan.views[3].points)


def test_views_are_partial_and_in_their_own_frames(hp1_scan, hp1_blade) -> None:
    # self-occlusion: no view sees both faces of the blade at one spot, so each view covers
    # well under the whole surface; frames differ (camera at each view's origin)
    for view in hp1_scan.views:
        rotation = view.pose[:3, :3]
        np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(rotation) == pytest.approx(1.0)
        inliers = view.points[~view.is_outlier]
        assert np.all(inliers[:, 2] > 0.0)  # everything is in front of the camera
    poses = [v.pose for v in hp1_scan.views]
    assert all(np.abs(a - b).max() > 0.1 for i, a in enumerate(poses) for b in poses[i + 1:])
    # self-occlusion: each view sees only part of the blade, all views together nearly all
    from scipy.spatial import cKDTree

    from steamtwin.geometry.fidelity import surface_samples
    from steamtwin.geometry.profile import reference_surface

    vertices, triangles, _ = reference_surface(hp1_blade)
    truth = surface_samples(vertices, triangles, 20_000, np.random.default_rng(0))
    seen = []
    for view in hp1_scan.views:
        distance = cKDTree(_in_blade_frame(view)[~view.is_outlier]).query(truth)[0]
        seen.append(distance < 1e-3)
        assert 0.15 < seen[-1].mean() < 0.7
    assert np.mean(np.any(seen, axis=0)) > 0.95


def test_written_scan_reads_back(hp1_scan, tmp_path) -> None:
    paths = write_scan(hp1_scan, tmp_path, file_format="pcd")
    manifest = json.loads((tmp_path / "scan.json").read_text())
    assert manifest["row"] == "hp1" and len(manifest["tracked_poses"]) == 6
    for path, view in zip(paths, hp1_scan.views, strict=True):
        np.testing.assert_allclose(read_point_cloud(path), view.points, atol=1e-7)  # float32
    truth = json.loads((tmp_path / "truth" / "poses.json").read_text())
    np.testing.assert_allclose(truth["poses"][2], hp1_scan.views[2].pose)


def test_bad_settings_are_refused(hp1_blade) -> None:
    with pytest.raises(ValueError, match="outlier_share"):
        scan_blade(hp1_blade, ScannerSettings(outlier_share=0.5))


def _fused_points_across_edge(blade, points: int) -> float:
    """Points of the fused cloud (KEPT_SHARE of ``points``) on the half circle π·r of the
    smaller edge at the narrowest section, at the cloud's mean spacing over the blade area."""
    import trimesh

    from steamtwin.geometry.preprocess_settings import KEPT_SHARE
    from steamtwin.geometry.profile import reference_surface

    vertices, triangles, _ = reference_surface(blade)
    area = trimesh.Trimesh(vertices, triangles, process=False).area
    design, params = blade.design, blade.profile.params
    scale = min(design.chord_scale(design.hub_radius), design.chord_scale(design.tip_radius))
    edge = min(params.leading_edge_radius, params.trailing_edge_radius) * float(scale)
    return np.pi * edge / np.sqrt(area / (KEPT_SHARE * points))


@pytest.mark.parametrize("row", ["hp1", "hp13", "ip1", "ip5", "ip9"])
def test_planned_scan_resolves_the_edges(reference_spec, row) -> None:
    from steamtwin.geometry.profile import make_blade
    from steamtwin.geometry.scanner import EDGE_SAMPLES, METHOD_SCAN_POINTS, planned_points

    blade = make_blade(reference_spec, row)
    points = planned_points(blade)
    assert points >= METHOD_SCAN_POINTS
    across = _fused_points_across_edge(blade, points)
    assert across >= EDGE_SAMPLES * (1 - 1e-9)
    if points > METHOD_SCAN_POINTS:  # the fewest that do: one point fewer falls short
        assert _fused_points_across_edge(blade, points - 1) < EDGE_SAMPLES
    # the short control-stage rotor needs no more than the method's 150k, the longer rows do
    assert (points == METHOD_SCAN_POINTS) == (row == "hp1")


def test_planned_points_scale_with_the_edge_samples_squared(reference_spec) -> None:
    from steamtwin.geometry.profile import make_blade
    from steamtwin.geometry.scanner import planned_points

    blade = make_blade(reference_spec, "ip9")
    base = planned_points(blade, edge_samples=3.0, minimum=1)
    assert planned_points(blade, edge_samples=6.0, minimum=1) == pytest.approx(4 * base, rel=1e-5)
    assert planned_points(blade, kept_share=0.25, minimum=1) > planned_points(blade, minimum=1)
    for bad in ({"edge_samples": 0.0}, {"kept_share": 1.5}, {"minimum": 0}):
        with pytest.raises(ValueError, match="edge_samples"):
            planned_points(blade, **bad)
