"""Tetrahedral blade meshes against the exact ground-truth blade."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.meshing import (
    aspect_ratios,
    blade_volume_mesh,
    dihedral_angles,
    mesh_quality,
)
from steamtwin.geometry.volume_mesh import REGIONS, MeshError, VolumeMesh


def test_default_hp1_mesh_size_and_quality(hp1_mesh: VolumeMesh, hp1_blade) -> None:
    quality = mesh_quality(hp1_mesh)
    assert 10_000 <= quality.node_count <= 30_000
    assert quality.min_dihedral_angle > 5.0
    assert quality.max_aspect_ratio < 10.0
    assert quality.min_volume > 0.0
    # the mesh fills the exact blade: the loft and the straight-sided tets lose < 0.1 %
    assert quality.total_volume == pytest.approx(hp1_blade.volume, rel=1e-3)


def test_mesh_frame_and_regions(hp1_mesh: VolumeMesh, hp1_blade) -> None:
    design = hp1_blade.design
    assert hp1_mesh.points[:, 2].min() == pytest.approx(design.hub_radius, abs=1e-9)
    assert hp1_mesh.points[:, 2].max() == pytest.approx(design.tip_radius, abs=1e-9)
    # root and tip caps: flat, at the hub and tip radii, area = section area x chord scale²
    for region, radius in (("root", design.hub_radius), ("tip", design.tip_radius)):
        faces = hp1_mesh.boundary_triangles[hp1_mesh.boundary_regions == REGIONS.index(region)]
        np.testing.assert_allclose(hp1_mesh.points[faces][..., 2], radius, atol=1e-9)
        exact = hp1_blade.profile.area * float(design.chord_scale(radius)) ** 2
        assert hp1_mesh.region_area(region) == pytest.approx(exact, rel=2e-3)
    # every region is present and the outward normals enclose a positive volume
    assert set(np.unique(hp1_mesh.boundary_regions)) == set(range(len(REGIONS)))
    p = hp1_mesh.points[hp1_mesh.boundary_triangles]
    enclosed = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0
    assert enclosed == pytest.approx(hp1_mesh.volume(), rel=1e-9)


def test_leading_edge_faces_lie_on_the_leading_edge(hp1_mesh: VolumeMesh, hp1_blade) -> None:
    faces = hp1_mesh.boundary_triangles[hp1_mesh.boundary_regions ==
                                        REGIONS.index("leading_edge")]
    centres = hp1_mesh.points[faces].mean(axis=1)
    local = np.array([hp1_blade.to_section(c.reshape(1, 3))[0] for c in centres])
    radius = np.linalg.norm(local - hp1_blade.profile.le_centre, axis=1)
    r_le = hp1_blade.profile.params.leading_edge_radius
    assert np.all(np.abs(radius - r_le) < 0.03 * r_le)


def test_quality_measures_of_known_tetrahedra() -> None:
    s = np.sqrt(2.0)
    regular = np.array([[1, 0, -1 / s], [-1, 0, -1 / s], [0, 1, 1 / s], [0, -1, 1 / s]])
    tet = np.array([[0, 1, 2, 3]])
    np.testing.assert_allclose(dihedral_angles(regular, tet), np.degrees(np.arccos(1 / 3)))
    np.testing.assert_allclose(aspect_ratios(regular, tet), 1.0)
    corner = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert sorted(dihedral_angles(corner, tet)[0])[:3] == pytest.approx([54.7356] * 3, abs=1e-4)
    assert dihedral_angles(corner, tet).max() == pytest.approx(90.0)


def test_bad_element_size_is_refused(reference_spec) -> None:
    with pytest.raises(MeshError, match="element_size"):
        blade_volume_mesh(reference_spec, "hp1", element_size=1.0)
