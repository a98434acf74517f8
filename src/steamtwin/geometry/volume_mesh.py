"""Tetrahedral volume meshes of blades: the data structure and its files (.msh, .vtu).

Frame (m): x axial (downstream), y tangential, z radial = distance from the turbine axis, so the
blade root sits at z = hub radius. Every boundary face of the tetrahedra is listed once, with its
normal pointing out of the blade, and labelled with one of :data:`REGIONS`.
"""

from __future__ import annotations

import contextlib
import ctypes
import signal
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from steamtwin.errors import MeshError

REGIONS = ("root", "tip", "pressure_side", "suction_side", "leading_edge", "trailing_edge")
#: Physical-group tags in .msh files: 1-6 for REGIONS (2-D), 7 for the blade volume (3-D).
VOLUME_TAG = len(REGIONS) + 1



@dataclass(frozen=True)
class VolumeMesh:
    """A tetrahedral blade mesh in metres (see the module docstring for the frame).

    ``points`` (N, 3) float64; ``tetrahedra`` (M, 4) int64 with positive volume;
    ``boundary_triangles`` (K, 3) int64, every boundary face once, outward normals;
    ``boundary_regions`` (K,) int64 indices into :data:`REGIONS`.
    """

    points: np.ndarray
    tetrahedra: np.ndarray
    boundary_triangles: np.ndarray
    boundary_regions: np.ndarray

    def volume(self) -> float:
        """Total volume (m³)."""
        return float(np.sum(tetrahedron_volumes(self.points, self.tetrahedra)))

    def region_area(self, region: str) -> float:
        """Area (m²) of the boundary faces labelled ``region``."""
        tri = self.boundary_triangles[self.boundary_regions == REGIONS.index(region)]
        p = self.points[tri]
        return float(0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
                                          axis=1).sum())


def tetrahedron_volumes(points: np.ndarray, tetrahedra: np.ndarray) -> np.ndarray:
    """Signed volumes (m³) of the tetrahedra (positive for right-handed vertex order)."""
    p = points[tetrahedra]
    return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
                     p[:, 3] - p[:, 0]) / 6.0


def boundary_faces(tetrahedra: np.ndarray) -> np.ndarray:
    """Faces (K, 3) used by exactly one tetrahedron, ordered so their normals point outward.

    Assumes positively oriented tetrahedra: for tet (a, b, c, d) the outward faces are
    (a, c, b), (a, b, d), (a, d, c), (b, c, d).
    """
    t = tetrahedra
    faces = np.concatenate([t[:, [0, 2, 1]], t[:, [0, 1, 3]], t[:, [0, 3, 2]], t[:, [1, 2, 3]]])
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inverse.ravel()] == 1]


