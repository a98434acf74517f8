"""The radius of a thin blade edge from the thickness next to it, where its arc holds too few
points for a circle fit.

A circle fitted to the points of an edge patch (Kåsa 1976) needs points on the arc; a 0.15-mm
edge at 0.23 mm spacing has about one per section, and the patch's other points lie on the
flanks, which leave the circle along its tangents: the fit comes out 3–5 times too large
(issue 19's slender blade, 0.15 mm trailing edge measured 0.74–0.83 mm). Near a thin edge
both flanks are straight lines, and the standard profile closes them with the circle tangent
to both (Dixon & Hall, "Fluid Mechanics and Thermodynamics of Turbomachinery", 7th ed. 2014,
§3.3; Pritchard 1985, ASME 85-GT-219): with the half wedge angle γ between the lines and the
thickness t₀ they extrapolate to at the edge's tip (distance 0 along the chord), the circle
whose tip is there has

    r = t₀ · cos γ / (2 · (1 − sin γ))

(its centre lies on the bisector r / sin γ from the lines' apex, its tip r farther towards the
apex, where the lines are t₀ apart). The flanks are measured over many points a few spacings
back from the tip, so the radius needs no point on the arc; an error δ of the tip's position
changes r by about δ · tan γ only (a thin wedge: a tenth of δ at γ = 5°).
"""

from __future__ import annotations

import math

import numpy as np

#: The flanks are measured from this many point spacings behind the tip (off the arc, whose
#: tangent points lie r·(1 − sin γ) behind it) ...
FLANK_FROM = 3.0
#: ... to this many spacings (at least :data:`FLANK_TO_MIN` m): a thin edge's flanks are
#: straight there (65-series and circular-arc sections: sagitta ≤ 0.02 mm over 3 mm of a 40-mm
#: chord turning 25°).
FLANK_TO = 10.0
FLANK_TO_MIN = 2.0e-3
#: Fewest points on each flank for a radius.
MIN_FLANK_POINTS = 4


def wedge_radius(xy: np.ndarray, edge_xy: np.ndarray, spacing: float) -> float:
    """Radius (m) of the edge circle of one section from its points.

    ``xy`` (n, 2; m): the section's side points near the edge (within :data:`FLANK_TO`
    spacings of it); ``edge_xy`` (k, 2; m): those of the edge patch (their median marks the
    edge); ``spacing`` (m): the cloud's point spacing. The chord direction is the principal
    axis of ``xy`` pointing to the edge, the tip the farthest point along it, the flanks the
    straight-line fits of the points on either side of the mid-line between
    :data:`FLANK_FROM` and :data:`FLANK_TO` spacings behind the tip (module docstring). NaN
    when a flank has fewer than :data:`MIN_FLANK_POINTS` points or the lines do not open
    away from the tip.
    """
    mark = np.median(edge_xy, axis=0)
    centred = xy - xy.mean(axis=0)
    axis = np.linalg.svd(centred, full_matrices=False)[2][0]
    if axis @ (mark - xy.mean(axis=0)) < 0.0:
        axis = -axis
    across = np.array([-axis[1], axis[0]])
    behind = float(np.max(xy @ axis)) - xy @ axis  # distance behind the tip along the chord
    offset = xy @ across
    window = (behind >= FLANK_FROM * spacing) & (
        behind <= max(FLANK_TO * spacing, FLANK_TO_MIN))
    if window.sum() < 2 * MIN_FLANK_POINTS:
        return math.nan
    middle = np.polyval(np.polyfit(behind[window], offset[window], 1), behind)
    lines = []
    for side in (offset > middle, offset <= middle):
        use = window & side
        if use.sum() < MIN_FLANK_POINTS:
            return math.nan
        lines.append(np.polyfit(behind[use], offset[use], 1))  # (slope, offset at the tip)
    (upper_slope, upper_tip), (lower_slope, lower_tip) = lines
    half_angle = 0.5 * (math.atan(upper_slope) - math.atan(lower_slope))
    thickness = upper_tip - lower_tip
    if not 0.0 < half_angle < 0.5 * math.pi:
        return math.nan
    return max(thickness, 0.0) * math.cos(half_angle) / (2.0 * (1.0 - math.sin(half_angle)))
