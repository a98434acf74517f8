"""The turn fraction across a thick trailing edge: the reference unit's hp8 (a 0.6 mm edge
radius at a 1 mm seed radius) and hp1 scanned sparsely (a 0.82 mm edge radius at 0.64 mm
point spacing).

Each face's length is read 1–3 seed radii short of the rear end. Taken on from there by the
straight distance, which is up to π/2 times shorter than the way round the edge's circle, the
two faces summed about 1 mm short of the perimeter the paths measure, and the turn stepped by
that much at the rear end: hp8 was refused. Taken on along the surface, the faces' offset
beyond the turn round the rear end is a third of it. Where the edge has a few points per
section, both faces' paths reach them about as soon, and which face they went to was a
toss-up: round the rear end the turn is taken from the way to it and the side of the faces'
bisector. The section here is a stadium — two flat faces joined by half circles — whose arc
length is known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.sections import section_turn

LENGTH, SPAN, HP8_RADIUS = 30e-3, 20e-3, 0.6e-3


def _perimeter(radius: float) -> float:
    """The stadium's perimeter (m) with edges of ``radius`` (m)."""
    return 2.0 * (LENGTH - 2.0 * radius) + 2.0 * math.pi * radius


def _stadium(count: int, noise: float, seed: int, radius: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (m) of the extruded stadium from x = 0 to ``LENGTH`` with edges of ``radius``
    (m), with ``noise`` (m) of scatter along the normal, their outward normals and their arc
    lengths (m) anticlockwise from the rear end (x = LENGTH)."""
    rng = np.random.default_rng(seed)
    flat, perimeter = LENGTH - 2.0 * radius, _perimeter(radius)
    arc = perimeter * rng.random(count)
    quarter = 0.5 * math.pi * radius
    # the rear half circle is split at the rear end: its upper quarter first, its lower last
    bounds = np.cumsum([quarter, flat, 2.0 * quarter, flat])
    part = np.searchsorted(bounds, arc, side="right")
    rear_centre, front_centre = np.array([LENGTH - radius, 0.0]), np.array([radius, 0.0])
    angle = np.select(
        [part == 0, part == 2, part == 4],
        [arc / radius, 0.5 * math.pi + (arc - bounds[1]) / radius,
         -0.5 * math.pi + (arc - bounds[3]) / radius], 0.0)
    circle = np.column_stack([np.cos(angle), np.sin(angle)])
    normals = np.select([part[:, None] == 1, part[:, None] == 3],
                        [np.array([0.0, 1.0]), np.array([0.0, -1.0])], circle)
    centre = np.where((part == 2)[:, None], front_centre, rear_centre)
    xy = np.select(
        [part[:, None] == 1, part[:, None] == 3],
        [np.column_stack([LENGTH - radius - (arc - bounds[0]), np.full(count, radius)]),
         np.column_stack([radius + (arc - bounds[2]), np.full(count, -radius)])],
        centre + radius * circle)
    xy += noise * rng.normal(size=(count, 1)) * normals
    points = np.column_stack([xy, SPAN * rng.random(count)])
    return points, np.column_stack([normals, np.zeros(count)]), arc


def test_turn_does_not_step_at_a_thick_trailing_edge():
    points, normals, arc = _stadium(8000, 0.02e-3, seed=4, radius=HP8_RADIUS)
    stadium = _perimeter(HP8_RADIUS)
    count = len(points)
    distances, index = cKDTree(points).query(points, k=20)
    seed_radius = float(np.median(distances[:, -1]))
    assert 1.5 * HP8_RADIUS < seed_radius < 2.0 * HP8_RADIUS  # hp8's proportions
    front = np.zeros((count, 2))
    rear = np.tile([LENGTH, 0.0], (count, 1))
    turn, perimeter = section_turn(points, normals, index, np.ones(count, dtype=bool), front,
                                   rear, seed_radius, 2e-3)
    # the turn runs anticlockwise from the rear end, as the arc here does
    error = (np.mod(turn - arc / stadium + 0.5, 1.0) - 0.5) * stadium
    signed = np.where(arc < 0.5 * stadium, arc, arc - stadium)  # from the rear end (m)
    # the faces' offset beyond the turn round the rear end (1–2 seed radii): measured 0.33 mm
    # (the faces taken on by the straight distance: 0.94 mm)
    after, before = (np.median(error[(np.abs(signed) > 2.5e-3) & (np.abs(signed) < 4e-3)
                                     & (np.sign(signed) == side)]) for side in (1.0, -1.0))
    assert abs(after - before) < 0.6e-3, (after - before) * 1e3
    assert np.allclose(perimeter, np.median(perimeter), rtol=0.01)
    assert abs(np.median(perimeter) / stadium - 1.0) < 0.05  # the paths' zig-zag: +3.6 %


def test_sparse_edge_points_keep_their_side_of_the_rear_end():
    """hp1 scanned sparsely: a 0.82 mm edge at 0.64 mm point spacing, a seed radius of about
    two edge radii. Measured from the front end alone, 5–19 of the ~190 points within 2 mm of
    the rear end went to the other face, up to 1.29 mm from it; taken round the rear end by the
    way to it and the side of the faces' bisector, at most one, 0.39 mm from it."""
    radius = 0.82e-3
    perimeter = _perimeter(radius)
    for seed in range(6):
        points, normals, arc = _stadium(3000, 0.011e-3, seed=seed, radius=radius)
        count = len(points)
        distances, index = cKDTree(points).query(points, k=20)
        seed_radius = float(np.median(distances[:, -1]))
        assert 1.8 * radius < seed_radius < 2.0 * radius
        turn, _ = section_turn(points, normals, index, np.ones(count, dtype=bool),
                               np.zeros((count, 2)), np.tile([LENGTH, 0.0], (count, 1)),
                               seed_radius, 0.8e-3)
        signed = np.where(arc < 0.5 * perimeter, arc, arc - perimeter)  # from the rear end (m)
        # the upper face (arc > 0) runs on from the rear end at θ = 0, the lower ends at θ = 1
        swapped = (np.abs(signed) < 2e-3) & ((turn < 0.5) != (signed > 0.0))
        assert np.all(np.abs(signed[swapped]) < 0.45e-3), (seed, signed[swapped] * 1e3)


def test_no_points_at_the_rear_end_is_an_error_that_says_so():
    """A rear end with no side point within a seed radius (a trailing edge not scanned) is
    refused by name, not turned into NaN lengths."""
    points, normals, _ = _stadium(3000, 0.011e-3, seed=0, radius=HP8_RADIUS)
    count = len(points)
    distances, index = cKDTree(points).query(points, k=20)
    seed_radius = float(np.median(distances[:, -1]))
    with pytest.raises(ReconstructionError, match="no side points at the rear end"):
        section_turn(points, normals, index, np.ones(count, dtype=bool), np.zeros((count, 2)),
                     np.tile([LENGTH + 10.0 * seed_radius, 0.0], (count, 1)), seed_radius,
                     0.8e-3)
