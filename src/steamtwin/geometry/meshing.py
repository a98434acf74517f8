"""Tetrahedral simulation meshes of blades (gmsh, HXT) and their quality.

The blade is rebuilt in gmsh's OpenCASCADE kernel as a loft (``addThruSections``) through
sections of the ground-truth blade; every section is a wire of the five Pritchard segments, so
the loft has one face per segment plus root and tip caps, which become the boundary regions.
The volume is meshed with the HXT algorithm (Marot, Pellerin & Remacle 2019, IJNME 117:967).
A reconstructed blade (an STL whose triangles carry the regions) is lofted the same way through
sections cut from its surface (:func:`mesh_stl`, :func:`mesh_surface`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.fidelity import surface_samples
from steamtwin.geometry.mesh_io import read_stl
from steamtwin.geometry.mesh_sections import section_loops
from steamtwin.geometry.pritchard import SEGMENT_REGION, SEGMENTS
from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.segmentation import segment_blade
from steamtwin.geometry.volume_mesh import (
    REGIONS,
    MeshError,
    VolumeMesh,
    boundary_faces,
    gmsh_session,
    tetrahedron_volumes,
    validate,
)
from steamtwin.progress import ProgressCallback
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
                      progress: ProgressCallback | None = None) -> VolumeMesh:
    """Tetrahedral mesh of the ground-truth blade of ``row`` (m; frame of :class:`VolumeMesh`).

    ``element_size`` is the target edge length in m (None: :func:`default_element_size`, about
    18k nodes for ``hp1``); the leading and trailing edges are refined by curvature.
    """
    return mesh_blade(make_blade(spec, row), element_size=element_size, progress=progress)


def mesh_blade(blade: Blade, *, element_size: float | None = None,
               progress: ProgressCallback | None = None) -> VolumeMesh:
    """Tetrahedral mesh of ``blade`` (see :func:`blade_volume_mesh`)."""
    size = default_element_size(blade) if element_size is None else float(element_size)
    chord = blade.profile.params.axial_chord
    if not (math.isfinite(size) and chord / 500.0 <= size <= chord):
        raise MeshError(f"element_size = {element_size!r} m is outside "
                        f"[{chord / 500.0:.3g}, {chord:.3g}] m for row {blade.row}")
    report = progress or (lambda fraction, message: None)
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
        report(0.2, "solid lofted through the sections")
        face_region = _classify_faces(gmsh, blade, volume)
        points, tets, face_of_triangle = _mesh_volume(gmsh, volume, face_region, size)
        report(0.9, "volume meshed (HXT)")
    mesh = _assemble(points, tets, face_of_triangle)
    validate(mesh, f"volume mesh of {blade.row}")
    report(1.0, "mesh checked")
    return mesh


def _mesh_volume(gmsh: object, volume: int, face_region: dict[int, int], size: float
                 ) -> tuple[np.ndarray, np.ndarray, dict[tuple[int, ...], int]]:
    """Mesh the lofted ``volume`` (HXT, curvature-refined, ``size`` m); return the nodes (m),
    the tetrahedra and the region of every boundary triangle (sorted node triple → region)."""
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", size / 10.0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", ELEMENTS_PER_TURN)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.model.mesh.generate(3)
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
    index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
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
    return coords.reshape(-1, 3), tets, face_of_triangle


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


# --- meshing a reconstructed (STL) blade ---------------------------------------------------------

#: Order of the side regions round a section, anticlockwise from the trailing edge.
SIDE_ORDER = ("suction_side", "leading_edge", "pressure_side", "trailing_edge")


def mesh_stl(path: str | Path, *, element_size: float | None = None,
             progress: ProgressCallback | None = None) -> VolumeMesh:
    """Tetrahedral mesh of a blade STL written by
    :func:`~steamtwin.geometry.mesh_io.write_stl` (see :func:`mesh_surface`).

    An STL without region attributes (from other software) is labelled by segmenting points
    sampled on it (:func:`~steamtwin.geometry.segmentation.segment_blade`): each triangle takes
    the patch of the sample nearest its centre.
    """
    path = Path(path)
    try:
        vertices, triangles, regions = read_stl(path)
        if regions is None:
            regions = label_triangles(vertices, triangles)
    except ReconstructionError as error:
        raise MeshError(str(error)) from None
    return mesh_surface(vertices, triangles, regions, element_size=element_size,
                        name=str(path), progress=progress)


def label_triangles(vertices: np.ndarray, triangles: np.ndarray, samples: int = 60_000,
                    random_state: int = 0) -> np.ndarray:
    """Region (index into REGIONS) of every triangle of a closed blade surface, from the
    segmentation of ``samples`` points spread over it; −1 where the nearest sample has none."""

    points = surface_samples(vertices, triangles, samples, random_state)
    labels = segment_blade(points).labels
    _, nearest = cKDTree(points).query(vertices[triangles].mean(axis=1))
    return labels[nearest]


def mesh_surface(vertices: np.ndarray, triangles: np.ndarray, regions: np.ndarray, *,
                 element_size: float | None = None, name: str = "reconstructed blade",
                 progress: ProgressCallback | None = None) -> VolumeMesh:
    """Tetrahedral mesh (HXT) of a closed blade surface whose triangles carry REGIONS labels.

    Like :func:`mesh_blade`, the blade is lofted in OpenCASCADE through 7 sections: the root
    and tip rims (the edges between the cap triangles and the side) and 5 planar cuts z = const
    between them. Each section is split where its pieces change region into four splines
    (suction side, leading edge, pressure side, trailing edge), so the loft's faces are the six
    regions; each face takes the region of the surface triangle nearest its centre.
    ``element_size`` (m; None: (volume / DEFAULT_CELLS)^(1/3)). Raises :class:`MeshError`.
    """
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it


    vertices = np.asarray(vertices, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.int64)
    regions = np.asarray(regions, dtype=np.int64)
    missing = [r for k, r in enumerate(REGIONS) if not np.any(regions == k)]
    if missing:
        raise MeshError(f"{name}: no triangles of the region(s) {missing}")
    surface = trimesh.Trimesh(vertices, triangles, process=False)
    if not (surface.is_watertight and surface.volume > 0.0):
        raise MeshError(f"{name}: the surface is not closed with outward normals")
    report = progress or (lambda fraction, message: None)
    root_rim = _rim(vertices, triangles, regions, REGIONS.index("root"))
    tip_rim = _rim(vertices, triangles, regions, REGIONS.index("tip"))
    chord = float(np.max(np.linalg.norm(root_rim[0][:, None, :2] - root_rim[0][None, ::7, :2],
                                        axis=2)))
    size = ((surface.volume / DEFAULT_CELLS) ** (1.0 / 3.0) if element_size is None
            else float(element_size))
    if not (math.isfinite(size) and chord / 500.0 <= size <= chord):
        raise MeshError(f"element_size = {element_size!r} m is outside "
                        f"[{chord / 500.0:.3g}, {chord:.3g}] m for {name}")
    levels = np.linspace(root_rim[0][:, 2].max(), tip_rim[0][:, 2].min(), LOFT_SECTIONS)[1:-1]
    sections = [root_rim]
    for height in levels:
        try:
            points, faces = section_loops(vertices, triangles, float(height))[0]
        except ReconstructionError as error:
            raise MeshError(f"{name}: {error}") from None
        sections.append((np.column_stack([points, np.full(len(points), height)]),
                         regions[faces]))
    sections.append(tip_rim)
    with gmsh_session() as gmsh:
        occ = gmsh.model.occ
        wires = [_section_wire(occ, *_split_section(points, labels, name), chord)
                 for points, labels in sections]
        (volume,) = [tag for dim, tag in occ.addThruSections(wires, makeSolid=True,
                                                             makeRuled=False) if dim == 3]
        occ.synchronize()
        report(0.2, "solid lofted through the sections")
        face_region = _classify_by_surface(gmsh, volume, vertices, triangles, regions, name)
        points, tets, face_of_triangle = _mesh_volume(gmsh, volume, face_region, size)
        report(0.9, "volume meshed (HXT)")
    mesh = _assemble(points, tets, face_of_triangle)
    validate(mesh, f"volume mesh of {name}")
    report(1.0, "mesh checked")
    return mesh


def _rim(vertices: np.ndarray, triangles: np.ndarray, regions: np.ndarray,
         cap: int) -> tuple[np.ndarray, np.ndarray]:
    """The closed loop (points (n, 3), region of the side triangle along each edge i → i + 1)
    where the cap triangles of region ``cap`` meet the side."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    owner = np.tile(np.arange(len(triangles)), 3)
    key = np.sort(edges, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    if np.any(counts != 2):
        raise MeshError("the surface has edges not shared by exactly two triangles")
    on_cap = regions[owner] == cap
    # rim edges: one cap and one side triangle
    cap_side = np.bincount(inverse, weights=on_cap.astype(float), minlength=len(counts)) == 1
    rim = cap_side[inverse] & on_cap
    start, end = edges[rim, 0], edges[rim, 1]  # directed as in the cap triangles
    side_of = {}
    for k in np.flatnonzero(cap_side[inverse] & ~on_cap):
        side_of[inverse[k]] = regions[owner[k]]
    successor = dict(zip(start.tolist(), end.tolist(), strict=True))
    region_of = {a: side_of[i] for a, i in zip(start.tolist(), inverse[rim].tolist(),
                                               strict=True)}
    if len(successor) != len(start):
        raise MeshError(f"the rim of the {REGIONS[cap]} cap is not a simple loop")
    loop = [start[0]]
    while successor[loop[-1]] != loop[0]:
        loop.append(successor[loop[-1]])
        if len(loop) > len(start):
            raise MeshError(f"the rim of the {REGIONS[cap]} cap is not a simple loop")
    if len(loop) != len(start):
        raise MeshError(f"the {REGIONS[cap]} cap has more than one rim")
    return vertices[loop], np.array([region_of[v] for v in loop])


def _split_section(points: np.ndarray, labels: np.ndarray, name: str
                   ) -> tuple[np.ndarray, list[int]]:
    """Anticlockwise loop starting at the first suction-side piece, and the indices where the
    four side regions of :data:`SIDE_ORDER` start (labels are per piece i → i + 1)."""
    x, y = points[:, 0], points[:, 1]
    if np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) < 0.0:  # clockwise: reverse
        points = points[::-1]
        labels = np.roll(labels[::-1], -1)
    changes = np.flatnonzero(labels != np.roll(labels, 1))
    runs = [int(labels[k]) for k in changes]
    wanted = [REGIONS.index(r) for r in SIDE_ORDER]
    first = runs.index(wanted[0]) if wanted[0] in runs else -1
    if len(runs) != 4 or first < 0 or runs[first:] + runs[:first] != wanted:
        found = [REGIONS[r] if r >= 0 else "none" for r in runs]
        raise MeshError(f"{name}: a section at z = {points[0, 2]:.6g} m runs through the "
                        f"regions {found}, expected {list(SIDE_ORDER)} once each")
    shift = int(changes[first])
    starts = [int((k - shift) % len(points)) for k in changes]
    return np.roll(points, -shift, axis=0), sorted(starts)


