"""Blades that are not ours: an independent construction of test blades and their scans.

Nothing here comes from :mod:`steamtwin.geometry` (numpy, scipy, trimesh and open3d only), so
the reconstruction is measured on shapes its author did not design. Lengths in m, angles in
degrees in the specs (rad inside).

**Sections** (chord units inside, then scaled by the chord): a camber line with a thickness
laid off perpendicular to it (Abbott & von Doenhoff 1959, "Theory of Wing Sections", §6.4,
eq. 6.6), or two circular arcs:

- ``naca4``: NACA 4-digit thickness (A&vD eq. 6.2, open trailing edge, coefficient −0.1015) on
  the parabolic 4-digit mean line (eq. 6.4), its maximum camber solved from the camber angle;
- ``naca65``: NACA 65-010 basic thickness form (A&vD Appendix I; NACA RM L51G31 Table 1),
  scaled to the thickness, on a circular-arc camber line;
- ``dca``: double circular arc (compressor practice, e.g. Cumpsty 2004, "Compressor
  Aerodynamics", §4.2): suction and pressure sides are circular arcs through the chord's ends
  with sagittas h_c ± t/2, h_c the camber arc's sagitta;
- ``turbine``: the 4-digit thickness law up to 25 % on a circular-arc camber up to 120° (the
  thick impulse/reaction sections of steam turbines).

Leading and trailing edges are circles of the given radius tangent to both sides (solved for
the two tangent points). The radius must exceed the side's own radius of curvature where it
touches, so rounded noses (4-digit, 65-series) need a radius above their native nose radius
(4-digit 1.1019 t² c, A&vD eq. 6.3; 65-010 0.687 % c, scaled by (t/0.1)²; both times
cos φ_LE on a camber line whose slope at the nose is tan φ_LE, as the thickness is laid off
perpendicular to it).

**Blades**: sections at span fraction η interpolate root and tip specs linearly (twist, taper,
thickness, edge radii); the camber line's mid-chord point is stacked on the span axis, moved by
``sweep`` (x) and ``lean`` (y), each ``a·η + b·η²`` (m). Blade frame: x axial, y tangential,
z = radius from the hub cap at ``hub_radius`` to the tip cap at ``hub_radius + span``; stagger
turns the chord from +x towards +y. Each section is sampled counter-clockwise on one parameter
grid for all span levels, chosen from the curvature so that the chord sag round the section is
≤ :data:`RING_SAG`; with rings every ≤ ``span_spacing`` the closed triangulation (side tube and
zipped flat caps) stays within :data:`MESH_SAG` of the exact surface (measured by
:meth:`ForeignBlade.mesh_sag`, tested).

**Scans**: points area-uniform over the closed triangulation (sides and caps), Gaussian noise
along the normal, outliers moved 0.2–2 mm outward along the normal, and discs without points
(holes), as a fused laser scan delivers them; :func:`random_pose` puts a cloud in a random rigid
pose (the scanner software's frame).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import trimesh
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq, root
from scipy.spatial.transform import Rotation

#: Largest chord sag of a section polygon round the section (m): leaves room below MESH_SAG
#: for the span direction, and keeps the polygon's area deficit (≤ 2/3 × sag × perimeter)
#: below 1e-4 of the area of the thinnest member (DCA, perimeter / area 1700 /m).
RING_SAG = 0.08e-6
#: Largest distance between the triangulation and the exact surface (m), as stated and tested.
MESH_SAG = 1e-6
#: Largest spacing of the section polygon (m), where the curvature would allow more. A quad of
#: a twisted surface (rings Δz apart, stagger turning at γ' rad/m) bends out of plane by about
#: Δs·Δz·|γ'|/4 (mixed derivative of the bilinear patch): 0.15 mm × 2 mm × 4.4 rad/m / 4 =
#: 0.33 µm on the most twisted member.
MAX_SPACING = 0.15e-3

#: NACA 65-010 basic thickness form: x/c and y/c in % (A&vD Appendix I; RM L51G31 Table 1).
NACA65_X = np.array([0.0, 0.5, 0.75, 1.25, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0,
                     40.0, 45.0, 50.0, 55.0, 60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0,
                     100.0])
NACA65_Y = np.array([0.0, 0.772, 0.932, 1.169, 1.574, 2.177, 2.647, 3.040, 3.666, 4.143, 4.503,
                     4.760, 4.924, 4.996, 4.963, 4.812, 4.530, 4.146, 3.682, 3.156, 2.584, 1.987,
                     1.385, 0.810, 0.306, 0.0])
#: Leading-edge radius of the 65-010 form / c (same table).
NACA65_NOSE = 0.00687
#: Area of the NACA 4-digit thickness form / (t c²): 10 (0.2969·2/3 − 0.1260/2 − 0.3516/3 +
#: 0.2843/4 − 0.1015/5) = 0.68508 (A&vD §6.4 give 0.685 t c²).
NACA4_AREA = 10.0 * (0.2969 * 2.0 / 3.0 - 0.1260 / 2.0 - 0.3516 / 3.0 + 0.2843 / 4.0
                     - 0.1015 / 5.0)
KINDS = ("naca4", "naca65", "dca", "turbine")
#: Parameter ranges of a section spec: stagger, camber (deg), thickness / chord, chord (m).
STAGGER_RANGE, CAMBER_RANGE = (0.0, 70.0), (0.0, 120.0)


def naca4_half_thickness(x: np.ndarray, thickness: float) -> np.ndarray:
    """Half thickness / c of the NACA 4-digit form at x/c (A&vD eq. 6.2)."""
    return 5.0 * thickness * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2
                              + 0.2843 * x**3 - 0.1015 * x**4)


#: 65-010 ordinates as a cubic spline in u = √(x/c), where a round nose is linear:
#: y = √(2 r x) = √(2 r) u, so the slope at u = 0 is fixed by the nose radius r.
_NACA65 = CubicSpline(np.sqrt(NACA65_X / 100.0), NACA65_Y / 100.0,
                      bc_type=((1, math.sqrt(2.0 * NACA65_NOSE)), "not-a-knot"))


def naca65_half_thickness(x: np.ndarray, thickness: float) -> np.ndarray:
    """Half thickness / c of the 65-010 form scaled to ``thickness`` / c, at x/c."""
    return _NACA65(np.sqrt(x)) * (thickness / 0.10)


def naca4_max_camber(camber_deg: float, position: float) -> float:
    """Maximum camber m / c of the 4-digit mean line with camber angle χ at x/c = p: the
    slopes at the ends are 2m/p and −2m/(1 − p) (A&vD eq. 6.4), so
    χ = atan(2m/p) + atan(2m/(1 − p))."""
    if camber_deg <= 0.0:
        return 0.0
    chi = math.radians(camber_deg)
    return brentq(lambda m: math.atan(2 * m / position) + math.atan(2 * m / (1 - position)) - chi,
                  0.0, 10.0, xtol=1e-15)


def arc_sagitta(camber_deg: float) -> float:
    """Sagitta / c of a circular arc over the chord turning by χ: tan(χ/4) / 2."""
    return 0.5 * math.tan(math.radians(camber_deg) / 4.0)


def _arc(x: np.ndarray, sagitta: float) -> tuple[np.ndarray, np.ndarray]:
    """y and dy/dx of the circular arc through (0, 0) and (1, 0) with the given sagitta."""
    if abs(sagitta) < 1e-12:
        return np.zeros_like(x), np.zeros_like(x)
    h = abs(sagitta)
    radius = (0.25 + h * h) / (2.0 * h)
    root_ = np.sqrt(radius**2 - (x - 0.5) ** 2)
    sign = math.copysign(1.0, sagitta)
    return sign * (root_ - (radius - h)), sign * (-(x - 0.5) / root_)


@dataclass(frozen=True)
class SectionSpec:
    """One blade section: ``kind`` of :data:`KINDS`, ``chord`` (m), ``stagger_deg`` (chord from
    +x towards +y), ``camber_deg`` (turning of the camber line), ``thickness`` (max / chord),
    ``le_radius`` and ``te_radius`` (m), ``camber_position`` (x/c of the 4-digit maximum
    camber)."""

    kind: str
    chord: float
    stagger_deg: float
    camber_deg: float
    thickness: float
    le_radius: float
    te_radius: float
    camber_position: float = 0.4

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"section kind {self.kind!r}: expected one of {KINDS}")
        if not 5e-3 <= self.chord <= 0.2:
            raise ValueError(f"chord {self.chord} m: expected 5–200 mm (in m)")
        if not STAGGER_RANGE[0] <= self.stagger_deg <= STAGGER_RANGE[1]:
            raise ValueError(f"stagger {self.stagger_deg}°: expected 0–70°")
        if not CAMBER_RANGE[0] <= self.camber_deg <= CAMBER_RANGE[1]:
            raise ValueError(f"camber {self.camber_deg}°: expected 0–120°")
        if not 0.01 <= self.thickness <= 0.3:
            raise ValueError(f"thickness {self.thickness}: expected 0.01–0.3 of the chord")
        if not (0 < self.le_radius < 0.2 * self.chord and 0 < self.te_radius < 0.2 * self.chord):
            raise ValueError("edge radii (m) must be positive and below 20 % of the chord")

    def camber(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Camber line y/c and slope at x/c."""
        if self.kind == "naca4":
            m, p = naca4_max_camber(self.camber_deg, self.camber_position), self.camber_position
            front = x < p
            y = np.where(front, m / p**2 * (2 * p * x - x**2),
                         m / (1 - p) ** 2 * (1 - 2 * p + 2 * p * x - x**2))
            slope = np.where(front, 2 * m / p**2 * (p - x), 2 * m / (1 - p) ** 2 * (p - x))
            return y, slope
        return _arc(x, arc_sagitta(self.camber_deg))

    def sides(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Upper (suction) and lower (pressure) side points (n, 2) / c at u = √(x/c)."""
        x = u * u
        if self.kind == "dca":
            h_c = arc_sagitta(self.camber_deg)
            upper = np.column_stack([x, _arc(x, h_c + 0.5 * self.thickness)[0]])
            lower = np.column_stack([x, _arc(x, h_c - 0.5 * self.thickness)[0]])
            return upper, lower
        law = naca65_half_thickness if self.kind == "naca65" else naca4_half_thickness
        h = law(x, self.thickness)
        yc, slope = self.camber(x)
        phi = np.arctan(slope)
        upper = np.column_stack([x - h * np.sin(phi), yc + h * np.cos(phi)])
        lower = np.column_stack([x + h * np.sin(phi), yc - h * np.cos(phi)])
        return upper, lower


def _side_frame(spec: SectionSpec, u: np.ndarray, which: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Points and outward unit normals of side ``which`` (0 upper, 1 lower) at u (chord units),
    tangents by central differences (step 1e-5 in u: truncation and rounding ~1e-10)."""
    step = 1e-5
    point = spec.sides(u)[which]
    tangent = (spec.sides(u + step)[which] - spec.sides(u - step)[which]) / (2 * step)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])  # left of the travel in +u
    return point, normal if which == 0 else -normal


