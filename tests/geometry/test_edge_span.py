"""The span model of a thin edge (geometry/edge_span.py through edge_model.py).

A synthetic twisted, tapering wedge: the sections of test_edge_model.py's WedgeSection (a
trailing-edge circle tangent to both straight flanks, Dixon & Hall §3.3 / Pritchard 1985)
with a radius that grows linearly along z and a stagger that turns about the mid-chord, so
the edge's centre moves on an arc and the flank lines turn along the span. The exact centre,
radius and tip are known at every z.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree
from test_edge_model import WedgeSection

from steamtwin.geometry.edge_circle import tip_and_half_angle
from steamtwin.geometry.edge_model import model_sparse_edges
from steamtwin.geometry.edge_span import (
    SpanEdgeModel,
    fit_span_edge,
    initial_coefficients,
    sample_span_edge,
    span_knots,
)
from steamtwin.geometry.volume_mesh import REGIONS

HEIGHT = 12e-3  # m of span
RADIUS = (0.18e-3, 0.22e-3)  # m, the trailing-edge radius at z = 0 and at HEIGHT
TWIST = math.radians(6.0)  # stagger change over HEIGHT (0.5°/mm, more than naca-twisted's)
PIVOT = np.array([-10e-3, 0.0])  # the stagger turns about the 20-mm wedge's mid-chord
HALF_WEDGE = math.radians(7.0)
SPACING = 0.15e-3  # π·r / spacing = 3.8–4.6 points across the half circle


def radius_at(z: np.ndarray) -> np.ndarray:
    return RADIUS[0] + (RADIUS[1] - RADIUS[0]) * z / HEIGHT


def turn(xy: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Section coordinates (n, 2) at heights z into the blade frame: rotated by the stagger
    about PIVOT."""
    angle = TWIST * z / HEIGHT
    c, s = np.cos(angle), np.sin(angle)
    v = xy - PIVOT
    return PIVOT + np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


def unturn(xy: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Blade-frame coordinates back into the section's own (the tip on +x at r(z))."""
    angle = -TWIST * z / HEIGHT
    c, s = np.cos(angle), np.sin(angle)
    v = xy - PIVOT
    return PIVOT + np.column_stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]])


