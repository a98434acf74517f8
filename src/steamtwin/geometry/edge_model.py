"""A model of thin, sparsely sampled blade edges: circles tangent to both flanks.

A leading or trailing edge whose half circle π·r holds only a few points of the cloud (a
0.2 mm trailing edge at 0.14 mm spacing: about four, each σ = 0.017 mm off) is not resolved by
the side's B-spline: its few knot spans there either smooth the edge off (cut short) or
overshoot it (a "beak" beyond the edge, a fold). The standard description of a blade profile
closes each end with a circle tangent to the pressure and suction sides (Dixon & Hall, "Fluid
Mechanics and Thermodynamics of Turbomachinery", 7th ed. 2014, §3.3 on profile geometry;
Pritchard 1985, ASME 85-GT-219, the edge circles of the eleven-parameter profile, as in
:mod:`~steamtwin.geometry.pritchard`). This module fits that model
(:mod:`~steamtwin.geometry.edge_circle`, one section) slab by slab along the span as the start
of one smooth model of the whole edge along the span (:mod:`~steamtwin.geometry.edge_span`)
and hands the side's fit that model's points instead of the sparse edge's own:

- in slabs along the span, the flanks next to the edge (side points between ``a`` and ``L``
  of arc length from the edge, on either side of it) are each a plane through their points
  (total least squares, Pearson 1901: the smallest principal axis), trimmed of stray points
  and refitted; within the slab's plane z = const each is a line n·p = d(z), n pointing into
  the blade — d varies linearly with z, so a twisting or leaning edge keeps its tangency over
  the slab's height;
- the circles inside the wedge tangent to both lines form a one-parameter family in the radius
  r: the centre solves n₁·c = d₁ + r, n₂·c = d₂ + r. The radius is the geometric fit of the
  slab's points to the arc and the lines beyond it (Chernov & Lesort 2005, "Least squares
  fitting of circles", J. Math. Imaging Vision 23:239; soft-L1 loss; a grid, then Brent's
  bounded method), then lines and radius are refitted together: in a thin wedge the tip moves
  along the bisector by δd / sin(β/2) for an error δd of a flank line
  (:mod:`~steamtwin.geometry.edge_circle`);
- a slab whose radius is off its neighbours' median by more than :data:`SPAN_SPREAD`, or
  whose arc points scatter or lean off the circle beyond the flanks' noise, gives no start;
  the slabs' circles start the span model — centre, radius and the lines' angles as smooth
  functions of z, fitted to the points of all slabs at once (:mod:`~steamtwin.geometry.
  edge_span`) —, which also stands in for the slabs without a circle of their own (holes,
  stray points, flanks cut short next to a cap) and, once fitted, takes the flank points
  again by arc length along itself rather than the cloud's order, and is refitted to them;
- the model is sampled on the arc and the flanks next to it (:data:`CUT_SPACINGS` spacings
  beyond the tangent points), denser than the cloud, and replaces the cloud's points there;
  every model point and every other point of the slab gets its side parameter ``s`` from its
  arc length along the model, scaled and shifted to the cloud's own ``s`` on the flanks (a
  straight-line fit per slab, median over ±:data:`ORDER_SLABS` slabs, interpolated in z
  across slabs without enough flank points): the cloud's order is
  0.3–0.8 mm off within a millimetre of a thin edge, and neighbouring slabs that disagree make
  the side's spline fold; a pooled edge's tip is put at one ``s`` along the whole span, the
  difference taken up by the faces' scale (:func:`_pinned`: the spline's breakpoints are
  the same at every height);
- where fewer than :data:`OWN_SHARE` of the slabs have a circle of their own (an edge below
  about one point spacing across), every slab's start comes from its flanks found by geometry
  and the cloud's order is read per face beyond the faces' mixing
  (:mod:`~steamtwin.geometry.edge_pooled`).

An edge is modelled where one of its slabs has a circle (or a geometric start) of its own, in
the slabs where the span model's half circle holds fewer than :data:`MODEL_SAMPLES` points of
the cloud's spacing, and only if in every one of those slabs the arc's points lie on median
within :data:`MODEL_BIAS` of the span model (a model that is not is first refitted over a
window of a few radii, for a nose whose flanks curve: :mod:`~steamtwin.geometry.edge_nose`);
otherwise the whole edge is left to the cloud's own points and order (a model continued from
a few slabs over most of the span can stand far off the points: the reference unit's hp8,
:func:`_model_off_points`; one edge's slabs modelled in part mix two orders, which cuts the
edge, :data:`ORDER_SLABS`). :attr:`EdgeModel.slabs` records
each slab's own fit, or why it has none.

Kept as one module because the slab fits, the span model's start, its check against the
points and the cloud's order against it all read the same slab records and flank windows in
one pass over an edge; the pooled start for edges too sparse per slab is apart
(:mod:`~steamtwin.geometry.edge_pooled`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from steamtwin.geometry.edge_circle import (
    MIN_ARC_POINTS,
    TRIM_FLOOR,
    arc_length_at,
    edge_distance,
    edge_distance_at,
    fit_tangent_circle,
    flank_plane,
    refine_edge,
    tangent_centre,
    tip_and_half_angle,
)
from steamtwin.geometry.edge_nose import nose_refit
from steamtwin.geometry.edge_pooled import (
    ORDER_BAND,
    ORDER_DISTANCE,
    face_order,
    geometric_start,
    order_arc,
    pooled_members,
)
from steamtwin.geometry.edge_span import (
    SpanEdgeModel,
    fit_span_edge,
    initial_coefficients,
    sample_span_edge,
    span_knots,
)
from steamtwin.geometry.volume_mesh import REGIONS

#: An edge is modelled where its half circle π·r holds fewer than this many point spacings.
MODEL_SAMPLES = 8.0
#: Slab height along the span in point spacings (at least :data:`MIN_SLAB` m).
SLAB_SPACINGS = 6.0
MIN_SLAB = 1.5e-3
#: Flank window length beyond its start, in point spacings (at least :data:`MIN_FLANK` m).
FLANK_SPACINGS = 16.0
MIN_FLANK = 2.0e-3
#: Fewest points of a flank for a slab to be modelled.
MIN_FLANK_POINTS = 12
#: Wedge angles (rad) within which the tangent-circle construction is well conditioned.
WEDGE_RANGE = (math.radians(2.0), math.radians(120.0))
#: Largest relative difference of a slab's radius from the median of its neighbours'.
SPAN_SPREAD = 0.1
#: The model reaches this many point spacings beyond its tangent points along the flanks.
CUT_SPACINGS = 2.0
#: Largest RMS of the arc's points about the circle, as a multiple of the flanks' RMS.
ARC_RMS = 1.5
#: Largest median distance (m) of a slab's arc points from the span model for the model to
#: stand in for them: the circle fit's trim floor, above the scan noise (σ 0.017 mm). Measured
#: (2026-11-27, worst slab of each modelled edge): the foreign-blade family's clouds that pass
#: (40k, 80k, blade frame) 0.009–0.032 mm; hp8 (192k) 0.27 mm, hp9 0.011 mm.
MODEL_BIAS = TRIM_FLOOR
#: Model points along the arc and along the span, per point spacing.
ARC_DENSITY = 2.0
RING_DENSITY = 1.0


@dataclass(frozen=True)
class EdgeSlab:
    """One slab's fit: ``edge``, ``z`` (m, centre), ``radius`` (m, NaN unless fitted),
    ``wedge`` angle (rad), RMS of the arc points about the circle (m), ``used`` — whether its
    model replaced the points —, ``reason`` when not, and the circle's ``centre`` (x, y; m)
    at ``z`` (NaN unless fitted)."""

    edge: str
    z: float
    radius: float
    wedge: float
    rms: float
    used: bool
    reason: str = ""
    centre: tuple[float, float] = (math.nan, math.nan)


@dataclass(frozen=True)
class EdgeModel:
    """Model points of the sparse edges: ``points`` (k, 3; m) and their side parameter ``s``
    (k,), ``replaced`` the cloud points (mask over the cloud) that they stand in for,
    ``parameters`` the side parameter from the model of every cloud point of a modelled slab
    (NaN elsewhere: keep their own; for the replaced points the start of their projection onto
    the fitted side, which from their own ``s`` — 0.3–0.8 mm of arc off next to a thin edge —
    can land on the other face), the per-slab records ``slabs`` and the model of
    each modelled edge along the span, ``spans`` (edge name → :class:`SpanEdgeModel`)."""

    points: np.ndarray
    s: np.ndarray
    replaced: np.ndarray
    parameters: np.ndarray
    slabs: tuple[EdgeSlab, ...]
    spans: dict[str, SpanEdgeModel] = field(default_factory=dict)

    def fit_data(self, points: np.ndarray, s: np.ndarray, side: np.ndarray) -> tuple:
        """For the side's fit: the cloud points kept (mask), every point's ``s`` with the
        model's where it gave one, and (s, z, xy) of the kept points then the model points."""
        kept = side & ~self.replaced
        s = np.where(np.isnan(self.parameters), s, self.parameters)
        return kept, s, (np.concatenate([s[kept], self.s]),
                         np.concatenate([points[kept, 2], self.points[:, 2]]),
                         np.vstack([points[kept, :2], self.points[:, :2]]))

    @classmethod
    def none(cls, count: int) -> EdgeModel:
        """No model: the ``count`` cloud points keep their own."""
        return cls(np.empty((0, 3)), np.empty(0), np.zeros(count, dtype=bool),
                   np.full(count, np.nan), ())