def validate(mesh: VolumeMesh, source: str = "volume mesh") -> None:
    """Raise :class:`MeshError` (prefixed by ``source``) unless ``mesh`` keeps its contract."""
    pts, tets = mesh.points, mesh.tetrahedra
    tri, reg = mesh.boundary_triangles, mesh.boundary_regions
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 4:
        raise MeshError(f"{source}: points must be an (N >= 4, 3) array, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise MeshError(f"{source}: points contain NaN or infinite coordinates")
    if tets.ndim != 2 or tets.shape[1] != 4 or len(tets) == 0:
        raise MeshError(f"{source}: tetrahedra must be an (M >= 1, 4) array, got {tets.shape}")
    if tri.ndim != 2 or tri.shape[1] != 3 or reg.shape != (len(tri),):
        raise MeshError(f"{source}: boundary arrays have shapes {tri.shape} and {reg.shape}")
    for name, cells in (("tetrahedra", tets), ("boundary_triangles", tri)):
        if cells.min() < 0 or cells.max() >= len(pts):
            raise MeshError(f"{source}: {name} index a point outside 0..{len(pts) - 1}")
    if reg.size and (reg.min() < 0 or reg.max() >= len(REGIONS)):
        raise MeshError(f"{source}: boundary region index outside 0..{len(REGIONS) - 1}")
    volumes = tetrahedron_volumes(pts, tets)
    if np.any(volumes <= 0.0):
        raise MeshError(f"{source}: {int(np.sum(volumes <= 0.0))} tetrahedra have "
                        "non-positive volume")
    expected = np.unique(np.sort(boundary_faces(tets), axis=1), axis=0)
    given = np.unique(np.sort(tri, axis=1), axis=0)
    if len(given) != len(tri) or not np.array_equal(expected, given):
        raise MeshError(f"{source}: boundary_triangles are not exactly the {len(expected)} "
                        f"boundary faces of the tetrahedra (got {len(tri)})")


def _ignore_sigpipe_again() -> None:
    """Undo what gmsh.initialize() does to SIGPIPE. Python ignores SIGPIPE, so that a write to
    a closed pipe or socket raises BrokenPipeError (Python docs, :mod:`signal`: "SIGPIPE is
    ignored"); gmsh's initialize sets it back to the default action — terminate — in C,
    behind Python's back (measured: the SigIgn bit of SIGPIPE in /proc/self/status cleared
    while ``signal.getsignal`` still says SIG_IGN). A process that meshed and then writes to
    a closed connection (the demo's OPC UA server and web server, a DevTools pipe to a
    browser that exited) was killed outright (exit 141). Set through libc, so that it also
    works off the main thread (``signal.signal`` is main-thread only)."""
    if not hasattr(signal, "SIGPIPE") or signal.getsignal(signal.SIGPIPE) != signal.SIG_IGN:
        return  # no SIGPIPE here, or the application chose otherwise: leave it
    libc = ctypes.CDLL(None, use_errno=True)
    libc.signal.argtypes = (ctypes.c_int, ctypes.c_void_p)
    libc.signal.restype = ctypes.c_void_p
    libc.signal(int(signal.SIGPIPE), ctypes.c_void_p(int(signal.SIG_IGN)))


@contextlib.contextmanager
def gmsh_session() -> Iterator[object]:
    """An initialised, silent gmsh with a fresh model; finalises only what it initialised."""
    import gmsh  # deferred: optional heavy library (a C++ kernel), only meshing pays it

    started = not gmsh.isInitialized()
    if started:
        gmsh.initialize(readConfigFiles=False)
        _ignore_sigpipe_again()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.Verbosity", 0)
    name = f"steamtwin-{id(object())}"
    gmsh.model.add(name)
    try:
        yield gmsh
    finally:
        gmsh.model.setCurrent(name)
        gmsh.model.remove()
        if started:
            gmsh.finalize()


def write_volume_mesh(mesh: VolumeMesh, path: str | Path) -> None:
    """Write ``mesh`` as gmsh 4.1 ``.msh`` (physical groups named by REGIONS + "blade") or ``.vtu``.

    In ``.vtu`` the boundary triangles carry the cell data ``region`` (index into REGIONS, −1 on
    the tetrahedra).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".msh", ".vtu"):
        raise MeshError(f"{path}: unknown mesh format {suffix!r}; use .msh or .vtu")
    validate(mesh, str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".vtu":
        import meshio  # deferred: ~0.5 s import, only .vtu files need it

        cells = [("tetra", mesh.tetrahedra), ("triangle", mesh.boundary_triangles)]
        region = [np.full(len(mesh.tetrahedra), -1, dtype=np.int64),
                  mesh.boundary_regions.astype(np.int64)]
        meshio.Mesh(mesh.points, cells, cell_data={"region": region}).write(path)
        return
    with gmsh_session() as gmsh:
        node_tags = np.arange(1, len(mesh.points) + 1)
        volume_tag = 1
        surfaces = []
        for index in range(len(REGIONS)):
            faces = mesh.boundary_triangles[mesh.boundary_regions == index]
            if len(faces) == 0:
                continue
            tag = index + 1
            gmsh.model.addDiscreteEntity(2, tag)
            surfaces.append(tag)
        gmsh.model.addDiscreteEntity(3, volume_tag, surfaces)
        gmsh.model.mesh.addNodes(3, volume_tag, node_tags, mesh.points.ravel())
        gmsh.model.mesh.addElementsByType(
            volume_tag, 4, np.arange(1, len(mesh.tetrahedra) + 1), (mesh.tetrahedra + 1).ravel())
        next_element = len(mesh.tetrahedra) + 1
        for index, name in enumerate(REGIONS):
            faces = mesh.boundary_triangles[mesh.boundary_regions == index]
            if len(faces) == 0:
                continue
            tags = np.arange(next_element, next_element + len(faces))
            next_element += len(faces)
            gmsh.model.mesh.addElementsByType(index + 1, 2, tags, (faces + 1).ravel())
            gmsh.model.addPhysicalGroup(2, [index + 1], index + 1, name=name)
        gmsh.model.addPhysicalGroup(3, [volume_tag], VOLUME_TAG, name="blade")
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.write(str(path))


def read_volume_mesh(path: str | Path) -> VolumeMesh:
    """Read a mesh written by :func:`write_volume_mesh` (or any gmsh 4.1 ``.msh`` with the same
    physical names); validates it, errors name the file."""
    path = Path(path)
    if not path.is_file():
        raise MeshError(f"{path}: no such mesh file")
    suffix = path.suffix.lower()
    if suffix == ".vtu":
        return _read_vtu(path)
    if suffix != ".msh":
        raise MeshError(f"{path}: unknown mesh format {suffix!r}; use .msh or .vtu")
    with gmsh_session() as gmsh:
        try:
            gmsh.merge(str(path))
        except Exception as error:  # gmsh raises a bare Exception with its log message
            raise MeshError(f"{path}: gmsh cannot read it: {error}") from None
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        if len(node_tags) == 0:
            raise MeshError(f"{path}: the file holds no nodes")
        index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
        points = coords.reshape(-1, 3).astype(np.float64)
        groups = {gmsh.model.getPhysicalName(dim, tag): (dim, tag)
                  for dim, tag in gmsh.model.getPhysicalGroups()}
        if "blade" not in groups:
            raise MeshError(f"{path}: no 3-D physical group named 'blade' "
                            f"(found {sorted(groups)})")
        tets = _group_elements(gmsh, *groups["blade"], 4, index)
        triangles, regions = [], []
        for region_index, name in enumerate(REGIONS):
            if name in groups:
                faces = _group_elements(gmsh, *groups[name], 2, index)
                triangles.append(faces)
                regions.append(np.full(len(faces), region_index, dtype=np.int64))
    if not triangles:
        raise MeshError(f"{path}: no physical groups named like the regions {REGIONS}")
    mesh = VolumeMesh(points, tets, np.concatenate(triangles), np.concatenate(regions))
    validate(mesh, str(path))
    return _compact(mesh)


def _group_elements(gmsh: object, dim: int, tag: int, element_type: int,
                    index: np.ndarray) -> np.ndarray:
    width = 4 if element_type == 4 else 3
    cells = []
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        types, _, nodes = gmsh.model.mesh.getElements(dim, int(entity))
        for kind, conn in zip(types, nodes, strict=True):
            if kind == element_type:
                cells.append(index[conn.astype(np.int64)].reshape(-1, width))
    return np.concatenate(cells) if cells else np.empty((0, width), dtype=np.int64)


def _read_vtu(path: Path) -> VolumeMesh:
    import meshio  # deferred: ~0.5 s import, only .vtu files need it

    try:
        data = meshio.read(path)
    except Exception as error:  # meshio raises assorted errors on malformed files
        raise MeshError(f"{path}: meshio cannot read it: {error}") from None
    tets = [c.data for c in data.cells if c.type == "tetra"]
    if not tets:
        raise MeshError(f"{path}: no tetrahedra in the file")
    if "region" not in data.cell_data:
        raise MeshError(f"{path}: no cell data 'region' labelling the boundary triangles")
    triangles, regions = [], []
    for block, region in zip(data.cells, data.cell_data["region"], strict=True):
        if block.type == "triangle":
            triangles.append(block.data)
            regions.append(np.asarray(region))
    if not triangles:
        raise MeshError(f"{path}: no boundary triangles in the file")
    mesh = VolumeMesh(np.asarray(data.points, dtype=np.float64),
                      np.concatenate(tets).astype(np.int64),
                      np.concatenate(triangles).astype(np.int64),
                      np.concatenate(regions).astype(np.int64))
    validate(mesh, str(path))
    return mesh


def _compact(mesh: VolumeMesh) -> VolumeMesh:
    """Drop points no tetrahedron uses and renumber."""
    used = np.unique(mesh.tetrahedra)
    if len(used) == len(mesh.points):
        return mesh
    new = np.full(len(mesh.points), -1, dtype=np.int64)
    new[used] = np.arange(len(used))
    return VolumeMesh(mesh.points[used], new[mesh.tetrahedra], new[mesh.boundary_triangles],
                      mesh.boundary_regions)
