"""Figure 9's blade field drawn as a surface: the mesh's own triangles, Gouraud-shaded."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.collections import TriMesh

from steamtwin.blade.mesh import REGIONS
from steamtwin.rom.figure import field_comparison_figure, field_figure, surface_triangulation


def test_the_triangulation_is_the_meshs_pressure_side_connectivity(coarse_blade):
    triangulation, nodes = surface_triangulation(coarse_blade)
    region = coarse_blade.boundary_regions == REGIONS.index("pressure_side")
    expected = coarse_blade.boundary_triangles[region]
    # mapped back to mesh node numbers, the triangles are the region's boundary triangles
    np.testing.assert_array_equal(nodes[triangulation.triangles], expected)
    np.testing.assert_allclose(triangulation.x, coarse_blade.points[nodes, 0] * 1e3)
    np.testing.assert_allclose(triangulation.y, coarse_blade.points[nodes, 2] * 1e3)
    with pytest.raises(ValueError, match="region 'shroud'"):
        surface_triangulation(coarse_blade, "shroud")


def test_each_panel_is_a_shaded_surface_of_the_field(coarse_blade, tmp_path):
    points = coarse_blade.points
    fom = 700.0 + 2000.0 * points[:, 2]  # K, linear in radius
    rom = fom + 0.5
    figure = field_figure(coarse_blade, fom, rom, "test")
    triangulation, nodes = surface_triangulation(coarse_blade)
    panels = figure.axes[:3]
    for axis, values in zip(panels, (fom[nodes] - 273.15, rom[nodes] - 273.15,
                                     np.full(nodes.size, 0.5)), strict=True):
        meshes = [c for c in axis.collections if isinstance(c, TriMesh)]
        assert len(meshes) == 1  # one surface, no scatter of nodes
        np.testing.assert_allclose(meshes[0].get_array(), values)
        paths = meshes[0].get_paths()  # one closed path per drawn triangle
        corners = np.stack([triangulation.x[triangulation.triangles],
                            triangulation.y[triangulation.triangles]], axis=-1)
        assert len(paths) == len(corners)
        np.testing.assert_allclose(paths[0].vertices[:3], corners[0])
    path = field_comparison_figure(coarse_blade, fom, rom, tmp_path / "fig9.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="shape"):
        field_figure(coarse_blade, fom[:-1], rom)
