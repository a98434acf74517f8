"""Surface-mesh files of the blade and geometry code: fused triangle meshes (STL, OBJ, PLY with
faces) read as input to the reconstruction, and the reconstruction's own binary STL with a region
per triangle (:func:`write_stl`, :func:`read_stl`).

The per-triangle region is written into the binary STL's attribute word (region index + 1 of
:data:`~steamtwin.geometry.volume_mesh.REGIONS`, 0 = none); STL readers that do not know this
ignore it. (The tetrahedral meshes' .msh/.vtu files are in :mod:`.volume_mesh`.)

Scanner software often delivers its fused result as a triangle mesh rather than a cloud. The
mesh is read with trimesh, checked (triangles present, finite coordinates, triangles of
non-zero area, a plausible size in metres — the cloud checks of
:func:`~steamtwin.geometry.pointcloud.check_point_cloud`) and turned into the cloud the
pipeline expects: points spread uniformly over the surface area (trimesh's
``sample.sample_surface``: a triangle chosen with probability proportional to its area and a
uniform point in it, Osada et al. 2002, "Shape distributions", ACM TOG 21:807, §4.2),
optionally with the mesh's own vertices. A PLY without faces is
a cloud and stays with :func:`~steamtwin.geometry.pointcloud.read_point_cloud`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.pointcloud import PointCloudError, check_point_cloud
from steamtwin.geometry.volume_mesh import REGIONS

#: Suffixes of triangle-mesh files (a .ply counts only when it holds faces).
MESH_SUFFIXES = (".stl", ".obj", ".ply")
#: Points sampled by default: the method's fused cloud (150k scanned → 80k kept).
DEFAULT_SAMPLES = 80_000
#: A triangle counts as degenerate when its area is below this share of the median area.
DEGENERATE_AREA = 1e-12


class MeshInputError(PointCloudError):
    """An unreadable, empty, non-finite or degenerate mesh; the message names the file."""


@dataclass(frozen=True)
class MeshSampling:
    """What :func:`mesh_to_cloud` did: ``triangles`` and ``vertices`` of the mesh,
    ``degenerate`` zero-area triangles left out, ``area`` (m²), ``samples`` surface points,
    ``vertices_added`` mesh vertices appended."""

    triangles: int
    vertices: int
    degenerate: int
    area: float
    samples: int
    vertices_added: int

    def as_dict(self) -> dict:
        """Report form (area in mm²)."""
        return {"triangles": self.triangles, "vertices": self.vertices,
                "degenerate_triangles": self.degenerate, "area_mm2": self.area * 1e6,
                "samples": self.samples, "vertices_added": self.vertices_added}


def ply_has_faces(path: str | Path) -> bool:
    """Whether the PLY header of ``path`` declares a non-empty ``face`` element."""
    path = Path(path)
    try:
        with path.open("rb") as handle:
            header = handle.read(65536)
    except OSError as error:
        raise MeshInputError(f"{path}: cannot read the file: {error.strerror}") from None
    end = header.find(b"end_header")
    for line in header[: end if end >= 0 else len(header)].decode("ascii", "replace").split("\n"):
        words = line.split()
        if len(words) == 3 and words[0] == "element" and words[1] == "face":
            return words[2].isdigit() and int(words[2]) > 0
    return False


def is_mesh_file(path: str | Path) -> bool:
    """Whether ``path`` is a triangle mesh by its suffix: .stl, .obj, or a .ply with faces."""
    suffix = Path(path).suffix.lower()
    if suffix == ".ply":
        return Path(path).is_file() and ply_has_faces(path)
    return suffix in (".stl", ".obj")


def read_mesh(path: str | Path, unit_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3; m, times ``unit_scale``) and triangles (m, 3) of an STL, OBJ or PLY
    mesh, vertices merged. Raises :class:`MeshInputError` naming the file when it is missing,
    unreadable, has no triangles or non-finite coordinates (zero-area triangles and the size
    are checked by :func:`mesh_to_cloud`)."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise MeshInputError(f"{path}: unknown mesh format {suffix!r}; expected one of "
                             f"{', '.join(MESH_SUFFIXES)}")
    if not (np.isfinite(unit_scale) and unit_scale > 0.0):
        raise MeshInputError(f"{path}: unit_scale must be a positive factor to metres "
                             f"(got {unit_scale})")
    if not path.is_file():
        raise MeshInputError(f"{path}: no such file")
    try:
        mesh = trimesh.load_mesh(path, file_type=suffix[1:], process=False, force="mesh")
    except Exception as error:  # trimesh raises assorted errors on malformed files
        raise MeshInputError(f"{path}: not a readable {suffix[1:].upper()} mesh: {error}"
                             ) from None
    faces = np.asarray(getattr(mesh, "faces", np.empty((0, 3))), dtype=np.int64)
    if faces.ndim != 2 or len(faces) == 0:
        raise MeshInputError(f"{path}: the file holds no triangles (expected a triangle mesh; "
                             "a cloud without faces is read as a point cloud)")
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    bad = ~np.all(np.isfinite(vertices), axis=1)
    if np.any(bad):
        raise MeshInputError(f"{path}: {int(bad.sum())} of {len(vertices)} vertices have NaN "
                             "or infinite coordinates")
    vertices = vertices * unit_scale
    merged = trimesh.Trimesh(vertices, faces, process=False)
    merged.merge_vertices()
    return np.asarray(merged.vertices, dtype=np.float64), np.asarray(merged.faces, np.int64)


def mesh_to_cloud(vertices: np.ndarray, triangles: np.ndarray, samples: int = DEFAULT_SAMPLES,
                  include_vertices: bool = False,
                  random_state: np.random.Generator | int | None = 0,
                  source: str = "mesh") -> tuple[np.ndarray, MeshSampling]:
    """Cloud (n, 3; m) of ``samples`` points spread uniformly by area over the triangles,
    plus the vertices when ``include_vertices``; and what was done. Zero-area triangles are
    left out; a mesh of only such triangles, or a cloud of implausible size (wrong units: read
    a file in mm with ``unit_scale=1e-3``), raises :class:`MeshInputError` naming ``source``."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    if samples < 1:
        raise MeshInputError(f"{source}: samples must be a positive count (got {samples})")
    areas = trimesh.triangles.area(vertices[triangles])
    scale = float(np.median(areas)) if len(areas) else 0.0
    degenerate = areas <= DEGENERATE_AREA * max(scale, np.finfo(float).tiny)
    if np.all(degenerate):
        raise MeshInputError(f"{source}: all {len(triangles)} triangles have zero area")
    mesh = trimesh.Trimesh(vertices, triangles[~degenerate], process=False)
    seed = (random_state if isinstance(random_state, int | None)
            else int(random_state.integers(2**31)))
    points, _ = trimesh.sample.sample_surface(mesh, samples, seed=seed)
    used = np.unique(triangles[~degenerate])
    cloud = np.vstack([points, vertices[used]]) if include_vertices else np.asarray(points)
    report = MeshSampling(triangles=len(triangles), vertices=len(vertices),
                          degenerate=int(degenerate.sum()), area=float(mesh.area),
                          samples=len(points),
                          vertices_added=len(used) if include_vertices else 0)
    return check_point_cloud(cloud, source), report


