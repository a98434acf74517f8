"""The guard's extent test at a scan hole in a face whose rims lie along the span (issue 19's
compressor blade, 80k seed 0: two overlapping 2-mm holes over the hub corner, refused for
0.26 mm where the fit was within 0.004 mm): a surface across the hole is not beyond the data,
a beak beyond an edge and a spike off the face of the same size still are."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.fit_guard import half_plane_depth, local_excursion

SPACING = 0.1e-3
#: Two overlapping 2-mm holes one above the other (m), as on the compressor blade.
HOLES = np.array([[0.0, 0.0, 1.65e-3], [0.0, 0.0, 2.48e-3]])
NORMAL = np.array([0.0, 1.0, 0.0])


def _plate_with_holes() -> np.ndarray:
    """Points (m) of a flat face y = 0, x ∈ [−6, 6] mm, z ∈ [0, 12] mm (its lower end 0.65 mm
    below the holes), spacing 0.1 mm jittered by ±0.03 mm, without the two holes."""
    rng = np.random.default_rng(0)
    x, z = np.meshgrid(np.arange(-6e-3, 6e-3 + 1e-9, SPACING),
                       np.arange(0.0, 12e-3 + 1e-9, SPACING))
    points = np.column_stack([x.ravel(), np.zeros(x.size), z.ravel()])
    points[:, [0, 2]] += rng.uniform(-0.3, 0.3, (len(points), 2)) * SPACING
    return points[np.min(np.linalg.norm(points[:, None] - HOLES[None], axis=2), axis=1) > 1e-3]


def _excursion(points: np.ndarray, samples: np.ndarray, bridge: bool) -> np.ndarray:
    normals = np.tile(NORMAL, (len(points), 1))
    excursion, _ = local_excursion(samples, np.tile(NORMAL, (len(samples), 1)), points,
                                   normals, bridge_holes=bridge)
    return excursion


def test_a_surface_across_a_hole_is_bridged_where_its_rims_lie_above_and_below() -> None:
    points = _plate_with_holes()
    # on the face inside the holes, 0.2–0.3 mm from their lower and upper rims
    samples = np.array([[0.1e-3, 0.0, 0.9e-3], [0.3e-3, 0.0, 1.0e-3], [-0.3e-3, 0.0, 1.0e-3],
                        [0.0, 0.0, 3.2e-3]])
    alone = _excursion(points, samples, bridge=False)
    bridged = _excursion(points, samples, bridge=True)
    # the extent alone: beyond the points round the hole by 0.15–0.25 mm (the former rule,
    # points as far out above and below along the section's tangent, left the three near the
    # lower rim at 0.17–0.21 mm)
    assert np.all(alone > 0.12e-3)
    assert np.all(bridged < 0.03e-3)


@pytest.mark.parametrize("where", ["beak beyond the edge", "spike off the face",
                                   "spike over the hole"])
def test_a_beak_or_spike_of_the_same_size_is_still_seen(where: str) -> None:
    points = _plate_with_holes()
    sample = {"beak beyond the edge": [6.2e-3, 0.0, 6.0e-3],
              "spike off the face": [3.0e-3, 0.2e-3, 6.0e-3],
              "spike over the hole": [0.0, 0.2e-3, 2.0e-3]}[where]
    bridged = _excursion(points, np.array([sample]), bridge=True)
    assert bridged[0] > 0.15e-3
    assert bridged[0] == pytest.approx(_excursion(points, np.array([sample]), bridge=False)[0])


def test_half_plane_depth_of_a_ring_and_of_a_half_disc() -> None:
    turn = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False) + 0.01
    ring = np.column_stack([np.cos(turn), np.sin(turn)])
    assert half_plane_depth(ring) == 19  # an open half-plane holds 19 or 20 of the 40
    assert half_plane_depth(ring[np.cos(turn) > 0.1]) == 0  # all on one side of the origin
    assert half_plane_depth(np.empty((0, 2))) == 0
