"""The turn fraction across a thick trailing edge (the reference unit's hp8: a 0.6 mm edge
radius at a 1 mm seed radius).

Each face's length is read 1–3 seed radii short of the rear end. Taken on from there by the
straight distance, which is up to π/2 times shorter than the way round the edge's circle, the
two faces summed about 1 mm short of the perimeter the paths measure, and the turn stepped by
that much at the rear end: hp8 was refused. Taken on along the surface, the step is a fraction
of it. The section here is a stadium — two flat faces joined by half circles — whose arc
length is known in closed form."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.sections import section_turn

LENGTH, RADIUS, SPAN = 30e-3, 0.6e-3, 20e-3
FLAT = LENGTH - 2.0 * RADIUS
PERIMETER = 2.0 * FLAT + 2.0 * math.pi * RADIUS


def _stadium(count: int, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (m) of the extruded stadium from x = 0 to ``LENGTH``, with ``noise`` (m) of
    scatter along the normal, their outward normals and their arc lengths (m) anticlockwise
    from the rear end (x = LENGTH)."""
    rng = np.random.default_rng(seed)
    arc = PERIMETER * rng.random(count)
    quarter = 0.5 * math.pi * RADIUS
    # the rear half circle is split at the rear end: its upper quarter first, its lower last
    bounds = np.cumsum([quarter, FLAT, 2.0 * quarter, FLAT])
    part = np.searchsorted(bounds, arc, side="right")
    rear_centre, front_centre = np.array([LENGTH - RADIUS, 0.0]), np.array([RADIUS, 0.0])
    angle = np.select(
        [part == 0, part == 2, part == 4],
        [arc / RADIUS, 0.5 * math.pi + (arc - bounds[1]) / RADIUS,
         -0.5 * math.pi + (arc - bounds[3]) / RADIUS], 0.0)
    circle = np.column_stack([np.cos(angle), np.sin(angle)])
    normals = np.select([part[:, None] == 1, part[:, None] == 3],
                        [np.array([0.0, 1.0]), np.array([0.0, -1.0])], circle)
    centre = np.where((part == 2)[:, None], front_centre, rear_centre)
    xy = np.select(
        [part[:, None] == 1, part[:, None] == 3],
        [np.column_stack([LENGTH - RADIUS - (arc - bounds[0]), np.full(count, RADIUS)]),
         np.column_stack([RADIUS + (arc - bounds[2]), np.full(count, -RADIUS)])],
        centre + RADIUS * circle)
    xy += noise * rng.normal(size=(count, 1)) * normals
    points = np.column_stack([xy, SPAN * rng.random(count)])
    return points, np.column_stack([normals, np.zeros(count)]), arc


def test_turn_does_not_step_at_a_thick_trailing_edge():
    points, normals, arc = _stadium(8000, 0.02e-3, seed=4)
    count = len(points)
    distances, index = cKDTree(points).query(points, k=20)
    seed_radius = float(np.median(distances[:, -1]))
    assert 1.5 * RADIUS < seed_radius < 2.0 * RADIUS  # hp8's proportions
    front = np.zeros((count, 2))
    rear = np.tile([LENGTH, 0.0], (count, 1))
    turn, perimeter = section_turn(points, normals, index, np.ones(count, dtype=bool), front,
                                   rear, seed_radius, 2e-3)
    # the turn runs anticlockwise from the rear end, as the arc here does
    error = (np.mod(turn - arc / PERIMETER + 0.5, 1.0) - 0.5) * PERIMETER
    signed = np.where(arc < 0.5 * PERIMETER, arc, arc - PERIMETER)  # from the rear end (m)
    after = np.median(error[(signed > 0.0) & (signed < 1.5e-3)])
    before = np.median(error[(signed < 0.0) & (signed > -1.5e-3)])
    # measured 0.20 mm (the faces taken on by the straight distance: 0.93 mm)
    assert abs(after - before) < 0.45e-3, (after - before) * 1e3
    assert np.allclose(perimeter, np.median(perimeter), rtol=0.01)
    assert abs(np.median(perimeter) / PERIMETER - 1.0) < 0.05  # the paths' zig-zag: +3.6 %