def _circular(values: np.ndarray) -> np.ndarray:
    """Values in (−0.5, 0.5] modulo 1."""
    return np.mod(values + 0.5, 1.0) - 0.5


def model_sparse_edges(points: np.ndarray, s: np.ndarray, mask: np.ndarray, labels: np.ndarray,
                       perimeter: np.ndarray, spacing: float, noise: float = 0.03e-3
                       ) -> EdgeModel:
    """Model points for the sparse leading and trailing edges of a blade side.

    ``points`` (n, 3; m) in the blade frame; ``s`` the side parameter (arc-length fraction
    anticlockwise from the rear end, NaN off the side) of the points under ``mask``;
    ``labels`` the segmentation's REGIONS indices; ``perimeter`` each side point's section
    perimeter (m); ``spacing`` the cloud's point spacing (m); ``noise`` the largest RMS (m)
    of the flank points about their plane for the flank to count as straight.
    """
    pieces, slabs, spans = [], [], {}
    replaced = np.zeros(len(points), dtype=bool)
    parameters = np.full(len(points), np.nan)
    for edge in ("trailing_edge", "leading_edge"):
        on = mask & (labels == REGIONS.index(edge))
        if on.sum() < MIN_ARC_POINTS:
            continue
        base = 0.0 if edge == "trailing_edge" else 0.5
        centre_s = float(np.mod(base + np.median(_circular(s[on] - base)), 1.0))
        result = _model_edge(points, s, mask, perimeter, spacing, noise, edge, centre_s)
        pieces += result[0]
        slabs += result[1]
        replaced |= result[2]
        parameters = np.where(np.isnan(result[3]), parameters, result[3])
        if result[4] is not None:
            spans[edge] = result[4]
    model_points = np.vstack([p for p, _ in pieces]) if pieces else np.empty((0, 3))
    model_s = np.concatenate([q for _, q in pieces]) if pieces else np.empty(0)
    return EdgeModel(points=model_points, s=model_s, replaced=replaced, parameters=parameters,
                     slabs=tuple(slabs), spans=spans)


