"""Volume-mesh contract and its .msh/.vtu files."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from steamtwin.geometry.volume_mesh import (
    REGIONS,
    MeshError,
    VolumeMesh,
    read_volume_mesh,
    validate,
    write_volume_mesh,
)

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop


@pytest.mark.parametrize("suffix", [".msh", ".vtu"])
def test_round_trip_keeps_every_array(hp1_mesh: VolumeMesh, tmp_path, suffix: str) -> None:
    path = tmp_path / f"blade{suffix}"
    write_volume_mesh(hp1_mesh, path)
    back = read_volume_mesh(path)
    np.testing.assert_allclose(back.points, hp1_mesh.points, rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(back.tetrahedra, hp1_mesh.tetrahedra)
    original = {tuple(sorted(t)): r for t, r in zip(hp1_mesh.boundary_triangles,
                                                    hp1_mesh.boundary_regions, strict=True)}
    again = {tuple(sorted(t)): r for t, r in zip(back.boundary_triangles, back.boundary_regions,
                                                 strict=True)}
    assert again == original
    assert back.points.dtype == np.float64 and back.tetrahedra.dtype == np.int64


def test_msh_has_named_physical_groups(hp1_mesh: VolumeMesh, tmp_path) -> None:
    path = tmp_path / "blade.msh"
    write_volume_mesh(hp1_mesh, path)
    text = path.read_text()
    assert text.startswith("$MeshFormat\n4.1")
    for name in (*REGIONS, "blade"):
        assert f'"{name}"' in text


def test_broken_meshes_are_refused(hp1_mesh: VolumeMesh, tmp_path) -> None:
    flipped = hp1_mesh.tetrahedra.copy()
    flipped[0] = flipped[0, [1, 0, 2, 3]]
    with pytest.raises(MeshError, match="non-positive volume"):
        validate(dataclasses.replace(hp1_mesh, tetrahedra=flipped))
    with pytest.raises(MeshError, match="boundary faces"):
        validate(dataclasses.replace(hp1_mesh, boundary_triangles=hp1_mesh.boundary_triangles[1:],
                                     boundary_regions=hp1_mesh.boundary_regions[1:]))
    nan_points = hp1_mesh.points.copy()
    nan_points[3, 1] = np.nan
    with pytest.raises(MeshError, match="NaN"):
        write_volume_mesh(dataclasses.replace(hp1_mesh, points=nan_points), tmp_path / "x.msh")


def test_bad_files_name_the_file(tmp_path) -> None:
    missing = tmp_path / "missing.msh"
    with pytest.raises(MeshError, match=r"missing\.msh"):
        read_volume_mesh(missing)
    garbage = tmp_path / "garbage.msh"
    garbage.write_text("this is not a mesh\n")
    with pytest.raises(MeshError, match=r"garbage\.msh"):
        read_volume_mesh(garbage)
    with pytest.raises(MeshError, match=r"blade\.stl"):
        read_volume_mesh_path = tmp_path / "blade.stl"
        read_volume_mesh_path.write_text("solid x\nendsolid x\n")
        read_volume_mesh(read_volume_mesh_path)
