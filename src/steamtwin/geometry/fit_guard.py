"""Two-way check of a reconstructed blade against its cloud: surface far from the data.

Kept as one module because both directions of the check share one envelope measurement (the
facing cloud points round each surface sample) and one report, which the repair reads whole.

The fit's residuals measure one way, the cloud points far from the fitted surface. A beak
beyond a thin trailing edge or a spike at a leading-edge nose is the other way: surface where
there are no points, which no residual sees. This module measures it (the surface side of the
Hausdorff distance, as in Cignoni, Rocchini & Scopigno 1998, "Metro: measuring error on
simplified surfaces", CGF 17:167, but against the surface the points define, not the points
themselves, so that a scan hole the fit bridges is not taken for a defect):

- every vertex of the side grid is a sample (the triangulation is piecewise linear, so its
  distance from a smooth surface peaks at vertices);
- its candidates are the side points the fit kept that lie nearest to it in the surface's
  parameters (``s`` unrolled round the perimeter, and z): the points of its own face, never
  the opposite face of a thin part; normals are the fitted surface's, consistently outward;
- the *envelope* is the :data:`ENVELOPE` candidates nearest to the vertex's normal line (of
  those whose normals are within :data:`FACING` of its own), each raised by l·tan(θ/2), the
  drop of a circular arc from the vertex to a point l off its normal line whose normal is
  turned by θ; the *excursion* is how far the vertex stands outside all of them, combined (root
  sum of squares) with how far it lies beyond the extent of its nearest cloud points in its
  tangent plane (all of them on one side). In a scan hole the nearest points surround the
  vertex and the surface bridges them tangentially: no excursion;
- or how far the vertex lies *inside*: behind the tangent planes of all of its
  ``neighbours`` nearest kept side points in space, each by its own (fitted, outward) normal
  — the least of those depths, so that a vertex on one face of a thin part is cleared by the
  points of its own face, and its own normal, which a micro-cusp of the fit can turn through
  the part, does not choose the plane (row ip5, seed 0: a column of such cusps at the
  trailing edge read 1.1–1.3 mm inside against the opposite face when the depth was taken
  along the vertex's normal; by the tangent planes at most 0.065 mm, limit 0.114 mm). On a
  convex face the plane reads the arc's drop R(1 − cos θ) to its point high, so that drop is
  taken off by the arc through that point (:func:`_depth_inside`), and the depth is held to
  the limit alone, not to the outward envelope's arc allowance; on a concave face it reads
  low.
  The residuals do not see such a dip or spike into the blade: the fit trims the points it
  misses by more than its outlier distance, and a spike may be narrower than the point
  spacing, so that no point lies far from the triangles round it. Issue 19: with sections.py
  at fa41e9a, examples/reconstruct_blade.py --quick passed a 0.83 mm inward tongue at the
  trailing edge of hp1 (53–100 % span) as watertight; the 20 or so pressure-side points round
  it lay 0.17–0.55 mm off the surface, all trimmed by the fit, in a strip one point across —
  0–7 of each one's 20 neighbours far too, short of a coverage gap's half. The depth reads
  0.43–0.60 mm there on 54 vertices beyond the limit and allowance (true 0.42–0.81 mm) where
  the good fit of the same cloud reads at most 0.11 mm (limit 0.17 mm). The rim zones
  (below) are judged outward only.

Limit (stated rule): a vertex is a defect beyond ``max(noise_factor × σ, spacing_factor × h,
floor)`` plus its allowance — σ the measured noise (1.4826 × the median absolute residual of
the side points the fit kept, the normal-consistent scale of the median absolute deviation), h
the median point spacing, the allowance (outward only) what a convex surface may drop beyond the
arc between an envelope point and the normal line: a convex curve through the point, tangent to
its plane, drops anywhere from 0 to l·tan θ there (the plane itself), so the allowance is the
largest l·(tan θ − tan(θ/2)) of the envelope, θ the turn within the plane of the normal and the
offset to the point (a turn across the offset, as round a nose for a beak beyond the edge's end,
is no slope along it) — l·tan(θ/2) to first order in θ, the arc drop itself (where the points
lie a spacing off the normal line on a sharp edge the vertex is judged only to what they allow);
on a tight edge whose facing points are turned far it is more (slender 80k seed 2: a vertex on a
0.15-mm trailing-edge circle, its facing points turned 58° and 0.64–0.73 mm off its normal line,
0.91–1.07 mm below its tangent plane, read 0.55 mm out against an arc allowance of 0.40 mm; the
turn happens at once on the circle and the rest is flat, a drop of ≈ 0.9 mm; the true deviation
is 0.005 mm). Within ``rim_spacings`` × h of a cap rim the side data end and the neighbourhoods
straddle the crease: there a vertex is measured in its own section against the side's points and
the cap's (:func:`rim_excursion`: the cap plane and its outline count as data), so that a bulge
of the rim ring is judged too; its allowance is :data:`RIM_SLACK` spacings. The side's points
there include those the fit trimmed whose nearest kept point faces as they were placed (the
points under a bulge are off it by more than the trimming distance), and the points within
:data:`RIM_NEAR` spacings of the vertex's normal line, where there are any, read alone.

Defects are the connected groups of offending vertices, named by their patch (leading or
trailing edge, suction or pressure side), span range (% from the root) and size (mm).

The other way (:func:`coverage_gaps`, the cloud side of the Hausdorff distance, Cignoni et al.
1998): the cloud points the segmentation assigned to a patch farther from the triangulation than
the same limit. A remaining outlier (0.2–2 mm off along the normal, isolated) is one of them,
but its neighbours lie on the surface; where the surface misses a part of the blade (an edge cut
short, a dent) the points there are far together. A far point counts when at least
``coherent_share`` of its ``neighbours`` nearest patch points are far too, or of its
``line_neighbours`` nearest side points along the span (:func:`_strips`: a strip about one
point across, as at a nose the fit flattened, whose apex points it trimmed), and the counted
points linked within ``link_spacings`` point spacings or as neighbours along the strip form a
gap when there are at least ``min_gap_points`` of them — named by patch, span range, chord
range and distance. Where an edge carries few points, :func:`edge_sampling` measures the
points per millimetre across the edge's half circle and what
:data:`~steamtwin.geometry.scanner.EDGE_SAMPLES` needs there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from steamtwin.geometry.bspline import PeriodicSurface
from steamtwin.geometry.edge_thickness import FLANK_TO, FLANK_TO_MIN, wedge_radius
from steamtwin.geometry.filters import plane_basis
from steamtwin.geometry.scanner import EDGE_SAMPLES
from steamtwin.geometry.segmentation import SIDE_REGIONS, Segmentation
from steamtwin.geometry.volume_mesh import REGIONS

#: Normal-consistent scale of the median absolute deviation (Gaussian: σ = 1.4826 × MAD).
MAD_SCALE = 1.4826
#: Largest angle (rad) between a sample's normal and those of the cloud points that define the
#: surface at it: 60° keeps a third of an edge circle and none of the opposite face.
FACING = math.radians(60.0)
#: Facing points nearest to a sample's normal line that make the envelope it is checked against.
ENVELOPE = 4
#: Span bands in which edges are measured: fifths of the span.
SPAN_BANDS = 5


class GuardedMesh(Protocol):
    """What the guard reads of a reconstruction (a
    :class:`~steamtwin.geometry.reconstruct.Reconstruction` is one; named structurally so that
    the reconstruction can call its guard without the two modules importing each other)."""

    vertices: np.ndarray  # (n, 3) m, the rings of the side grid root to tip, then the caps
    triangles: np.ndarray  # (m, 3)
    points: np.ndarray  # (p, 3) m, the input cloud
    segmentation: Segmentation
    surface: PeriodicSurface
    residuals: np.ndarray  # (p,) m
    inliers: np.ndarray  # (p,) bool
    parameters: np.ndarray  # (p,) s of the side points
    ring_parameters: np.ndarray  # s of the vertices of a ring


@dataclass(frozen=True)
class GuardSettings:
    """Hyper-parameters of :func:`guard_surface` (lengths in m).

    ``neighbours`` cloud points define the local surface at each vertex; a vertex is a defect
    beyond ``max(noise_factor × σ, spacing_factor × h, floor)`` (σ measured noise, h point
    spacing, module docstring); ``penalty_factors`` are the penalty multipliers of the repair
    refits tried in turn after the first fit (empty: refuse at once); vertices within
    ``rim_spacings`` point spacings of a cap rim are measured against the rim's own section
    (:func:`rim_excursion`: the side data end there and the neighbourhoods straddle the crease,
    as in the segmentation's rim zone; 8 spacings, measured: a one-vertex false alarm of 0.20
    mm 7.5 spacings from the hub rim of a foreign blade whose true deviation is ≤ 0.04 mm by
    :func:`local_excursion` — tests/geometry/test_foreign_blades.py, thick-impulse, 40k
    points, seed 1). A defect of fewer than ``min_vertices`` connected
    vertices counts only beyond ``isolated_limit`` (the issue's ceiling for any written STL):
    an overshoot of the spline spans a knot interval, i.e. several vertices of the
    triangulation, while isolated one- and two-vertex excursions of 0.23–0.47 mm were measured
    on foreign-blade fits whose true deviation is ≤ 0.05 mm (80k points; the local neighbours
    a vertex is judged by thin out at the clouds' holes and outliers).

    The other way (:func:`coverage_gaps`): a patch point farther from the triangulation than
    the limit counts when at least ``coherent_share`` of its ``neighbours`` nearest patch
    points are also that far (an isolated outlier has none: 1 % outliers put on average 0.2 of
    its 20 neighbours out); counted points linked within ``link_spacings`` spacings form a gap
    when there are ``min_gap_points`` or more (a gap one point spacing across and a few long).
    A far point also counts when ``coherent_share`` of its ``line_neighbours`` nearest side
    points in the surface's parameters, the across distance weighted ``line_stretch`` times the
    span's, are far by a like amount (:func:`_strips`): for points spread at random at
    spacing h (ρ = ln 2/(π h²), Clark & Evans 1954, Ecology 35:445) that neighbourhood reaches
    h·√(k/(w ln 2)) = 0.49 h across and w times that (29 h) along the span — a strip one point
    across, as the apex points a fit flattened across a nose trimmed (lean-sweep 40k seed 3:
    18 points 0.11–0.20 mm off at the leading edge at 56–63 % span, 15–35 % of their 20
    nearest points far; none such on the 43 cached first fits of the family within 0.1 mm).

    ``bridge_holes``: a vertex beyond its nearest points but surrounded by the side's points in
    its tangent plane, or in a hole through a thin edge between rims along the span, is a
    bridged scan hole (:func:`local_excursion`'s ``bridge_holes``; the span rims clear
    compressor-dca 80k seed 5, 0.25 mm read where the fit is within 0.017 mm): it
    clears the false alarms at holes through thin edges (compressor-dca 80k seed 1 passes,
    0.043 mm) and across faces (seed 0, docs/benchmarks.md "The guard's holes by depth"). On
    thick-impulse 80k seed 0 such a false alarm (0.29 mm where the fit is within 0.003 mm) was
    what started the repair that also removed a 0.33 mm bulge of the tip rim; since the rim
    zones are judged (:func:`rim_excursion`) the rim check starts it, and that cloud passes
    with the bridging too. On by default, as the edge model (``ReconstructionSettings.
    model_edges``) it goes with: with both on, the 80k family in random poses gives 9 pass /
    0 fail / 3 refused (docs/benchmarks.md, "The edge model as the default again").
    ``cpu_budget`` (s of the process's CPU time, None: unlimited): a repair refit is started
    only when the reconstruction's CPU time so far plus the dearest refit's stays within it
    (:mod:`~steamtwin.geometry.repair_budget`; issue 19: ≤ 30 s per 80k-point cloud).
    """

    neighbours: int = 20
    noise_factor: float = 6.0
    spacing_factor: float = 0.35
    floor: float = 0.03e-3
    penalty_factors: tuple[float, ...] = (10.0, 100.0)
    rim_spacings: float = 8.0
    min_vertices: int = 3
    isolated_limit: float = 0.5e-3
    coherent_share: float = 0.5
    link_spacings: float = 3.0
    min_gap_points: int = 10
    line_neighbours: int = 10
    line_stretch: float = 60.0
    cpu_budget: float | None = 30.0
    bridge_holes: bool = True


@dataclass(frozen=True)
class Defect:
    """Connected vertices of the fitted surface beyond the limit: the patch they lie on, their
    span range (fractions from the root), the largest excursion (m) and the vertex count."""

    region: str
    span_from: float
    span_to: float
    size: float
    vertices: int

    def describe(self) -> str:
        """e.g. "0.37 mm at the trailing edge at 60–80 % span (12 vertices)"."""
        place = self.region.replace("_", " ")
        lo, hi = round(self.span_from * 100), round(self.span_to * 100)
        span = f"{lo} %" if lo == hi else f"{lo}–{hi} %"
        return f"{self.size * 1e3:.2f} mm at the {place} at {span} span ({self.vertices} vertices)"


@dataclass(frozen=True)
class CoverageGap:
    """Cloud points coherently farther from the fitted triangulation than the limit: the patch
    most of them carry, their span and chord ranges (fractions from the root and from the
    leading edge), the largest distance (m) and the point count."""

    region: str
    span_from: float
    span_to: float
    chord_from: float
    chord_to: float
    distance: float
    points: int

    def describe(self) -> str:
        """e.g. "0.83 mm of the cloud off the surface at the trailing edge at 3–18 % span,
        90–100 % chord (149 points)"."""
        place = self.region.replace("_", " ")
        span = _percent_range(self.span_from, self.span_to)
        chord = _percent_range(self.chord_from, self.chord_to)
        return (f"cloud points {self.distance * 1e3:.2f} mm off the surface at the {place} at "
                f"{span} span, {chord} chord ({self.points} points)")


def _percent_range(lo: float, hi: float) -> str:
    a, b = round(lo * 100), round(hi * 100)
    return f"{a} %" if a == b else f"{a}–{b} %"


@dataclass(frozen=True)
class GuardReport:
    """Result of :func:`guard_surface`: per-vertex ``excursion`` (m), the ``limit`` (m), the
    measured ``noise`` σ and ``spacing`` h (m), ``defects`` (largest first), ``judged`` the
    vertices held to the limit (all: the rim zones by :func:`rim_excursion`), the per-vertex
    ``allowance`` (m) added to the limit (:func:`local_excursion`), ``repairs``, the penalty
    factor of the fit that passed (1 = the first fit), ``gaps`` the cloud's parts the surface misses
    (:func:`coverage_gaps`, largest first) and ``back_distance`` the distance (m) of every
    patch point from the triangulation (NaN for unassigned points)."""

    excursion: np.ndarray
    limit: float
    noise: float
    spacing: float
    defects: list[Defect] = field(default_factory=list)
    judged: np.ndarray | None = None
    allowance: np.ndarray | None = None
    repairs: float = 1.0
    gaps: list[CoverageGap] = field(default_factory=list)
    back_distance: np.ndarray | None = None

    @property
    def worst(self) -> float:
        """The largest defect size or gap distance (m; 0 when none)."""
        return max([d.size for d in self.defects] + [g.distance for g in self.gaps] + [0.0])

    @property
    def failed(self) -> bool:
        """Whether the surface stands off the cloud (defects) or misses part of it (gaps)."""
        return bool(self.defects or self.gaps)

    def summary(self) -> dict:
        """Figures in report units (mm)."""
        judged = self.excursion if self.judged is None else self.excursion[self.judged]
        return {"guard_limit_mm": self.limit * 1e3,
                "guard_max_excursion_mm": float(judged.max()) * 1e3,
                "guard_p99_excursion_mm": float(np.percentile(judged, 99.0)) * 1e3,
                "guard_rim_max_excursion_mm": float(self.excursion.max()) * 1e3,
                "guard_noise_mm": self.noise * 1e3,
                "guard_defects": [d.describe() for d in self.defects],
                "guard_gaps": [g.describe() for g in self.gaps],
                **({} if self.back_distance is None else {
                    "guard_back_max_mm": float(np.nanmax(self.back_distance)) * 1e3,
                    "guard_back_p99_mm": float(np.nanpercentile(self.back_distance, 99.0))
                    * 1e3}),
                "guard_penalty_factor": self.repairs}


def local_excursion(samples: np.ndarray, sample_normals: np.ndarray, cloud: np.ndarray,
                    cloud_normals: np.ndarray, neighbours: int = 20,
                    extent_points: np.ndarray | None = None,
                    keys: tuple[np.ndarray, np.ndarray] | None = None,
                    bridge_holes: bool = False, bridge_from: float = 0.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) of every sample (n, 3; m, unit normals (n, 3)) from the cloud's surface
    (module docstring): among the 3 × ``neighbours`` nearest cloud points whose normals are
    within :data:`FACING` of the sample's, the :data:`ENVELOPE` nearest to the sample's normal
    line say how far the sample stands outside all of them, each raised by the drop l·tan(θ/2)
    of a circular arc from the sample to it (l its distance from the normal line, θ the turn
    between the two normals) — on a convex edge a point l off the normal line lies that far
    below the tangent plane, so a sample on the edge is not taken for a beak — or how far it
    lies behind the tangent planes of all of its ``neighbours`` nearest ``cloud`` points in
    space, each by the point's own normal, less the arc's drop to the nearest plane's point
    (inside the part, :func:`_depth_inside`);
    the sample lies beyond the data by the gap to the nearest of the ``neighbours`` nearest
    ``extent_points`` (default: the cloud; all patches, caps included) when all of them lie
    on one side of it in its tangent plane. A sample with fewer than :data:`ENVELOPE` facing
    points (a gap across a thin edge) is judged by the extent alone.

    ``keys`` (samples' and cloud's, m) are the coordinates in which the candidates are the
    nearest (default: the positions); the guard passes the surface parameters unrolled, so
    that the candidates of a vertex are the points of its own face — never the opposite face
    of a thin part, whose nearness and k-NN normals (flipped there by the propagation) would
    otherwise pass for the surface below it. With ``bridge_holes``, a sample beyond its nearest
    points but surrounded by ``cloud`` points (not the caps', whose outline reaches out across
    the whole section) in its tangent plane is a bridged scan hole, not beyond the data; in a
    hole through a thin edge, with rims only above and below it along the edge, it is beyond
    them by its height over the rims' tangent planes (:func:`_bridged`; checked where it lies
    more than ``bridge_from`` (m) beyond them).

    Returns the excursion and its allowance (m): outward, the most a convex surface may drop
    beyond the arc to an envelope point, l·(tan θ − tan(θ/2)) (the rest of the way to the
    point's tangent plane, θ within the plane of the normal and the offset; module
    docstring), largest over the envelope — a sample with its envelope points right on its
    normal line is judged to the noise, one across a gap in the
    points on an edge only to what the gap allows; inward (:func:`_depth_inside`, which takes
    the arc's drop off itself) none. The reading further beyond its allowance is returned:
    the envelope's allowance once hid a surface 0.13 mm inside a sparse nose (0.21–0.27 mm
    of arc drop from points 0.4–0.5 mm off the normal line, lean-sweep 40k seed 3).
    """
    candidates = min(3 * neighbours, len(cloud))
    if candidates < ENVELOPE:
        raise ValueError(f"the guard needs at least {ENVELOPE} cloud points, got {len(cloud)}")
    sample_keys, cloud_keys = keys if keys is not None else (samples, cloud)
    _, index = cKDTree(cloud_keys).query(sample_keys, k=candidates)
    extent_points = cloud if extent_points is None else extent_points
    _, extent_index = cKDTree(extent_points).query(samples, k=min(neighbours,
                                                                  len(extent_points)))
    excursion = np.empty(len(samples))
    allowance = np.zeros(len(samples))
    cloud_tree = cKDTree(cloud)
    # inside: the points nearest in space, whatever face (below)
    _, behind_index = cloud_tree.query(samples, k=min(neighbours, len(cloud)))
    behind_index = behind_index.reshape(len(samples), -1)
    for start in range(0, len(samples), 20_000):  # bounded memory
        sl = slice(start, start + 20_000)
        normal = sample_normals[sl]
        facing = np.einsum("mki,mi->mk", cloud_normals[index[sl]], normal) > math.cos(FACING)
        offset = cloud[index[sl]] - samples[sl, None, :]  # (m, c, 3)
        height = np.einsum("mki,mi->mk", offset, normal)
        lateral = offset - height[:, :, None] * normal[:, None, :]
        spread = np.linalg.norm(lateral, axis=2)
        # the envelope: the facing points nearest to the normal line
        nearest = np.argsort(np.where(facing, spread, np.inf), axis=1)[:, :ENVELOPE]
        envelope = np.take_along_axis(height, nearest, axis=1)
        # the drop of a circular arc from the sample to a point l off its normal line whose
        # normal is turned by θ: l·tan(θ/2) (the chord bisects the turn)
        turn = np.take_along_axis(np.einsum("mki,mi->mk", cloud_normals[index[sl]], normal),
                                  nearest, axis=1)
        half = np.sqrt(np.clip((1.0 - turn) / (1.0 + turn), 0.0, None))  # tan(θ/2)
        lateral_nearest = np.take_along_axis(spread, nearest, axis=1)
        sagitta = lateral_nearest * half
        envelope = envelope + sagitta
        # a convex surface through the point, tangent to its plane, drops anywhere from 0 to
        # l·tan θ (the plane itself) by the normal line: the rest beyond the arc's is allowed.
        # θ is the turn within the plane of the sample's normal and the offset to the point,
        # tan θ = n_p·u / n_p·n_v (u the unit offset in the tangent plane): a point whose
        # normal turns across the offset (round a nose, for a beak beyond the edge's end along
        # it) does not slope away along it
        envelope_normals = np.take_along_axis(cloud_normals[index[sl]], nearest[:, :, None],
                                              axis=1)
        towards_point = np.take_along_axis(lateral, nearest[:, :, None], axis=1)
        towards_point /= np.maximum(lateral_nearest, 1e-300)[:, :, None]
        slope = (np.maximum(np.einsum("mki,mki->mk", envelope_normals, towards_point), 0.0)
                 / np.clip(turn, math.cos(FACING), 1.0))
        slack = lateral_nearest * (slope - slope / (1.0 + np.sqrt(1.0 + slope * slope)))
        top = np.argmax(envelope, axis=1)
        above = -envelope[np.arange(len(top)), top]  # > 0: the sample stands outside them all
        # the extent: whether every one of the nearest points of the whole cloud lies on the
        # side of their centroid, seen from the sample, in the sample's tangent plane
        apart = extent_points[extent_index[sl]] - samples[sl, None, :]
        apart -= np.einsum("mki,mi->mk", apart, normal)[:, :, None] * normal[:, None, :]
        centre = apart.mean(axis=1)
        towards = centre / np.maximum(np.linalg.norm(centre, axis=1, keepdims=True), 1e-300)
        beyond = np.maximum(np.einsum("mki,mi->mk", apart, towards).min(axis=1), 0.0)
        # too few facing points (a gap across a thin edge): the extent alone
        enough = facing.sum(axis=1) >= ENVELOPE
        stands = np.where(enough, above, 0.0)
        if bridge_holes:
            checked = np.where(beyond > bridge_from, beyond, 0.0)
            beyond = np.minimum(beyond, _bridged(samples[sl], normal, checked, cloud,
                                                 cloud_tree, cloud_normals))
        # inside: how far the sample lies behind the tangent planes of all its nearest points,
        # by their own normals — not the sample's, which a micro-cusp of the fit can turn
        # through the part (then its facing points are the opposite face of a thin edge) —
        # less the arc's drop to the nearest plane's point
        near = behind_index[sl]
        inside = _depth_inside(cloud[near] - samples[sl, None, :], cloud_normals[near], normal)
        outside = np.hypot(np.maximum(stands, 0.0), beyond)
        drop = np.where(enough, slack.max(axis=1), 0.0)
        # each reading against its own allowance: the convex slack is the outward envelope's
        # (the inward depth allows for the arc itself); the one further beyond is reported
        inward = inside > outside - drop
        excursion[sl] = np.where(inward, inside, outside)
        allowance[sl] = np.where(inward, 0.0, drop)
    return excursion, allowance


def _depth_inside(offset: np.ndarray, point_normals: np.ndarray, normal: np.ndarray
                  ) -> np.ndarray:
    """How far each sample lies inside the surface of its nearest points (m): its depth
    behind the nearest of their tangent planes, (p − v)·n_p least over the points, less the
    drop of the arc to that point: where the point's normal n_p is turned from the sample's
    n_v by θ < 90°, the depth along n_v below the circular arc through the point, tangent
    there — on such an arc the chord p − v bisects the turn, so (p − v)·(n_p + n_v) = 0, and
    a sample d inside along n_v reads d(1 + cos θ): the depth is (p − v)·(n_p + n_v) /
    (1 + cos θ), if less than the plane's. On a convex face the plane alone reads the arc's
    drop c·sin(θ/2) to a point a chord c away high; on a sparse round nose that is the
    whole reading (slender 80k seed 0: 0.11–0.14 mm at a leading edge whose nearest points
    lie 0.25–0.3 mm off its normal line, turned 63–77°, where the fit is 0.02 mm inside).
    Only the nearest plane's point is taken round its arc: the points of a flank beyond the
    edge circle read the sample outside their arcs (the circle through them is too large),
    and the least over all of them under-read a 0.5-mm dip into hp1's trailing edge as 0.33
    mm (tests/geometry/test_fit_guard.py). ``offset`` (n, k, 3) are p − v, ``point_normals``
    (n, k, 3) the points' unit normals, ``normal`` (n, 3) the samples'."""
    depth = np.einsum("mki,mki->mk", offset, point_normals)
    nearest = np.argmin(depth, axis=1)[:, None]
    plane = np.take_along_axis(depth, nearest, axis=1)[:, 0]
    point, point_normal = (np.take_along_axis(a, nearest[:, :, None], axis=1)[:, 0]
                           for a in (offset, point_normals))
    turn = np.einsum("mi,mi->m", point_normal, normal)
    along = np.einsum("mi,mi->m", point, normal)
    arc = np.where(turn > 0.0, (plane + along) / np.maximum(1.0 + turn, 1.0), np.inf)
    return np.minimum(plane, arc)


#: Reach, in multiples of a sample's distance from the nearest cloud point, within which the
#: points round it show a bridged hole (:func:`_bridged`). A sample d inside the rim of a hole
#: of radius R is surrounded by the rim within √(d·(2R − d)) (a flat face), so 5 d covers every
#: sample deeper than R/13 (below that it is within the limit anyway); a beak beyond an edge
#: line is never surrounded, unless the line turns outward by more than 1 in 5 along the span
#: (the former rule's reach). Measured on compressor-dca 80k seed 0 (random pose): the 29
#: false-alarm vertices in its holes at 1–3 mm span have half-plane depth 0 within 2 d and
#: 0–17 within 5 × their excursion (the former rule's reach), 13–1018 within 5 d.
BRIDGE_REACH = 5.0
#: Fewest points in every half of a sample's tangent plane (its half-plane depth; Tukey 1975,
#: "Mathematics and the picturing of data", Proc. ICM 2:523) that make it surrounded: a stray
#: point or two beyond an edge (the clouds' 1 % outliers lie off along the normal, not along
#: the surface) does not turn a beak into a bridged hole.
BRIDGE_DEPTH = 4


def half_plane_depth(offsets: np.ndarray) -> int:
    """Fewest of the 2-D ``offsets`` (k, 2) in any open half-plane whose boundary line passes
    through the origin (0 when the origin lies outside their convex hull): the counts of the
    half-turns that start just after each point's angle, whose minimum is the depth."""
    if len(offsets) == 0:
        return 0
    angle = np.sort(np.arctan2(offsets[:, 1], offsets[:, 0]))
    doubled = np.concatenate([angle, angle + 2.0 * math.pi])
    counts = np.searchsorted(doubled, angle + math.pi) - np.arange(1, len(angle) + 1)
    return int(counts.min())


def _bridged(samples: np.ndarray, normals: np.ndarray, beyond: np.ndarray, points: np.ndarray,
             tree: cKDTree, point_normals: np.ndarray) -> np.ndarray:
    """How far (m) each sample that lies ``beyond`` (m, > 0) its nearest points stands beyond
    the data once a scan hole it may bridge is allowed for (inf: no hole, the extent stands).

    A surface across a hole interpolates between the hole's rims (issue 19's compressor blade:
    2-mm holes through its 0.15-mm edges and across its faces near the hub, true deviation
    ≤ 0.005 mm where the extent alone said 0.2–0.36 mm); a beak or spike beyond an edge
    extrapolates: all the data lie on one side of it. Two readings of the rims:

    - surrounded (0): the ``points`` within :data:`BRIDGE_REACH` × its distance from the
      nearest of them, projected onto its tangent plane, surround it — at least
      :data:`BRIDGE_DEPTH` of them in every half-plane through it (a hole in a face);
    - along the span (:func:`_span_bridge`, ``point_normals`` the points' unit normals): a hole
      through an edge thinner than the hole has no rim beside the edge, only above and below
      it along the edge line; there the sample stands beyond the data by how far it lies
      outside the rims' tangent planes, interpolated between them.
    """
    result = np.full(len(samples), np.inf)
    checked = np.flatnonzero(beyond > 0.0)
    if len(checked) == 0:
        return result
    gap, _ = tree.query(samples[checked])
    for i, distance in zip(checked, gap, strict=True):
        near = points[tree.query_ball_point(samples[i], BRIDGE_REACH * distance)] - samples[i]
        if half_plane_depth(near @ plane_basis(normals[i]).T) >= BRIDGE_DEPTH:
            result[i] = 0.0
        else:
            result[i] = _span_bridge(samples[i], normals[i], distance, points, tree,
                                     point_normals)
    return result


#: Reach along the span, in multiples of a sample's distance d from the nearest cloud point,
#: within which :func:`_span_bridge` looks for a hole's far rim: along any line through a hole
#: of diameter D the far rim lies within D − d, so 20 d covers every sample deeper than D/21 —
#: for the issue's 2-mm holes deeper than 0.095 mm, the limit at 0.1-mm spacing (compressor-dca
#: 80k seed 5: the far rim 1.2–1.5 mm along the leading edge from vertices 0.21–0.30 mm from
#: their nearest point, 4.4–7.1 d).
BRIDGE_SPAN_REACH = 20.0


def _span_bridge(sample: np.ndarray, normal: np.ndarray, distance: float, points: np.ndarray,
                 tree: cKDTree, point_normals: np.ndarray) -> float:
    """How far (m) ``sample`` (3,; m, unit ``normal``) stands outside the tangent planes of the
    rims of a hole along the span, or inf when the data do not reach past it on both sides.

    ``distance`` (m) is its distance from the nearest of ``points`` (unit normals
    ``point_normals``). The span axis z, turned into its tangent plane, is the edge line's
    direction; the rims are the points within ``distance`` of the line through the sample
    (not the faces behind a thin edge, which run along it too) and within
    :data:`BRIDGE_SPAN_REACH` × ``distance`` along it, on each side the :data:`BRIDGE_DEPTH`
    nearest. A surface across the hole continues the rims: on a convex edge it lies inside
    the tangent plane of every rim point, whatever its place round the edge. The reading is
    the largest, over the pairs of a rim point above and one below whose line passes within
    half the sample's distance of it across (beside a sheet's boundary, as beyond a face's
    edge, the rims' line runs at its distance), of the sample's height over their tangent
    planes interpolated linearly to it along the line (an edge leaning off the span axis, whose
    planes the normals — the sections', horizontal — tilt, tilts them oppositely above and
    below; a convex body lies inside all its tangent planes). A beak beyond the edge, or a fin
    in the plane of a face beyond it, stands outside the planes of the edge's points by its
    size; a reading over half the sample's distance is no hole (inf); a beak beyond a tip or
    root rim has no data on its far side."""
    along = np.array([0.0, 0.0, 1.0]) - normal[2] * normal
    length = float(np.linalg.norm(along))
    if length < 0.5:  # the span axis within 30° of the normal: no edge line along the span
        return math.inf
    along /= length
    index = np.asarray(tree.query_ball_point(sample, BRIDGE_SPAN_REACH * distance), dtype=int)
    near = points[index] - sample
    u, w = near @ along, near @ np.cross(normal, along)
    line = np.linalg.norm(near - u[:, None] * along, axis=1) <= distance
    rims = []
    for side in (1.0, -1.0):
        on = np.flatnonzero(line & (side * u > 0.0))
        if len(on) < BRIDGE_DEPTH:
            return math.inf
        rims.append(on[np.argsort(side * u[on])[:BRIDGE_DEPTH]])
    # the sample's height over each rim point's tangent plane
    over = -np.einsum("ki,ki->k", near, point_normals[index])
    a, b = np.meshgrid(*rims, indexing="ij")
    t = u[a] / (u[a] - u[b])  # the sample's place on the line from a to b, 0 at a
    on_line = np.abs(w[a] + t * (w[b] - w[a])) <= 0.5 * distance
    if not np.any(on_line):
        return math.inf
    reading = max(float(np.max((over[a] + t * (over[b] - over[a]))[on_line])), 0.0)
    return reading if reading <= 0.5 * distance else math.inf


#: Slack (point spacings) added to the limit at the rims: there the outline is known from one
#: side only (the cap's points inside it, the side's below it) and the rim ring of a sparse
#: fit sits within about the issue's 0.1 mm of it (measured: hp1 from 20k exact samples,
#: 0.27 mm spacing, a true 0.12 mm at the tip rim read 0.14 mm, within the limit plus a quarter
#: spacing by 0.04 mm; the 80k family's clean rims read ≤ 0.095 mm; thick-impulse 80k seed 0's
#: 0.33 mm tip-rim bulge reads 0.17–0.30 mm at its three worst vertices, beyond it).
RIM_SLACK = 0.25
#: Distance (point spacings) from a rim sample's normal line within which the outline's points
#: alone make its reading, when there are any (:func:`rim_excursion`): 1.5 spacings hold a
#: few points of a Poisson sample on either side of the line.
RIM_NEAR = 1.5


def rim_excursion(samples: np.ndarray, sample_normals: np.ndarray,
                  outlines: list[tuple[np.ndarray, np.ndarray]], neighbours: int = 20,
                  near: tuple[float, ...] = ()) -> np.ndarray:
    """How far each rim sample (n, 3; m, horizontal outward unit normals (n, 3)) stands
    outside the data next to it in its own section (m).

    Next to a cap the side's points end and the neighbourhoods of :func:`local_excursion`
    straddle the crease; there the cap's points (the cap plane and its outline) are data as
    well as the side's. ``outlines`` are such sets of points (p, 3; m) with their unit normals
    (for a cap point the outward normal of the rim next to it); of each, the ``neighbours``
    points nearest to the sample whose normals are within :data:`FACING` of its own make its
    section's outline there — taken per set, so that a dense cap does not crowd out the side's
    points just above its plane, nor the side the cap's outline. In the section plane each is
    raised by the drop l·tan(θ/2) of a circular arc from the sample to a point l off its
    normal line whose normal is turned by θ (as in :func:`local_excursion`: on a 0.35-mm
    leading edge the outline's points nearest the normal line can be 0.3 mm off it), and the
    excursion is how far the sample lies outside the highest of them (the surface side of the
    Hausdorff distance, Cignoni et al. 1998, against the outline). The normals are the fitted
    surface's, not k-NN blends, so the drop is not added to the limit again (unlike
    :func:`local_excursion`'s allowance). A bulge beyond the outline has all of them inside; a
    sample with no facing point gets 0 (a hole at the rim). Where the i-th set has facing
    points within ``near[i]`` (m; 0 when not given) of the sample's normal line, only those
    count — for the side's points, not the cap's, whose points near that line lie inside the
    outline, not on it: the drop is the
    arc's only where the fitted normals turn as the data do, and at a bulge they turn faster
    on its flanks (issue 19, naca-twisted 80k seed 6: a 0.20-mm bulge at the tip rim's
    leading edge read 0.11 mm through a point 0.43 mm off the normal line, turned 56°, whose
    drop was 0.23 mm; its points within 0.2 mm read 0.20 mm).
    """
    if len(near) > len(outlines):
        raise ValueError(f"{len(near)} near-line reaches for {len(outlines)} sets of points")
    reaches = (*near, *(0.0,) * (len(outlines) - len(near)))
    normal = _flat(sample_normals)[:, :2]
    across = np.column_stack([-normal[:, 1], normal[:, 0]])
    top = np.full(len(samples), -np.inf)
    for (data, data_normals), reach in zip(outlines, reaches, strict=True):
        k = min(neighbours, len(data))
        if k == 0:
            continue
        _, index = cKDTree(data).query(samples, k=k)
        index = index.reshape(len(samples), k)
        offset = data[index, :2] - samples[:, None, :2]
        height = np.einsum("mki,mi->mk", offset, normal)
        lateral = np.abs(np.einsum("mki,mi->mk", offset, across))
        turn = np.einsum("mki,mi->mk", _flat(data_normals[index.ravel()]).reshape(
            len(samples), k, 3)[:, :, :2], normal)
        drop = lateral * np.sqrt(np.clip((1.0 - turn) / (1.0 + turn), 0.0, None))  # l·tan(θ/2)
        facing = turn > math.cos(FACING)
        close = facing & (lateral <= reach)
        counted = np.where(close.any(axis=1, keepdims=True), close, facing)
        envelope = np.where(counted, height + drop, -np.inf)
        top = np.maximum(top, envelope.max(axis=1))
    return np.where(np.isfinite(top), np.maximum(-top, 0.0), 0.0)


def _flat(normals: np.ndarray) -> np.ndarray:
    """Unit normals (n, 3) turned into the section plane z = const (their x-y part)."""
    flat = np.column_stack([normals[:, :2], np.zeros(len(normals))])
    return flat / np.maximum(np.linalg.norm(flat, axis=1, keepdims=True), 1e-12)


def guard_surface(reconstruction: GuardedMesh, settings: GuardSettings | None = None
                  ) -> GuardReport:
    """Excursions of the reconstruction's vertices from its cloud, the limit and the defects.

    A vertex is checked against the side points the fit kept nearest to it in the surface's
    parameters (its own face) and against the extent of all points the segmentation assigned
    to a patch (isolated strays left out); σ comes from the residuals of the kept side points.
    """
    settings = settings or GuardSettings()
    segmentation = reconstruction.segmentation
    side = np.isin(segmentation.labels, [REGIONS.index(name) for name in SIDE_REGIONS])
    surface = reconstruction.surface
    columns = len(reconstruction.ring_parameters)
    s = np.tile(reconstruction.ring_parameters, len(reconstruction.vertices) // columns)
    vertex_normals = np.column_stack([surface.outward_normals(s, reconstruction.vertices[:, 2]),
                                      np.zeros(len(s))])
    # the side points the fit kept, with the fitted surface's normals at their parameters
    # (consistently outward), looked up by parameter: s unrolled onto a circle as long as
    # the section's perimeter, and z
    placed = side & ~np.isnan(reconstruction.parameters)
    placed_normals = np.zeros((len(placed), 3))
    placed_normals[placed, :2] = surface.outward_normals(reconstruction.parameters[placed],
                                                         reconstruction.points[placed, 2])
    kept = placed & reconstruction.inliers
    cloud = reconstruction.points[kept]
    cloud_s = reconstruction.parameters[kept]
    cloud_normals = placed_normals[kept]
    radius = float(np.nanmedian(segmentation.perimeter)) / (2.0 * math.pi)

    def unrolled(parameter: np.ndarray, z: np.ndarray) -> np.ndarray:
        turn = 2.0 * math.pi * parameter
        return np.column_stack([radius * np.cos(turn), radius * np.sin(turn), z])

    excursion, allowance = local_excursion(
        reconstruction.vertices, vertex_normals, cloud, cloud_normals, settings.neighbours,
        reconstruction.points[segmentation.labels >= 0],
        keys=(unrolled(s, reconstruction.vertices[:, 2]), unrolled(cloud_s, cloud[:, 2])),
        bridge_holes=settings.bridge_holes,
        bridge_from=settings.floor)
    noise = MAD_SCALE * float(np.median(np.abs(reconstruction.residuals[kept])))
    spacing = segmentation.spacing
    limit = max(settings.noise_factor * noise, settings.spacing_factor * spacing,
                settings.floor)
    rings = reconstruction.vertices.reshape(-1, columns, 3)
    fraction = np.linspace(0.0, 1.0, len(rings))[:, None]
    height = rings[-1, :, 2] - rings[0, :, 2]
    from_rim = (np.minimum(fraction, 1.0 - fraction) * height[None, :]).ravel()
    # the rim zones: judged in their own sections against the side's and the caps' points,
    # a cap point with the outward normal of the rim vertex nearest to it
    rim = from_rim < settings.rim_spacings * spacing
    cap_points = reconstruction.points[np.isin(segmentation.labels, [REGIONS.index("root"),
                                                                     REGIONS.index("tip")])]
    _, nearest = cKDTree(reconstruction.vertices[rim]).query(cap_points)
    allowance[rim] = RIM_SLACK * spacing
    # the side points the fit kept, and those it trimmed whose nearest kept point lies on a
    # face turned as the surface is where the fit placed them: at a bulge the points under
    # it are off the surface by more than the trimming distance, and without them the
    # outline there is read from points farther round the edge; a point of the opposite face
    # of a thin edge, placed on this one, lies among that face's kept points (its k-NN normal
    # can be turned with this face's: slender 80k seed 2's 0.15-mm tip trailing edge)
    outline = placed.copy()
    trimmed = np.flatnonzero(placed & ~reconstruction.inliers)
    if trimmed.size and cloud.size:
        _, nearest_kept = cKDTree(cloud).query(reconstruction.points[trimmed])
        along = np.einsum("ij,ij->i", placed_normals[trimmed], cloud_normals[nearest_kept])
        outline[trimmed[along <= math.cos(FACING)]] = False
    excursion[rim] = rim_excursion(
        reconstruction.vertices[rim], vertex_normals[rim],
        [(reconstruction.points[outline], placed_normals[outline]),
         (cap_points, vertex_normals[rim][nearest])],
        settings.neighbours, (RIM_NEAR * spacing,))
    judged = np.ones(len(excursion), dtype=bool)
    defects = [d for d in _defects(reconstruction, excursion, limit + allowance)
               if d.vertices >= settings.min_vertices or d.size > settings.isolated_limit]
    back_distance = np.full(len(reconstruction.points), np.nan)
    assigned = segmentation.labels >= 0
    back_distance[assigned] = mesh_distance(reconstruction.points[assigned],
                                            reconstruction.vertices, reconstruction.triangles)
    gaps = coverage_gaps(reconstruction, back_distance, limit, settings)
    return GuardReport(excursion=excursion, limit=limit, noise=noise, spacing=spacing,
                       defects=defects, judged=judged, allowance=allowance, gaps=gaps,
                       back_distance=back_distance)


def mesh_distance(points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray
                  ) -> np.ndarray:
    """Unsigned distance (m) of ``points`` (n, 3; m) from a triangle mesh: open3d's
    ``RaycastingScene.compute_distance`` (closest point on the triangles, Embree BVH) in
    single precision about the mesh's centre — rounding below 0.1 µm for parts up to 1 m."""
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    centre = vertices.mean(axis=0)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices - centre, np.float32)),
                        o3d.core.Tensor(np.asarray(triangles, np.uint32)))
    query = o3d.core.Tensor(np.asarray(points - centre, np.float32))
    return scene.compute_distance(query).numpy().astype(np.float64)


