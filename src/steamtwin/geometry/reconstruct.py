"""Surface reconstruction of a scanned blade: patches → B-spline surfaces → watertight STL.

Input: a fused, cleaned cloud in the blade frame (m; x axial, y tangential, z = radius; a fused
scan is brought there by :func:`~steamtwin.geometry.fidelity.align_to_nominal`, a cloud of a
blade without a nominal by :func:`~steamtwin.geometry.frame.estimate_blade_frame`). Steps:

1. :func:`~steamtwin.geometry.segmentation.segment_blade`: normals, curvature, region growing,
   labels root/tip/pressure_side/suction_side/leading_edge/trailing_edge.
2. Parameters of the side points: the turn fraction round the section from geodesic arc
   length (:func:`~steamtwin.geometry.sections.section_turn`), mapped to the arc-length
   fraction ``s`` counted anticlockwise from the rear end (:func:`initial_parameters`);
   monotone round any section, also where a strongly cambered face is no graph over the
   chord, and unchanged by the twist and taper of a stacked blade.
3. The side is one periodic cubic B-spline surface (:mod:`~steamtwin.geometry.bspline`) whose
   starting knots are dense on the leading- and trailing-edge patches (``edge_knot_spans`` per
   edge, no wider than a third of the edge circle's half-turn, :func:`edge_arcs`) and graded to
   ``side_knot_spacing`` along the sides, then refined adaptively — robust to the stray points
   and the thin spans of sparse clouds, stopping before the surface folds; a side that still
   folds or misses the cloud is refused (:func:`check_side_fit`); each cap is a least-squares
   plane (a degree-1 patch).
4. The side is sampled on a grid — chordwise spacing from the curvature (chord sag ``sag``,
   at most ``chordwise_spacing``), ``span_spacing`` along the span, the grid lines through the
   patch boundaries — triangulated as a closed tube between the rims where it meets the cap
   planes, and closed by ear-clipped caps; trimesh checks that it is watertight, consistently
   wound and of positive volume.

The patch of every triangle is kept in ``Reconstruction.regions``; :func:`~steamtwin.geometry.
mesh_io.write_stl` writes it into the STL, :mod:`.reconstruction_report` reports the result.

Kept as one module because the steps share one state — the side's parameters, its knots and the
guard's repair loop, which refits from step 3 — while each step's own work lives in its module
(segmentation, sections, bspline, edge_model, fit_guard, repair_budget).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from threadpoolctl import threadpool_limits

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.bspline import AdaptiveSurfaceFit, PeriodicSurface, clamped_knots
from steamtwin.geometry.edge_density import MIN_POINTS_ACROSS, check_edge_density
from steamtwin.geometry.edge_model import EdgeModel, model_sparse_edges
from steamtwin.geometry.fit_guard import (
    GuardReport,
    GuardSettings,
    guard_surface,
    refusal_message,
    remnants,
    sparse_edges,
)
from steamtwin.geometry.mesh_sections import check_closed
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import cap_triangles
from steamtwin.geometry.repair_budget import RepairBudget
from steamtwin.geometry.segmentation import (
    SIDE_REGIONS,
    CapPlane,
    Segmentation,
    SegmentationSettings,
    fit_cap_plane,
    segment_blade,
)
from steamtwin.geometry.volume_mesh import REGIONS

#: Sections where row metrics are compared: fractions of the span from the hub ("hub", "mid",
#: "tip"), 5 % inside the ends so that the cut stays clear of the cap rims.
METRIC_SECTIONS = (("hub", 0.05), ("mid", 0.5), ("tip", 0.95))
#: Points per group when measuring arc length along the sections (median of each group).
GROUP = 7
#: BLAS threads of a reconstruction. Its linear algebra is on short vectors (the norms and dot
#: products inside scipy's LSMR, ~0.6 ms a call), where more threads only wait for each other:
#: one edge-model call took 184 s of process CPU with OpenBLAS's default threads on a loaded
#: 2-core machine and 34 s with one (docs/benchmarks.md, "A sparse edge pooled along the
#: span"), and the guard's repair budget counts process CPU (:mod:`.repair_budget`).
BLAS_THREADS = 1


@dataclass(frozen=True)
class ReconstructionSettings:
    """Hyper-parameters of :func:`reconstruct_blade` (lengths in m).

    ``tolerance`` is the RMS fit residual aimed at by knot insertion; points farther than
    ``outlier_distance`` (and 5 robust standard deviations) from their surface are left out of
    the fits; ``max_breaks`` bounds the knots round the profile; ``side_knot_spacing`` and
    ``edge_knot_spans`` set the starting knots, ``spanwise_knot_spacing`` the knots along the
    span; ``chordwise_spacing``, ``sag`` and ``span_spacing`` control the triangulation;
    ``guard`` checks the surface against the cloud (None: not checked,
    :mod:`~steamtwin.geometry.fit_guard`); ``penalty_factor`` multiplies the fit's smoothing
    penalty (the guard's repairs raise it); ``model_edges``: sparse edges as tangent circles,
    projected points replaced (:mod:`~steamtwin.geometry.edge_model`; on by default: all 22
    rows of the reference unit within every limit, docs/benchmarks.md);
    ``min_edge_points_across``: an edge with fewer point spacings on its half circle is refused
    before the fits (:mod:`~steamtwin.geometry.edge_density`; None: not checked).
    """

    segmentation: SegmentationSettings = field(default_factory=SegmentationSettings)
    tolerance: float = 0.02e-3
    outlier_distance: float = 0.1e-3
    max_breaks: int = 2000
    side_knot_spacing: float = 6.0e-3
    edge_knot_spans: int = 3
    spanwise_knot_spacing: float = 15e-3
    chordwise_spacing: float = 0.5e-3
    sag: float = 1e-6
    span_spacing: float = 1e-3
    guard: GuardSettings | None = field(default_factory=GuardSettings)
    penalty_factor: float = 1.0
    model_edges: bool = True
    min_edge_points_across: float | None = MIN_POINTS_ACROSS


@dataclass(frozen=True)
class Reconstruction:
    """A reconstructed blade: a closed triangulation and what it was made from.

    ``vertices`` (m), ``triangles`` (outward), ``regions`` per triangle (index into REGIONS);
    ``points`` the input cloud (m) and ``segmentation`` its per-point results; ``residuals``
    the signed distance of every labelled point from its fitted patch (m, positive outside, in
    the section plane for the side; NaN for unassigned points) — the deviation map;
    ``inliers`` the points the fits kept; ``parameters`` the side points' ``s`` (NaN
    elsewhere); ``boundaries`` the ``s`` where the side patches meet; ``fit_history`` the
    refinement rounds of the side; ``ring_parameters`` the ``s`` of the vertices of every ring
    (the vertices are the rings of the side grid, root to tip; the caps reuse the end rings);
    ``guard`` the two-way check of the surface against the cloud (None when not checked).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    regions: np.ndarray
    points: np.ndarray
    segmentation: Segmentation
    surface: PeriodicSurface
    root: CapPlane
    tip: CapPlane
    residuals: np.ndarray
    inliers: np.ndarray
    parameters: np.ndarray
    boundaries: dict[str, float]
    fit_history: list[dict]
    ring_parameters: np.ndarray
    guard: GuardReport | None = None

    @property
    def volume(self) -> float:
        """Enclosed volume (m³)."""
        import trimesh  # deferred: heavy import (~1-2 s), only the mesh steps pay it

        return float(trimesh.Trimesh(self.vertices, self.triangles, process=False).volume)

    def summary(self) -> dict:
        """Counts and fit figures in report units (mm)."""
        labels = self.segmentation.labels
        fitted = ~np.isnan(self.residuals)
        side = np.isin(labels, [REGIONS.index(name) for name in SIDE_REGIONS])
        kept_side = side & self.inliers
        return {
            "points": len(labels),
            "patch_points": self.segmentation.counts(),
            "trimmed_by_fit": int(np.sum(fitted & ~self.inliers)),
            "side_fit_rms_mm": float(np.sqrt(np.mean(self.residuals[kept_side] ** 2))) * 1e3,
            "side_fit_max_mm": float(np.abs(self.residuals[kept_side]).max()) * 1e3,
            "root_cap_rms_mm": self.root.rms * 1e3,
            "tip_cap_rms_mm": self.tip.rms * 1e3,
            "breakpoints": len(self.surface.breaks),
            "fit_history": [{**h, "rms": h["rms"] * 1e3, "max": h["max"] * 1e3}
                            for h in self.fit_history],
            "triangles": len(self.triangles),
            "volume_cm3": self.volume * 1e6,
            **(self.guard.summary() if self.guard is not None else {}),
        }


