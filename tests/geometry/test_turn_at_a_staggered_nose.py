"""The turn fraction next to the tip of a blade whose faces both leave the front end upwards
(issue 19: the slender family blade, 50° staggered at the tip, in a random pose).

There a line y = y_front through the most upstream point crosses the lower face again within a
millimetre; cut along it, the ring's paths reached most of that face only by a detour along
the span, and the face's turn was squeezed into a tenth of the turn (its share is about a
half), so the side's start parameters ran 20 mm off and the fit folded. Cut along the line
into the nose, each face's turn follows its arc length."""

from __future__ import annotations

import numpy as np
from foreign_blades import family_blade, laser_cloud, random_pose
from scipy.spatial import cKDTree

from steamtwin.geometry.frame import estimate_blade_frame
from steamtwin.geometry.segmentation import segment_blade


def _arc_fractions(blade, frame, pose: np.ndarray, height: float, xy: np.ndarray
                   ) -> tuple[np.ndarray, float, float]:
    """Arc fraction of the exact section at blade height ``height`` (m) nearest to each
    frame point ``xy`` (m), counted round the section from its first vertex, and the arc
    fractions of the section's most upstream and most downstream points in the frame."""
    polygon = blade.section((height - blade.spec.hub_radius) / blade.spec.span).polygon(2e-7)
    in_frame = frame.to_blade(np.column_stack([polygon, np.full(len(polygon), height)])
                              @ pose[:3, :3].T + pose[:3, 3])[:, :2]
    steps = np.linalg.norm(np.diff(np.vstack([in_frame, in_frame[:1]]), axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])[:-1] / steps.sum()
    nearest = cKDTree(in_frame).query(xy)[1]
    return arc[nearest], arc[np.argmin(in_frame[:, 0])], arc[np.argmax(in_frame[:, 0])]


def test_each_face_keeps_its_share_of_the_turn_next_to_the_tip():
    blade = family_blade("slender")
    cloud = laser_cloud(blade, points=80_000, seed=5)
    scan, pose = random_pose(cloud.points, 1005)
    frame = estimate_blade_frame(scan)
    points = frame.to_blade(scan)
    segmentation = segment_blade(points)
    ordered = np.isfinite(segmentation.turn)
    top = float(points[ordered, 2].max())
    spreads = {}
    for depth in (12e-3, 6e-3):  # slabs 12 and 6 mm below the tip cap, 1 mm thick
        slab = ordered & (np.abs(points[:, 2] - (top - depth)) < 0.5e-3)
        blade_height = float(np.median(((frame.to_scan(points[slab]) - pose[:3, 3])
                                        @ pose[:3, :3])[:, 2]))
        arc, front, rear = _arc_fractions(blade, frame, pose, blade_height, points[slab, :2])
        # the face from the front end to the rear end, in the order of the section's vertices
        first = np.mod(arc - front, 1.0) < np.mod(rear - front, 1.0)
        for name, face in (("first", first), ("second", ~first)):
            share = np.mod(rear - front, 1.0) if name == "first" else np.mod(front - rear, 1.0)
            turn = segmentation.turn[slab][face]
            # the face's turn unwrapped about its median, so a face across θ = 0 is one range
            centred = np.mod(turn - np.median(turn) + 0.5, 1.0)
            spread = float(np.percentile(centred, 95) - np.percentile(centred, 5))
            spreads[depth, name] = spread / (0.9 * share)
    # measured 1.01–1.10 (cut along y = y_front: 0.17–0.23 on the squeezed face, 0.99–1.01)
    assert all(0.7 < ratio < 1.4 for ratio in spreads.values()), spreads
