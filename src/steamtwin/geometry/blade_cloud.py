"""A blade cloud as the reconstruction takes it: :class:`ReconstructionError`, which every
reconstruction step raises, and the input check :func:`check_blade_cloud` (lengths in m)."""

from __future__ import annotations

import math

import numpy as np

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.pointcloud import PointCloudError, check_point_cloud

#: Fewest points a blade cloud must have to be reconstructed.
MIN_POINTS = 2000


class ReconstructionError(GeometryAreaError):
    """A cloud that cannot be segmented or reconstructed; the message names the problem."""


def check_blade_cloud(points: np.ndarray, source: str = "point cloud") -> np.ndarray:
    """Validate a cloud for reconstruction: finite, at least :data:`MIN_POINTS` points, not flat.

    Raises :class:`ReconstructionError` naming the problem.
    """
    try:
        points = check_point_cloud(points, source)
    except PointCloudError as error:
        raise ReconstructionError(str(error)) from None
    if len(points) < MIN_POINTS:
        raise ReconstructionError(f"{source}: only {len(points)} points; reconstructing a "
                                  f"blade needs at least {MIN_POINTS}")
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred[:: max(1, len(points) // 20000)], compute_uv=False)
    if singular[2] < 1e-3 * singular[0]:
        raise ReconstructionError(f"{source}: the cloud is flat (all points within "
                                  f"{singular[2] / math.sqrt(len(centred)) * 1e3:.3g} mm of a "
                                  "plane), not a blade")
    return points