def _left_to_cloud(count: int, fits: list, reason: str | None = None) -> tuple:
    """:func:`_model_edge`'s result for an edge left to the cloud's ``count`` points: no model
    pieces, the slab records (each marked unused for ``reason`` when given), nothing replaced,
    no parameters, no span model."""
    slabs = [slab if reason is None else replace(slab, used=False, reason=reason)
             for slab, _, _ in fits]
    return [], slabs, np.zeros(count, bool), np.full(count, np.nan), None


def _model_edge(points: np.ndarray, s: np.ndarray, mask: np.ndarray, perimeter: np.ndarray,
                spacing: float, noise: float, edge: str, centre_s: float) -> tuple:
    """Slabs of one edge: (model point pieces, slab records, replaced mask, parameters, span
    model or None). The slabs next to a cap are modelled like the others (the span model
    holds there, :data:`ORDER_SLABS`)."""
    arc = np.full(len(points), np.inf)
    arc[mask] = _circular(s[mask] - centre_s) * perimeter[mask]  # signed arc length (m)
    # the half circle of a modelled edge is shorter than MODEL_SAMPLES spacings: its tangent
    # points lie within π r / 2 < MODEL_SAMPLES·spacing / 2 of the edge's middle
    start = 0.5 * MODEL_SAMPLES * spacing + 2.0 * spacing
    length = max(FLANK_SPACINGS * spacing, MIN_FLANK)
    reach = start + length
    near = np.flatnonzero(np.abs(arc) <= reach)
    z_near = points[near, 2]
    height = max(SLAB_SPACINGS * spacing, MIN_SLAB)
    lo, hi = float(z_near.min()), float(z_near.max())
    count = max(1, round((hi - lo) / height))
    edges_z = np.linspace(lo, hi, count + 1)
    fits = []
    for k in range(count):
        members = near[(z_near >= edges_z[k]) & (z_near <= edges_z[k + 1])]
        record, geometry = _fit_slab(points, arc, members, spacing, noise,
                                     0.5 * (edges_z[k] + edges_z[k + 1]), start)
        fits.append((EdgeSlab(edge=edge, z=0.5 * (edges_z[k] + edges_z[k + 1]), **record),
                     geometry, members))
    # along the span the edge changes slowly: a slab whose radius is off the median of its
    # neighbours' by more than SPAN_SPREAD is a bad fit (in a thin wedge the centre moves
    # along the bisector by δr / sin(β/2), eight times the radius error at 14°)
    radii = np.array([slab.radius if slab.used else np.nan for slab, _, _ in fits])
    for k, (slab, _, members) in enumerate(fits):
        around = radii[max(0, k - 2): k + 3]
        typical = float(np.nanmedian(around)) if np.isfinite(around).sum() >= 3 else math.nan
        if slab.used and not abs(slab.radius - typical) <= SPAN_SPREAD * typical:
            fits[k] = (replace(slab, used=False, reason="radius off its neighbours'"), None,
                       members)
    own = [k for k, (slab, _, _) in enumerate(fits) if slab.used]
    window, r_max = (start, reach), MODEL_SAMPLES * spacing / math.pi
    z_own = np.array([fits[k][0].z for k in own])
    start = np.array([_section_values(fits[k][1]) for k in own]).reshape(-1, 5)
    pooled = len(own) < OWN_SHARE * len(fits)
    if pooled:  # too sparse per slab: flanks by geometry
        z_own, start = _with_geometric_start(points, arc, edges_z, noise, window, r_max,
                                             z_own, start)
        across = math.pi * float(np.median(start[:, 2])) / spacing if len(z_own) else 0.0
        if across >= POOLED_ACROSS:  # resolved, yet no slab's circle: not a sparse edge
            reason = (f"no circle of its own in {len(fits) - len(own)} of {len(fits)} slabs, "
                      f"though {across:.1f} spacings across: left to the cloud")
            return _left_to_cloud(len(points), fits, reason)
    if not len(z_own):
        return _left_to_cloud(len(points), fits)
    # one model along the span (edge_span), started from the slabs' own circles, fitted to
    # the points of every slab of the edge: the slabs without a circle of their own (a hole,
    # stray points, the flanks cut short next to a cap) are filled by the model
    z_range = (float(edges_z[0]), float(edges_z[-1]))
    knots = span_knots(z_range)
    start[:, 3:] = np.unwrap(start[:, 3:], axis=0)
    model, _ = fit_span_edge(points[near], SpanEdgeModel(
        knots, initial_coefficients(knots, z_own, start), z_range), (0.02 * r_max, 2.0 * r_max))
    # the flank window again, by arc length along this model rather than the cloud's order,
    # and the model refitted to it (correspondences reselected from the current fit, as in
    # the iterative closest point method, Besl & McKay 1992, IEEE PAMI 14:239): next to a cap
    # the cloud's order can compress the arc length by half, and the straight flank lines
    # then lean to a curved flank's far points (high-camber-turbine 40k seed 0, random pose,
    # 2026-11-27: window 6.6–6.8 mm of true arc instead of ~3.9 on the suction side over the
    # last 8 mm, radius 0.30 → 0.37 mm, model 0.18 mm off at the tip; refitted 0.036 mm).
    # A window far smaller than the first (a model far off) keeps the first fit.
    window = _window_by_model(points, arc, model, reach, z_range)
    if 2 * len(window) >= len(near):
        model, _ = fit_span_edge(points[window], model, (0.02 * r_max, 2.0 * r_max))
    centres, radii, _ = model.at(np.array([slab.z for slab, _, _ in fits]))
    off = _model_off_points(points, fits, model, radii, spacing)
    nose = off is not None  # flanks that curve within the window: a nose (edge_nose)
    if nose:
        model = nose_refit(points, _window_by_model(points, arc, model, 2.0 * reach, z_range),
                           model, spacing, (0.02 * r_max, 2.0 * r_max))
        centres, radii, _ = model.at(np.array([slab.z for slab, _, _ in fits]))
        off = _model_off_points(points, fits, model, radii, spacing)
    if off is not None:  # the model stands off the cloud: the edge is left to the cloud
        reason = (f"span model off the arc's points at z = {off[0] * 1e3:.1f} mm (median "
                  f"{off[1] * 1e3:+.3f} mm)")
        return _left_to_cloud(len(points), fits, reason)
    # the cloud's order along the edge, scale and shift of its arc length against the model's
    # (:func:`_order_against_model`), smoothed along the span: each slab's own is noisy by a
    # few tenths of a millimetre, and the side's spline, smooth over several slabs, folds
    # where neighbouring slabs disagree
    if pooled:  # the cloud's order mixes the faces: the model's members, an order per face
        fits = [(slab, geometry, members) for (slab, geometry, _), members in zip(
            fits, pooled_members(points, arc, model, reach, edges_z), strict=True)]
        order = np.array([face_order(points, arc, members, model, reach)
                          for _, _, members in fits])
    else:
        order = np.array([_order_against_model(points, arc, members, model, spacing,
                                               ORDER_DISTANCE if nose else TRIM_FLOOR)
                          for _, _, members in fits])
    smooth = np.full((len(fits), 3), np.nan)
    for k in range(len(fits)):
        around = order[max(0, k - ORDER_SLABS): k + ORDER_SLABS + 1]
        if np.isfinite(around[:, 0]).any():
            smooth[k] = np.nanmedian(around, axis=0)
    known = np.flatnonzero(np.isfinite(smooth[:, 0]))  # slabs between: interpolated in z
    # a pooled edge's tip at one side parameter along the span (:func:`_pinned`)
    lengths = np.array([_slab_length(perimeter, members) for _, _, members in fits])
    tip = float(np.median(smooth[known, 0] / lengths[known])) if len(known) else 0.0
    pieces, slabs = [], []
    replaced = np.zeros(len(points), dtype=bool)
    parameters = np.full(len(points), np.nan)
    for k, (slab, _, members) in enumerate(fits):
        fitted = {"radius": float(radii[k]), "centre": (float(centres[k, 0]),
                                                        float(centres[k, 1]))}
        if math.pi * radii[k] >= MODEL_SAMPLES * spacing:
            slab = replace(slab, **fitted, used=False, reason="edge resolved by the cloud")
        elif len(known):
            slab = replace(slab, **fitted, used=True, reason="" if slab.used else
                           f"filled by the span model ({slab.reason})")
            order_k = np.array([np.interp(k, known, smooth[known, i]) for i in range(3)])
            if pooled:
                order_k = _pinned(order_k, tip * lengths[k], ORDER_BAND[1] * reach)
            applied = _apply_model(points, lengths[k], members, model, spacing, centre_s,
                                   (edges_z[k], edges_z[k + 1]), order_k)
            pieces.append(applied[0])
            replaced[applied[1]] = True
            parameters[applied[2]] = applied[3]
        slabs.append(slab)
    return pieces, slabs, replaced, parameters, model if pieces else None