def _fillet(spec: SectionSpec, radius: float, trailing: bool,
            guess: tuple[float, float] | None) -> tuple[float, float, np.ndarray]:
    """u of the tangent points on the upper and lower side and the centre (chord units) of the
    edge circle of ``radius`` / c: P_u − ρ N_u = P_l − ρ N_l."""
    def residual(v: np.ndarray) -> np.ndarray:
        pu, nu = _side_frame(spec, np.array([v[0]]), 0)
        pl, nl = _side_frame(spec, np.array([v[1]]), 1)
        return (pu - radius * nu - pl + radius * nl)[0]

    if guess is None:  # grid search on the edge's half of the chord
        grid = np.linspace(0.72, 1.0 - 1e-6, 300) if trailing else np.geomspace(1e-3, 0.7, 300)
        pu, nu = _side_frame(spec, grid, 0)
        pl, nl = _side_frame(spec, grid, 1)
        gap = np.linalg.norm((pu - radius * nu)[:, None] - (pl - radius * nl)[None], axis=2)
        if not trailing:  # near u = 0 both offsets meet at the nose itself: scale the gap
            gap /= np.linalg.norm(pu[:, None] - pl[None], axis=2) + 1e-12
        i, j = np.unravel_index(np.argmin(gap), gap.shape)
        guess = (grid[i], grid[j])
    solution = root(residual, np.array(guess), method="hybr", options={"xtol": 1e-13})
    u_up, u_low = solution.x
    if (np.abs(residual(solution.x)).max() > 1e-10 or max(u_up, u_low) < 1e-3
            or not (0.0 < u_up < 1.0 and 0.0 < u_low < 1.0)):
        edge = "trailing" if trailing else "leading"
        raise ValueError(
            f"no {edge}-edge circle of radius {radius * spec.chord * 1e3:.3g} mm tangent to both "
            f"sides of the {spec.kind} section: the radius must exceed the side's own radius of "
            "curvature there (native nose) and the edge's half thickness")
    point, normal = _side_frame(spec, np.array([u_up]), 0)
    return float(u_up), float(u_low), point[0] - radius * normal[0]


