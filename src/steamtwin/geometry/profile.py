"""Parametric turbine blades: Pritchard's 11-parameter profile stacked along the span.

The ground truth of the geometry package. A blade section is built with the construction of
L. J. Pritchard, "An eleven parameter axial turbine airfoil geometry model", ASME 85-GT-219
(1985): a leading-edge circle, a trailing-edge circle, a suction side made of a cubic from the
leading edge to the throat point and a circular arc ("unguided turning") from the throat point to
the trailing edge, and a pressure-side cubic. The exit half-wedge angle is solved so that the
suction-side arc is tangent at both of its ends (Pritchard's closure condition).

Section frame (m): ``x`` axial (downstream), ``y`` tangential, rotor blades move towards +y; the
leading-edge circle is centred at ``(r_le, Ct)``, the trailing-edge circle at ``(Cx - r_te, 0)``;
the neighbouring blade sits at ``y + pitch``. Blade angles are measured from the axial direction,
positive towards +y (Pritchard's convention: inlet angle > 0, outlet angle < 0 for a turbine).

A blade is the mean section stacked on its area centroid, rotated by the free-vortex change of the
stagger angle (twist) and scaled linearly in chord (taper) between hub and tip; ``z`` is the
distance from the turbine axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.optimize import brentq
from scipy.spatial import cKDTree

from steamtwin.errors import GeometryAreaError
from steamtwin.spec import TurbineSpec

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


# --- rows of the reference turbine ------------------------------------------------------------

HP_ROWS = tuple(f"hp{k}" for k in range(1, 14))
IP_ROWS = tuple(f"ip{k}" for k in range(1, 10))
ROWS = HP_ROWS + IP_ROWS

# Design choices for sizing the sections, each with its source:
#: Zweifel's optimum tangential loading coefficient, used to set the axial chord from the pitch
#: (Zweifel 1945, Brown Boveri Rev. 32; Dixon & Hall, Fluid Mechanics and Thermodynamics of
#: Turbomachinery, 7th ed. 2014, §3.6: Z ≈ 0.8).
ZWEIFEL = 0.8
#: Unguided turning 5-10° is usual for subsonic turbine blading (Pritchard 1985, his example
#: blades; Moustapha et al., Axial and Radial Turbines, 2003, ch. 4).
UNGUIDED_TURNING = math.radians(7.0)
#: Inlet half-wedge angle and leading-edge radius / axial chord: Pritchard's example rotor
#: (1985) uses ε_in ≈ 10-25°, r_le ≈ 0.04-0.08·Cx. The 130° impulse section of the control stage
#: takes a thin wedge: with Pritchard's cubic suction side any thicker nose pinches the passage
#: upstream below :data:`MIN_PASSAGE_RATIO` of the throat (checked in ``pritchard_profile``).
INLET_HALF_WEDGE = {"impulse": math.radians(4.0), "reaction": math.radians(12.0)}
#: Narrowest blade-to-blade distance allowed, as a fraction of the throat: below it the channel
#: would choke upstream of the throat (a converging passage is the design intent, Pritchard 1985).
MIN_PASSAGE_RATIO = 0.65
LEADING_EDGE_RADIUS_RATIO = {"impulse": 0.05, "reaction": 0.06}
#: Trailing-edge radius: 1.5 % of the axial chord, at least 0.35 mm for milling
#: (Moustapha et al. 2003 §4.4: t_te/o ≈ 0.02-0.1 for HP blading).
TRAILING_EDGE_RADIUS_RATIO = 0.015
MIN_TRAILING_EDGE_RADIUS = 0.35e-3
#: Tip/hub chord ratio: the governing stage's short impulse blades are prismatic; the reaction
#: blades are slightly tapered to relieve the root of centrifugal load (engineering choice within
#: the 0.8-1.0 of HP drum blading, Traupel 2001 §19).
TAPER_RATIO = {"impulse": 1.0, "reaction": 0.9}


@dataclass(frozen=True)
class RowDesign:
    """One blade row sized from the turbine spec (SI units; angles in rad).

    ``mean_section`` holds Pritchard's parameters at the mean radius. ``hub_radius``/``tip_radius``
    bound the blade in z; ``taper_ratio`` is tip chord / hub chord; the twist follows the
    free-vortex stagger ``stagger(r)`` (:meth:`section_rotation`).
    """

    row: str
    kind: str  # "rotor" or "stator"
    mean_section: PritchardParameters
    hub_radius: float
    tip_radius: float
    taper_ratio: float
    axial_velocity: float  # m/s
    inlet_swirl_radius: float  # c_theta * r upstream of the row (m²/s), free vortex constant
    outlet_swirl_radius: float  # c_theta * r downstream of the row (m²/s)
    angular_speed: float  # rad/s of the blade frame's relative motion (0 for stators)

    @property
    def mean_radius(self) -> float:
        return self.mean_section.radius

    @property
    def span(self) -> float:
        return self.tip_radius - self.hub_radius

    def blade_angles(self, radius: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Free-vortex relative inlet/outlet flow angles at ``radius`` (rad, from axial).

        c_θ·r = const and constant axial velocity (the free-vortex design, Dixon & Hall §6.2).
        """
        return free_vortex_angles(radius, self.angular_speed, self.axial_velocity,
                                  self.inlet_swirl_radius, self.outlet_swirl_radius)

    def section_rotation(self, radius: float | np.ndarray) -> np.ndarray:
        """Twist (rad, anticlockwise in x-y) of the section at ``radius`` relative to the mean.

        The stagger of a section follows the mean of its blade angles (circular-arc camber line);
        the twist is its change from the mean radius.
        """
        inlet, outlet = self.blade_angles(radius)
        inlet_m, outlet_m = self.blade_angles(self.mean_radius)
        return 0.5 * (inlet + outlet) - 0.5 * (inlet_m + outlet_m)

    def chord_scale(self, radius: float | np.ndarray) -> np.ndarray:
        """Chord of the section at ``radius`` relative to the mean section (linear taper)."""
        f = (np.asarray(radius, dtype=float) - self.hub_radius) / self.span
        return (1.0 + (self.taper_ratio - 1.0) * f) / (1.0 + 0.5 * (self.taper_ratio - 1.0))