#: Slabs either side over which the cloud's order against the model is smoothed (median):
#: ±15 mm at 1.5-mm slabs. The cloud's own order comes from nine slab mappings interpolated
#: along the span (reconstruct.initial_parameters), so its true change is slow, while each
#: slab's scale and shift against the model scatter by 0.5 mm of arc; where neighbouring
#: slabs disagree the side's spline, smooth over 15-mm knot spans in z, cuts the edge short.
#: Measured (bench_foreign_blades, 80k, random pose, 2026-11-27): lean-sweep seed 1 with ±3
#: slabs, a 0.77-mm jump of the shift between two slabs at 60 % span cut the trailing edge
#: 0.23 mm; with ±10 the whole blade is within 0.068 mm of the exact surface. The slabs next
#: to a cap were once left to the cloud's own points and order (3 slabs each end); that
#: mixture of orders cut the edge 0.16–0.20 mm at the rims (naca-twisted seeds 0 and 1),
#: while the span model itself holds to the cap planes (tests/geometry/test_edge_span.py):
#: modelled to the caps, naca-twisted comes within 0.037 / 0.044 mm of the exact surface.
ORDER_SLABS = 10


#: Below this share of slabs with a circle of their own the edge is started from every
#: slab's flanks found by geometry (:mod:`~steamtwin.geometry.edge_pooled`) and fitted pooled
#: along the span: slender 80k's trailing edge (0.93 spacings across) had none of 167 (random
#: pose, 2026-11-27). lean-sweep 80k seed 0's trailing edge has 34 of 80, good ones (0.25 →
#: 0.2 mm as drawn): taken pooled at a share of 0.5 it failed, 0.128 mm (passes 0.079 without).
OWN_SHARE = 0.1
#: The pooled fit is for an edge too sparse for a slab's own circle: where its geometric
#: start's median radius spans this many point spacings or more on its half circle (π·r / h),
#: a slab holds enough arc points for its own circle, and none fitting means flanks that are
#: not lines (a round nose), which pooling does not mend — the edge is left to the cloud. The
#: reference unit's hp5 leading edge (0 of 67 own circles, start radii 0.53–0.58 mm at a
#: 0.23-mm spacing: 7.5 across) was taken pooled at the model's radius bound and refused
#: (3.9 mm off); slender 80k's trailing edge, the case the pooled fit is for, is 0.9–1.0 across
#: (2026-11-27). 3: the sampling theorem's 1 (:mod:`.edge_density`) three times over.
POOLED_ACROSS = 3.0


