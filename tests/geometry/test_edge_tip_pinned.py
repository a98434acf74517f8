"""A modelled edge's tip at one side parameter along the span (geometry/edge_model.py,
``_pinned``).

The side's B-spline has one set of breakpoints in ``s`` for the whole span, so a thin edge
whose tip wanders in ``s`` leaves its knots: on slender 80k seed 0 the trailing edge's tip
moved over 4 mm of arc along the span and the side folded where it jumped (docs/benchmarks.md,
branch ``slender``). test_edge_pooled.py's sparse wedge (r 0.15 mm, 4.4 points per mm², faces
mixed next to the edge) with the cloud's order shifted along the span by 2 mm of arc over its
40 mm: the model's tip stays at one ``s`` and its order still meets the cloud's far out.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_edge_pooled import HEIGHT, SPACING, sparse_scan

from steamtwin.geometry.edge_circle import arc_length_at
from steamtwin.geometry.edge_model import model_sparse_edges

SHIFT = 2e-3  # m of arc over the span


@pytest.fixture(scope="module")
def wandering():
    points, s, labels, perimeter = sparse_scan()
    s = np.mod(s + SHIFT * points[:, 2] / HEIGHT / perimeter, 1.0)
    model = model_sparse_edges(points, s, np.ones(len(points), dtype=bool), labels, perimeter,
                               SPACING)
    return model, s, perimeter[0]


def _tip_arc(model, perimeter: float) -> np.ndarray:
    """The model's s at its tip (u = 0) in each ring, as arc length (m)."""
    span = model.spans["trailing_edge"]
    u = arc_length_at(model.points[:, :2], *span.at(model.points[:, 2]))
    s = (np.mod(model.s + 0.5, 1.0) - 0.5) * perimeter
    tips = []
    for z in np.unique(model.points[:, 2]):
        ring = model.points[:, 2] == z
        order = np.argsort(u[ring])
        tips.append(np.interp(0.0, u[ring][order], s[ring][order]))
    return np.array(tips)


def test_tip_at_one_parameter_along_the_span(wandering) -> None:
    model, _, perimeter = wandering
    tips = _tip_arc(model, perimeter)
    assert len(tips) > 100
    # before: the tip followed the cloud's order, 2 mm of arc over the span
    assert np.ptp(tips) < 0.01e-3


def test_order_meets_the_cloud_far_from_the_edge(wandering) -> None:
    """The points the model orders farthest out keep the cloud's own s (on the faces'
    unmixed part) to within the order fit's own offset (0.16 mm of arc unpinned, 0.17 mm
    pinned), so the side's parameter stays continuous there."""
    model, s, perimeter = wandering
    points, _, _, _ = sparse_scan()
    span = model.spans["trailing_edge"]
    given = np.flatnonzero(np.isfinite(model.parameters))
    u = arc_length_at(points[given, :2], *span.at(points[given, 2]))
    far = np.abs(u) > 0.9 * np.abs(u).max()
    assert far.sum() > 50
    difference = (np.mod(model.parameters[given[far]] - s[given[far]] + 0.5, 1.0) - 0.5)
    assert np.median(np.abs(difference)) * perimeter < 0.2e-3


def test_pinned_order_meets_the_former_at_the_ends_and_keeps_half_its_slope() -> None:
    """The pinned order equals the former at u = ±outer; a shift beyond half the smaller
    slope × outer is cut to that (the tip then keeps the rest of its offset)."""
    from steamtwin.geometry.edge_model import _pinned
    from steamtwin.geometry.edge_pooled import order_arc

    outer, order = 10e-3, np.array([1e-3, 1.0, 1.2])
    ends = np.array([-outer, outer])
    pinned = _pinned(order, -2e-3, outer)
    assert pinned[0] == pytest.approx(-2e-3)
    assert order_arc(pinned, ends) == pytest.approx(order_arc(order, ends))
    cut = _pinned(order, 12e-3, outer)  # 11 mm of shift over 10 mm: cut to 5 mm
    assert cut[0] == pytest.approx(6e-3) and cut[2] == pytest.approx(0.7)  # ≥ half of 1.2
    assert order_arc(cut, ends) == pytest.approx(order_arc(order, ends))