def free_vortex_angles(radius: float | np.ndarray, angular_speed: float, axial_velocity: float,
                       inlet_swirl_radius: float, outlet_swirl_radius: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Relative inlet/outlet flow angles (rad, from axial) of a free-vortex row at ``radius``.

    c_θ·r = const and constant axial velocity (free vortex, Dixon & Hall 2014 §6.2); the blade
    frame moves at ``angular_speed`` (rad/s, 0 for a stator).
    """
    r = np.asarray(radius, dtype=float)
    u = angular_speed * r
    inlet = np.arctan((inlet_swirl_radius / r - u) / axial_velocity)
    outlet = np.arctan((outlet_swirl_radius / r - u) / axial_velocity)
    return inlet, outlet


def _section_from_angles(radius: float, blade_count: int, inlet: float, outlet: float,
                         style: str) -> PritchardParameters:
    """Pritchard parameters of a section from its blade angles (rad, from axial)."""
    pitch = 2.0 * math.pi * radius / blade_count
    # Zweifel: Z = 2 (s/Cx) cos²β2 (tan β1 − tan β2)  (angles of opposite sign, Dixon & Hall §3.6)
    axial_chord = 2.0 * pitch * math.cos(outlet) ** 2 * (math.tan(inlet) - math.tan(outlet))
    axial_chord /= ZWEIFEL
    # stagger of a circular-arc camber line = mean of the blade angles (Dixon & Hall §3.4)
    stagger = 0.5 * (inlet + outlet)
    return PritchardParameters(
        radius=radius,
        axial_chord=axial_chord,
        tangential_chord=-axial_chord * math.tan(stagger),
        unguided_turning=UNGUIDED_TURNING,
        inlet_angle=inlet,
        inlet_half_wedge=INLET_HALF_WEDGE[style],
        leading_edge_radius=LEADING_EDGE_RADIUS_RATIO[style] * axial_chord,
        outlet_angle=outlet,
        trailing_edge_radius=max(TRAILING_EDGE_RADIUS_RATIO * axial_chord,
                                 MIN_TRAILING_EDGE_RADIUS),
        blade_count=blade_count,
        # throat by the cosine rule o = s·cos|β2| (Ainley & Mathieson 1951, ARC R&M 2974)
        throat=pitch * math.cos(outlet),
    )


def row_design(spec: TurbineSpec, row: str) -> RowDesign:
    """Size blade row ``row`` (``hp1``…``hp13``, ``ip1``…``ip9``) from the turbine spec.

    HP rotor rows: ``hp1`` is the control-stage rotor, ``hp2``… the pressure stages. Velocity
    triangles at the mean radius: stator exit angle α1 (spec, from the wheel plane), zero exit
    swirl and constant axial velocity, with the blade speed from the optimum velocity ratio for
    the stage reaction Λ, u/c1 = cos α1 / (2(1 − Λ)) — which is exactly the reaction of that
    triangle (Dixon & Hall 2014 §4.5; impulse: u/c1 = cos α1 / 2).
    IP stator rows are sized by :func:`steamtwin.geometry.ip_rows.ip_row_design`.
    """
    if row in IP_ROWS:
        from steamtwin.geometry.ip_rows import ip_row_design

        return ip_row_design(spec, row)
    if row not in HP_ROWS:
        raise GeometryError(f"unknown blade row {row!r}; known rows: {', '.join(ROWS)}")
    index = HP_ROWS.index(row)
    if index == 0:
        blading, style = spec.control_stage.blading, "impulse"
    else:
        if index > len(spec.stages):
            raise GeometryError(f"row {row!r}: spec {spec.name!r} has only "
                                f"{len(spec.stages)} pressure stages")
        blading, style = spec.stages[index - 1].blading, "reaction"
    omega = spec.design.rotational_speed
    radius = 0.5 * blading.mean_diameter
    u = omega * radius
    alpha1 = blading.nozzle_exit_angle  # from the wheel plane (steam-turbine convention)
    c1 = u * 2.0 * (1.0 - blading.reaction) / math.cos(alpha1)
    axial_velocity = c1 * math.sin(alpha1)
    swirl_in = c1 * math.cos(alpha1) * radius
    inlet, outlet = free_vortex_angles(radius, omega, axial_velocity, swirl_in, 0.0)
    return RowDesign(
        row=row,
        kind="rotor",
        mean_section=_section_from_angles(radius, blading.blade_count, float(inlet),
                                          float(outlet), style),
        hub_radius=radius - 0.5 * blading.blade_height,
        tip_radius=radius + 0.5 * blading.blade_height,
        taper_ratio=TAPER_RATIO[style],
        axial_velocity=axial_velocity,
        inlet_swirl_radius=swirl_in,
        outlet_swirl_radius=0.0,
        angular_speed=omega,
    )


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
        from steamtwin.geometry.volume_mesh import REGIONS

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
        cap = _cap_triangles(outline)
        tris.append(cap[:, ::-1])  # root: normal towards -z
        regions.append(np.full(len(cap), REGIONS.index("root")))
        tris.append(cap + (span_count - 1) * n)
        regions.append(np.full(len(cap), REGIONS.index("tip")))
        return vertices, np.concatenate(tris).astype(np.int64), np.concatenate(regions)


def _cap_triangles(outline: np.ndarray) -> np.ndarray:
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