def reconstruct_blade(points: np.ndarray, settings: ReconstructionSettings | None = None,
                      segmentation: Segmentation | None = None) -> Reconstruction:
    """Reconstruct a watertight blade from a cloud in the blade frame (m), with
    :data:`BLAS_THREADS` BLAS thread(s).

    Raises :class:`~steamtwin.geometry.blade_cloud.ReconstructionError` naming the problem
    (empty, too small or flat cloud; missing caps or edges; an edge too sparse to fit,
    :mod:`.edge_density`; a surface that does not close; a surface that stands off the cloud or
    misses part of it, :func:`guarded`).
    ``segmentation``: the cloud's, when already computed.
    """
    with threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        return _reconstruct(points, settings or ReconstructionSettings(), segmentation)


def _reconstruct(points: np.ndarray, settings: ReconstructionSettings,
                 segmentation: Segmentation | None) -> Reconstruction:
    """:func:`reconstruct_blade` within its BLAS limit."""
    budget = RepairBudget.start(settings.guard.cpu_budget if settings.guard else None)
    segmentation = segmentation or segment_blade(points, settings.segmentation)
    budget.mark()  # the refits repeat what follows
    points = np.asarray(points, dtype=np.float64)
    if settings.min_edge_points_across is not None:  # before the fits: 0.1–0.4 s at 40k–80k
        check_edge_density(points, segmentation, settings.min_edge_points_across)
    labels = segmentation.labels
    have = np.isin(labels, [REGIONS.index(name) for name in SIDE_REGIONS])
    s0, perimeter = initial_parameters(points, segmentation, have)
    boundaries = patch_boundaries(s0[have], labels[have])
    breaks = initial_breaks(boundaries, perimeter, settings,
                            edge_arcs(segmentation, labels, perimeter))
    root, tip = _refit_caps(points, labels, segmentation)
    z_lo, z_hi = _span_range(points[have], root, tip)
    interior = max(0, math.ceil((z_hi - z_lo) / settings.spanwise_knot_spacing) - 1)
    z_knots = clamped_knots(z_lo, z_hi, interior)
    fit = AdaptiveSurfaceFit(tolerance=settings.tolerance, max_breaks=settings.max_breaks,
                             outlier_distance=settings.outlier_distance,
                             penalty_factor=settings.penalty_factor)
    model = (model_sparse_edges(points, s0, have, labels, segmentation.perimeter,
                                segmentation.spacing) if settings.model_edges
             else EdgeModel.none(len(points)))
    kept, s0, fit_data = model.fit_data(points, s0, have)
    surface = fit.fit(*fit_data, breaks, z_knots).surface_
    check_side_fit(fit, lambda: sparse_edges(points, segmentation))
    parameters, residuals = np.full((2, len(points)), np.nan)
    inliers, own, count = np.zeros(len(points), bool), model.replaced, int(kept.sum())
    parameters[kept], residuals[kept] = fit.parameters_[:count], fit.residuals_[:count]
    inliers[kept] = fit.inliers_[:count]
    parameters[own] = surface.project(points[own, :2], points[own, 2], s0[own])  # the replaced
    residuals[own] = surface.residuals(points[own, :2], points[own, 2], parameters[own])
    inliers[own] = np.abs(residuals[own]) <= settings.outlier_distance
    boundaries = patch_boundaries(parameters[have], labels[have])
    for plane, name, outward in ((root, "root", -1.0), (tip, "tip", 1.0)):
        on = labels == REGIONS.index(name)
        residuals[on] = outward * (points[on, 2] - plane.height(points[on, :2]))
        inliers[on] = np.abs(residuals[on]) <= max(5.0 * plane.rms, settings.outlier_distance)
    vertices, triangles, regions, ring_s = triangulate(surface, root, tip, boundaries, settings)
    check_closed(vertices, triangles)
    return guarded(Reconstruction(vertices=vertices, triangles=triangles, regions=regions,
                                  points=points, segmentation=segmentation, surface=surface,
                                  root=root, tip=tip, residuals=residuals, inliers=inliers,
                                  parameters=parameters, boundaries=boundaries,
                                  fit_history=fit.history_, ring_parameters=ring_s), settings,
                   budget)


