"""The guard's extent test at a scan hole that cuts a thin edge whose rims lie only along the
edge (issue 19's compressor blade, 80k seed 5: a 2-mm hole across its 0.15-mm leading edge,
refused for 0.25 mm where the fit was within 0.017 mm — the far rim 1.2 mm down the edge, beyond
the reach of a surrounding rim): a surface across the hole is not beyond the data; a beak of the
same size beyond the edge, one reaching into the hole from its rim, a fin beyond the edge in the
plane of a face and one beyond the tip still are."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.fit_guard import local_excursion

RADIUS = 0.15e-3  # edge radius = half thickness (m)
#: A 1-mm-radius ball about a point of the upper face 0.5 mm behind the nose (m): on the nose
#: line the hole runs from z = −0.75 to 0.75 mm.
HOLE = np.array([-0.5e-3, RADIUS, 0.0])
TOP = 5e-3  # the plate's tip (m)


def _edge_with_hole() -> tuple[np.ndarray, np.ndarray]:
    """Points (m) and outward normals of a 0.3-mm plate, x ∈ [−4, 0] mm, closed by a
    half-cylinder edge of radius 0.15 mm about x = 0, z ∈ [−5, 5] mm, sampled uniformly at
    random, 100 points per mm² (0.1-mm spacing), without the hole."""
    rng = np.random.default_rng(1)
    density = 100e6
    parts, normals = [], []
    for sign in (1.0, -1.0):
        count = round(density * 4e-3 * 2 * TOP)
        xz = rng.uniform([-4e-3, -TOP], [0.0, TOP], (count, 2))
        parts.append(np.column_stack([xz[:, 0], np.full(count, sign * RADIUS), xz[:, 1]]))
        normals.append(np.tile([0.0, sign, 0.0], (count, 1)))
    count = round(density * np.pi * RADIUS * 2 * TOP)
    turn = rng.uniform(-0.5 * np.pi, 0.5 * np.pi, count)
    z = rng.uniform(-TOP, TOP, count)
    parts.append(np.column_stack([RADIUS * np.cos(turn), RADIUS * np.sin(turn), z]))
    normals.append(np.column_stack([np.cos(turn), np.sin(turn), np.zeros(count)]))
    points, normals = np.vstack(parts), np.vstack(normals)
    keep = np.linalg.norm(points - HOLE, axis=1) > 1e-3
    return points[keep], normals[keep]


def _excursion(samples: np.ndarray, sample_normals: np.ndarray, bridge: bool) -> np.ndarray:
    points, normals = _edge_with_hole()
    excursion, _ = local_excursion(samples, sample_normals, points, normals,
                                   extent_points=points, bridge_holes=bridge)
    return excursion


def test_a_surface_across_a_hole_through_a_thin_edge_is_not_beyond_the_data() -> None:
    # on the nose line inside the hole, 0.2–0.3 mm below its upper rim (z = 0.75 mm), and
    # one 0.25 mm into the hole from the side of its lower rim
    samples = np.array([[RADIUS, 0.0, 0.45e-3], [RADIUS, 0.0, 0.55e-3],
                        [RADIUS * np.cos(0.3), RADIUS * np.sin(0.3), 0.5e-3],
                        [RADIUS, 0.0, -0.5e-3]])
    sample_normals = np.column_stack([samples[:, :2] / RADIUS, np.zeros(len(samples))])
    alone = _excursion(samples, sample_normals, bridge=False)
    bridged = _excursion(samples, sample_normals, bridge=True)
    assert np.all(alone > 0.15e-3)  # the extent alone: all the points near it lie above
    assert np.all(bridged < 0.03e-3)


@pytest.mark.parametrize("where", ["beak beyond the edge", "beak into the hole",
                                   "fin beyond the edge", "beak beyond the tip"])
def test_a_beak_of_the_same_size_at_a_thin_edge_is_still_seen(where: str) -> None:
    sample, normal = {
        "beak beyond the edge": ([RADIUS + 0.3e-3, 0.0, 3.0e-3], [1.0, 0.0, 0.0]),
        # from the upper rim into the hole, 0.3 mm out beyond the nose line
        "beak into the hole": ([RADIUS + 0.3e-3, 0.0, 0.5e-3], [1.0, 0.0, 0.0]),
        # in the plane of the upper face, 0.3 mm beyond the nose, facing as the face
        "fin beyond the edge": ([RADIUS + 0.3e-3, RADIUS, 3.0e-3], [0.0, 1.0, 0.0]),
        "beak beyond the tip": ([RADIUS, 0.0, TOP + 0.3e-3], [1.0, 0.0, 0.0]),
    }[where]
    samples, normals = np.array([sample]), np.array([normal])
    bridged = _excursion(samples, normals, bridge=True)
    if where == "beak into the hole":
        # surrounded in its tangent plane (the rims above and below, the faces beside): the
        # extent is bridged, the height over the rims stays (0.35 mm without the bridging)
        assert bridged[0] > 0.18e-3
    else:
        assert bridged[0] > 0.25e-3
        assert bridged[0] == pytest.approx(_excursion(samples, normals, bridge=False)[0])
