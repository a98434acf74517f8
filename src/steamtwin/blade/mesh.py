"""Tetrahedral solids for the blade conduction model, shaped like the geometry `VolumeMesh`.

The blade mesh itself comes from ``steamtwin.geometry.meshing.blade_volume_mesh``; the FEM only
needs an object with ``points`` (N, 3) m, ``tetrahedra`` (M, 4), ``boundary_triangles`` (K, 3)
and ``boundary_regions`` (K,) indices into :data:`REGIONS`. This module checks such an object
and converts it to a scikit-fem mesh.

:func:`block_mesh` meshes a rectangular block with the same region names (x axial, y tangential,
z radial): the solid of the analytic verification cases (slab, fin) and of the tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import MeshTet

from steamtwin.errors import MeshError

REGIONS = ("root", "tip", "pressure_side", "suction_side", "leading_edge", "trailing_edge")
"""Boundary regions of a blade, the order of the geometry package's ``VolumeMesh``."""



@dataclass(frozen=True)
class SolidMesh:
    """A tetrahedral solid with tagged boundary triangles (same fields as ``VolumeMesh``).

    ``points`` (N, 3) in m; ``tetrahedra`` (M, 4) and ``boundary_triangles`` (K, 3) node indices;
    ``boundary_regions`` (K,) indices into :data:`REGIONS`.
    """

    points: np.ndarray
    tetrahedra: np.ndarray
    boundary_triangles: np.ndarray
    boundary_regions: np.ndarray


def checked_mesh(mesh: object) -> SolidMesh:
    """Validate a ``VolumeMesh``-shaped object and return it as a :class:`SolidMesh`.

    Raises :class:`MeshError` naming the field for wrong shapes, non-finite points, indices out
    of range or region ids outside :data:`REGIONS`.
    """
    try:
        points = np.asarray(mesh.points, dtype=float)  # type: ignore[attr-defined]
        tetrahedra = np.asarray(mesh.tetrahedra, dtype=np.int64)  # type: ignore[attr-defined]
        triangles = np.asarray(mesh.boundary_triangles, dtype=np.int64)  # type: ignore[attr-defined]
        regions = np.asarray(mesh.boundary_regions, dtype=np.int64)  # type: ignore[attr-defined]
    except AttributeError as error:
        raise MeshError(f"not a volume mesh: {error}") from None
    if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] < 4:
        raise MeshError(f"points must have shape (N ≥ 4, 3), got {points.shape}")
    if not np.all(np.isfinite(points)):
        raise MeshError("points must be finite")
    if tetrahedra.ndim != 2 or tetrahedra.shape[1] != 4 or tetrahedra.shape[0] == 0:
        raise MeshError(f"tetrahedra must have shape (M ≥ 1, 4), got {tetrahedra.shape}")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise MeshError(f"boundary_triangles must have shape (K, 3), got {triangles.shape}")
    if regions.shape != (triangles.shape[0],):
        raise MeshError(
            f"boundary_regions must have shape ({triangles.shape[0]},), got {regions.shape}"
        )
    n = points.shape[0]
    for name, cells in (("tetrahedra", tetrahedra), ("boundary_triangles", triangles)):
        if cells.size and (cells.min() < 0 or cells.max() >= n):
            raise MeshError(f"{name} index a node outside 0…{n - 1}")
    if regions.size and (regions.min() < 0 or regions.max() >= len(REGIONS)):
        raise MeshError(f"boundary_regions must index REGIONS {REGIONS}")
    return SolidMesh(points, tetrahedra, triangles, regions)


def to_skfem(mesh: SolidMesh) -> MeshTet:
    """The scikit-fem mesh of a solid (positively oriented tetrahedra)."""
    p = mesh.points
    t = mesh.tetrahedra.copy()
    a, b, c, d = (p[t[:, i]] for i in range(4))
    volume6 = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    if np.any(np.abs(volume6) <= 1e-30 * np.max(np.abs(volume6))):
        raise MeshError("the mesh has degenerate (zero-volume) tetrahedra")
    flip = volume6 < 0.0
    t[flip, 2], t[flip, 3] = mesh.tetrahedra[flip, 3], mesh.tetrahedra[flip, 2]
    # node order inside each tetrahedron kept (oriented above); validation done above
    return MeshTet(np.ascontiguousarray(p.T), np.ascontiguousarray(t.T), sort_t=False,
                   validate=False)


def block_mesh(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> SolidMesh:
    """A tetrahedral block on the tensor grid ``x × y × z`` (m) with blade-named faces.

    Faces: z min ``root``, z max ``tip``, y min ``pressure_side``, y max ``suction_side``,
    x min ``leading_edge``, x max ``trailing_edge``. Used for the analytic verification
    (slab, fin) and the tests; not a blade.
    """
    skmesh = MeshTet.init_tensor(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float))
    boundary = skmesh.boundary_facets()
    centres = skmesh.p[:, skmesh.facets[:, boundary]].mean(axis=1)
    lows = [float(np.min(v)) for v in (x, y, z)]
    highs = [float(np.max(v)) for v in (x, y, z)]
    tolerance = 1e-9 * max(h - lo for h, lo in zip(highs, lows, strict=True))
    regions = np.full(boundary.size, -1, dtype=np.int64)
    faces = (
        (2, lows[2], "root"), (2, highs[2], "tip"),
        (1, lows[1], "pressure_side"), (1, highs[1], "suction_side"),
        (0, lows[0], "leading_edge"), (0, highs[0], "trailing_edge"),
    )
    for axis, value, name in faces:
        on_face = (regions < 0) & (np.abs(centres[axis] - value) <= tolerance)
        regions[on_face] = REGIONS.index(name)
    triangles = skmesh.facets[:, boundary].T.astype(np.int64)
    # orient outward: the block is convex, so outward means away from its centre
    corners = skmesh.p.T[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    centre = 0.5 * (np.array(lows) + np.array(highs))
    inward = np.einsum("ij,ij->i", normal, corners.mean(axis=1) - centre) < 0.0
    triangles[inward] = triangles[inward][:, ::-1]
    return SolidMesh(
        points=np.ascontiguousarray(skmesh.p.T),
        tetrahedra=np.ascontiguousarray(skmesh.t.T.astype(np.int64)),
        boundary_triangles=triangles,
        boundary_regions=regions,
    )
