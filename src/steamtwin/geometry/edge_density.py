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
"""

from __future__ import annotations

import math

import numpy as np

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.edge_model import MODEL_SAMPLES
from steamtwin.geometry.fit_guard import EdgeSampling, edge_sampling
from steamtwin.geometry.segmentation import Segmentation

#: Fewest points across an edge's half circle (median over its span bands) for the cloud to be
#: reconstructed: the sampling theorem's 1 with a 20 % margin (module docstring).
MIN_POINTS_ACROSS = 1.2


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


def check_edge_density(points: np.ndarray, segmentation: Segmentation,
                       minimum: float = MIN_POINTS_ACROSS) -> dict[str, float]:
    """The median points across each edge's half circle (``points`` (n, 3) in m, in the blade
    frame; ``segmentation`` the cloud's). Raises :class:`SparseEdgeError` when an edge's
    median is below ``minimum`` and the circle through its points holds fewer than
    :data:`~steamtwin.geometry.edge_model.MODEL_SAMPLES` spacings, with :func:`~steamtwin.
    geometry.fit_guard.edge_sampling`'s description of the bands below ``minimum`` (span
    range, points per mm and per mm², × this scan's density). Edges without a sampled band
    are left out."""
    figures = {}
    for edge in ("leading_edge", "trailing_edge"):
        bands = edge_sampling(points, segmentation, edge)
        if not bands:
            continue
        figures[edge] = float(np.median([points_across(band) for band in bands]))
        circle = float(np.median([points_across(band, band.circle_radius) for band in bands]))
        if figures[edge] < minimum and circle < MODEL_SAMPLES:
            low = [band.describe() for band in bands if points_across(band) < minimum]
            raise SparseEdgeError(
                f"too few points on the {edge.replace('_', ' ')} to fit it: "
                f"{figures[edge]:.2f} point spacings across its half circle (median over the "
                f"span), needs ≥ {minimum:g} — " + "; ".join(low)
                + " — refused before the side fit", bands)
    return figures
