"""The blade frame from the data: our own rows (exact surface samples with scanner-like noise
and stray points) in random rigid poses, against the pose that put them there."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from steamtwin.cli.geometry import geometry_app
from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.fidelity import (
    align_to_nominal,
    blade_distance,
    chord_line,
    distances_to_mesh,
    sample_triangles,
    surface_samples,
    truth_section,
)
from steamtwin.geometry.frame import (
    estimate_blade_frame,
    nominal_starts,
    reconstruct_in_any_pose,
)
from steamtwin.geometry.mesh_io import read_stl
from steamtwin.geometry.pointcloud import write_point_cloud
from steamtwin.geometry.profile import Blade, make_blade, reference_surface
from steamtwin.geometry.reconstruct import reconstruct_blade
from steamtwin.geometry.rigid import transform
from steamtwin.spec import TurbineSpec, load_spec

pytestmark = pytest.mark.slow  # 61 s of the full suite (2026-11-27): not in the quick loop

runner = CliRunner()
EZ = np.array([0.0, 0.0, 1.0])
#: Rows with their hub/tip rule: hp5 is tapered (0.9), hp1 and ip3 are prismatic and need the
#: handedness (this package's rows: suction side towards +y).
ROW_SUCTION_SIDE = {"hp1": "+y", "hp5": None, "ip3": "+y"}


def noisy_cloud(blade: Blade, count: int, seed: int = 0) -> np.ndarray:
    """Points uniform over the exact surface, moved along the normal by N(0, 0.017 mm) (the
    issue's fused clouds), with 1 % stray points 0.2–2 mm off the surface."""
    vertices, triangles, _ = reference_surface(blade)
    rng = np.random.default_rng(seed)
    points, _, normals = sample_triangles(vertices, triangles, count, rng)
    offset = rng.normal(0.0, 0.017e-3, count)
    stray = rng.random(count) < 0.01
    offset[stray] = rng.uniform(0.2e-3, 2e-3, stray.sum())
    return points + offset[:, None] * normals


def mid_chord(blade: Blade) -> np.ndarray:
    """Unit chord direction (leading → trailing edge) of the exact mid-span section."""
    radius = blade.design.hub_radius + 0.5 * blade.design.span
    first, second, _ = chord_line(truth_section(blade, radius))
    return np.append((second - first) / np.linalg.norm(second - first), 0.0)


def degrees(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(np.dot(a, b), -1.0, 1.0))))


@pytest.fixture(scope="module")
def spec() -> TurbineSpec:
    return load_spec("reference")


@pytest.fixture(scope="module")
def clouds(spec) -> dict[str, tuple[Blade, np.ndarray]]:
    blades = {row: make_blade(spec, row) for row in ROW_SUCTION_SIDE}
    return {row: (blade, noisy_cloud(blade, 20_000)) for row, blade in blades.items()}


@pytest.fixture(scope="module")
def hp1_clean(spec) -> tuple[Blade, np.ndarray]:
    blade = make_blade(spec, "hp1")
    vertices, triangles, _ = reference_surface(blade)
    return blade, surface_samples(vertices, triangles, 20_000, np.random.default_rng(4))


@pytest.fixture(scope="module")
def hp1_direct(hp1_clean):
    return reconstruct_blade(hp1_clean[1])


quaternions = st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda q: np.linalg.norm(q) > 0.1)


@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(row=st.sampled_from(sorted(ROW_SUCTION_SIDE)), quaternion=quaternions,
       shift=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3))
