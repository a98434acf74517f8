"""Parametric turbine blades: a row's Pritchard section (:mod:`.pritchard`) stacked along the
span — the ground truth of the geometry package.

A blade is the mean section of its row (:func:`row_design`: :mod:`.row_sizing` for the HP rows,
:mod:`.ip_rows` for the IP rows) stacked on its area centroid, rotated by the free-vortex change
of the stagger angle (twist) and scaled linearly in chord (taper) between hub and tip. Frame (m):
x axial, y tangential, ``z`` the distance from the turbine axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from steamtwin.geometry.ip_rows import ip_row_design
from steamtwin.geometry.pritchard import (
    SEGMENT_REGION,
    GeometryError,
    PritchardProfile,
    pritchard_profile,
)
from steamtwin.geometry.row_sizing import HP_ROWS, IP_ROWS, ROWS, RowDesign, hp_row_design
from steamtwin.geometry.volume_mesh import REGIONS
from steamtwin.spec import TurbineSpec


def row_design(spec: TurbineSpec, row: str) -> RowDesign:
    """Size blade row ``row`` (``hp1``…``hp13``, ``ip1``…``ip9``) from the turbine spec: HP rotor
    rows by :func:`~steamtwin.geometry.row_sizing.hp_row_design`, IP stator rows by
    :func:`~steamtwin.geometry.ip_rows.ip_row_design`."""
    if row in IP_ROWS:
        return ip_row_design(spec, row)
    if row not in HP_ROWS:
        raise GeometryError(f"unknown blade row {row!r}; known rows: {', '.join(ROWS)}")
    return hp_row_design(spec, row)


# --- the stacked blade ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Blade:
    """A blade: the mean Pritchard section stacked from hub to tip (exact ground truth).

    Frame (m): x axial, y tangential, z = distance from the turbine axis.
    """

    design: RowDesign
    profile: PritchardProfile

    @property
    def row(self) -> str:
        return self.design.row

    def section_transform(self, radius: float) -> tuple[np.ndarray, float, np.ndarray]:
        """Rotation matrix, scale and fixed point mapping the mean section to ``radius``."""
        angle = float(self.design.section_rotation(radius))
        rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        return rot, float(self.design.chord_scale(radius)), self.profile.centroid

    def place(self, points_2d: np.ndarray, radius: float) -> np.ndarray:
        """Map mean-section points (n, 2) to 3-D points of the section at ``radius``."""
        rot, scale, c = self.section_transform(radius)
        xy = c + scale * (points_2d - c) @ rot.T
        return np.column_stack([xy, np.full(len(xy), radius)])

    def to_section(self, points: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`place`: 3-D points to mean-section coordinates (n, 2)."""
        out = np.empty((len(points), 2))
        for radius in np.unique(points[:, 2]):
            sel = points[:, 2] == radius
            rot, scale, c = self.section_transform(float(radius))
            out[sel] = c + ((points[sel, :2] - c) @ rot) / scale
        return out

    @cached_property
    def reference_mesh(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """See :func:`reference_surface`."""
        count = math.ceil(self.design.span / REFERENCE_SPAN_SPACING) + 1
        return self.surface_mesh(REFERENCE_PROFILE_SPACING, span_count=count)

    @cached_property
    def volume(self) -> float:
        """Exact volume (m³): mean area × ∫ scale² dr (area scales with the chord squared)."""
        r = np.linspace(self.design.hub_radius, self.design.tip_radius, 2001)
        s2 = self.design.chord_scale(r) ** 2
        return self.profile.area * float(np.trapezoid(s2, r))

    def surface_mesh(self, spacing: float, span_count: int | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closed triangulation of the exact blade surface, outward normals.

        ``spacing`` (m) sets the point spacing along the profile, ``span_count`` the number of
        sections (default: span / spacing). Returns ``(vertices (n,3), triangles (m,3),
        region (m,))`` with region indices into :data:`~steamtwin.geometry.volume_mesh.REGIONS`.
        """
        outline, segment = self.profile.sample(spacing)
        outline = outline[::-1]  # anticlockwise in x-y: outward normals for increasing z
        edge_region = np.array([REGIONS.index(SEGMENT_REGION[s]) for s in segment])
        edge_region = np.roll(edge_region[::-1], -1)
        n = len(outline)
        if span_count is None:
            span_count = max(2, math.ceil(self.design.span / spacing) + 1)
        radii = np.linspace(self.design.hub_radius, self.design.tip_radius, span_count)
        vertices = np.concatenate([self.place(outline, float(r)) for r in radii])
        k = np.arange(n)
        tris, regions = [], []
        for level in range(span_count - 1):
            a = level * n + k
            b = level * n + (k + 1) % n
            c, d = a + n, b + n
            tris.append(np.column_stack([a, b, d]))
            tris.append(np.column_stack([a, d, c]))
            regions += [edge_region, edge_region]
        cap = cap_triangles(outline)
        tris.append(cap[:, ::-1])  # root: normal towards -z
        regions.append(np.full(len(cap), REGIONS.index("root")))
        tris.append(cap + (span_count - 1) * n)
        regions.append(np.full(len(cap), REGIONS.index("tip")))
        return vertices, np.concatenate(tris).astype(np.int64), np.concatenate(regions)


def cap_triangles(outline: np.ndarray) -> np.ndarray:
    """Triangulate an anticlockwise simple polygon by ear clipping (positive areas).

    At each step the convex ear with the largest smallest angle that contains no other vertex is
    cut off (best-ear clipping, Eberly 2002 "Triangulation by ear clipping").
    """
    remaining = list(range(len(outline)))
    tris = []
    while len(remaining) > 3:
        idx = np.array(remaining)
        a, b, c = outline[np.roll(idx, 1)], outline[idx], outline[np.roll(idx, -1)]
        ab, ac = b - a, c - a
        cross = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]
        quality = np.minimum.reduce([_angle(a, b, c), _angle(b, c, a), _angle(c, a, b)])
        quality[cross <= 0.0] = -1.0
        for k in np.argsort(-quality):
            if quality[k] < 0.0:
                raise GeometryError("cap outline is not a simple anticlockwise polygon")
            others = np.delete(idx, [(k - 1) % len(idx), k, (k + 1) % len(idx)])
            if not np.any(_inside_triangle(outline[others], a[k], b[k], c[k])):
                tris.append((idx[k - 1], idx[k], idx[(k + 1) % len(idx)]))
                remaining.pop(int(k))
                break
    tris.append(tuple(remaining))
    return np.array(tris, dtype=np.int64)


def _angle(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Angle at p of triangles (p, q, r), rad."""
    u, v = q - p, r - p
    cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
    return np.arccos(np.clip(cos, -1.0, 1.0))


def _inside_triangle(points: np.ndarray, a: np.ndarray, b: np.ndarray,
                     c: np.ndarray) -> np.ndarray:
    """Whether points lie inside or on the anticlockwise triangle (a, b, c)."""
    def side(p, q):
        return (q[0] - p[0]) * (points[:, 1] - p[1]) - (q[1] - p[1]) * (points[:, 0] - p[0])

    return (side(a, b) >= 0.0) & (side(b, c) >= 0.0) & (side(c, a) >= 0.0)


def make_blade(spec: TurbineSpec, row: str) -> Blade:
    """The ground-truth blade of ``row`` sized from ``spec``."""
    design = row_design(spec, row)
    return Blade(design=design, profile=pritchard_profile(design.mean_section))


#: Reference triangulation of the exact surface: 0.05 mm along the profile (chord sag below
#: 0.4 µm on the smallest trailing-edge circle) and 0.5 mm along the span (sections vary slowly).
REFERENCE_PROFILE_SPACING = 5e-5
REFERENCE_SPAN_SPACING = 5e-4


def reference_surface(blade: Blade) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fine triangulation standing in for the exact surface in scans and deviations
    (computed once per blade object; treat the arrays as read-only)."""
    return blade.reference_mesh