def guarded(reconstruction: Reconstruction, settings: ReconstructionSettings,
            budget: RepairBudget | None = None) -> Reconstruction:
    """The reconstruction with its guard report (:func:`~steamtwin.geometry.fit_guard.
    guard_surface`); a surface off the cloud or missing part of it is refitted with the
    guard's stronger penalties in turn (a beak is an overshoot of the spline where few points
    hold it), refused with :class:`ReconstructionError` saying where and how far when none
    passes; a repair passes only without a vertex beyond the limit where the first fit's
    defects lay (:func:`~steamtwin.geometry.fit_guard.remnants`). The repairs stop at one that
    does not shrink the worst defect (more penalty only smooths further from the cloud), or
    when one more would overrun ``GuardSettings.cpu_budget``
    (:mod:`~steamtwin.geometry.repair_budget`; default: from now)."""
    if settings.guard is None:
        return reconstruction
    budget = budget or RepairBudget.start(settings.guard.cpu_budget)
    report = guard_surface(reconstruction, settings.guard)
    budget.measure()
    if not report.failed:
        return replace(reconstruction, guard=replace(report, repairs=settings.penalty_factor))
    first, worst = report, report.worst
    for factor in [f for f in settings.guard.penalty_factors if f > settings.penalty_factor]:
        if not budget.allows_refit():
            break
        budget.mark()
        try:
            repaired = _reconstruct(reconstruction.points,
                                    replace(settings, penalty_factor=factor, guard=None),
                                    reconstruction.segmentation)
        except ReconstructionError:
            break  # the stronger penalty misses the cloud: refuse with the defect found
        trial = guard_surface(repaired, settings.guard)
        left = remnants(repaired, trial, first.defects)  # of any size where a defect was
        budget.measure()
        if not trial.failed and not left:
            return replace(repaired, guard=replace(trial, repairs=factor))
        trial_worst = max([trial.worst] + [d.size for d in left])
        if trial_worst >= worst:
            break
        worst = trial_worst
    raise ReconstructionError(refusal_message(first, reconstruction.points,
                                              reconstruction.segmentation))