def _with_geometric_start(points: np.ndarray, arc: np.ndarray, edges_z: np.ndarray,
                          noise: float, window: tuple[float, float], r_max: float,
                          z_own: np.ndarray, own: np.ndarray) -> tuple:
    """The own circles' start values (heights ``z_own``, values ``own``) with the geometric
    starts of the slabs between (:func:`~steamtwin.geometry.edge_pooled.geometric_start`),
    by height."""
    z_geometric, geometric = geometric_start(points, arc, edges_z, noise, window,
                                             (0.02 * r_max, 2.0 * r_max))
    height = edges_z[1] - edges_z[0]
    if len(z_own) and len(z_geometric):
        apart = np.abs(z_geometric[:, None] - z_own[None, :]).min(axis=1) > 0.5 * height
        z_geometric, geometric = z_geometric[apart], geometric[apart]
        # the geometric angles on the own circles' branch (both are unwrapped along z)
        shift = 2.0 * math.pi * np.round((np.median(own[:, 3:], axis=0)
                                          - np.median(geometric[:, 3:], axis=0))
                                         / (2.0 * math.pi)) if len(geometric) else 0.0
        geometric[:, 3:] += shift
    z = np.concatenate([z_own, z_geometric])
    order = np.argsort(z)
    return z[order], np.vstack([own, geometric])[order]