def twisted_scan(seed: int = 0, outliers: float = 0.05, gap: tuple[float, float] | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points (n, 3), s, labels and perimeters of the twisted wedge: σ 0.017 mm along the
    normal, ``outliers`` of the trailing edge's points 0.2–2 mm outward, and no points within
    3 mm of the trailing edge for z in ``gap`` (m)."""
    rng = np.random.default_rng(seed)
    bins = np.linspace(0.0, HEIGHT, 241)  # 0.05-mm layers, one section each
    pieces = []
    for lo, hi in itertools.pairwise(bins):
        section = WedgeSection(float(radius_at(np.array(0.5 * (lo + hi)))), HALF_WEDGE)
        count = rng.poisson(section.perimeter * (hi - lo) / SPACING**2)
        u = rng.uniform(0.0, section.perimeter, count)
        z = rng.uniform(lo, hi, count)
        xy, normal = section.at(u)
        distance = np.minimum(u, section.perimeter - u)
        offset = rng.normal(0.0, 0.017e-3, count)
        edge = distance < 1e-3
        stray = edge & (rng.uniform(size=count) < outliers)
        offset[stray] = rng.uniform(0.2e-3, 2e-3, stray.sum())
        xy = turn(xy + offset[:, None] * normal, z)
        labels = np.where(edge, REGIONS.index("trailing_edge"),
                          np.where(np.abs(u - section.perimeter / 2) < 3e-3,
                                   REGIONS.index("leading_edge"),
                                   REGIONS.index("suction_side")))
        keep = np.ones(count, dtype=bool)
        if gap is not None and gap[0] <= 0.5 * (lo + hi) <= gap[1]:
            keep = distance > 3e-3
        pieces.append((np.column_stack([xy, z])[keep], (u / section.perimeter)[keep],
                       labels[keep], np.full(keep.sum(), section.perimeter)))
    return tuple(np.concatenate(column) for column in zip(*pieces, strict=True))


def exact_centre(z: np.ndarray) -> np.ndarray:
    return turn(np.zeros((len(z), 2)), z)


def span_model(gap: tuple[float, float] | None = None, seed: int = 0):
    points, s, labels, perimeter = twisted_scan(seed=seed, gap=gap)
    model = model_sparse_edges(points, s, np.ones(len(points), dtype=bool), labels, perimeter,
                               SPACING)
    return points, model


@pytest.fixture(scope="module")
def twisted():
    return span_model()


def test_span_model_recovers_centre_and_radius_at_every_z(twisted) -> None:
    """≈ 4 points across the half circle, σ 0.017 mm, 5 % of the edge's points stray 0.2–2 mm
    outward: centre within 0.03 mm and radius within 0.02 mm of the truth at every z of the
    model (0.05-mm steps), the slab records likewise."""
    _, model = twisted
    span = model.spans["trailing_edge"]
    z = np.arange(span.z_range[0], span.z_range[1], 0.05e-3)
    centre, radius, _ = span.at(z)
    assert np.linalg.norm(centre - exact_centre(z), axis=1).max() < 0.03e-3
    assert np.abs(radius - radius_at(z)).max() < 0.02e-3
    # the model reaches to within two slabs of both ends of the edge
    assert span.z_range[0] < 2 * 1.5e-3 and span.z_range[1] > HEIGHT - 2 * 1.5e-3
    used = [slab for slab in model.slabs if slab.edge == "trailing_edge" and slab.used]
    assert len(used) >= 6


def test_span_model_tip_is_never_beyond_the_true_tip(twisted) -> None:
    """No model point lies beyond the true tip (x = r(z) in the section's own frame) by more
    than 0.04 mm: the stray points outward do not make a beak."""
    _, model = twisted
    local = unturn(model.points[:, :2], model.points[:, 2])
    assert len(local) > 0
    assert (local[:, 0] - radius_at(model.points[:, 2])).max() < 0.04e-3
    # the model reaches the tip, not short of it by more than the noise
    tips = local[:, 0] - radius_at(model.points[:, 2])
    assert tips.max() > -0.02e-3


GAP = (4.3e-3, 6.2e-3)  # m of span without trailing-edge points


def test_a_slab_without_edge_points_is_filled_by_the_span_model() -> None:
    """No points within 3 mm of the trailing edge for 4.3–6.2 mm of span (a scan hole across
    the whole 1.5-mm slab at 4.5–6.0 mm): that slab is filled by the model, whose centre and
    radius there are within 0.03 / 0.02 mm of the truth, and its model points lie on the true
    edge."""
    _, model = span_model(gap=GAP, seed=1)
    span = model.spans["trailing_edge"]
    z = np.arange(*GAP, 0.05e-3)
    centre, radius, _ = span.at(z)
    assert np.linalg.norm(centre - exact_centre(z), axis=1).max() < 0.03e-3
    assert np.abs(radius - radius_at(z)).max() < 0.02e-3
    filled = [slab for slab in model.slabs if slab.edge == "trailing_edge"
              and GAP[0] < slab.z < GAP[1]]
    assert filled and all(slab.used and slab.reason.startswith("filled") for slab in filled)
    inside = (model.points[:, 2] > GAP[0]) & (model.points[:, 2] < GAP[1])
    assert inside.sum() > 0
    local = unturn(model.points[inside, :2], model.points[inside, 2])
    tip = np.abs(local[:, 1]) < 0.02e-3
    assert np.abs(local[tip, 0] - radius_at(model.points[inside, 2][tip])).max() < 0.03e-3


def test_fit_span_edge_recovers_a_known_model_from_a_poor_start() -> None:
    """Points sampled exactly on a known span model, the fit started 0.05 mm, 0.05 mm and
    3° off: the fit returns the model (centre, radius within 1 µm)."""
    points, s, labels, _ = twisted_scan(seed=2, outliers=0.0)
    near = (labels == REGIONS.index("trailing_edge")) | (np.minimum(s, 1 - s) < 0.07)
    points = points[near]
    z_range = (0.0, HEIGHT)
    knots = span_knots(z_range)
    z = np.linspace(0.0, HEIGHT, 9)
    centre = exact_centre(z)
    angle = TWIST * z / HEIGHT
    values = np.column_stack([centre[:, 0] + 0.05e-3, centre[:, 1] - 0.05e-3,
                              radius_at(z) + 0.05e-3,
                              # inward normals: the rear flank (line 0), then the front one
                              angle + math.pi / 2 + HALF_WEDGE + math.radians(3.0),
                              angle - math.pi / 2 - HALF_WEDGE - math.radians(3.0)])
    start = SpanEdgeModel(knots, initial_coefficients(knots, z, values), z_range)
    model, keep = fit_span_edge(points, start, (0.01e-3, 1e-3))
    check = np.linspace(1e-3, HEIGHT - 1e-3, 50)
    fitted_centre, fitted_radius, _ = model.at(check)
    assert np.linalg.norm(fitted_centre - exact_centre(check), axis=1).max() < 0.01e-3
    assert np.abs(fitted_radius - radius_at(check)).max() < 0.01e-3
    assert keep.mean() > 0.95


def capped_scan(seed: int) -> tuple:
    """The twisted wedge's scan with flat root and tip caps at z = 0 and HEIGHT (20 cap points
    each) and the mask of its side points."""
    points, s, labels, perimeter = twisted_scan(seed=seed)
    cap_xy = np.zeros((20, 2))
    points = np.vstack([points, np.column_stack([cap_xy, np.zeros(20)]),
                        np.column_stack([cap_xy, np.full(20, HEIGHT)])])
    labels = np.concatenate([labels, np.full(20, REGIONS.index("root")),
                             np.full(20, REGIONS.index("tip"))])
    s = np.concatenate([s, np.full(40, np.nan)])
    perimeter = np.concatenate([perimeter, np.full(40, np.nan)])
    side = ~np.isin(labels, [REGIONS.index("root"), REGIONS.index("tip")])
    return points, s, labels, perimeter, side


@pytest.fixture(scope="module")
def capped():
    points, s, labels, perimeter, side = capped_scan(seed=3)
    return points, model_sparse_edges(points, s, side, labels, perimeter, SPACING)


def test_slabs_next_to_a_cap_are_modelled_too(capped) -> None:
    """With root and tip caps at z = 0 and HEIGHT, the slabs next to either cap are modelled
    like the others (one order along the whole edge: the cloud's own order there beside
    modelled slabs cut the edge at the rims), and the points they replace reach to within a
    slab (1.5 mm) of both caps."""
    points, model = capped
    slabs = [slab for slab in model.slabs if slab.edge == "trailing_edge"]
    near_cap = [slab for slab in slabs if min(slab.z, HEIGHT - slab.z) < 4.5e-3]
    assert near_cap and all(slab.used for slab in near_cap)
    z = points[model.replaced, 2]
    assert z.min() < 1.5e-3 and z.max() > HEIGHT - 1.5e-3


def test_span_model_holds_up_to_the_cap_planes_without_a_bulge(capped) -> None:
    """The wedge ends at flat caps (z = 0 and HEIGHT): the span model's surface — its arc and
    flanks sampled in rings (``sample_span_edge``) from one cap plane to the other — lies
    within 0.04 mm of the exact section at every height, the cap rings included (the model
    is held to the ends by the end slabs' points although those keep their own in the side's
    fit), its tip within 0.04 mm of the exact tip, and no model point of the side's fit lies
    beyond either cap plane."""
    _, model = capped
    span = model.spans["trailing_edge"]
    z = np.linspace(0.0, HEIGHT, 49)
    samples, _ = sample_span_edge(span, z, np.linspace(-1.0, 1.0, 41), np.full(len(z), 1e-3))
    centre, radius, normals = span.at(z)
    tip = centre + radius[:, None] * tip_and_half_angle(normals)[0]
    exact_tip = turn(np.column_stack([radius_at(z), np.zeros(len(z))]), z)
    assert np.linalg.norm(tip - exact_tip, axis=1).max() < 0.04e-3
    for height in z:  # distance to the exact section, sampled every 0.5 µm of arc near the tip
        section = WedgeSection(float(radius_at(np.array(height))), HALF_WEDGE)
        u = np.concatenate([np.arange(0.0, 2e-3, 0.5e-6),
                            section.perimeter - np.arange(0.5e-6, 2e-3, 0.5e-6)])
        exact = turn(section.at(u)[0], np.full(len(u), height))
        ring = samples[np.isclose(samples[:, 2], height)]
        distance, _ = cKDTree(exact).query(ring[:, :2])
        assert distance.max() < 0.04e-3, f"z = {height * 1e3:.2f} mm"
    assert len(model.points) and model.points[:, 2].min() >= 0.0
    assert model.points[:, 2].max() <= HEIGHT
