"""A family blade's 80k cloud in a random pose, segmented in the frame found from the data, and
its exact sections in that frame — for the tests of the turn fraction round the sections
(issue 19)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from foreign_blades import ForeignBlade, family_blade, laser_cloud, random_pose

from steamtwin.geometry.frame import BladeFrame, estimate_blade_frame
from steamtwin.geometry.segmentation import Segmentation, segment_blade


@dataclass(frozen=True)
class PosedCloud:
    """``points`` (m) in the ``frame`` estimated from the cloud in the scan ``pose`` (4×4,
    scan ← blade) and their ``segmentation``."""

    blade: ForeignBlade
    pose: np.ndarray
    frame: BladeFrame
    points: np.ndarray
    segmentation: Segmentation

    def blade_height(self, selected: np.ndarray) -> float:
        """Median height (m) in the blade's own frame of the points under ``selected``."""
        scanned = self.frame.to_scan(self.points[selected])
        in_blade = (scanned - self.pose[:3, 3]) @ self.pose[:3, :3]
        return float(np.median(in_blade[:, 2]))

    def section(self, height: float) -> np.ndarray:
        """The exact section (x-y, m) at blade height ``height`` (m), in the estimated frame."""
        polygon = self.blade.section((height - self.blade.spec.hub_radius)
                                     / self.blade.spec.span).polygon(2e-7)
        at = np.column_stack([polygon, np.full(len(polygon), height)])
        return self.frame.to_blade(at @ self.pose[:3, :3].T + self.pose[:3, 3])[:, :2]


def posed_cloud(name: str, seed: int) -> PosedCloud:
    """The 80k-point cloud of family blade ``name`` and ``seed`` in the random pose of seed
    1000 + ``seed`` (as ``bench_foreign_blades.py``), segmented in its estimated frame."""
    blade = family_blade(name)
    scan, pose = random_pose(laser_cloud(blade, points=80_000, seed=seed).points, 1000 + seed)
    frame = estimate_blade_frame(scan)
    points = frame.to_blade(scan)
    return PosedCloud(blade, pose, frame, points, segment_blade(points))