# --- parameters and knots ------------------------------------------------------------------------


def initial_parameters(points: np.ndarray, segmentation: Segmentation, mask: np.ndarray
                       ) -> tuple[np.ndarray, float]:
    """Start parameter ``s`` ∈ [0, 1) of the points under ``mask`` (NaN elsewhere) and the
    median section perimeter (m).

    The turn fraction θ of the segmentation (``Segmentation.turn``, from
    :func:`~steamtwin.geometry.sections.section_turn`: geodesic arc length anticlockwise
    from the rear end over the perimeter) is monotone round any section — also where a strongly
    cambered face is no graph over the chord — and unchanged by twist and taper. θ is then
    mapped to the arc-length fraction measured on 9 thin slabs spread over the span: the medians
    of their points in θ order, in groups of :data:`GROUP` (robust to stray points), give a
    polyline whose cumulative length is the arc length. The mapping of each slab is the median
    of its own and its neighbours' and is interpolated linearly along the span (graph distances
    stretch differently where the sampling differs).
    """
    theta = np.full(len(points), np.nan)
    theta[mask] = segmentation.turn[mask]
    z = points[mask, 2]
    grid = np.linspace(0.0, 1.0, 2001)
    height = 2.0 * segmentation.spacing
    fractions, perimeters, centres = [], [], []
    for centre in np.linspace(np.percentile(z, 10.0), np.percentile(z, 90.0), 9):
        members = np.flatnonzero(mask)[np.abs(z - centre) < height]
        if len(members) < 200:
            continue
        order = members[np.argsort(theta[members])]
        groups = len(order) // GROUP
        xy = np.median(points[order[: GROUP * groups], :2].reshape(groups, GROUP, 2), axis=1)
        angle = theta[order[: GROUP * groups]].reshape(groups, GROUP).mean(axis=1)
        steps = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1)
        length = np.concatenate([[0.0], np.cumsum(steps)])
        knots = np.concatenate([[0.0], angle, [1.0]])
        values = np.concatenate([[0.0], length[:-1] + 0.5 * steps[-1], [length[-1]]])
        fractions.append(np.maximum.accumulate(np.interp(grid, knots, values / length[-1])))
        perimeters.append(length[-1])
        centres.append(centre)
    if not fractions:
        raise ReconstructionError("too few side points to order them round the section")
    # the median of each slab and its two neighbours, interpolated along the span
    fractions = np.array(fractions)
    padded = np.vstack([fractions[:1], fractions, fractions[-1:]])
    mappings = np.median(np.stack([padded[:-2], padded[1:-1], padded[2:]]), axis=0)
    mappings = (mappings - mappings[:, :1]) / (mappings[:, -1:] - mappings[:, :1])
    at = np.array([np.interp(theta[mask], grid, row) for row in mappings])  # (slabs, n)
    position = np.interp(z, centres, np.arange(len(centres)))
    lower = np.minimum(np.floor(position).astype(int), len(centres) - 1)
    upper = np.minimum(lower + 1, len(centres) - 1)
    weight = position - lower
    columns = np.arange(len(z))
    s = np.full(len(points), np.nan)
    s[mask] = np.mod((1.0 - weight) * at[lower, columns] + weight * at[upper, columns], 1.0)
    return s, float(np.median(perimeters))


