"""Pritchard's 11-parameter blade section (one profile in its section plane).

A section is built with the construction of L. J. Pritchard, "An eleven parameter axial turbine
airfoil geometry model", ASME 85-GT-219 (1985): a leading-edge circle, a trailing-edge circle, a
suction side made of a cubic from the leading edge to the throat point and a circular arc
("unguided turning") from the throat point to the trailing edge, and a pressure-side cubic. The
exit half-wedge angle is solved so that the suction-side arc is tangent at both of its ends
(Pritchard's closure condition).

Section frame (m): ``x`` axial (downstream), ``y`` tangential, rotor blades move towards +y; the
leading-edge circle is centred at ``(r_le, Ct)``, the trailing-edge circle at ``(Cx - r_te, 0)``;
the neighbouring blade sits at ``y + pitch``. Blade angles are measured from the axial direction,
positive towards +y (Pritchard's convention: inlet angle > 0, outlet angle < 0 for a turbine).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.optimize import brentq
from scipy.spatial import cKDTree

from steamtwin.errors import GeometryAreaError

#: Profile segments, in the order they are walked (suction side first, clockwise in x-y).
SEGMENTS = ("suction_cubic", "suction_arc", "trailing_edge", "pressure_side", "leading_edge")


#: Surface region of each segment (names of :data:`steamtwin.geometry.volume_mesh.REGIONS`).
SEGMENT_REGION = ("suction_side", "suction_side", "trailing_edge", "pressure_side", "leading_edge")


class GeometryError(GeometryAreaError):
    """Blade parameters that do not give a valid profile, or an unknown row."""


@dataclass(frozen=True)
class PritchardParameters:
    """Pritchard's eleven parameters of one blade section (lengths in m, angles in rad)."""

    radius: float
    axial_chord: float
    tangential_chord: float
    unguided_turning: float
    inlet_angle: float
    inlet_half_wedge: float
    leading_edge_radius: float
    outlet_angle: float
    trailing_edge_radius: float
    blade_count: int
    throat: float

    @property
    def pitch(self) -> float:
        """Blade pitch 2πR/N at the section radius (m)."""
        return 2.0 * math.pi * self.radius / self.blade_count

    def validate(self) -> None:
        """Raise :class:`GeometryError` naming the first parameter outside its range."""
        checks = (
            ("radius", self.radius > 0.0),
            ("axial_chord", self.axial_chord > 0.0),
            ("blade_count", self.blade_count >= 3),
            ("unguided_turning", 0.0 < self.unguided_turning < math.radians(30.0)),
            ("inlet_angle", -math.radians(10.0) < self.inlet_angle < math.radians(80.0)),
            ("inlet_half_wedge", 0.0 < self.inlet_half_wedge < math.radians(40.0)),
            ("outlet_angle", -math.radians(80.0) < self.outlet_angle < -math.radians(30.0)),
            ("leading_edge_radius", 0.0 < self.leading_edge_radius < 0.2 * self.axial_chord),
            ("trailing_edge_radius", 0.0 < self.trailing_edge_radius < 0.1 * self.axial_chord),
            ("throat", 0.0 < self.throat < self.pitch),
        )
        for name, ok in checks:
            if not ok:
                raise GeometryError(f"Pritchard parameter {name} = {getattr(self, name)!r} "
                                    "is outside its valid range")
        for name in ("radius", "axial_chord", "tangential_chord", "throat"):
            if not math.isfinite(getattr(self, name)):
                raise GeometryError(f"Pritchard parameter {name} is not finite")


def _cubic(xa: float, ya: float, slope_a: float, xb: float, yb: float,
           slope_b: float) -> np.ndarray:
    """Coefficients (c0..c3) of y(x) through two points with given slopes dy/dx."""
    matrix = np.array([[1.0, xa, xa**2, xa**3], [0.0, 1.0, 2 * xa, 3 * xa**2],
                       [1.0, xb, xb**2, xb**3], [0.0, 1.0, 2 * xb, 3 * xb**2]])
    return np.linalg.solve(matrix, np.array([ya, slope_a, yb, slope_b]))


def _tangent_circle(p1: np.ndarray, beta1: float, p2: np.ndarray,
                    beta2: float) -> tuple[np.ndarray, float, float]:
    """Centre, radius at p1 and radius at p2 of the circle normal to both blade directions."""
    n1 = np.array([-math.sin(beta1), math.cos(beta1)])
    n2 = np.array([-math.sin(beta2), math.cos(beta2)])
    a, b = np.linalg.solve(np.column_stack([n1, -n2]), p2 - p1)
    return p1 + a * n1, a, b


