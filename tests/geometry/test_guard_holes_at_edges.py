"""The guard's extent test at a scan hole that cuts through a thin edge (issue 19's compressor
blade: 2-mm holes through its 0.15-mm edges, refused for 0.36 mm where the fit was within
0.005 mm): a surface bridging the hole is not beyond the data, a beak beyond the edge still
is."""

from __future__ import annotations

import numpy as np

from steamtwin.geometry.fit_guard import local_excursion

HALF = 0.2e-3  # half thickness = edge radius (m)
SPACING = 0.1e-3


def _thin_plate_with_hole() -> tuple[np.ndarray, np.ndarray]:
    """Points (m) and outward normals of a 0.4-mm plate, x ≤ 0, closed by a half-cylinder
    edge at x = 0, z ∈ [−6, 6] mm, spacing 0.1 mm, without a 1-mm-radius ball about a point
    of the upper face 0.3 mm from the edge (the hole takes both faces and the edge)."""
    z = np.arange(-6e-3, 6e-3, SPACING)
    x = np.arange(-6e-3, 0.0, SPACING)
    turn = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 7)[1:-1]
    parts, normals = [], []
    for sign in (1.0, -1.0):
        xx, zz = np.meshgrid(x, z)
        parts.append(np.column_stack([xx.ravel(), np.full(xx.size, sign * HALF), zz.ravel()]))
        normals.append(np.tile([0.0, sign, 0.0], (xx.size, 1)))
    aa, zz = np.meshgrid(turn, z)
    parts.append(np.column_stack([HALF * np.cos(aa.ravel()), HALF * np.sin(aa.ravel()),
                                  zz.ravel()]))
    normals.append(np.column_stack([np.cos(aa.ravel()), np.sin(aa.ravel()),
                                    np.zeros(aa.size)]))
    points, normals = np.vstack(parts), np.vstack(normals)
    keep = np.linalg.norm(points - [-0.3e-3, HALF, 0.0], axis=1) > 1e-3
    return points[keep], normals[keep]


def test_a_surface_across_a_hole_through_an_edge_is_not_beyond_the_data() -> None:
    points, normals = _thin_plate_with_hole()
    upper = normals[:, 1] > 0.5
    # on the true upper face, inside the hole, nearer its rim towards mid-chord; and a beak
    # 0.4 mm beyond the edge where the edge is scanned
    samples = np.array([[-0.15e-3, HALF, 0.35e-3], [0.6e-3, 0.0, -4e-3]])
    sample_normals = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    without, _ = local_excursion(samples, sample_normals, points[upper], normals[upper],
                                 extent_points=points)
    with_axis, _ = local_excursion(samples, sample_normals, points[upper], normals[upper],
                                   extent_points=points, bridge_holes=True)
    assert without[0] > 0.2e-3  # the extent alone: beyond the points round the hole
    assert with_axis[0] < 0.03e-3  # bridged: points above and below reach as far out
    assert with_axis[1] == without[1] > 0.3e-3  # the beak stays (0.35 mm beyond the tip)