#: Largest share of the side points the fit may leave out before the side counts as not fitted.
MAX_TRIMMED = 0.1


def check_side_fit(fit: AdaptiveSurfaceFit, edges=None) -> None:
    """Raise :class:`ReconstructionError` when the fitted side folds over itself or leaves more
    than :data:`MAX_TRIMMED` of the side points out (farther than the outlier distance): the
    surface then does not follow the cloud, whatever the triangulation would make of it.
    ``edges()`` gives the note on sparse edges (:func:`~.fit_guard.sparse_edges`)."""
    trimmed = float(np.mean(~fit.inliers_))
    if fit.surface_.folds() or trimmed > MAX_TRIMMED:
        raise ReconstructionError(
            f"the fitted side folds over itself or misses the cloud ({trimmed:.0%} of the side "
            f"points farther than {fit.outlier_distance * 1e3:.3g} mm): is the cloud too "
            "sparse at the edges, or not in the blade frame?" + (edges() if edges else ""))


def _circular(s: np.ndarray, centre: float) -> np.ndarray:
    """``s`` shifted into [centre − 0.5, centre + 0.5)."""
    return np.mod(s - centre + 0.5, 1.0) + centre - 0.5


def patch_boundaries(s: np.ndarray, labels: np.ndarray) -> dict[str, float]:
    """Parameters ``s`` where the side patches meet, keyed ``"<before>|<after>"`` going round
    the profile from the trailing edge (suction side, leading edge, pressure side): each
    boundary is the threshold that best separates the two patches' points."""
    ids = {name: REGIONS.index(name) for name in SIDE_REGIONS}
    for name in ("leading_edge", "trailing_edge"):
        if np.sum(labels == ids[name]) < 10:
            raise ReconstructionError(f"no {name.replace('_', ' ')} found: fewer than 10 points "
                                      "of high curvature at that end of the chord")
    te = float(np.median(_circular(s[labels == ids["trailing_edge"]], 0.0)))
    le = float(np.mod(np.median(_circular(s[labels == ids["leading_edge"]], 0.5)), 1.0))
    order = ["trailing_edge", "suction_side", "leading_edge", "pressure_side"]
    centres = {"trailing_edge": te, "leading_edge": le}
    boundaries = {}
    for a, b in zip(order, order[1:] + order[:1], strict=True):
        # measure s from a quarter turn before the edge patch of the pair (edges are narrow)
        base = centres[a] - 0.25 if a in centres else centres[b] - 0.75
        sa = np.mod(s[labels == ids[a]] - base, 1.0)
        sb = np.mod(s[labels == ids[b]] - base, 1.0)
        boundaries[f"{a}|{b}"] = float(np.mod(base + _separation(sa, sb), 1.0))
    return boundaries


def _separation(before: np.ndarray, after: np.ndarray) -> float:
    """Threshold t maximising #(before < t) + #(after ≥ t)."""
    before, after = np.sort(before), np.sort(after)
    candidates = np.concatenate([before, after])
    score = np.searchsorted(before, candidates) + len(after) - np.searchsorted(after, candidates)
    return float(candidates[np.argmax(score)])