def read_mesh_cloud(path: str | Path, samples: int = DEFAULT_SAMPLES,
                    include_vertices: bool = False, unit_scale: float = 1.0,
                    random_state: np.random.Generator | int | None = 0
                    ) -> tuple[np.ndarray, MeshSampling]:
    """:func:`read_mesh` then :func:`mesh_to_cloud`: the cloud (m) of a mesh file."""
    vertices, triangles = read_mesh(path, unit_scale)
    return mesh_to_cloud(vertices, triangles, samples, include_vertices, random_state, str(path))


class RegionMesh(Protocol):
    """A closed triangle mesh with a region per triangle — what :func:`write_stl` writes (a
    :class:`~steamtwin.geometry.reconstruct.Reconstruction` is one)."""

    vertices: np.ndarray  # (n, 3), m
    triangles: np.ndarray  # (m, 3) vertex indices, outward
    regions: np.ndarray  # (m,) indices into REGIONS


def write_stl(reconstruction: RegionMesh, path: str | Path) -> Path:
    """Write the triangulation as binary STL (m) with the region of each triangle in its
    attribute word (REGIONS index + 1)."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = trimesh.Trimesh(reconstruction.vertices, reconstruction.triangles, process=False)
    data = bytearray(trimesh.exchange.stl.export_stl(mesh))
    records = np.frombuffer(data, dtype=np.uint8, offset=84).reshape(-1, 50)
    records[:, 48:50] = np.frombuffer((reconstruction.regions + 1).astype("<u2").tobytes(),
                                      dtype=np.uint8).reshape(-1, 2)
    path.write_bytes(bytes(data))
    return path


def read_stl(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Vertices (m), triangles and regions (None when the file carries none) of a binary or
    ASCII STL; vertices are merged. Raises :class:`ReconstructionError` naming the file."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    path = Path(path)
    if not path.is_file():
        raise ReconstructionError(f"{path}: no such STL file")
    try:
        mesh = trimesh.load_mesh(path, file_type="stl", process=False)
    except Exception as error:  # trimesh raises assorted errors on malformed files
        raise ReconstructionError(f"{path}: not a readable STL: {error}") from None
    if len(mesh.faces) == 0:
        raise ReconstructionError(f"{path}: the STL holds no triangles")
    regions = None
    raw = path.read_bytes()
    count = int.from_bytes(raw[80:84], "little") if len(raw) >= 84 else -1
    if len(raw) == 84 + 50 * count == 84 + 50 * len(mesh.faces):
        words = np.frombuffer(raw, dtype=np.uint8, offset=84).reshape(-1, 50)[:, 48:50]
        attribute = words.copy().view("<u2").ravel().astype(np.int64)
        if np.all((attribute >= 1) & (attribute <= len(REGIONS))):
            regions = attribute - 1
    mesh.merge_vertices()
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, np.int64), regions
