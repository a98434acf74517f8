"""The guard's outward reading at a tight edge (issue 19: slender 80k seed 2, a vertex on a
0.15-mm trailing-edge circle whose only facing points lie on the flank, turned 58°, 0.64–0.73
mm off its normal line): a convex surface through such a point drops anywhere from 0 to
l·tan θ by the vertex's normal line, so a vertex on the circle is no beak — one standing 0.5
mm out along its normal still is."""

from __future__ import annotations

import math

import numpy as np

from steamtwin.geometry.fit_guard import local_excursion

RADIUS = 0.15e-3  # edge circle (m)
ROWS = 0.23e-3  # spacing of the sections along the edge (m)
FIRST = 1.0e-3  # the flanks' points start this far below the circle's centre (m)


def _edge() -> tuple[np.ndarray, np.ndarray]:
    """Points (m) and outward normals of a U-shaped edge along y: flat flanks x = ±RADIUS
    sampled every 0.25 mm from z = −FIRST down to −3 mm (the circle of RADIUS about the origin
    in x-z, apex +z, holds no point), sections every :data:`ROWS` along y."""
    y = (np.arange(-10, 10) + 0.4) * ROWS
    profile, normals = [], []
    for depth in np.arange(FIRST, 3e-3, 0.25e-3):
        for side in (1.0, -1.0):
            profile.append([side * RADIUS, 0.0, -depth])
            normals.append([side, 0.0, 0.0])
    profile, normals = np.array(profile), np.array(normals)
    points = (profile[None, :, :] + y[:, None, None] * np.array([0.0, 1.0, 0.0])).reshape(-1, 3)
    return points, np.tile(normals, (len(y), 1))


def test_a_vertex_on_a_tight_edge_circle_is_no_beak() -> None:
    """A vertex on the circle 32° round from the apex (its facing points turned 58°) reads
    within its allowance; the arc's l·tan(θ/2) alone read it 0.20 mm beyond (a false alarm
    over the 0.1-mm limit). 0.5 mm out along its normal it reads more than 0.2 mm beyond."""
    points, normals = _edge()
    turn = math.radians(32.0)
    normal = np.array([math.sin(turn), 0.0, math.cos(turn)])
    samples = np.array([RADIUS * normal, (RADIUS + 0.5e-3) * normal])
    excursion, allowance = local_excursion(samples, np.tile(normal, (2, 1)), points, normals)
    assert excursion[0] - allowance[0] < 0.0
    assert excursion[1] - allowance[1] > 0.2e-3