def edge_arcs(segmentation: Segmentation, labels: np.ndarray, perimeter: float
              ) -> dict[str, float]:
    """Half-turn arc length π r of each edge circle as a fraction of the ``perimeter`` (m), the
    radius r the smallest radius of curvature of the edge patch (the 90th percentile of its
    points' curvature; k-NN estimates blend in the flatter sides, so r is rather too large)."""
    arcs = {}
    for edge in ("trailing_edge", "leading_edge"):
        on = labels == REGIONS.index(edge)
        if np.any(on):
            radius = 1.0 / max(float(np.percentile(segmentation.curvature[on], 90.0)), 1e-9)
            arcs[edge] = math.pi * radius / perimeter
    return arcs


def initial_breaks(boundaries: dict[str, float], perimeter: float,
                   settings: ReconstructionSettings, arcs: dict[str, float] | None = None
                   ) -> np.ndarray:
    """Starting breakpoints in [0, 1): ``edge_knot_spans`` spans across each edge patch — or
    across the edge circle's half-turn ``arcs[edge]`` (fraction of the perimeter) when that is
    narrower: on a sparse cloud the patch spreads onto the sides and spans as wide as the
    circle cut across it —, growing by half the distance from the edge up to
    ``side_knot_spacing`` along the sides."""
    grid = np.linspace(0.0, 1.0, 20_001)
    spacing = np.full(len(grid), settings.side_knot_spacing / perimeter)
    for edge in ("trailing_edge", "leading_edge"):
        lo = next(v for k, v in boundaries.items() if k.endswith(f"|{edge}"))
        hi = next(v for k, v in boundaries.items() if k.startswith(f"{edge}|"))
        width = min(float(np.mod(hi - lo, 1.0)), (arcs or {}).get(edge, 1.0))
        lo = lo + 0.5 * (np.mod(hi - lo, 1.0) - width)
        centre = lo + 0.5 * width
        outside = np.maximum(np.abs(_circular(grid, centre) - centre) - 0.5 * width, 0.0)
        spacing = np.minimum(spacing, width / settings.edge_knot_spans + 0.5 * outside)
    density = np.concatenate([[0.0], np.cumsum(0.5 * (1 / spacing[1:] + 1 / spacing[:-1])
                                               * np.diff(grid))])
    count = max(8, math.ceil(density[-1]))
    return np.interp(np.arange(count) * density[-1] / count, density, grid)


def _refit_caps(points: np.ndarray, labels: np.ndarray, segmentation: Segmentation
                ) -> tuple[CapPlane, CapPlane]:
    """Cap planes fitted to all points labelled root or tip."""
    planes = []
    for name in ("root", "tip"):
        on = labels == REGIONS.index(name)
        planes.append(fit_cap_plane(points[on]) if on.sum() >= 3
                      else getattr(segmentation, name))
    return planes[0], planes[1]


def _span_range(side: np.ndarray, root: CapPlane, tip: CapPlane) -> tuple[float, float]:
    """z range (m) of the side surface: the side points and the cap planes over them."""
    lo = min(side[:, 2].min(), root.height(side[:, :2]).min())
    hi = max(side[:, 2].max(), tip.height(side[:, :2]).max())
    margin = 1e-3 * (hi - lo)
    return lo - margin, hi + margin


# --- triangulation -------------------------------------------------------------------------------


def _rim(surface: PeriodicSurface, plane: CapPlane, s: np.ndarray, start: float) -> np.ndarray:
    """z of the side surface's intersection with a cap plane at every ``s``."""
    z = np.full(len(s), start)
    for _ in range(8):  # fixed point: the plane's slope is tiny
        z = plane.height(surface(s, z))
    return z