@example(row="hp5", quaternion=[1.0, 0.0, 0.0, 0.0], shift=[0.0, 0.0, 0.0])  # span flipped
@example(row="hp1", quaternion=[0.0, 1.0, 0.0, 0.0], shift=[0.1, 0.0, 0.0])  # span flipped
@example(row="ip3", quaternion=[0.0, 0.0, 1.0, 0.0], shift=[0.0, 0.5, 0.0])  # chord flipped
def test_frame_of_a_row_in_any_pose(clouds, row, quaternion, shift) -> None:
    blade, points = clouds[row]
    rotation = Rotation.from_quat(quaternion).as_matrix()
    scan = points @ rotation.T + np.array(shift)
    frame = estimate_blade_frame(scan, suction_side=ROW_SUCTION_SIDE[row])
    # measured over the 22 rows, 80k points, 4 poses each (benchmarks/bench_frame.py): span
    # axis ≤ 0.026°, chord ≤ 0.77°
    assert degrees(frame.span_axis, rotation @ EZ) < 0.5
    assert not frame.hub_tip_ambiguous and not frame.edges_ambiguous
    assert degrees(frame.chord_direction, rotation @ mid_chord(blade)) < 3.0
    rule = "taper" if ROW_SUCTION_SIDE[row] is None else "handedness"
    assert frame.rules["hub_tip"].startswith(rule)
    if not frame.kept_scan_frame:
        # the hub cap at z = 0, the tip cap at the span; x, y, z right-handed
        caps = np.array([[*blade.profile.centroid, blade.design.hub_radius],
                         [*blade.profile.centroid, blade.design.tip_radius]])
        z = frame.to_blade(caps @ rotation.T + np.array(shift))[:, 2]
        assert z == pytest.approx([0.0, blade.design.span], abs=0.05e-3)
        assert frame.span == pytest.approx(blade.design.span, abs=0.05e-3)
        assert np.linalg.det(frame.rotation) == pytest.approx(1.0)
        np.testing.assert_allclose(frame.rotation @ frame.rotation.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(frame.to_scan(frame.to_blade(scan)), scan, atol=1e-12)


def test_hub_and_tip_of_an_untapered_blade_are_ambiguous_without_more(clouds) -> None:
    _, points = clouds["hp1"]
    rotation = Rotation.from_euler("xyz", [120.0, 35.0, -70.0], degrees=True).as_matrix()
    scan = points @ rotation.T
    frame = estimate_blade_frame(scan)
    assert frame.hub_tip_ambiguous and frame.rules["hub_tip"].startswith("ambiguous")
    report = json.loads(json.dumps(frame.as_dict()))  # JSON-able as it is
    assert report["hub_tip_ambiguous"] is True and report["kept_scan_frame"] is False
    np.testing.assert_allclose(report["matrix_scan_to_blade_m"], frame.matrix)
    # the hub end given as the scan axis pointing towards it decides
    hub_towards = rotation @ -EZ
    largest = int(np.argmax(np.abs(hub_towards)))
    given = f"{'+' if hub_towards[largest] > 0 else '-'}{'xyz'[largest]}"
    frame = estimate_blade_frame(scan, hub_end=given)
    assert not frame.hub_tip_ambiguous and frame.rules["hub_tip"].startswith("given")
    assert degrees(frame.span_axis, rotation @ EZ) < 0.5
    with pytest.raises(ValueError, match="hub_end must be one of"):
        estimate_blade_frame(scan, hub_end="up")


def test_symmetric_prism_is_ambiguous() -> None:
    """An elliptic prism (25 × 4 mm semi-axes, 40 mm long): no taper, no camber, both ends of
    the section alike — every choice but the span axis is ambiguous."""
    rng = np.random.default_rng(1)
    angle = rng.uniform(0.0, 2.0 * math.pi, 12_000)
    side = np.column_stack([25e-3 * np.cos(angle), 4e-3 * np.sin(angle),
                            rng.uniform(0.0, 40e-3, len(angle))])
    radius, turn = np.sqrt(rng.random(6_000)), rng.uniform(0.0, 2.0 * math.pi, 6_000)
    cap = np.column_stack([25e-3 * radius * np.cos(turn), 4e-3 * radius * np.sin(turn)])
    prism = np.vstack([side, np.column_stack([cap[:3000], np.zeros(3000)]),
                       np.column_stack([cap[3000:], np.full(3000, 40e-3)])])
    rotation = Rotation.from_euler("zyx", [10.0, 80.0, 30.0], degrees=True).as_matrix()
    frame = estimate_blade_frame(prism @ rotation.T, suction_side="+y")
    axis = rotation @ EZ
    assert min(degrees(frame.span_axis, axis), degrees(frame.span_axis, -axis)) < 0.5
    assert frame.hub_tip_ambiguous and frame.edges_ambiguous
    assert frame.span == pytest.approx(40e-3, abs=0.05e-3)


def test_an_open_tube_has_no_end_faces(clouds) -> None:
    blade, points = clouds["hp5"]
    inside = (points[:, 2] > blade.design.hub_radius + 1e-3) & (
        points[:, 2] < blade.design.tip_radius - 1e-3)
    with pytest.raises(ReconstructionError, match="no planar end face"):
        estimate_blade_frame(points[inside])


def test_a_cloud_in_the_blade_frame_reconstructs_as_before(hp1_clean, hp1_direct) -> None:
    _, points = hp1_clean
    result, frame = reconstruct_in_any_pose(points)
    assert frame.kept_scan_frame and "already a blade frame" in frame.rules["frame"]
    np.testing.assert_array_equal(frame.rotation, np.eye(3))
    np.testing.assert_array_equal(result.vertices, hp1_direct.vertices)
    np.testing.assert_array_equal(result.triangles, hp1_direct.triangles)


def test_reconstruction_in_any_pose_is_the_same_surface(hp1_clean, hp1_direct) -> None:
    blade, points = hp1_clean
    results = []
    for angles, shift in (([40.0, 150.0, -20.0], [0.3, -0.1, 0.2]), ([100.0, 20.0, 30.0],
                                                                      [-0.5, 0.0, 0.1])):
        rotation = Rotation.from_euler("zxz", angles, degrees=True).as_matrix()
        result, frame = reconstruct_in_any_pose(points @ rotation.T + shift, suction_side="+y")
        assert not frame.kept_scan_frame
        results.append(result)
        vertices = (frame.to_scan(result.vertices) - shift) @ rotation  # the nominal frame
        posed = blade_distance(blade, vertices)
        direct = blade_distance(blade, hp1_direct.vertices)
        # measured (20k exact points): RMS 0.0082 / 0.0095 mm, max 0.105 / 0.121 mm (posed /
        # reconstructed in the nominal frame; both at the trailing edge's tip corner)
        assert np.sqrt(np.mean(posed**2)) < 1.2 * np.sqrt(np.mean(direct**2))
        assert posed.max() < 1.2 * direct.max()
        assert result.volume == pytest.approx(hp1_direct.volume, rel=1e-3)
    # the frame from the data makes the reconstruction independent of the pose
    np.testing.assert_allclose(results[0].vertices, results[1].vertices, atol=1e-9)


def test_cli_frame_from_the_data_and_scan_frame_stl(spec, tmp_path) -> None:
    # exact points: 20k noisy points with 1 % stray ones are too sparse for hp5's 100 mm span
    # in any frame ("the fitted side folds over itself", issue 19 item 3)
    vertices, triangles, _ = reference_surface(make_blade(spec, "hp5"))
    points = surface_samples(vertices, triangles, 25_000, np.random.default_rng(2))
    rotation = Rotation.from_euler("xyz", [170.0, -20.0, 65.0], degrees=True).as_matrix()
    scan = points @ rotation.T + np.array([0.1, 0.2, -0.4])
    cloud = tmp_path / "posed.ply"
    write_point_cloud(scan, cloud)
    result = runner.invoke(geometry_app, ["reconstruct", str(cloud), "--out",
                                          str(tmp_path / "scan.stl"), "--frame", "scan"])
    assert result.exit_code == 0, result.output
    assert "blade frame from the data" in result.output and "taper" in result.output
    assert "AMBIGUOUS" not in result.output
    vertices, triangles, _ = read_stl(tmp_path / "scan.stl")
    # the STL written in the scan frame lies on the scan cloud (its points within 3σ of noise)
    distance = distances_to_mesh(scan, vertices, triangles)
    assert np.median(distance) < 0.02e-3
    result = runner.invoke(geometry_app, ["reconstruct", str(cloud), "--out",
                                          str(tmp_path / "blade.stl"), "--hub-end", "up"])
    assert result.exit_code == 2 and "--hub-end must be one of" in result.output
    result = runner.invoke(geometry_app, ["reconstruct", str(cloud), "--out",
                                          str(tmp_path / "blade.stl"), "--frame", "cad"])
    assert result.exit_code == 2 and "--frame must be 'blade' or 'scan'" in result.output


def test_the_frames_start_the_best_fit_to_the_nominal(clouds) -> None:
    blade, points = clouds["ip3"]
    rotation = Rotation.from_euler("yxz", [200.0, -60.0, 15.0], degrees=True).as_matrix()
    scan = points @ rotation.T + np.array([0.2, 0.4, -0.1])
    starts = nominal_starts(scan, blade)
    assert len(starts) == 1  # the handedness tells hub from tip
    # the coarse pose alone: the cloud's frame onto the nominal's, both from the data
    coarse = blade_distance(blade, transform(points @ rotation.T + np.array([0.2, 0.4, -0.1]),
                                             starts[0]))
    assert np.median(coarse) < 2e-3  # measured 0.93 mm: well inside the ICP's 8 mm first reach
    pose, rms = align_to_nominal(scan, blade, starts=starts)
    assert rms < 0.2e-3  # measured 0.13 mm: the 1 % stray points 0.2–2 mm off dominate it
    np.testing.assert_allclose(pose[:3, :3], rotation.T, atol=1e-4)


def test_cli_refuses_a_row_whose_nominal_does_not_match(clouds, tmp_path) -> None:
    _, points = clouds["hp5"]
    cloud = tmp_path / "hp5.ply"
    write_point_cloud(points[:8000], cloud)
    result = runner.invoke(geometry_app, ["reconstruct", str(cloud), "--row", "hp1", "--out",
                                          str(tmp_path / "x.stl")])
    assert result.exit_code == 2
    assert "the cloud does not match row hp1's nominal blade (best fit RMS" in result.output
    assert "leave out --row to reconstruct in a frame from the data" in result.output
    assert not (tmp_path / "x.stl").exists()
