"""Refusing an edge too sparse for any fit, before the expensive ones (issue 19: ≤ 30 s CPU).

A leading or trailing edge whose half circle π·r holds about one point spacing or less is not
resolved by the cloud: the edge turns the surface through 180° within one spacing. By the
sampling theorem (Shannon 1949, "Communication in the presence of noise", Proc. IRE 37:10) a
feature — here the edge's curvature pulse of width π·r along the arc, whose fundamental has
wavelength 2π·r — is recovered only from samples at most half a wavelength apart,
h ≤ π·r, i.e. ``points across`` n = π·r / h ≥ 1. On a random (Poisson) cloud the points fall
unevenly: in a strip of the edge one spacing high the arc holds n points on average and none
with probability e^(−n), so at n = 1 a third (37 %) of the edge's one-spacing strips have no
point on the arc at all. :data:`MIN_POINTS_ACROSS` is the sampling theorem's 1 with a 20 %
margin for the figure's own scatter (±10 % over one cloud's span bands; within 5 % of the
density drawn on a synthetic edge, ``tests/geometry/test_early_edge_refusal.py``).

An edge's figure is the median over its span bands of :func:`~steamtwin.geometry.fit_guard.
edge_sampling`'s points across, √ρ·π·r, r from the flanks where they give one. Round a
resolved nose the flank lines can miss the tip and read r 20–80 × too small, in up to three of
five bands (thick-impulse's 2-mm leading edge at 80k). The circle through the edge's points
never reads a sparse edge's radius too small (it takes the flanks' points and comes out larger,
:func:`~steamtwin.geometry.fit_guard.edge_radius`), so an edge is refused only when that circle
too holds fewer than :data:`~steamtwin.geometry.edge_model.MODEL_SAMPLES` spacings — the edge
model's own bound of an unresolved edge. Missing a refusal here costs time (the later checks
still refuse); a wrong refusal would cost a blade that fits.

Below one spacing across, the edge model pooled along the span (:mod:`~steamtwin.geometry.
edge_pooled`) still holds an edge whose span model gets enough arc points per knot span
(:data:`~steamtwin.geometry.edge_span.KNOT_SPACING`): ρ·π·r·Δz = n·√ρ·Δz for n points
across. Its flanks are fixed by thousands of points, its tip along the bisector by the arc's:
from λ of them σ/√λ (0.009 mm at λ = 4, σ 0.017 mm), and a knot span holds none with
probability e^(−λ) (Poisson: 1.8 % at 4), filled by the P-spline from its neighbours. So an
edge is refused only when it also holds fewer than :data:`MIN_POOLED_POINTS` arc points per
knot span (median over its bands). Measured (2026-11-28): slender 80k's 0.15-mm trailing edge,
0.93–0.98 across, holds ≈ 5 (its pooled model within 0.03 mm of the exact tip; seed 0
within the issue's limits, docs/benchmarks.md, branch ``slender``); at 40k ≈ 2.4, refused.
"""

from __future__ import annotations

import math

import numpy as np

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.edge_model import MODEL_SAMPLES
from steamtwin.geometry.edge_span import KNOT_SPACING
from steamtwin.geometry.fit_guard import EdgeSampling, edge_sampling
from steamtwin.geometry.segmentation import Segmentation

#: Fewest points across an edge's half circle (median over its span bands) for the cloud to be
#: reconstructed: the sampling theorem's 1 with a 20 % margin (module docstring).
MIN_POINTS_ACROSS = 1.2
#: Fewest arc points per knot span of the pooled edge model (median over the bands) for an
#: edge below :data:`MIN_POINTS_ACROSS` to be fitted (module docstring).
MIN_POOLED_POINTS = 4.0


class SparseEdgeError(ReconstructionError):
    """An edge sampled below :data:`MIN_POINTS_ACROSS`, refused before the side is fitted;
    ``bands`` are the edge's span bands (:class:`~steamtwin.geometry.fit_guard.EdgeSampling`)."""

    def __init__(self, message: str, bands: list[EdgeSampling]) -> None:
        super().__init__(message)
        self.bands = bands


def points_across(band: EdgeSampling, radius: float | None = None) -> float:
    """Point spacings on the band's half circle, √ρ·π·r (dimensionless); r the band's radius,
    or ``radius`` (m) when given."""
    return band.per_mm * math.pi * (band.radius if radius is None else radius) * 1e3


def pooled_points(band: EdgeSampling) -> float:
    """Arc points per knot span of the pooled edge model, ρ·π·r·Δz (dimensionless; Δz
    :data:`~steamtwin.geometry.edge_span.KNOT_SPACING`)."""
    return points_across(band) * band.per_mm * KNOT_SPACING * 1e3


def pooled_needed(band: EdgeSampling) -> float:
    """Points per mm (√ρ) for :data:`MIN_POOLED_POINTS` arc points per knot span."""
    return math.sqrt(MIN_POOLED_POINTS / (math.pi * band.radius * KNOT_SPACING * 1e6))


def check_edge_density(points: np.ndarray, segmentation: Segmentation,
                       minimum: float = MIN_POINTS_ACROSS) -> dict[str, float]:
    """The median points across each edge's half circle (``points`` (n, 3) in m, in the blade
    frame; ``segmentation`` the cloud's). Raises :class:`SparseEdgeError` when an edge's
    median is below ``minimum``, the circle through its points holds fewer than
    :data:`~steamtwin.geometry.edge_model.MODEL_SAMPLES` spacings and its bands fewer than
    :data:`MIN_POOLED_POINTS` arc points per knot span of the pooled model (median), with
    :func:`~steamtwin.geometry.fit_guard.edge_sampling`'s description of the bands below
    ``minimum`` (span range, points per mm and per mm², × this scan's density) and the density
    the pooled model needs in each. Edges without a sampled band are left out."""
    figures = {}
    for edge in ("leading_edge", "trailing_edge"):
        bands = edge_sampling(points, segmentation, edge)
        if not bands:
            continue
        figures[edge] = float(np.median([points_across(band) for band in bands]))
        circle = float(np.median([points_across(band, band.circle_radius) for band in bands]))
        pooled = float(np.median([pooled_points(band) for band in bands]))
        if figures[edge] < minimum and circle < MODEL_SAMPLES and pooled < MIN_POOLED_POINTS:
            low = [band for band in bands if points_across(band) < minimum]
            raise SparseEdgeError(
                f"too few points on the {edge.replace('_', ' ')} to fit it: "
                f"{figures[edge]:.2f} point spacings across its half circle (median over the "
                f"span), needs ≥ {minimum:g}, or ≥ {MIN_POOLED_POINTS:g} arc points per "
                f"{KNOT_SPACING * 1e3:g} mm of span for the edge model pooled along the span "
                f"(has {pooled:.1f}) — " + "; ".join(
                    f"{band.describe()}; pooled: needs ≥ {pooled_needed(band):.1f} points per "
                    f"mm ({pooled_needed(band) ** 2:.0f} per mm²)" for band in low)
                + " — refused before the side fit", bands)
    return figures