@dataclass(frozen=True)
class PritchardProfile:
    """A closed Pritchard section: key points, solved exit half-wedge angle and segment curves."""

    params: PritchardParameters
    outlet_half_wedge: float  # rad, solved
    le_centre: np.ndarray
    te_centre: np.ndarray
    suction_arc_centre: np.ndarray
    suction_arc_radius: float
    points: dict[int, np.ndarray]  # Pritchard's key points 1..5
    angles: dict[int, float]  # blade angle at each key point (rad)
    suction_cubic: np.ndarray  # y(x) coefficients, point 3 -> 2
    pressure_cubic: np.ndarray  # y(x) coefficients, point 5 -> 4

    def segment(self, index: int, count: int) -> np.ndarray:
        """``count`` points of segment ``index`` (see :data:`SEGMENTS`), both ends included."""
        p = self.points
        if index in (0, 3):
            coef = self.suction_cubic if index == 0 else self.pressure_cubic
            xa, xb = (p[3][0], p[2][0]) if index == 0 else (p[5][0], p[4][0])
            dense = np.linspace(xa, xb, 4001)
            dense_y = np.polynomial.polynomial.polyval(dense, coef)
            length = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(dense),
                                                                  np.diff(dense_y)))])
            x = np.interp(np.linspace(0.0, length[-1], count), length, dense)
            return np.column_stack([x, np.polynomial.polynomial.polyval(x, coef)])
        if index == 1:
            centre, start, end = self.suction_arc_centre, p[2], p[1]
        elif index == 2:
            centre, start, end = self.te_centre, p[1], p[5]
        else:
            centre, start, end = self.le_centre, p[4], p[3]
        a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
        a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
        # every arc of the profile is walked clockwise (decreasing angle)
        while a1 >= a0:
            a1 -= 2.0 * math.pi
        radius = float(np.hypot(*(start - centre)))
        theta = np.linspace(a0, a1, count)
        return centre + radius * np.column_stack([np.cos(theta), np.sin(theta)])

    def segment_lengths(self) -> np.ndarray:
        """Arc length of each segment (m)."""
        return np.array([np.sum(np.hypot(*np.diff(self.segment(i, 2001), axis=0).T))
                         for i in range(len(SEGMENTS))])

    def sample(self, spacing: float) -> tuple[np.ndarray, np.ndarray]:
        """Closed polyline with about ``spacing`` (m) between points, and segment id per edge.

        Returns ``(points (n, 2), segment (n,))``: edge ``i`` joins point ``i`` and ``i + 1``
        (cyclically) and lies on segment ``segment[i]``. Segment ends are always vertices.
        """
        lengths = self.segment_lengths()
        chunks, ids = [], []
        for i, length in enumerate(lengths):
            count = max(4, math.ceil(length / spacing) + 1)
            pts = self.segment(i, count)[:-1]
            chunks.append(pts)
            ids.append(np.full(len(pts), i, dtype=np.int64))
        return np.concatenate(chunks), np.concatenate(ids)

    @cached_property
    def dense(self) -> tuple[np.ndarray, np.ndarray]:
        """A very fine polyline (≈ 5 µm spacing) standing in for the exact curve."""
        return self.sample(5e-6)

    @cached_property
    def area(self) -> float:
        """Section area (m²)."""
        return abs(_polygon_area(self.dense[0]))

    @cached_property
    def centroid(self) -> np.ndarray:
        """Area centroid of the section (m)."""
        return _polygon_centroid(self.dense[0])


