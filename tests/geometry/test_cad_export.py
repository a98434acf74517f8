"""CAD export: the clamped side equals the periodic one, the STEP face equals it to 1 µm, the
solid's volume equals the STL's, IGES is written and read back."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.bspline import PeriodicSurface, clamped_knots
from steamtwin.geometry.cad_export import CadExportError, clamped_side, write_cad
from steamtwin.geometry.reconstruct import ReconstructionSettings, triangulate
from steamtwin.geometry.segmentation import CapPlane
from steamtwin.geometry.volume_mesh import gmsh_session

BOUNDARIES = {"trailing_edge|suction_side": 0.05, "suction_side|leading_edge": 0.45,
              "leading_edge|pressure_side": 0.55, "pressure_side|trailing_edge": 0.95}


def _blade(breaks: int = 30, seed: int = 0) -> tuple[PeriodicSurface, CapPlane, CapPlane]:
    """A tapered, leaning, lens-like section (10 mm chord, 20 mm span) on uneven knots, caps
    tilted."""
    rng = np.random.default_rng(seed)
    knots = np.sort(np.r_[0.0, rng.uniform(0.0, 1.0, breaks - 1)])
    z_knots = clamped_knots(0.500, 0.520, 2)
    greville = np.array([z_knots[j + 1:j + 4].mean() for j in range(len(z_knots) - 4)])
    angle = 2.0 * np.pi * np.arange(breaks) / breaks
    coefficients = np.zeros((breaks, len(greville), 2))
    for j, z in enumerate(greville):
        scale = 1.0 - 5.0 * (z - 0.5)
        coefficients[:, j, 0] = 5e-3 * scale * np.cos(angle) + 0.2 * (z - 0.5)
        coefficients[:, j, 1] = 1.2e-3 * scale * np.sin(angle) + 2e-4 * np.sin(2 * angle)
    root = CapPlane(np.array([0.500 + 2e-3, 0.05, -0.02]), 0.0)
    tip = CapPlane(np.array([0.520 - 2e-3, -0.03, 0.04]), 0.0)
    return PeriodicSurface(knots, z_knots, coefficients), root, tip


def test_clamped_side_is_the_periodic_surface() -> None:
    surface, _, _ = _blade()
    clamped = clamped_side(surface)
    rng = np.random.default_rng(1)
    s = rng.uniform(0.0, 1.0, 500)
    z = rng.uniform(surface.z_knots[0], surface.z_knots[-1], 500)
    expected = np.column_stack([surface(s, z), z])
    assert np.abs(clamped(s, z) - expected).max() < 1e-12
    assert np.abs(clamped(np.zeros(3), z[:3]) - clamped(np.ones(3), z[:3])).max() < 1e-15
    assert clamped.control_points.shape[:2] == (len(surface.breaks) + 3,
                                                len(surface.z_knots) - 4)


def _reread(path, size: float | None = None) -> dict:
    """Faces, their areas and (with ``size``, m) the volume of a 2-D mesh of a CAD file read
    back with gmsh in metres."""
    import trimesh

    with gmsh_session() as gmsh:
        gmsh.option.setString("Geometry.OCCTargetUnit", "M")
        gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        faces = [tag for _, tag in gmsh.model.getEntities(2)]
        result = {"faces": faces, "volumes": len(gmsh.model.getEntities(3)),
                  "areas": [gmsh.model.occ.getMass(2, tag) for tag in faces],
                  "types": [gmsh.model.getType(2, tag) for tag in faces],
                  "centres": np.array([gmsh.model.occ.getCenterOfMass(2, tag)
                                       for tag in faces])}
        side = faces[int(np.argmax(result["areas"]))]
        low, high = gmsh.model.getParametrizationBounds(2, side)
        rng = np.random.default_rng(2)
        uv = np.column_stack([rng.uniform(low[0], high[0], 400),
                              rng.uniform(low[1], high[1], 400)])
        result["side_uv"] = uv
        result["side_xyz"] = np.reshape(gmsh.model.getValue(2, side, uv.ravel()), (-1, 3))
        if size is not None:
            gmsh.option.setNumber("Mesh.MeshSizeMax", size)
            gmsh.model.mesh.generate(2)
            nodes, coords, _ = gmsh.model.mesh.getNodes()
            index = np.zeros(int(nodes.max()) + 1, dtype=int)
            index[nodes.astype(int)] = np.arange(len(nodes))
            triangles = np.vstack([index[gmsh.model.mesh.getElements(2, tag)[2][0].astype(int)]
                                   .reshape(-1, 3) for tag in faces])
            mesh = trimesh.Trimesh(coords.reshape(-1, 3), triangles)
            mesh.merge_vertices()
            result["watertight"] = mesh.is_watertight
            result["volume"] = abs(mesh.volume)
    return result


def test_step_solid_matches_the_surface_and_the_stl(tmp_path) -> None:
    surface, root, tip = _blade()
    step, iges = tmp_path / "blade.step", tmp_path / "blade.igs"
    export = write_cad(surface, root, tip, [step, iges])
    assert export.solid and export.faces == 3 and export.unit == "mm"
    assert "MILLI" in step.read_text(errors="replace")
    read = _reread(step, size=0.25e-3)
    assert read["volumes"] == 1 and len(read["faces"]) == 3
    assert read["types"].count("Plane") == 2 and "BSpline surface" in read["types"]
    # the face's u is the side's s: points at (u, v) lie on the PeriodicSurface at (u, z)
    s, xyz = read["side_uv"][:, 0], read["side_xyz"]
    assert np.abs(xyz[:, :2] - surface(s, xyz[:, 2])).max() <= 1e-6
    # the cap faces lie in the cap planes: their centroids are on them
    caps = read["centres"][[t == "Plane" for t in read["types"]]]
    caps = caps[np.argsort(caps[:, 2])]
    for plane, centre in zip((root, tip), caps, strict=True):
        assert centre[2] == pytest.approx(plane.height(centre[None, :2])[0], abs=1e-9)
    vertices, triangles, _, _ = triangulate(surface, root, tip, BOUNDARIES,
                                            ReconstructionSettings())
    import trimesh

    stl_volume = trimesh.Trimesh(vertices, triangles, process=False).volume
    assert read["watertight"]
    assert read["volume"] == pytest.approx(stl_volume, rel=1e-3)


def test_iges_is_written_and_read_back(tmp_path) -> None:
    surface, root, tip = _blade(breaks=12, seed=3)
    iges = tmp_path / "blade.iges"
    write_cad(surface, root, tip, [iges])
    read = _reread(iges)
    assert len(read["faces"]) == 3
    s, xyz = read["side_uv"][:, 0], read["side_xyz"]
    assert np.abs(xyz[:, :2] - surface(s, xyz[:, 2])).max() <= 1e-6


def test_unknown_suffix_is_refused(tmp_path) -> None:
    surface, root, tip = _blade(breaks=12)
    with pytest.raises(CadExportError, match=r"blade\.dxf: unknown CAD format"):
        write_cad(surface, root, tip, [tmp_path / "blade.dxf"])