def _window_by_model(points: np.ndarray, arc: np.ndarray, model: SpanEdgeModel,
                     reach: float, z_range: tuple[float, float]) -> np.ndarray:
    """Indices of the side points within ``reach`` (m) of arc length along ``model`` from its
    tip, taken from those within twice that of the cloud's own arc length ``arc`` (m)."""
    candidates = np.flatnonzero((np.abs(arc) <= 2.0 * reach) & (points[:, 2] >= z_range[0])
                                & (points[:, 2] <= z_range[1]))
    section = model.at(points[candidates, 2])
    return candidates[np.abs(arc_length_at(points[candidates, :2], *section)) <= reach]


def _model_off_points(points: np.ndarray, fits: list, model: SpanEdgeModel,
                      radii: np.ndarray, spacing: float) -> tuple[float, float] | None:
    """The first slab the model would stand in for (π·r below :data:`MODEL_SAMPLES` spacings)
    whose arc points lie off the model, as (z, median signed distance; m), or None.

    The span model is started from the slabs with a circle of their own and continued by its
    P-splines over those without; where those are many and far from the others, the robust fit can
    fail to bring the model back to the points within its evaluations (scipy ``least_squares``
    before 2026-11-28 on hp8 of the reference
    unit, 192k points, 2026-11-27: 5 of 81 slabs with a circle of their own, all at 50–58 %
    span, a 0.6-mm trailing edge between flanks 4° apart; the model 0.5–0.7 mm off the exact
    surface over the last 10 % of span at either end, the STL refused 1.91 mm off). A model is
    only as good as its fit to the points it replaces: on average over its half circle the
    arc's points lie within the noise of it, :data:`MODEL_BIAS` (the median: robust to stray
    points)."""
    for k, (slab, _, members) in enumerate(fits):
        if math.pi * radii[k] >= MODEL_SAMPLES * spacing or len(members) == 0:
            continue
        distance, sector = edge_distance_at(points[members, :2], *model.at(points[members, 2]))[:2]
        if sector.sum() >= MIN_ARC_POINTS and not abs(np.median(distance[sector])) <= MODEL_BIAS:
            return slab.z, float(np.median(distance[sector]))
    return None


def _section_values(geometry: tuple) -> list[float]:
    """A slab's circle at its middle as the span model's values: centre x, y, radius and the
    angles of the two lines' inward normals."""
    normals, d0, _, _, radius = geometry
    centre = tangent_centre(normals, d0[None, :], radius)[0]
    return [float(centre[0]), float(centre[1]), radius,
            *np.arctan2(normals[:, 1], normals[:, 0]).tolist()]