def _polygon_area(points: np.ndarray) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _polygon_centroid(points: np.ndarray) -> np.ndarray:
    x, y = points[:, 0], points[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = 0.5 * np.sum(cross)
    cx = np.sum((x + np.roll(x, -1)) * cross) / (6.0 * area)
    cy = np.sum((y + np.roll(y, -1)) * cross) / (6.0 * area)
    return np.array([cx, cy])


def _key_points(params: PritchardParameters, eps_out: float) -> tuple[dict, dict]:
    """Pritchard's five key points for a trial exit half-wedge angle (his eqs. for points 1-5)."""
    cx, ct, r_le, r_te = (params.axial_chord, params.tangential_chord,
                          params.leading_edge_radius, params.trailing_edge_radius)
    b1 = params.outlet_angle - eps_out
    b2 = b1 + params.unguided_turning
    b3 = params.inlet_angle + params.inlet_half_wedge
    b4 = params.inlet_angle - params.inlet_half_wedge
    b5 = params.outlet_angle + eps_out
    te = np.array([cx - r_te, 0.0])
    le = np.array([r_le, ct])
    o = params.throat
    points = {
        1: te + r_te * np.array([-math.sin(b1), math.cos(b1)]),
        2: te + np.array([0.0, params.pitch]) + (o + r_te) * np.array([math.sin(b2),
                                                                         -math.cos(b2)]),
        3: le + r_le * np.array([-math.sin(b3), math.cos(b3)]),
        4: le + r_le * np.array([math.sin(b4), -math.cos(b4)]),
        5: te + r_te * np.array([math.sin(b5), -math.cos(b5)]),
    }
    return points, {1: b1, 2: b2, 3: b3, 4: b4, 5: b5}


def pritchard_profile(params: PritchardParameters) -> PritchardProfile:
    """Build the section of ``params`` (Pritchard 1985), solving the exit half-wedge angle.

    Raises :class:`GeometryError` when the parameters give no valid closed profile.
    """
    params.validate()

    def mismatch(eps_out: float) -> float:
        points, angles = _key_points(params, eps_out)
        _, r1, r2 = _tangent_circle(points[1], angles[1], points[2], angles[2])
        return r1 - r2

    grid = np.radians(np.linspace(0.05, 30.0, 300))
    values = np.array([mismatch(e) for e in grid])
    change = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    if change.size == 0:
        raise GeometryError(
            f"no exit half-wedge angle closes the suction-side arc for {params!r}: reduce the "
            "throat or the unguided turning")
    k = int(change[0])
    eps_out = float(brentq(mismatch, grid[k], grid[k + 1], xtol=1e-12))
    points, angles = _key_points(params, eps_out)
    centre, signed_radius, _ = _tangent_circle(points[1], angles[1], points[2], angles[2])
    radius = -signed_radius  # the centre lies inside the blade, against the suction normal
    if radius <= 0.0:
        raise GeometryError(f"suction-side arc bends the wrong way for {params!r}")
    if not (points[3][0] < points[2][0] < points[1][0] and points[4][0] < points[5][0]):
        raise GeometryError(f"key points out of axial order for {params!r}")
    profile = PritchardProfile(
        params=params,
        outlet_half_wedge=eps_out,
        le_centre=np.array([params.leading_edge_radius, params.tangential_chord]),
        te_centre=np.array([params.axial_chord - params.trailing_edge_radius, 0.0]),
        suction_arc_centre=centre,
        suction_arc_radius=float(radius),
        points=points,
        angles=angles,
        suction_cubic=_cubic(*points[3], math.tan(angles[3]), *points[2], math.tan(angles[2])),
        pressure_cubic=_cubic(*points[5], math.tan(angles[5]), *points[4], math.tan(angles[4])),
    )
    _check_simple(profile)
    return profile


def _check_simple(profile: PritchardProfile) -> None:
    """Refuse self-intersecting profiles (pressure and suction sides crossing)."""
    pts, _ = profile.sample(profile.params.axial_chord / 150.0)
    a, b = pts, np.roll(pts, -1, axis=0)
    n = len(pts)
    d = b - a
    # all pairs of non-adjacent edges
    i, j = np.triu_indices(n, k=2)
    keep = (j - i) % n != n - 1
    i, j = i[keep], j[keep]
    cross = d[i, 0] * d[j, 1] - d[i, 1] * d[j, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = a[j] - a[i]
        s = (w[:, 0] * d[j, 1] - w[:, 1] * d[j, 0]) / cross
        t = (w[:, 0] * d[i, 1] - w[:, 1] * d[i, 0]) / cross
    hit = (cross != 0) & (s > 0) & (s < 1) & (t > 0) & (t < 1)
    if np.any(hit) or _polygon_area(pts) >= 0.0:
        raise GeometryError(f"profile of {profile.params!r} intersects itself")
    passage = float(cKDTree(pts + np.array([0.0, profile.params.pitch])).query(pts)[0].min())
    if passage < MIN_PASSAGE_RATIO * profile.params.throat:
        raise GeometryError(
            f"the blade-to-blade passage narrows to {passage * 1e3:.2f} mm, below "
            f"{MIN_PASSAGE_RATIO:.0%} of the throat {profile.params.throat * 1e3:.2f} mm: "
            f"{profile.params!r}")


#: Narrowest blade-to-blade distance allowed, as a fraction of the throat: below it the channel
#: would choke upstream of the throat (a converging passage is the design intent, Pritchard 1985).
MIN_PASSAGE_RATIO = 0.65
