"""Mesh input: meshes written by trimesh become area-uniform clouds on their surface; bad files
are refused naming the file."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.geometry.fidelity import distances_to_mesh
from steamtwin.geometry.mesh_io import (
    MeshInputError,
    is_mesh_file,
    mesh_to_cloud,
    read_mesh,
    read_mesh_cloud,
)
from steamtwin.geometry.pointcloud import PointCloudError, write_point_cloud


def _cylinder() -> trimesh.Trimesh:
    """A closed cylinder, radius 20 mm, 60 mm long, its axis along z from 0.5 m."""
    mesh = trimesh.creation.cylinder(radius=0.02, height=0.06, sections=128)
    mesh.apply_translation([0.0, 0.0, 0.53])
    return mesh


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_mesh_files_become_clouds_on_the_surface(tmp_path, suffix: str) -> None:
    mesh = _cylinder()
    path = tmp_path / f"blade{suffix}"
    mesh.export(path)
    assert is_mesh_file(path)
    vertices, triangles = read_mesh(path)
    assert len(triangles) == len(mesh.faces)
    cloud, report = read_mesh_cloud(path, samples=20_000, include_vertices=True)
    assert report.samples == 20_000 and report.vertices_added == len(vertices)
    assert len(cloud) == 20_000 + len(vertices)
    assert report.area == pytest.approx(mesh.area, rel=1e-6)  # STL: float32
    # every point lies on the mesh
    distance = distances_to_mesh(cloud[::20], np.asarray(mesh.vertices), np.asarray(mesh.faces))
    assert np.abs(distance).max() < 1e-7


def test_samples_are_area_uniform() -> None:
    """The share of points on the caps equals the caps' share of the area (binomial bound)."""
    mesh = _cylinder()
    cloud, _ = mesh_to_cloud(np.asarray(mesh.vertices), np.asarray(mesh.faces), 40_000,
                             random_state=1)
    on_caps = np.isclose(np.abs(cloud[:, 2] - 0.53), 0.03, atol=1e-9)
    caps = 2.0 * 0.5 * 128 * 0.02**2 * np.sin(2.0 * np.pi / 128)  # two 128-gons
    share = caps / (caps + float(
        trimesh.Trimesh(mesh.vertices, mesh.faces[np.abs(mesh.face_normals[:, 2]) < 0.01]).area))
    sigma = np.sqrt(share * (1 - share) / len(cloud))
    assert abs(on_caps.mean() - share) < 5 * sigma


@settings(max_examples=15, deadline=None)
@given(scale=st.floats(0.02, 50.0), count=st.integers(100, 3000))
def test_sample_count_and_size_hold_for_any_scale(scale: float, count: int) -> None:
    box = trimesh.creation.box(extents=[0.05 * scale, 0.02 * scale, 0.1 * scale])
    cloud, report = mesh_to_cloud(np.asarray(box.vertices), np.asarray(box.faces), count)
    assert len(cloud) == count == report.samples
    half = 0.5 * np.array([0.05, 0.02, 0.1]) * scale
    assert np.all(np.abs(cloud) <= half * (1 + 1e-9))


def test_a_ply_without_faces_is_a_cloud(tmp_path) -> None:
    path = tmp_path / "cloud.ply"
    write_point_cloud(np.asarray(_cylinder().sample(500)), path)
    assert not is_mesh_file(path)


def test_millimetre_files_need_their_scale(tmp_path) -> None:
    mesh = _cylinder()
    mesh.apply_scale(1e3)
    path = tmp_path / "blade_mm.stl"
    mesh.export(path)
    with pytest.raises(PointCloudError, match=r"blade_mm\.stl: .*millimetres"):
        read_mesh_cloud(path, samples=1000)
    cloud, _ = read_mesh_cloud(path, samples=1000, unit_scale=1e-3)
    assert np.abs(cloud[:, 2]).max() == pytest.approx(0.56, abs=1e-9)


def test_bad_meshes_are_refused(tmp_path) -> None:
    missing = tmp_path / "missing.stl"
    with pytest.raises(MeshInputError, match=r"missing\.stl: no such file"):
        read_mesh(missing)
    garbage = tmp_path / "garbage.stl"
    garbage.write_bytes(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex a b c\n")
    with pytest.raises(MeshInputError, match=r"garbage\.stl"):
        read_mesh(garbage)
    nan = tmp_path / "nan.obj"
    nan.write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    with pytest.raises(MeshInputError, match=r"nan\.obj: .*NaN"):
        read_mesh(nan)
    flat = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    with pytest.raises(MeshInputError, match=r"flat: all 1 triangles have zero area"):
        mesh_to_cloud(flat, np.array([[0, 1, 2]]), 100, source="flat")
    with pytest.raises(MeshInputError, match=r"unknown mesh format '\.dxf'"):
        read_mesh(tmp_path / "blade.dxf")