def coverage_gaps(reconstruction: GuardedMesh, back_distance: np.ndarray, limit: float,
                  settings: GuardSettings) -> list[CoverageGap]:
    """The parts of the cloud the triangulation misses (module docstring): patch points
    farther than ``limit`` (m) from it (``back_distance``, m, NaN for unassigned points) whose
    neighbourhood is far as well, linked into groups; each group of at least
    ``settings.min_gap_points`` points is a gap, largest distance first."""
    assigned = np.flatnonzero(~np.isnan(back_distance))
    points = reconstruction.points[assigned]
    far = back_distance[assigned] > limit
    if far.sum() < settings.min_gap_points:
        return []
    k = min(settings.neighbours + 1, len(points))
    _, index = cKDTree(points).query(points[far], k=k)
    share = far[index[:, 1:]].mean(axis=1)  # the point itself left out
    coherent = np.flatnonzero(far)[share >= settings.coherent_share]
    strip, strip_pairs = _strips(reconstruction.parameters[assigned], points[:, 2],
                                 back_distance[assigned], limit,
                                 float(np.nanmedian(reconstruction.segmentation.perimeter)),
                                 settings)
    members = np.union1d(coherent, strip)
    if len(members) < settings.min_gap_points:
        return []
    spacing = reconstruction.segmentation.spacing
    pairs = cKDTree(points[members]).query_pairs(settings.link_spacings * spacing,
                                                 output_type="ndarray")
    pairs = np.concatenate([pairs.reshape(-1, 2), np.searchsorted(members, strip_pairs)])
    graph = coo_array((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                      shape=(len(members), len(members)))
    _, component = connected_components(graph, directed=False)
    z = reconstruction.vertices[:, 2]
    lo, hi = float(z.min()), float(z.max())
    chord = _chord_fraction(reconstruction)
    labels = reconstruction.segmentation.labels[assigned]
    gaps = []
    for group in np.unique(component):
        inside = members[component == group]
        if len(inside) < settings.min_gap_points:
            continue
        where = points[inside]
        span = (where[:, 2] - lo) / (hi - lo)
        along = chord(where)
        region = np.bincount(labels[inside], minlength=len(REGIONS)).argmax()
        gaps.append(CoverageGap(region=REGIONS[region], span_from=float(span.min()),
                                span_to=float(span.max()), chord_from=float(along.min()),
                                chord_to=float(along.max()),
                                distance=float(back_distance[assigned][inside].max()),
                                points=len(inside)))
    return sorted(gaps, key=lambda g: -g.distance)


def _strips(parameters: np.ndarray, z: np.ndarray, distance: np.ndarray, limit: float,
            perimeter: float, settings: GuardSettings) -> tuple[np.ndarray, np.ndarray]:
    """The points farther than ``limit`` (m; ``distance`` (m) from the triangulation, per
    point) coherent along a strip one point across: of their ``settings.line_neighbours``
    nearest points with a side parameter (``parameters``, NaN for the others) in the surface's
    parameters — s unrolled round a circle of the section's ``perimeter`` (m) with the across
    distance weighted ``settings.line_stretch`` times z's, so that the neighbourhood follows
    the span about a spacing across — at least ``settings.coherent_share`` far by a like
    amount (within a factor :data:`LIKE` either way: a scan's outlier, 0.2–2 mm off along the
    normal, does not join a strip of points 0.1–0.2 mm off, nor they it). Returns their
    indices and the pairs (indices) of such points in each other's neighbourhoods (the links
    of the strip)."""
    on = np.flatnonzero(~np.isnan(parameters))
    wanted = np.flatnonzero(distance[on] > limit)
    k = min(settings.line_neighbours + 1, len(on))
    if len(wanted) == 0 or k < 2:
        return np.empty(0, dtype=int), np.empty((0, 2), dtype=int)
    turn = 2.0 * math.pi * parameters[on]
    radius = settings.line_stretch * perimeter / (2.0 * math.pi)
    keys = np.column_stack([radius * np.cos(turn), radius * np.sin(turn), z[on]])
    _, index = cKDTree(keys).query(keys[wanted], k=k)
    neighbours = on[index[:, 1:]]  # the point itself left out
    own = distance[on[wanted]][:, None]
    near = distance[neighbours]
    like = (near > limit) & (near <= LIKE * own) & (LIKE * near >= own)
    counted = like.mean(axis=1) >= settings.coherent_share
    members = on[wanted[counted]]
    rows = np.repeat(members, k - 1).reshape(-1, k - 1)[like[counted]]
    partners = neighbours[counted][like[counted]]
    keep = np.isin(partners, members)
    return members, np.column_stack([rows[keep], partners[keep]])


#: Ratio within which the distances of two far points make them one strip (:func:`_strips`).
LIKE = 2.0


def _chord_fraction(reconstruction: GuardedMesh):
    """Function of points (n, 3; m) → their position along the chord of the nearest ring of
    the triangulation (0 at the leading edge, 1 at the trailing edge): the projection on the
    line from the ring's leading-edge vertex (the middle of the leading-edge patch) to its
    trailing-edge vertex (the middle of the trailing-edge patch), clipped to [0, 1]."""
    s = reconstruction.ring_parameters
    rings = reconstruction.vertices.reshape(-1, len(s), 3)
    ends = []
    for edge in ("leading_edge", "trailing_edge"):
        lo = next(v for key, v in reconstruction.boundaries.items() if key.endswith(f"|{edge}"))
        hi = next(v for key, v in reconstruction.boundaries.items()
                  if key.startswith(f"{edge}|"))
        middle = np.mod(lo + 0.5 * np.mod(hi - lo, 1.0), 1.0)
        ends.append(int(np.argmin(np.abs(np.mod(s - middle + 0.5, 1.0) - 0.5))))
    ring_z = rings[:, 0, 2]

    def along(points: np.ndarray) -> np.ndarray:
        ring = np.clip(np.searchsorted(ring_z, points[:, 2]), 0, len(ring_z) - 1)
        front, rear = rings[ring, ends[0], :2], rings[ring, ends[1], :2]
        chord = rear - front
        t = np.einsum("ij,ij->i", points[:, :2] - front, chord) / np.einsum("ij,ij->i", chord,
                                                                             chord)
        return np.clip(t, 0.0, 1.0)

    return along


def _defects(reconstruction: GuardedMesh, excursion: np.ndarray, limit: np.ndarray
             ) -> list[Defect]:
    """Connected groups (over the triangle edges) of the vertices beyond their ``limit``."""
    bad = excursion > limit
    if not np.any(bad):
        return []
    vertices, triangles = reconstruction.vertices, reconstruction.triangles
    region = np.full(len(vertices), -1)
    region[triangles.ravel()] = np.repeat(reconstruction.regions, 3)
    edges = triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    edges = edges[bad[edges[:, 0]] & bad[edges[:, 1]]]
    graph = coo_array((np.ones(len(edges)), (edges[:, 0], edges[:, 1])),
                      shape=(len(vertices), len(vertices)))
    _, component = connected_components(graph, directed=False)
    z = vertices[:, 2]
    lo, hi = float(z.min()), float(z.max())
    defects = []
    for label in np.unique(component[bad]):
        members = np.flatnonzero(bad & (component == label))
        worst = members[np.argmax(excursion[members])]
        span = (z[members] - lo) / (hi - lo)
        defects.append(Defect(region=REGIONS[region[worst]], span_from=float(span.min()),
                              span_to=float(span.max()), size=float(excursion[worst]),
                              vertices=len(members)))
    return sorted(defects, key=lambda d: -d.size)


def remnants(reconstruction: GuardedMesh, report: GuardReport, earlier: list[Defect]
             ) -> list[Defect]:
    """The groups of vertices of ``report`` beyond their limit, of any size, where a defect of
    an earlier fit of the same cloud lay (same patch, span ranges within one ring of each
    other). After a repair a group of one or two vertices there is what is left of a defect
    found, not an isolated false alarm (``GuardSettings.min_vertices``): on thick-impulse 80k
    seed 0 the first repair left a 0.16–0.19-mm bulge of the tip rim of which the rim check
    reads one vertex over the limit (0.142 against 0.131 mm; the next repair passes within
    0.06 mm)."""
    if not earlier:
        return []
    rings = len(reconstruction.vertices) // len(reconstruction.ring_parameters)
    ring = 1.0 / max(rings - 1, 1)
    groups = _defects(reconstruction, report.excursion, report.limit + report.allowance)
    return [group for group in groups
            if any(group.region == defect.region and group.span_from <= defect.span_to + ring
                   and group.span_to >= defect.span_from - ring for defect in earlier)]


@dataclass(frozen=True)
class EdgeSampling:
    """Points on an edge in one span band: ``radius`` (m) of its circle, ``per_mm`` points per
    millimetre across its half circle, ``needed`` per millimetre for
    :data:`~steamtwin.geometry.scanner.EDGE_SAMPLES` on the half circle π·r (its square is
    the area density, points per mm², that the scan needs there); ``circle_radius`` (m) the
    circle fits' alone (:func:`edge_radius`; ≥ ``radius``)."""

    edge: str
    span_from: float
    span_to: float
    radius: float
    per_mm: float
    needed: float
    circle_radius: float = math.nan

    def describe(self) -> str:
        """e.g. "trailing edge at 60–80 % span: 2.1 points per mm across its 0.47 mm half
        circle, needs ≥ 9.6 (92 points per mm², 21 × this scan's density)"."""
        return (f"{self.edge.replace('_', ' ')} at {self.span_from * 100:.0f}–"
                f"{self.span_to * 100:.0f} % span: {self.per_mm:.1f} points per mm across its "
                f"{math.pi * self.radius * 1e3:.2f} mm half circle, needs ≥ {self.needed:.1f} "
                f"({self.needed ** 2:.0f} points per mm², "
                f"{(self.needed / self.per_mm) ** 2:.1f} × this scan's density)")


def fit_circle(xy: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre (2,) and radius of the algebraic least-squares circle through ``xy`` (n, 2; m):
    x² + y² = 2ax + 2by + c (Kåsa 1976, IEEE Trans. Instrum. Meas. 25:8), in coordinates
    centred on the points for conditioning."""
    mean = xy.mean(axis=0)
    p = xy - mean
    design = np.column_stack([2.0 * p, np.ones(len(p))])
    (a, b, c), *_ = np.linalg.lstsq(design, np.sum(p * p, axis=1), rcond=None)
    return mean + np.array([a, b]), float(math.sqrt(max(c + a * a + b * b, 0.0)))


def edge_radius(xy: np.ndarray, rounds: int = 4) -> float:
    """Radius (m) of an edge circle from its patch's points ``xy`` (n, 2; m) in one section:
    :func:`fit_circle`, refitted ``rounds`` times to the points within a quarter radius of
    the circle — the patch also holds points of the flanks, which leave the circle along its
    tangents and pull a single fit to a larger radius."""
    centre, radius = fit_circle(xy)
    for _ in range(rounds):
        keep = np.abs(np.linalg.norm(xy - centre, axis=1) - radius) < 0.25 * radius
        if keep.sum() < 5:
            break
        centre, radius = fit_circle(xy[keep])
    return radius


def _slabs(members: np.ndarray, lo: float, hi: float, height: float, points: np.ndarray
           ) -> list[np.ndarray]:
    """The xy (m) of ``points`` in each slab of ``height`` (m) from ``lo`` to ``hi`` in which
    ``members`` has at least 5 points."""
    result = []
    for start in np.arange(lo, hi, height):
        count = np.count_nonzero((members[:, 2] >= start) & (members[:, 2] < start + height))
        if count >= 5:
            result.append(points[(points[:, 2] >= start) & (points[:, 2] < start + height), :2])
    return result


def edge_sampling(points: np.ndarray, segmentation: Segmentation, edge: str,
                  bands: int = SPAN_BANDS, samples: float = EDGE_SAMPLES) -> list[EdgeSampling]:
    """Sampling of the ``edge`` ("leading_edge" or "trailing_edge") patch in ``bands`` span
    bands, and what ``samples`` points across its half circle need.

    The radius is the median over slabs three spacings high of the smaller of two estimates:
    the circle through the patch's points (:func:`edge_radius`, right where the arc holds
    points) and the circle tangent to the flanks at the thickness they extrapolate to at the
    tip (:func:`~steamtwin.geometry.edge_thickness.wedge_radius`, right where it holds none —
    a circle fit there takes the flanks' points and comes out 3–5 × too large). The points per
    millimetre are √ρ, ρ the band's area density of side points from their median
    nearest-neighbour distance h̃: for points spread uniformly at random over a surface,
    P(h > x) = exp(−πρx²), so ρ = ln 2 / (π h̃²) (Clark & Evans 1954, Ecology 35:445). The
    figure needed puts ``samples`` spacings 1/√ρ on the half circle π·r: √ρ ≥ samples / (π r).
    Bands with fewer than 12 edge points are skipped."""
    on = segmentation.labels == REGIONS.index(edge)
    side = np.isin(segmentation.labels, [REGIONS.index(name) for name in SIDE_REGIONS])
    z_all = points[side, 2]
    lo, hi = float(z_all.min()), float(z_all.max())
    spacing = segmentation.spacing
    slab = 3.0 * spacing
    reach = 1.2 * max(FLANK_TO * spacing, FLANK_TO_MIN)
    result = []
    for k in range(bands):
        a, b = lo + k * (hi - lo) / bands, lo + (k + 1) * (hi - lo) / bands
        in_band = (points[:, 2] >= a) & (points[:, 2] < b)
        members = points[on & in_band]
        if len(members) < 12:
            continue
        band_side = points[side & in_band]
        circles = [edge_radius(xy) for xy in _slabs(members, a, b, slab, members)]
        if not circles:
            continue
        radius = circle = float(np.median(circles))
        # the flanks from slabs twice as high (more points on each); trusted where most slabs
        # have two straight flanks: round a resolved nose their lines miss the tip
        wedges = [wedge_radius(near[np.linalg.norm(near - np.median(xy, axis=0), axis=1)
                                    <= reach], xy, spacing)
                  for xy, near in zip(_slabs(members, a, b, 2.0 * slab, members),
                                      _slabs(members, a, b, 2.0 * slab, band_side),
                                      strict=True)]
        if np.isfinite(wedges).sum() >= max(3.0, 0.5 * len(wedges)):
            radius = min(radius, float(np.nanmedian(wedges)))
        gap = float(np.median(cKDTree(band_side).query(band_side, k=2)[0][:, 1]))
        per_mm = math.sqrt(math.log(2.0) / (math.pi * gap * gap)) * 1e-3
        needed = samples / (math.pi * radius * 1e3)
        result.append(EdgeSampling(edge=edge, span_from=k / bands, span_to=(k + 1) / bands,
                                   radius=radius, per_mm=per_mm, needed=needed,
                                   circle_radius=circle))
    return result


#: A coverage gap that reaches within this share of the chord of its end lies at that edge,
#: whatever patch its points carry: on a thin, sparse edge (0.15 mm radius at 0.23 mm spacing,
#: issue 19's slender blade) the segmentation cannot resolve the edge's curvature, labels its
#: points suction or pressure side, and the gaps of a surface cut short there sit at 99–100 %
#: chord on a side patch.
EDGE_CHORD = 0.02


def at_edges(report: GuardReport) -> dict[str, list[Defect | CoverageGap]]:
    """The defects and gaps of ``report`` at each edge ("leading_edge", "trailing_edge"):
    those on its patch, and the gaps within :data:`EDGE_CHORD` of its end of the chord."""
    found: dict[str, list[Defect | CoverageGap]] = {"leading_edge": [], "trailing_edge": []}
    for finding in [*report.defects, *report.gaps]:
        if finding.region in found:
            found[finding.region].append(finding)
        elif isinstance(finding, CoverageGap) and finding.chord_to >= 1.0 - EDGE_CHORD:
            found["trailing_edge"].append(finding)
        elif isinstance(finding, CoverageGap) and finding.chord_from <= EDGE_CHORD:
            found["leading_edge"].append(finding)
    return found


def sparse_edges(points: np.ndarray, segmentation: Segmentation) -> str:
    """A note for a refusal without guard findings (a side that folds): every edge band sampled
    below what :data:`~steamtwin.geometry.scanner.EDGE_SAMPLES` needs (:func:`edge_sampling`:
    a thin edge's radius from its flanks, right to ~10 % below the point spacing; a round
    nose below it is still read up to 2 × large, so its figure is a lower bound), or "" when
    none is."""
    bands = [band.describe() for edge in ("leading_edge", "trailing_edge")
             for band in edge_sampling(points, segmentation, edge) if band.per_mm < band.needed]
    return "; too few points on the edge: " + "; ".join(bands) if bands else ""


def refusal_message(report: GuardReport, points: np.ndarray, segmentation: Segmentation) -> str:
    """The error of a surface that stays beyond the limit after the repairs: the defects and,
    for those at an edge band sampled below what it needs (:func:`at_edges`), the density
    needed there."""
    found = [d.describe() for d in report.defects[:3]] + [g.describe() for g in report.gaps[:3]]
    lines = [f"the fitted surface stands off the cloud or misses part of it by more than "
             f"{report.limit * 1e3:.3g} mm (from σ = {report.noise * 1e3:.2g} mm of noise and a "
             f"{report.spacing * 1e3:.2g} mm point spacing): " + "; ".join(found)]
    sparse = []
    for edge, hit in at_edges(report).items():
        for band in edge_sampling(points, segmentation, edge):
            overlaps = any(d.span_from <= band.span_to and d.span_to >= band.span_from
                           for d in hit)
            if overlaps and band.per_mm < band.needed:
                sparse.append(band.describe())
    if sparse:
        lines.append("too few points on the edge: " + "; ".join(sparse))
    return "; ".join(lines) + " — not written as a watertight surface"
