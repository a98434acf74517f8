"""The drawn HP rotor section and its triangular (r, z) mesh.

:class:`RotorGeometry` is the spec's ``[rotor]`` section checked for drawability: a rotor body
of two outer radii (control stage, first pressure stages) with a central bore (or solid), and a
heat-relief groove — a circular-segment notch, or a U with a semicircular root when deeper than
its radius. :func:`rotor_mesh` meshes the half-section (x = r, y = z, m) with gmsh's
Frontal-Delaunay mesher (Geuzaine & Remacle, Int. J. Numer. Meth. Eng. 79 (2009) 1309), graded
from ``groove_size`` within a groove radius of the groove to ``size`` far from it by a distance
threshold field, so the stress concentration at the groove root is resolved (a notch needs
elements of about ρ/5 or less for its peak stress within a few per cent: Pilkey & Pilkey,
*Peterson's Stress Concentration Factors*, 3rd ed., 2008, §1.9 on FE resolution).

Named boundary facets of the mesh: ``"ends"`` (the cuts z = 0 and z = L, adiabatic), ``"bore"``
(or ``"axis"`` for a solid rotor, r = 0) and ``"steam:<group>"`` for the outer surface each
metal group's steam wets; outer surface outside every interval is in no boundary (adiabatic).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from skfem import MeshTri

from steamtwin.errors import RotorAreaError
from steamtwin.geometry.volume_mesh import gmsh_session
from steamtwin.spec.schema import METAL_DEPTH_RANGE_M
from steamtwin.spec.turbine import RotorSection, TurbineSpec

STEAM_PREFIX = "steam:"
"""Prefix of a steam-wetted boundary's name; the metal group's name follows."""

#: Outline vertex: (r, z) in m and the centre of the arc to the next vertex (None: a line).
_Vertex = tuple[tuple[float, float], tuple[float, float] | None]


@dataclass(frozen=True)
class RotorGeometry:
    """A drawable rotor section (SI, m); raises :class:`RotorAreaError` naming the ``rotor.``
    field when it is not (bore or groove leaving under 10 mm of metal, a groove across the
    radius step or the section's ends, wetted intervals outside the section or overlapping)."""

    section: RotorSection

    def __post_init__(self) -> None:
        problems = self.section.problems(METAL_DEPTH_RANGE_M[0])
        if problems:
            raise RotorAreaError("; ".join(problems))

    @property
    def groups(self) -> tuple[str, ...]:
        """The metal groups whose steam wets the section, in the order of ``rotor.steam``."""
        return tuple(dict.fromkeys(steam.group for steam in self.section.steam))

    @property
    def solid(self) -> bool:
        """Whether the rotor has no bore."""
        return self.section.bore_radius == 0.0

    @property
    def groove_root(self) -> tuple[float, float]:
        """(r, z) in m of the groove root on the surface, where the thermal stress peaks."""
        s = self.section
        return (s.outer_radius(s.groove_position) - s.groove_depth, s.groove_position)

    @property
    def bore_point(self) -> tuple[float, float]:
        """(r, z) in m of the bore (the axis if solid) at the groove's axial position."""
        return (self.section.bore_radius, self.section.groove_position)

    def outline(self) -> list[_Vertex]:
        """The closed outline, counter-clockwise in (r, z) from (bore, 0): ends, outer surface
        with the step and the groove, bore (split at the groove's z)."""
        s = self.section
        bore, length = s.bore_radius, s.axial_length
        outer: list[_Vertex] = [((s.control_stage_radius, 0.0), None)]
        groove = self._groove()
        if s.groove_position < s.stage_start:
            outer += groove
        if s.stage_start < length and s.stage_radius != s.control_stage_radius:
            outer += [((s.control_stage_radius, s.stage_start), None),
                      ((s.stage_radius, s.stage_start), None)]
        if s.groove_position >= s.stage_start:
            outer += groove
        outer.append(((s.stage_radius if s.stage_start < length else s.control_stage_radius,
                       length), None))
        return [((bore, 0.0), None), *outer, ((bore, length), None),
                ((bore, s.groove_position), None)]

    def _groove(self) -> list[_Vertex]:
        s = self.section
        radius, rho, depth, z = (s.outer_radius(s.groove_position), s.groove_radius,
                                 s.groove_depth, s.groove_position)
        centre = (radius - depth + rho, z)
        half = s.groove_half_width
        root = ((radius - depth, z), centre)
        if depth <= rho:  # a circular segment: two arcs through the root
            return [((radius, z - half), centre), root, ((radius, z + half), None)]
        return [((radius, z - rho), None), ((centre[0], z - rho), centre), root,
                ((centre[0], z + rho), None), ((radius, z + rho), None)]


def rotor_geometry(spec: TurbineSpec) -> RotorGeometry:
    """The rotor section of ``spec``; :class:`RotorAreaError` saying what to add without one."""
    if spec.rotor is None:
        raise RotorAreaError(
            f"turbine spec {spec.name!r} has no [rotor] section: add one with the rotor "
            "drawing's axial_length, control_stage_radius, stage_radius, stage_start, "
            "groove_radius, groove_depth, groove_position and [[rotor.steam]] intervals "
            "(docs/spec.md, section [rotor]; the built-in 'reference' spec has an example)")
    return RotorGeometry(spec.rotor)


def rotor_mesh(geometry: RotorGeometry, size: float, groove_size: float | None = None
               ) -> MeshTri:
    """Triangular mesh of the (r, z) half-section: elements of ``size`` (m) far from the groove,
    ``groove_size`` (m, default groove radius / 6) within a groove radius of it, with the named
    boundaries of the module docstring. The groove root and :attr:`RotorGeometry.bore_point`
    are mesh nodes (:func:`critical_nodes`)."""
    s = geometry.section
    fine = s.groove_radius / 6.0 if groove_size is None else groove_size
    if not (math.isfinite(size) and math.isfinite(fine) and 0.0 < fine <= size):
        raise RotorAreaError(f"mesh sizes must satisfy 0 < groove_size ({fine!r} m) ≤ size "
                             f"({size!r} m)")
    outline = geometry.outline()
    with gmsh_session() as gmsh:
        geo = gmsh.model.geo
        points = [geo.addPoint(r, z, 0.0) for (r, z), _ in outline]
        curves, groove_curves = [], []
        for i, (_, centre) in enumerate(outline):
            start, end = points[i], points[(i + 1) % len(points)]
            if centre is None:
                curves.append(geo.addLine(start, end))
            else:
                middle = geo.addPoint(centre[0], centre[1], 0.0)
                curves.append(geo.addCircleArc(start, middle, end))
                groove_curves.append(curves[-1])
        geo.addPlaneSurface([geo.addCurveLoop(curves)])
        geo.synchronize()
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "CurvesList", groove_curves)
        field.setNumber(distance, "Sampling", 50)
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", fine)
        field.setNumber(threshold, "SizeMax", size)
        field.setNumber(threshold, "DistMin", s.groove_radius)
        field.setNumber(threshold, "DistMax", s.groove_radius + 4.0 * size)
        field.setAsBackgroundMesh(threshold)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                       "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        mesh = generated_triangles(gmsh)
    return mesh.with_boundaries(_boundaries(mesh, geometry))


