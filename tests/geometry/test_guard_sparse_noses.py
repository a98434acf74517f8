"""The guard's inward reading at a sparse round nose (issue 19: a 0.2-mm edge circle with
points 0.2–0.5 mm apart across it): a surface that rounds the nose right is not inside, one
0.13 mm inside it is — whatever the spacing of the points across the nose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from steamtwin.geometry.fit_guard import local_excursion

RADIUS = 0.2e-3  # edge circle (m)
ROWS = 0.25e-3  # spacing of the sections along the edge (m)
DEPTH = 0.13e-3  # how far the wrong surface lies inside the nose (m)


def _nose(turns_deg: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Points (m) and outward normals of a U-shaped edge along y: the circle of
    :data:`RADIUS` about the origin in x-z (apex at z = RADIUS, normal +z), sampled at
    ±``turns_deg`` from the apex, and two flat flanks x = ±RADIUS, z ≤ 0, every 0.25 mm down to
    1.5 mm; sections every :data:`ROWS` along y, none through the apex sample at y = 0."""
    y = (np.arange(-10, 10) + 0.4) * ROWS
    profile, normals = [], []
    for turn in np.radians(turns_deg):
        for side in (1.0, -1.0):
            n = np.array([side * math.sin(turn), 0.0, math.cos(turn)])
            profile.append(RADIUS * n)
            normals.append(n)
    for depth in np.arange(0.0, 1.5e-3, 0.25e-3):
        for side in (1.0, -1.0):
            profile.append(np.array([side * RADIUS, 0.0, -depth]))
            normals.append(np.array([side, 0.0, 0.0]))
    profile, normals = np.array(profile), np.array(normals)
    points = (profile[None, :, :] + y[:, None, None] * np.array([0.0, 1.0, 0.0])).reshape(-1, 3)
    return points, np.tile(normals, (len(y), 1))


@pytest.mark.parametrize("turns_deg", [
    (70.0,),  # no point within 60° of the apex (slender 80k seed 0's leading edge)
    (35.0, 70.0),  # points on the arc facing the apex (lean-sweep 40k seed 3's)
])
def test_a_sparse_round_nose_is_read_to_the_surface_not_the_arc(turns_deg) -> None:
    """At the apex, a sample on the circle reads at most noise-free zero beyond its allowance,
    and one 0.13 mm inside reads 0.13 mm with no arc allowance to hide it. The tangent planes
    alone read the arc's drop R(1 − cos θ), 0.13 mm at 70° (a false alarm where no point
    faced the apex); the outward envelope's arc allowance, 0.09 mm with the points at 35°,
    hid most of the depth (a miss)."""
    points, normals = _nose(turns_deg)
    up = np.array([0.0, 0.0, 1.0])
    samples = np.array([RADIUS * up, (RADIUS - DEPTH) * up])
    excursion, allowance = local_excursion(samples, np.tile(up, (2, 1)), points, normals)
    assert excursion[0] - allowance[0] < 0.005e-3  # the right surface is not off the nose
    assert excursion[1] - allowance[1] == pytest.approx(DEPTH, abs=0.005e-3)
