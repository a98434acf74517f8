"""Closed triangle meshes: the watertightness check and plane sections (lengths in m) — used by
the reconstruction, the row metrics, the STL meshing and the reconstruction report."""

from __future__ import annotations

import numpy as np

from steamtwin.geometry.blade_cloud import ReconstructionError


def check_closed(vertices: np.ndarray, triangles: np.ndarray) -> None:
    """Raise :class:`ReconstructionError` unless the triangulation is a watertight, consistently
    wound surface enclosing a positive volume."""
    import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

    mesh = trimesh.Trimesh(vertices, triangles, process=False)
    problems = []
    if not mesh.is_watertight:
        problems.append("not watertight")
    if not mesh.is_winding_consistent:
        problems.append("inconsistent winding")
    if not mesh.volume > 0.0:
        problems.append(f"volume {mesh.volume:.3g} m³ is not positive")
    if problems:
        raise ReconstructionError("the reconstructed surface is " + ", ".join(problems))


def section_loops(vertices: np.ndarray, triangles: np.ndarray, height: float
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Closed loops where the plane z = ``height`` cuts a closed triangle mesh, longest first.

    Each loop is ``(points (n, 2) x-y in m, face (n,))``: the piece from point i to point i + 1
    lies on triangle ``face[i]``. A vertex on the plane counts as above it, so every cut
    triangle has exactly two cut edges; each edge's point is computed once and the loops follow
    the mesh's own edge-face topology.
    """
    above = vertices[:, 2] >= height
    corners = triangles[:, [[0, 1], [1, 2], [2, 0]]]  # (m, 3, 2)
    cut = above[corners[..., 0]] != above[corners[..., 1]]
    faces = np.flatnonzero(cut.sum(axis=1) == 2)
    if faces.size == 0:
        raise ReconstructionError(f"the mesh does not reach the plane z = {height:.6g} m")
    pairs = np.sort(corners[faces][cut[faces]].reshape(-1, 2), axis=1)  # two cut edges per face
    unique, edge_of = np.unique(pairs, axis=0, return_inverse=True)
    edge_of = edge_of.reshape(-1, 2)
    a, b = vertices[unique[:, 0]], vertices[unique[:, 1]]
    t = (height - a[:, 2]) / (b[:, 2] - a[:, 2])
    crossing = a[:, :2] + t[:, None] * (b[:, :2] - a[:, :2])
    # every cut edge joins the two cut faces that share it
    if np.any(np.bincount(edge_of.ravel(), minlength=len(unique)) != 2):
        raise ReconstructionError(f"the cut at z = {height:.6g} m is not closed: the mesh has "
                                  "holes")
    order = np.argsort(edge_of.ravel(), kind="stable")
    owners = (order // 2).reshape(-1, 2)  # the two cut faces of every cut edge
    visited = np.zeros(len(faces), dtype=bool)
    loops = []
    for start in range(len(faces)):
        if visited[start]:
            continue
        chain, face_ids = [], []
        face, edge = start, edge_of[start, 0]
        while not visited[face]:
            visited[face] = True
            chain.append(edge)
            face_ids.append(faces[face])
            edge = edge_of[face, 1] if edge_of[face, 0] == edge else edge_of[face, 0]
            face = owners[edge, 1] if owners[edge, 0] == face else owners[edge, 0]
        loops.append((crossing[chain], np.array(face_ids)))
    return sorted(loops, key=lambda loop: -len(loop[0]))