def _section_wire(occ: object, points: np.ndarray, starts: list[int], chord: float) -> int:
    """An OpenCASCADE wire of one spline per region run, sharing the run end points."""
    n = len(points)
    corner = [occ.addPoint(*points[k]) for k in starts]
    curves = []
    for k, begin in enumerate(starts):
        end = starts[(k + 1) % len(starts)] if k + 1 < len(starts) else n + starts[0]
        run = points[np.arange(begin, end + 1) % n]
        length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(run, axis=0),
                                                                  axis=1))])
        count = int(np.clip(length[-1] / (chord / 60.0), 8, 60))
        at = np.linspace(0.0, length[-1], count)[1:-1]
        inner = np.column_stack([np.interp(at, length, run[:, j]) for j in range(3)])
        tags = [occ.addPoint(*p) for p in inner]
        curves.append(occ.addSpline([corner[k], *tags, corner[(k + 1) % len(starts)]]))
    return occ.addWire(curves)


def _classify_by_surface(gmsh: object, volume: int, vertices: np.ndarray,
                         triangles: np.ndarray, regions: np.ndarray, name: str
                         ) -> dict[int, int]:
    """Region of every face of the lofted volume: the two flattest in z are the root (lower)
    and tip caps; a side face takes the region of the surface triangle nearest its parametric
    centre (which may lie off a curved cap's outline, never off a side face)."""
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    faces = [face for _, face in gmsh.model.getBoundary([(3, volume)], oriented=False)]
    boxes = np.array([gmsh.model.getBoundingBox(2, face) for face in faces])
    order = np.argsort(boxes[:, 5] - boxes[:, 2])
    caps = sorted(order[:2], key=lambda k: boxes[k, 2])
    found = {faces[caps[0]]: REGIONS.index("root"), faces[caps[1]]: REGIONS.index("tip")}
    sides = [faces[k] for k in order[2:]]
    middles = []
    for face in sides:
        lo, hi = gmsh.model.getParametrizationBounds(2, face)
        middles.append(gmsh.model.getValue(2, face, 0.5 * (np.asarray(lo) + np.asarray(hi))))
    centre = vertices.mean(axis=0)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices - centre, np.float32)),
                        o3d.core.Tensor(np.asarray(triangles, np.uint32)))
    answer = scene.compute_closest_points(o3d.core.Tensor(
        np.asarray(np.array(middles) - centre, np.float32)))
    found.update(zip(sides, regions[answer["primitive_ids"].numpy().astype(np.int64)].tolist(),
                     strict=True))
    if sorted(found.values()) != list(range(len(REGIONS))):
        raise MeshError(f"{name}: the loft's faces map to the regions "
                        f"{[REGIONS[r] if r >= 0 else 'none' for r in found.values()]}, "
                        "expected each region once")
    return found