def _fit_slab(points: np.ndarray, arc: np.ndarray, members: np.ndarray, spacing: float,
              noise: float, z_mid: float, start: float) -> tuple:
    """Fit one slab: (EdgeSlab fields, geometry (normals, d0, d1, z_mid, radius) or None)."""
    failed = {"radius": math.nan, "wedge": math.nan, "rms": math.nan, "used": False}
    arc_m = arc[members]
    flanks = [members[arc_m <= -start], members[arc_m >= start]]
    if min(len(f) for f in flanks) < MIN_FLANK_POINTS:
        return {**failed, "reason": "too few points"}, None
    fits = [flank_plane(points[f] - [0.0, 0.0, z_mid]) for f in flanks]
    normals = np.array([f[0] for f in fits])
    d0 = np.array([f[1] for f in fits])
    d1 = np.array([f[2] for f in fits])
    for i in range(2):  # each normal into the blade: towards the other flank's points
        if normals[i] @ points[flanks[1 - i], :2].mean(axis=0) < d0[i]:
            normals[i], d0[i], d1[i] = -normals[i], -d0[i], -d1[i]

    def line_offsets(z: np.ndarray) -> np.ndarray:
        return d0[None, :] + (z - z_mid)[:, None] * d1[None, :]

    flank_rms = max(float(np.sqrt(np.mean(
        (np.einsum("ij,j->i", points[f, :2], normals[i])
         - line_offsets(points[f, 2])[:, i])[fits[i][3]] ** 2))) for i, f in enumerate(flanks))
    wedge = math.pi - math.acos(float(np.clip(normals[0] @ normals[1], -1.0, 1.0)))
    record = {**failed, "wedge": wedge}
    if not WEDGE_RANGE[0] <= wedge <= WEDGE_RANGE[1]:
        return {**record, "reason": "wedge angle out of range"}, None
    if flank_rms > noise:
        return {**record, "reason": f"flanks not straight (RMS {flank_rms * 1e3:.3f} mm)"}, None
    r_max = MODEL_SAMPLES * spacing / math.pi
    bounds = (0.02 * r_max, 2.0 * r_max)
    # all the slab's points: those on the flanks beyond the tangent points are at the lines'
    # distance whatever the radius; the order s is unreliable right at a sparse edge
    xy, offsets = points[members, :2], line_offsets(points[members, 2])
    radius, keep = fit_tangent_circle(xy, normals, offsets, bounds)
    normals, d0, d1, radius = refine_edge(xy, points[members, 2] - z_mid, normals, d0, d1,
                                          radius, keep, bounds)
    offsets = line_offsets(points[members, 2])
    residual, sector = edge_distance(xy, normals, offsets, radius)
    fitted_arc = sector & keep
    rms = float(np.sqrt(np.mean(residual[fitted_arc] ** 2))) if fitted_arc.any() else math.nan
    centre = tangent_centre(normals, line_offsets(np.array([z_mid])), radius)[0]
    record = {**record, "radius": radius, "rms": rms, "centre": (float(centre[0]),
                                                                 float(centre[1]))}
    if not bounds[0] * 1.01 < radius < bounds[1] * 0.99:
        return {**record, "reason": "radius at a bound of its search"}, None
    if math.pi * radius >= MODEL_SAMPLES * spacing:
        return {**record, "reason": "edge resolved by the cloud"}, None
    # the arc's points about the circle as the flanks' about their lines (the noise), and on
    # average on it: a circle off by a fraction of the noise along a thin wedge's bisector
    # is off by several times that at the tip
    bias = float(np.mean(residual[sector & keep])) if sector.any() else math.nan
    if ((sector & keep).sum() < MIN_ARC_POINTS or not rms <= ARC_RMS * flank_rms
            or not abs(bias) <= flank_rms):
        return {**record, "reason": "arc points do not follow the circle"}, None
    return {**record, "used": True, "reason": ""}, (normals, d0, d1, z_mid, radius)


def _model_cut(model: SpanEdgeModel, z: np.ndarray, spacing: float) -> tuple:
    """The model at heights ``z`` (centre, radius, normals) and the arc length (m) from its
    tip at which it ends on either flank, :data:`CUT_SPACINGS` beyond the tangent points."""
    centre, radius, normals = model.at(z)
    return (centre, radius, normals), radius * tip_and_half_angle(normals)[1] + (
        CUT_SPACINGS * spacing)


def _order_against_model(points: np.ndarray, arc: np.ndarray, members: np.ndarray,
                         model: SpanEdgeModel, spacing: float, tolerance: float
                         ) -> tuple[float, float, float]:
    """Shift and scale (twice: on either face, as :func:`~steamtwin.geometry.edge_pooled.
    face_order`) of the cloud's arc length (from its s) against the model's arc length
    u on the flanks beyond the model (a straight-line fit: the slope is the local ratio of
    the parametrisation's length to the model's) of the points within ``tolerance`` (m) of
    the model (a nose's flanks curve off its lines: :data:`~steamtwin.geometry.edge_pooled.
    ORDER_DISTANCE`); NaN when too few flank points follow the model or the slope is off by
    more than a factor two."""
    if len(members) == 0:
        return math.nan, math.nan, math.nan
    section, cut = _model_cut(model, points[members, 2], spacing)
    xy = points[members, :2]
    u = arc_length_at(xy, *section)
    distance = edge_distance_at(xy, *section)[0]
    on_flank = (np.abs(u) > cut + spacing) & (np.abs(distance) < tolerance)
    if on_flank.sum() < 2 * MIN_FLANK_POINTS:
        return math.nan, math.nan, math.nan
    scale, shift = np.polyfit(u[on_flank], arc[members[on_flank]], 1)
    return (float(shift), float(scale), float(scale)) if 0.5 < scale < 2.0 else (
        math.nan, math.nan, math.nan)