def generated_triangles(gmsh: Any) -> MeshTri:
    """Mesh the open gmsh session's plane model in 2-D and return its triangles as a skfem
    ``MeshTri`` in (x, y) = (r, z), m; nodes no triangle uses (the arcs' centres) dropped."""
    gmsh.model.mesh.generate(2)
    tags, coordinates, _ = gmsh.model.mesh.getNodes()
    _, element_nodes = gmsh.model.mesh.getElementsByType(2)
    position = np.full(int(tags.max()) + 1, -1)
    position[tags.astype(int)] = np.arange(tags.size)
    triangles = position[element_nodes.astype(int).reshape(-1, 3)].T
    used = np.unique(triangles)
    renumber = np.full(tags.size, -1)
    renumber[used] = np.arange(used.size)
    nodes = coordinates.reshape(-1, 3)[used, :2].T
    return MeshTri(np.ascontiguousarray(nodes), np.ascontiguousarray(renumber[triangles]))


def _boundaries(mesh: MeshTri, geometry: RotorGeometry) -> dict[str, np.ndarray]:
    """Boundary facet indices by name: each facet by its end points and midpoint."""
    s = geometry.section
    facets = mesh.boundary_facets()
    ends = mesh.p[:, mesh.facets[:, facets]]  # (2 coordinates, 2 end points, facets)
    r, z = ends[0], ends[1]
    tolerance = 1e-9 * s.axial_length
    on_end = (np.all(np.abs(z) < tolerance, axis=0)
              | np.all(np.abs(z - s.axial_length) < tolerance, axis=0))
    on_bore = np.all(np.abs(r - s.bore_radius) < tolerance, axis=0)
    outer = ~(on_end | on_bore)
    middle = z.mean(axis=0)
    named = {"ends": facets[on_end], "axis" if geometry.solid else "bore": facets[on_bore]}
    taken = np.zeros(facets.size, dtype=bool)
    for steam in s.steam:
        inside = outer & ~taken & (middle >= steam.start) & (middle <= steam.end)
        taken |= inside
        name = STEAM_PREFIX + steam.group
        named[name] = np.union1d(named.get(name, np.array([], dtype=int)), facets[inside])
    return named


def critical_nodes(mesh: MeshTri, geometry: RotorGeometry) -> dict[str, int]:
    """Node index of the ``"groove_root"`` and of the ``"bore"`` point at the groove's z."""
    found = {}
    for name, (r, z) in (("groove_root", geometry.groove_root), ("bore", geometry.bore_point)):
        distance = np.hypot(mesh.p[0] - r, mesh.p[1] - z)
        node = int(np.argmin(distance))
        if distance[node] > 1e-9 * geometry.section.axial_length:
            raise RotorAreaError(f"the mesh has no node at the {name} point ({r:g}, {z:g}) m: "
                                 "build it with rotor_mesh")
        found[name] = node
    return found