#: The pieces of a section, counter-clockwise from the trailing edge: trailing-edge arc (lower →
#: upper tangent point), upper side (TE → LE), leading-edge arc, lower side (LE → TE).
PIECES = ("trailing_edge", "upper", "leading_edge", "lower")


class Section:
    """A section of ``spec``: tangent points, edge circles and its closed curve in the blade
    frame (m), at piece-local parameters w ∈ [0, 1)."""

    def __init__(self, spec: SectionSpec, offset: np.ndarray | None = None,
                 guesses: tuple | None = None) -> None:
        self.spec = spec
        c = spec.chord
        self.te = _fillet(spec, spec.te_radius / c, True, guesses[0] if guesses else None)
        self.le = _fillet(spec, spec.le_radius / c, False, guesses[1] if guesses else None)
        gamma = math.radians(spec.stagger_deg)
        self.rotation = np.array([[math.cos(gamma), -math.sin(gamma)],
                                  [math.sin(gamma), math.cos(gamma)]])
        self.reference = np.array([0.5, float(spec.camber(np.array([0.5]))[0][0])])
        self.offset = np.zeros(2) if offset is None else np.asarray(offset, float)

    def guesses(self) -> tuple:
        """Tangent-point parameters, to start the solve of a neighbouring section."""
        return (self.te[:2], self.le[:2])

    def to_frame(self, local: np.ndarray) -> np.ndarray:
        """Chord-unit points → blade frame (m)."""
        return (local - self.reference) @ self.rotation.T * self.spec.chord + self.offset

    def _arc_angles(self, trailing: bool) -> tuple[float, float, np.ndarray, float]:
        u_up, u_low, centre = self.te if trailing else self.le
        n_up = _side_frame(self.spec, np.array([u_up]), 0)[1][0]
        n_low = _side_frame(self.spec, np.array([u_low]), 1)[1][0]
        start, end = (n_low, n_up) if trailing else (n_up, n_low)
        a0, a1 = math.atan2(start[1], start[0]), math.atan2(end[1], end[0])
        sweep = (a1 - a0) % (2 * math.pi)
        radius = (self.spec.te_radius if trailing else self.spec.le_radius) / self.spec.chord
        return a0, sweep, centre, radius

    def piece(self, name: str, w: np.ndarray) -> np.ndarray:
        """Points (n, 2, m) of one piece at w ∈ [0, 1] (counter-clockwise)."""
        w = np.asarray(w, dtype=float)
        if name in ("trailing_edge", "leading_edge"):
            a0, sweep, centre, radius = self._arc_angles(name == "trailing_edge")
            angle = a0 + w * sweep
            local = centre + radius * np.column_stack([np.cos(angle), np.sin(angle)])
        elif name == "upper":
            u = self.te[0] + w * (self.le[0] - self.te[0])
            local = self.spec.sides(u)[0]
        else:
            u = self.le[1] + w * (self.te[1] - self.le[1])
            local = self.spec.sides(u)[1]
        return self.to_frame(local)

    def chord_fraction(self, name: str, w: np.ndarray) -> np.ndarray:
        """A parameter from 0 at the leading-edge arc's middle to 1 at the trailing edge's,
        monotone along each side (x/c on the sides): pairs the two sides for cap strips."""
        w = np.asarray(w, dtype=float)
        if name == "upper":
            return (self.te[0] + w * (self.le[0] - self.te[0])) ** 2
        if name == "lower":
            return (self.le[1] + w * (self.te[1] - self.le[1])) ** 2
        if name == "trailing_edge":  # lower tangent → 1 at the middle → upper tangent
            return np.where(w < 0.5, self.te[1] ** 2 + 2 * w * (1 - self.te[1] ** 2),
                            1 - (2 * w - 1) * (1 - self.te[0] ** 2))
        return np.where(w < 0.5, (1 - 2 * w) * self.le[0] ** 2, (2 * w - 1) * self.le[1] ** 2)

    def curve(self, grid: dict[str, np.ndarray]) -> np.ndarray:
        """The closed polyline (n, 2, m) at the piece grids (each in [0, 1), in PIECES order)."""
        return np.vstack([self.piece(name, grid[name]) for name in PIECES])

    def polygon(self, sag: float = RING_SAG) -> np.ndarray:
        """Counter-clockwise polygon (n, 2, m) whose chord sag is ≤ ``sag``."""
        return self.curve(piece_grids([self], sag))

    def area(self, sag: float = 1e-9) -> float:
        """Enclosed area (m²) of the curve (polygon at a chord sag of ``sag``: the deficit is
        below 2/3 × sag × perimeter)."""
        return polygon_area(self.polygon(sag))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """z component of the cross product of 2-D vectors (n, 2)."""
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def polygon_area(polygon: np.ndarray) -> float:
    """Signed area (m², positive counter-clockwise) by the shoelace formula."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def piece_grids(sections: list[Section], sag: float = RING_SAG,
                max_spacing: float = MAX_SPACING) -> dict[str, np.ndarray]:
    """Parameters w ∈ [0, 1) per piece, common to all ``sections``, with chord sag ≤ ``sag``.

    A chord of length L over a curve of radius R has the sag L²/(8R), so the spacing is
    √(8 R sag) (at most ``max_spacing``); the density (points per unit w) is the largest over
    the sections, curvature from the circumradius of neighbouring points of a 4001-point
    sampling (so the sag reaches ``sag`` within 10 %). Arcs get their middle (the nose) as a
    grid point.
    """
    dense = np.linspace(0.0, 1.0, 4001)
    grids = {}
    for name in PIECES:
        density = np.zeros(len(dense))
        for section in sections:
            p = section.piece(name, dense)
            a, b, c = p[:-2], p[1:-1], p[2:]
            cross = np.abs(_cross(b - a, c - a))
            sides = (np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - b, axis=1)
                     * np.linalg.norm(c - a, axis=1))
            kappa = 2.0 * cross / np.maximum(sides, 1e-300)
            kappa = np.concatenate([kappa[:1], kappa, kappa[-1:]])
            spacing = np.minimum(np.sqrt(8.0 * sag / np.maximum(kappa, 1e-12)), max_spacing)
            speed = np.linalg.norm(np.gradient(p, dense, axis=0), axis=1)
            density = np.maximum(density, speed / spacing)
        cumulative = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1])
                                                     * np.diff(dense))])
        count = max(math.ceil(cumulative[-1] * 1.05), 4)
        w = np.interp(np.linspace(0.0, cumulative[-1], count + 1), cumulative, dense)[:-1]
        if name in ("trailing_edge", "leading_edge"):
            w = np.unique(np.concatenate([w, [0.5]]))
        grids[name] = w
    return grids


@dataclass(frozen=True)
class BladeSpec:
    """A blade: ``root`` and ``tip`` sections (same kind; every number interpolated linearly
    over the span), ``span`` (m), ``hub_radius`` (m, z of the hub cap), ``lean`` and ``sweep``
    (m): the stacking point's y and x offsets a·η + b·η² at span fraction η; ``span_spacing``
    (m) between rings of the triangulation."""

    root: SectionSpec
    tip: SectionSpec
    span: float
    hub_radius: float = 0.45
    lean: tuple[float, float] = (0.0, 0.0)
    sweep: tuple[float, float] = (0.0, 0.0)
    span_spacing: float = 2e-3

    def __post_init__(self) -> None:
        if self.root.kind != self.tip.kind:
            raise ValueError(f"root {self.root.kind} and tip {self.tip.kind}: one kind per blade")
        if not 0.02 <= self.span <= 0.25:
            raise ValueError(f"span {self.span} m: expected 20–250 mm (in m)")

    def section_spec(self, eta: float) -> SectionSpec:
        """The section at span fraction ``eta`` ∈ [0, 1]."""
        names = ("chord", "stagger_deg", "camber_deg", "thickness", "le_radius", "te_radius",
                 "camber_position")
        return replace(self.root, **{n: (1 - eta) * getattr(self.root, n)
                                     + eta * getattr(self.tip, n) for n in names})

    def offset(self, eta: float) -> np.ndarray:
        """Stacking point (x, y) at span fraction ``eta`` (m)."""
        return np.array([self.sweep[0] * eta + self.sweep[1] * eta**2,
                         self.lean[0] * eta + self.lean[1] * eta**2])


def _section_spec_mm(kind: str, chord_mm: float, stagger: float, camber: float, thickness: float,
                     le_mm: float, te_mm: float) -> SectionSpec:
    return SectionSpec(kind, chord_mm * 1e-3, stagger, camber, thickness, le_mm * 1e-3,
                       te_mm * 1e-3)


#: Named members of the family (sizes of HP/IP steam-turbine and compressor blading).
FAMILY: dict[str, BladeSpec] = {
    # impulse rotor: prismatic, 25 % thick, circular-arc camber (native nose 1.76 mm)
    "thick-impulse": BladeSpec(_section_spec_mm("turbine", 40, 5, 100, 0.25, 2.5, 0.3),
                               _section_spec_mm("turbine", 40, 5, 100, 0.25, 2.5, 0.3), 0.04),
    # NACA 4412-like (camber 18.9°), twisted 20° → 40°, 0.2 mm trailing-edge radius
    "naca-twisted": BladeSpec(_section_spec_mm("naca4", 40, 20, 18.9, 0.12, 0.7, 0.2),
                              _section_spec_mm("naca4", 40, 40, 18.9, 0.12, 0.7, 0.2), 0.08),
    # 250 mm, 10° → 50°, 65-series thickness 10 % → 7 %: a 2.45 mm thick tip, 0.15 mm nose
    "slender": BladeSpec(_section_spec_mm("naca65", 40, 10, 25, 0.10, 0.3, 0.15),
                         _section_spec_mm("naca65", 35, 50, 25, 0.07, 0.15, 0.15), 0.25),
    # compressor double circular arc: low camber, stagger 60° → 70°; rings every 1 mm, as a
    # thin twisted section loses 1.3e-4 of its volume to the span-wise chord sag at 2 mm
    "compressor-dca": BladeSpec(_section_spec_mm("dca", 30, 60, 10, 0.06, 0.15, 0.15),
                                _section_spec_mm("dca", 30, 70, 10, 0.06, 0.15, 0.15), 0.06,
                                span_spacing=1e-3),
    # reaction/impulse turbine section turning 120°
    "high-camber-turbine": BladeSpec(_section_spec_mm("turbine", 35, 10, 120, 0.18, 1.5, 0.3),
                                     _section_spec_mm("turbine", 35, 15, 120, 0.18, 1.5, 0.3),
                                     0.05),
    # tapered 50 → 35 mm, leaned 5 mm (quadratic), swept 3 mm (linear)
    "lean-sweep": BladeSpec(_section_spec_mm("naca65", 50, 30, 30, 0.10, 0.5, 0.25),
                            _section_spec_mm("naca65", 35, 35, 30, 0.08, 0.3, 0.2), 0.12,
                            lean=(0.0, 5e-3), sweep=(3e-3, 0.0)),
}


@dataclass(frozen=True)
class ForeignBlade:
    """A blade of the family: exact sections at any span fraction, a closed triangulation
    within :data:`MESH_SAG` of the exact surface, and signed distances to it (m)."""

    spec: BladeSpec

    def section(self, eta: float, guesses: tuple | None = None) -> Section:
        """The exact section at span fraction ``eta`` (blade frame, m)."""
        return Section(self.spec.section_spec(eta), self.spec.offset(eta), guesses)

    def height(self, eta: np.ndarray | float) -> np.ndarray | float:
        """z (m) at span fraction ``eta``."""
        return self.spec.hub_radius + np.asarray(eta) * self.spec.span

    @cached_property
    def levels(self) -> np.ndarray:
        """Span fractions of the rings of the triangulation."""
        count = max(2, math.ceil(self.spec.span / self.spec.span_spacing))
        return np.linspace(0.0, 1.0, count + 1)

    @cached_property
    def sections(self) -> list[Section]:
        """Sections at :attr:`levels`, each solve started from its neighbour's."""
        out, guesses = [], None
        for eta in self.levels:
            out.append(self.section(float(eta), guesses))
            guesses = out[-1].guesses()
        return out

    @cached_property
    def grid(self) -> dict[str, np.ndarray]:
        """The piece parameters of every ring (:func:`piece_grids` over the span)."""
        return piece_grids(self.sections[:: max(1, len(self.sections) // 8)] + self.sections[-1:])

    @cached_property
    def ring_size(self) -> int:
        """Vertices per ring."""
        return sum(len(w) for w in self.grid.values())

    @cached_property
    def mesh(self) -> trimesh.Trimesh:
        """Closed triangulation (m), outward: :attr:`side_faces` side triangles, then the caps."""
        rings = [np.column_stack([s.curve(self.grid), np.full(self.ring_size, float(z))])
                 for s, z in zip(self.sections, self.height(self.levels), strict=True)]
        vertices = np.vstack(rings)
        m, k = self.ring_size, len(rings)
        i = np.arange(m)
        j = (i + 1) % m
        faces = []
        for level in range(k - 1):
            a, b = level * m + i, level * m + j
            c, d = (level + 1) * m + j, (level + 1) * m + i
            faces.append(np.column_stack([a, b, c]))
            faces.append(np.column_stack([a, c, d]))
        hub = self._cap_triangles(self.sections[0], rings[0][:, :2])
        tip = self._cap_triangles(self.sections[-1], rings[-1][:, :2])
        faces.append(hub[:, ::-1])  # hub: normal −z
        faces.append(tip + (k - 1) * m)  # tip: normal +z
        mesh = trimesh.Trimesh(vertices, np.vstack(faces), process=False)
        if not (mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0):
            raise ValueError("the blade's triangulation is not closed and outward")
        return mesh

    @cached_property
    def side_faces(self) -> int:
        """Number of side triangles (the first faces of :attr:`mesh`; the caps follow)."""
        return 2 * self.ring_size * (len(self.levels) - 1)

    def _cap_triangles(self, section: Section, ring: np.ndarray) -> np.ndarray:
        """Counter-clockwise triangles of a flat cap on the ring's vertices: a strip zipped
        between the upper and lower halves (leading- to trailing-edge arc middle), paired by
        :meth:`Section.chord_fraction`; checked to tile the polygon (all counter-clockwise and
        together its area)."""
        counts = [len(self.grid[n]) for n in PIECES]
        starts = np.concatenate([[0], np.cumsum(counts)])
        q = np.concatenate([section.chord_fraction(n, self.grid[n]) for n in PIECES])
        i_te = starts[0] + int(np.flatnonzero(self.grid["trailing_edge"] == 0.5)[0])
        i_le = starts[2] + int(np.flatnonzero(self.grid["leading_edge"] == 0.5)[0])
        m = len(ring)
        upper = np.arange(i_te, i_le + 1)[::-1]  # LE middle → TE middle along the upper side
        lower = np.concatenate([np.arange(i_le, m), np.arange(0, i_te + 1)])
        triangles, a, b = [], 0, 0
        while a < len(upper) - 1 or b < len(lower) - 1:
            step_upper = b == len(lower) - 1 or (
                a < len(upper) - 1 and q[upper[a + 1]] <= q[lower[b + 1]])
            if step_upper:
                tri = (upper[a], upper[a + 1], lower[b])
                a += 1
            else:
                tri = (upper[a], lower[b + 1], lower[b])
                b += 1
            if len(set(tri)) == 3:
                triangles.append(tri)
        triangles = np.array(triangles)
        p = ring[triangles]
        signed = 0.5 * _cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        if np.all(signed < 0):
            triangles, signed = triangles[:, ::-1], -signed
        if not (np.all(signed > 0) and math.isclose(signed.sum(), polygon_area(ring),
                                                    rel_tol=1e-9)):
            raise ValueError("the cap strip does not tile the section")
        return triangles

    def mesh_sag(self) -> float:
        """Largest distance (m) from the mesh of exact side points at the middle of every ring
        segment and of every quad between rings (parameter mid-points: where a chord or a
        triangle is farthest from the surface it spans)."""
        worst = 0.0
        mids = {n: 0.5 * (w + np.append(w[1:], 1.0)) for n, w in self.grid.items()}
        ring = {n: w for n, w in self.grid.items()}
        levels = self.levels
        mid_levels = 0.5 * (levels[1:] + levels[:-1])
        for eta_set, grid in ((levels, mids), (mid_levels, ring), (mid_levels, mids)):
            points = []
            for eta in eta_set[:: max(1, len(eta_set) // 40)]:
                section = self.section(float(eta), self.sections[0].guesses())
                points.append(np.column_stack([section.curve(grid),
                                               np.full(self.ring_size, self.height(eta))]))
            worst = max(worst, float(np.abs(self.signed_distance(np.vstack(points))).max()))
        return worst

    def locate(self, points: np.ndarray) -> tuple[np.ndarray, list[str]]:
        """Span fraction and piece (or "hub"/"tip" cap) of the nearest mesh vertex of each point
        (m): where on the blade a deviation lies."""
        from scipy.spatial import cKDTree

        vertex = cKDTree(self.mesh.vertices).query(np.asarray(points))[1]
        ring, index = np.divmod(vertex, self.ring_size)
        starts = np.cumsum([len(self.grid[n]) for n in PIECES])
        pieces = [PIECES[int(np.searchsorted(starts, i, side="right"))] for i in index]
        eta = self.levels[ring]
        z = np.asarray(points)[:, 2]
        for cap, height in (("hub", self.height(0.0)), ("tip", self.height(1.0))):
            on = np.abs(z - height) < 0.2e-3
            pieces = [cap if flag else name for flag, name in zip(on, pieces, strict=True)]
        return eta, pieces

    @cached_property
    def _side_scene(self) -> tuple:
        import open3d as o3d

        mesh = self.mesh
        side = np.asarray(mesh.faces[: self.side_faces])
        centre = mesh.vertices.mean(axis=0)
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices - centre, np.float32)),
                            o3d.core.Tensor(np.asarray(side, np.uint32)))
        return scene, centre, mesh.face_normals[: len(side)]

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Signed distance (m, positive outside) of points (n, 3, m) to the blade.

        Sides: the triangulation (within :data:`MESH_SAG`), queried by open3d in single
        precision about the mesh centre (rounding < 20 nm for 0.3 m parts), sign from the
        nearest face's outward normal (exact for the convex rims, the only creases). Caps:
        analytic in double precision, |z − z_cap| above the section polygon.
        """
        import open3d as o3d
        from matplotlib.path import Path as MplPath

        points = np.asarray(points, dtype=float)
        scene, centre, normals = self._side_scene
        query = o3d.core.Tensor(np.asarray(points - centre, np.float32))
        result = scene.compute_closest_points(query)
        closest = result["points"].numpy().astype(float) + centre
        face = result["primitive_ids"].numpy().astype(int)
        delta = points - closest
        distance = np.linalg.norm(delta, axis=1)
        sign = np.where(np.einsum("ij,ij->i", delta, normals[face]) >= 0.0, 1.0, -1.0)
        signed = sign * distance
        for section, z_cap, outward in ((self.sections[0], self.height(0.0), -1.0),
                                        (self.sections[-1], self.height(1.0), 1.0)):
            polygon = section.curve(self.grid)
            inside = MplPath(polygon).contains_points(points[:, :2])
            cap = outward * (points[:, 2] - z_cap)
            nearer = inside & (np.abs(cap) < np.abs(signed))
            signed[nearer] = cap[nearer]
        return signed


def family_blade(name: str) -> ForeignBlade:
    """The named member of :data:`FAMILY`."""
    if name not in FAMILY:
        raise KeyError(f"no family member {name!r}: expected one of {sorted(FAMILY)}")
    return ForeignBlade(FAMILY[name])


# --- scans ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LaserCloud:
    """A fused scan (m): ``points`` (n, 3), which are ``outliers``, the ``hole_centres`` (on the
    surface) and ``hole_radius`` of the discs left without points, and the ``normals`` of the
    surface where each point was drawn."""

    points: np.ndarray
    outliers: np.ndarray
    hole_centres: np.ndarray
    hole_radius: float
    normals: np.ndarray


def laser_cloud(blade: ForeignBlade, points: int = 80_000, noise: float = 0.017e-3,
                outlier_share: float = 0.01, outlier_range: tuple[float, float] = (0.2e-3, 2e-3),
                holes: int = 10, hole_diameter: float = 2e-3,
                seed: int | np.random.Generator = 0) -> LaserCloud:
    """``points`` points area-uniform over the closed surface, ``noise`` (σ, m) along the
    normal, a share of outliers moved outward along the normal by a uniform 0.2–2 mm, and
    ``holes`` discs of ``hole_diameter`` (m; radius measured in 3-D from a surface point)
    without points; blade frame, seeded."""
    rng = np.random.default_rng(seed)
    mesh = blade.mesh
    hole_centres = _surface_samples(mesh, holes, rng)[0]
    radius = 0.5 * hole_diameter
    kept_p, kept_n = [], []
    have = 0
    while have < points:
        p, n = _surface_samples(mesh, int(1.2 * (points - have)) + 100, rng)
        if holes:
            far = np.min(np.linalg.norm(p[:, None] - hole_centres[None], axis=2), axis=1) > radius
            p, n = p[far], n[far]
        kept_p.append(p)
        kept_n.append(n)
        have += len(p)
    p, n = np.vstack(kept_p)[:points], np.vstack(kept_n)[:points]
    offset = rng.normal(0.0, noise, points)
    outliers = np.zeros(points, dtype=bool)
    outliers[rng.choice(points, round(outlier_share * points), replace=False)] = True
    offset[outliers] = rng.uniform(*outlier_range, int(outliers.sum()))
    return LaserCloud(points=p + offset[:, None] * n, outliers=outliers,
                      hole_centres=hole_centres, hole_radius=radius, normals=n)


def _surface_samples(mesh: trimesh.Trimesh, count: int, rng: np.random.Generator
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Area-uniform points on a mesh and the face normal at each."""
    area = mesh.area_faces
    face = rng.choice(len(area), size=count, p=area / area.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    tri = mesh.triangles[face]
    points = tri[:, 0] + u[:, None] * (tri[:, 1] - tri[:, 0]) + v[:, None] * (tri[:, 2] - tri[:, 0])
    return points, mesh.face_normals[face]


def random_pose(points: np.ndarray, seed: int | np.random.Generator = 0,
                max_translation: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The cloud (m) in a random rigid pose: a uniform random rotation (scipy
    ``Rotation.random``) and a translation in a random direction of length up to
    ``max_translation`` (m). Returns the points in the scan frame and the 4×4 transform
    scan ← blade."""
    rng = np.random.default_rng(seed)
    rotation = Rotation.random(random_state=rng).as_matrix()
    direction = rng.normal(size=3)
    translation = direction / np.linalg.norm(direction) * rng.uniform(0.0, max_translation)
    transform = np.eye(4)
    transform[:3, :3], transform[:3, 3] = rotation, translation
    return np.asarray(points) @ rotation.T + translation, transform


# --- measuring a reconstruction ------------------------------------------------------------------


def mesh_distances(points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray
                   ) -> np.ndarray:
    """Unsigned distance (m) of points to a triangle mesh (open3d, single precision about the
    mesh centre: rounding < 20 nm for parts up to 0.3 m; sliver triangles of ear-clipped caps
    may add ~10 µm)."""
    import open3d as o3d

    centre = np.asarray(vertices).mean(axis=0)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices - centre, np.float32)),
                        o3d.core.Tensor(np.asarray(triangles, np.uint32)))
    query = o3d.core.Tensor(np.asarray(points - centre, np.float32))
    return scene.compute_distance(query).numpy().astype(float)


def compare_with_exact(blade: ForeignBlade, vertices: np.ndarray, triangles: np.ndarray,
                       samples: int = 200_000, seed: int = 0) -> dict[str, float]:
    """A reconstructed mesh (blade frame, m) against the exact surface, both ways (m).

    ``rms``/``max``: ``samples`` area-uniform points of the reconstruction and all its vertices
    → exact surface (catches spikes and beaks; RMS over the area samples); ``back_max``:
    ``samples`` points of the exact surface → reconstruction (catches missing or cut-off parts);
    ``at_eta``/``at``: span fraction and piece (:meth:`ForeignBlade.locate`) of the worse of the
    two maxima.
    """
    rng = np.random.default_rng(seed)
    recon = trimesh.Trimesh(vertices, triangles, process=False)
    ours = _surface_samples(recon, samples, rng)[0]
    forward = np.abs(blade.signed_distance(np.vstack([ours, vertices])))
    exact = _surface_samples(blade.mesh, samples, rng)[0]
    backward = mesh_distances(exact, np.asarray(vertices, float), np.asarray(triangles))
    candidates = np.vstack([ours, vertices])
    worst = (candidates[np.argmax(forward)] if forward.max() >= backward.max()
             else exact[np.argmax(backward)])
    eta, piece = blade.locate(worst[None])
    return {"rms": float(np.sqrt(np.mean(forward[:samples] ** 2))), "max": float(forward.max()),
            "back_max": float(backward.max()), "at_eta": float(eta[0]), "at": piece[0]}
