"""Tetrahedral simulation meshes of blades (gmsh, HXT) and their quality.

The blade is rebuilt in gmsh's OpenCASCADE kernel as a loft (``addThruSections``) through
sections of the ground-truth blade; every section is a wire of the five Pritchard segments, so
the loft has one face per segment plus root and tip caps, which become the boundary regions.
The volume is meshed with the HXT algorithm (Marot, Pellerin & Remacle 2019, IJNME 117:967).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from steamtwin.geometry.profile import SEGMENT_REGION, SEGMENTS, Blade, make_blade
from steamtwin.geometry.volume_mesh import (
    REGIONS,
    MeshError,
    VolumeMesh,
    boundary_faces,
    gmsh_session,
    tetrahedron_volumes,
    validate,
)
from steamtwin.spec import TurbineSpec

#: Default element size: (blade volume / DEFAULT_CELLS)^(1/3), i.e. about this many size³ cells
#: in the blade. 7500 gives 15-25k nodes for every HP row (hp1: ~18.5k, size 1.37 mm) with three
#: or more elements across the thinnest section; see tests/geometry/test_meshing.py.
DEFAULT_CELLS = 7500.0
#: Loft sections along the span (the twist is smooth: 7 sections capture it to < 1 µm).
LOFT_SECTIONS = 7
#: Curvature refinement: elements per 2π of a curve (gmsh Mesh.MeshSizeFromCurvature); resolves
#: the leading- and trailing-edge circles.
ELEMENTS_PER_TURN = 20


@dataclass(frozen=True)
class MeshQuality:
    """Quality figures of a tetrahedral mesh.

    Angles in degrees; the aspect ratio is the normalised radius ratio R / (3 r) (circumradius
    over three times the inradius: 1 for a regular tetrahedron, growing without bound for
    slivers). Volumes in m³.
    """

    node_count: int
    tetrahedron_count: int
    min_dihedral_angle: float
    max_dihedral_angle: float
    max_aspect_ratio: float
    mean_aspect_ratio: float
    min_volume: float
    total_volume: float
    share_below_10_deg: float  # share of tetrahedra with a dihedral angle below 10°

    def as_dict(self) -> dict[str, float | int]:
        return dict(self.__dict__)


def default_element_size(blade: Blade) -> float:
    """Default element size (m): (blade volume / :data:`DEFAULT_CELLS`)^(1/3)."""
    return (blade.volume / DEFAULT_CELLS) ** (1.0 / 3.0)


def blade_volume_mesh(spec: TurbineSpec, row: str = "hp1", *, element_size: float | None = None,
                      progress: Callable[[float], None] | None = None) -> VolumeMesh:
    """Tetrahedral mesh of the ground-truth blade of ``row`` (m; frame of :class:`VolumeMesh`).

    ``element_size`` is the target edge length in m (None: :func:`default_element_size`, about
    18k nodes for ``hp1``); the leading and trailing edges are refined by curvature.
    """
    return mesh_blade(make_blade(spec, row), element_size=element_size, progress=progress)


def mesh_blade(blade: Blade, *, element_size: float | None = None,
               progress: Callable[[float], None] | None = None) -> VolumeMesh:
    """Tetrahedral mesh of ``blade`` (see :func:`blade_volume_mesh`)."""
    size = default_element_size(blade) if element_size is None else float(element_size)
    chord = blade.profile.params.axial_chord
    if not (math.isfinite(size) and chord / 500.0 <= size <= chord):
        raise MeshError(f"element_size = {element_size!r} m is outside "
                        f"[{chord / 500.0:.3g}, {chord:.3g}] m for row {blade.row}")
    report = progress or (lambda fraction: None)
    radii = np.linspace(blade.design.hub_radius, blade.design.tip_radius, LOFT_SECTIONS)
    lengths = blade.profile.segment_lengths()
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        wires = []
        for radius in radii:
            curves = []
            first_point = previous_end = None
            for index in range(len(SEGMENTS)):
                count = int(np.clip(lengths[index] / (chord / 60.0), 8, 60))
                pts = blade.place(blade.profile.segment(index, count), float(radius))
                tags = [occ.addPoint(*p) for p in pts[1:-1]]
                start = previous_end if previous_end is not None else occ.addPoint(*pts[0])
                if first_point is None:
                    first_point = start
                end = (first_point if index == len(SEGMENTS) - 1 else occ.addPoint(*pts[-1]))
                curves.append(occ.addSpline([start, *tags, end]))
                previous_end = end
            wires.append(occ.addWire(curves))
        (volume,) = [tag for dim, tag in occ.addThruSections(wires, makeSolid=True,
                                                             makeRuled=False) if dim == 3]
        occ.synchronize()
        report(0.2)
        face_region = _classify_faces(gmsh, blade, volume)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", size / 10.0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", ELEMENTS_PER_TURN)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.model.mesh.generate(3)
        report(0.9)
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
        points = coords.reshape(-1, 3)
        types, _, conn = gmsh.model.mesh.getElements(3, volume)
        tets = np.concatenate([index[c.astype(np.int64)].reshape(-1, 4)
                               for t, c in zip(types, conn, strict=True) if t == 4])
        face_of_triangle = {}
        for face, region in face_region.items():
            types, _, conn = gmsh.model.mesh.getElements(2, face)
            for t, c in zip(types, conn, strict=True):
                if t == 2:
                    for tri in index[c.astype(np.int64)].reshape(-1, 3):
                        face_of_triangle[tuple(sorted(tri))] = region
    mesh = _assemble(points, tets, face_of_triangle)
    validate(mesh, f"volume mesh of {blade.row}")
    report(1.0)
    return mesh


def _classify_faces(gmsh: object, blade: Blade, volume: int) -> dict[int, int]:
    """Region index of every face of the lofted volume, from the ground truth at its centre."""
    outline, segment = blade.profile.sample(blade.profile.params.axial_chord / 400.0)
    regions = {}
    for dim, face in gmsh.model.getBoundary([(3, volume)], oriented=False):
        lo, hi = gmsh.model.getParametrizationBounds(dim, face)
        centre = gmsh.model.getValue(dim, face, 0.5 * (np.asarray(lo) + np.asarray(hi)))
        if abs(centre[2] - blade.design.hub_radius) < 1e-9:
            regions[face] = REGIONS.index("root")
        elif abs(centre[2] - blade.design.tip_radius) < 1e-9:
            regions[face] = REGIONS.index("tip")
        else:
            local = blade.to_section(np.asarray(centre).reshape(1, 3))[0]
            nearest = int(np.argmin(np.linalg.norm(outline - local, axis=1)))
            regions[face] = REGIONS.index(SEGMENT_REGION[segment[nearest]])
    if len(regions) != len(SEGMENTS) + 2:
        raise MeshError(f"loft of {blade.row} has {len(regions)} faces, expected "
                        f"{len(SEGMENTS) + 2}")
    return regions


def _assemble(points: np.ndarray, tets: np.ndarray,
              face_region: dict[tuple[int, ...], int]) -> VolumeMesh:
    """Compact the nodes, orient the tetrahedra and label the boundary faces."""
    used = np.unique(tets)
    new = np.full(len(points), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    points = np.ascontiguousarray(points[used], dtype=np.float64)
    tets = new[tets]
    negative = tetrahedron_volumes(points, tets) < 0.0
    tets[negative] = tets[negative][:, [0, 2, 1, 3]]
    faces = boundary_faces(tets)
    old_of_new = used
    regions = np.empty(len(faces), dtype=np.int64)
    for k, face in enumerate(faces):
        key = tuple(sorted(old_of_new[face]))
        if key not in face_region:
            raise MeshError("a boundary face of the tetrahedra lies on no face of the blade")
        regions[k] = face_region[key]
    return VolumeMesh(points, tets.astype(np.int64), faces.astype(np.int64), regions)


def dihedral_angles(points: np.ndarray, tetrahedra: np.ndarray) -> np.ndarray:
    """The six interior dihedral angles (M, 6) of each tetrahedron, degrees."""
    p = points[tetrahedra]
    # outward-ish face normals of the faces opposite vertices 0..3
    faces = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))
    normals = []
    for a, b, c in faces:
        n = np.cross(p[:, b] - p[:, a], p[:, c] - p[:, a])
        normals.append(n / np.linalg.norm(n, axis=1, keepdims=True))
    angles = []
    for i in range(4):
        for j in range(i + 1, 4):
            cos = -np.einsum("ij,ij->i", normals[i], normals[j])
            angles.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return np.column_stack(angles)


def aspect_ratios(points: np.ndarray, tetrahedra: np.ndarray) -> np.ndarray:
    """Normalised radius ratio R / (3 r) of each tetrahedron (1 = regular)."""
    p = points[tetrahedra]
    volume = np.abs(tetrahedron_volumes(points, tetrahedra))
    area = sum(0.5 * np.linalg.norm(np.cross(p[:, b] - p[:, a], p[:, c] - p[:, a]), axis=1)
               for a, b, c in ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)))
    inradius = 3.0 * volume / area
    # circumradius: |a|² (b×c) + |b|² (c×a) + |c|² (a×b) over 12 V, edges from vertex 0
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    num = (np.sum(a * a, axis=1)[:, None] * np.cross(b, c)
           + np.sum(b * b, axis=1)[:, None] * np.cross(c, a)
           + np.sum(c * c, axis=1)[:, None] * np.cross(a, b))
    circumradius = np.linalg.norm(num, axis=1) / (12.0 * volume)
    return circumradius / (3.0 * inradius)


def mesh_quality(mesh: VolumeMesh) -> MeshQuality:
    """Dihedral angles, aspect ratios and volumes of ``mesh`` (see :class:`MeshQuality`)."""
    dihedral = dihedral_angles(mesh.points, mesh.tetrahedra)
    aspect = aspect_ratios(mesh.points, mesh.tetrahedra)
    volumes = tetrahedron_volumes(mesh.points, mesh.tetrahedra)
    return MeshQuality(
        node_count=len(mesh.points),
        tetrahedron_count=len(mesh.tetrahedra),
        min_dihedral_angle=float(dihedral.min()),
        max_dihedral_angle=float(dihedral.max()),
        max_aspect_ratio=float(aspect.max()),
        mean_aspect_ratio=float(aspect.mean()),
        min_volume=float(volumes.min()),
        total_volume=float(volumes.sum()),
        share_below_10_deg=float(np.mean(dihedral.min(axis=1) < 10.0)),
    )