def _slab_length(perimeter: np.ndarray, members: np.ndarray) -> float:
    """The section perimeter (m) of a slab's ``members``: their median, or the cloud's."""
    return float(np.median(perimeter[members])) if len(members) else float(
        np.median(perimeter[np.isfinite(perimeter)]))


def _pinned(order: np.ndarray, tip: float, outer: float) -> np.ndarray:
    """The order (c, b₀, b₁) of :func:`~steamtwin.geometry.edge_pooled.order_arc` with its
    tip moved to the cloud's arc length ``tip`` (m) and each face's slope changed so that the
    order still meets the former at u = ∓``outer`` (m), where the modelled points end.

    The side's spline has one set of breakpoints in ``s`` along the whole span, so an edge
    whose tip wanders in ``s`` by more than its knot spans round the edge (a third of the half
    circle, ~0.15 mm for a 0.15-mm edge) is cut where it leaves them, or folds where it jumps.
    A pooled edge's shift c of the cloud's order against the model is a fit to the points
    7.5–10 mm from the tip and scatters by millimetres: on slender 80k seed 0 the trailing
    edge's tip wandered over −1.4…+2.6 mm of arc, jumping 2.9 mm within 10 mm of span at 150
    mm — where the side folded (2026-11-28). Only pooled edges are pinned: pinning every
    modelled edge took lean-sweep 80k seed 3 (random pose) from a refusal to a watertight STL
    0.11 mm off at the tip (a fail). Pinned at its median, the difference goes into
    the faces' scale over the ±``outer`` of points the model orders (10 mm: a 0.25 change of a
    slope of 1, within the factor two the order's fit allows). A shift beyond half the smaller
    slope × ``outer`` is cut to that (the tip then stays off by the rest): the cloud's order beyond
    ``outer`` must not be reached before the tip (tried with the edge's s taken per 10-mm
    band, on slender 80k seed 1's leading edge, 5 mm of arc off its median over the top 12 mm
    of span: its pressure face's points were ordered back onto the suction face, leaving the
    spline without points over 22 mm of arc)."""
    c, b0, b1 = order
    limit = 0.5 * outer * min(b0, b1)
    shift = float(np.clip(tip - c, -limit, limit))
    return np.array([c + shift, b0 + shift / outer, b1 - shift / outer])


def _apply_model(points: np.ndarray, length: float, members: np.ndarray,
                 model: SpanEdgeModel, spacing: float, centre_s: float,
                 z_range: tuple[float, float], order: np.ndarray) -> tuple:
    """Model points of a slab and the parameters of its cloud points: ((model points, s),
    replaced indices, the slab's indices, their s). The cloud's order s is unreliable next to a
    sparse edge: every point of the slab gets the s of its arc length u along the model,
    through the (smoothed) ``order`` of :func:`_order_against_model` (shift, scale either
    side, :func:`~steamtwin.geometry.edge_pooled.order_arc`).
    Model points lie in rings every spacing / RING_DENSITY over the slab, ARC_DENSITY per
    spacing along the model, out to the cut on either flank."""
    section, cut = _model_cut(model, points[members, 2], spacing)
    xy = points[members, :2]
    u = arc_length_at(xy, *section)
    sector = edge_distance_at(xy, *section)[1]
    rings = max(1, math.ceil((z_range[1] - z_range[0]) * RING_DENSITY / spacing))
    z = z_range[0] + (np.arange(rings) + 0.5) * (z_range[1] - z_range[0]) / rings
    ring_cut = _model_cut(model, z, spacing)[1]
    fraction = np.linspace(-1.0, 1.0, max(5, math.ceil(2.0 * float(ring_cut.max())
                                                       * ARC_DENSITY / spacing) + 1))
    model_xyz, model_u = sample_span_edge(model, z, fraction, ring_cut)
    model_s = np.mod(centre_s + order_arc(order, model_u) / length, 1.0)
    replaced = sector | (np.abs(u) < cut)  # the model's points, and stray points beyond it
    members_s = np.mod(centre_s + order_arc(order, u) / length, 1.0)
    return (model_xyz, model_s), members[replaced], members, members_s