def ring_parameters(surface: PeriodicSurface, levels: np.ndarray, boundaries: dict[str, float],
                    spacing: float, sag: float) -> np.ndarray:
    """Parameters ``s`` of the vertices round each section: chord sag ≤ ``sag`` on the most
    curved of the sections at ``levels`` (spacing √(8 r sag), at most ``spacing``, m), with
    vertices exactly on the patch boundaries."""
    fine = np.linspace(0.0, 1.0, 40_000, endpoint=False)
    curvature = np.zeros(len(fine))
    speed = np.zeros(len(fine))
    for z in levels:
        d1, d2 = surface(fine, z, ds=1), surface(fine, z, ds=2)
        norm = np.linalg.norm(d1, axis=1)
        curvature = np.maximum(curvature,
                               np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / norm**3)
        speed = np.maximum(speed, norm)
    # sag-limited, but never below 1/20 of the spacing (a fold of a failed fit would otherwise
    # ask for millions of vertices)
    step = np.clip(np.sqrt(8.0 * sag / np.maximum(curvature, 1e-12)), spacing / 20.0, spacing)
    density = np.concatenate([[0.0], np.cumsum(speed / step)]) / len(fine)
    count = max(16, math.ceil(density[-1]))
    s = np.interp(np.arange(count) * density[-1] / count, density,
                  np.append(fine, 1.0))
    fixed = np.sort(np.mod(np.array(list(boundaries.values())), 1.0))
    gap = 0.3 / count
    distance = np.abs(np.mod(s[:, None] - fixed[None, :] + 0.5, 1.0) - 0.5)
    s = s[distance.min(axis=1) > gap]
    return np.sort(np.concatenate([s, fixed]))


def triangulate(surface: PeriodicSurface, root: CapPlane, tip: CapPlane,
                boundaries: dict[str, float], settings: ReconstructionSettings
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Closed triangulation of the side surface between the cap planes, and the caps.

    Returns ``(vertices (n, 3) ring by ring, triangles (m, 3) outward, region per triangle,
    s of the vertices of a ring)``.
    """
    z_mid = 0.5 * (surface.z_knots[0] + surface.z_knots[-1])
    probe = np.linspace(0.0, 1.0, 64, endpoint=False)
    z_root = float(np.mean(_rim(surface, root, probe, z_mid)))
    z_tip = float(np.mean(_rim(surface, tip, probe, z_mid)))
    if not z_tip > z_root:
        raise ReconstructionError("the tip cap does not lie above the root cap")
    s = ring_parameters(surface, np.linspace(z_root, z_tip, 5), boundaries,
                        settings.chordwise_spacing, settings.sag)
    n = len(s)
    bottom, top = _rim(surface, root, s, z_root), _rim(surface, tip, s, z_tip)
    levels = max(2, math.ceil((z_tip - z_root) / settings.span_spacing) + 1)
    fraction = np.linspace(0.0, 1.0, levels)
    z = bottom[None, :] + fraction[:, None] * (top - bottom)[None, :]
    ss = np.broadcast_to(s, z.shape).ravel()
    vertices = np.column_stack([surface(ss, z.ravel()), z.ravel()])
    k = np.arange(n)
    tris = []
    for level in range(levels - 1):
        a, b = level * n + k, level * n + (k + 1) % n
        tris += [np.column_stack([a, b, b + n]), np.column_stack([a, b + n, a + n])]
    side = np.concatenate(tris)
    middle = np.mod(s + 0.5 * np.diff(np.append(s, 1.0 + s[0])), 1.0)
    column_region = regions_at(middle, boundaries)
    side_region = np.tile(np.repeat(column_region[None, :], 2, axis=0).ravel(), levels - 1)
    try:
        cap = cap_triangles(vertices[:n, :2])
        cap_top = cap_triangles(vertices[-n:, :2])
    except GeometryError as error:
        raise ReconstructionError(f"a cap outline of the fitted surface is not a simple "
                                  f"polygon ({error}): the fitted side folds over itself — is "
                                  "the cloud too sparse at the edges, or not in the blade "
                                  "frame?") from None
    triangles = np.concatenate([side, cap[:, ::-1], cap_top + (levels - 1) * n])
    regions = np.concatenate([side_region, np.full(len(cap), REGIONS.index("root")),
                              np.full(len(cap_top), REGIONS.index("tip"))])
    return vertices, triangles.astype(np.int64), regions.astype(np.int64), s


def regions_at(s: np.ndarray, boundaries: dict[str, float]) -> np.ndarray:
    """Side region (REGIONS index) at parameters ``s``."""
    starts = sorted((value, key.split("|")[1]) for key, value in boundaries.items())
    values = np.array([v for v, _ in starts])
    names = [name for _, name in starts]
    position = np.searchsorted(values, np.mod(s, 1.0), side="right") - 1  # −1: before the first
    return np.array([REGIONS.index(names[p]) for p in position])
