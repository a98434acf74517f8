"""The points of a blade's flat end face among the cap-like points near one end of its span.

Cap-like points (k-NN normals within 20° of the span axis) near an end are mostly end-face
points, but at a thin, sparsely sampled edge many side points have tilted normals too — over a
tenth of the span on a 250 mm blade (issue 19) — and a least-squares plane through them all
turns away from the end face. The end face lies within the height that a plane up to a small
tilt off perpendicular to the axis spans over the points' extent across it (plus four point
spacings of noise) from the extreme end; the side points beyond are left out. Used by the
frame from the data (:mod:`steamtwin.geometry.frame`) and by the segmentation's caps where no
smooth patch forms on a narrow end face (:mod:`steamtwin.geometry.segmentation`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["END_FACE_TILT", "end_face_points"]

#: The end face's tilt off perpendicular to the axis that the window allows: the twist and
#: taper of our rows tilt the side normals' axis by up to 2.3° off the end planes (hp5); issue
#: 19's compressor blade by 4.8–7.2°, where the window holds a part of the end face only,
#: which gives the same plane (:mod:`steamtwin.geometry.frame`). In the blade frame the axis is
#: the end planes' own normal.
END_FACE_TILT = math.radians(5.0)


def end_face_points(members: np.ndarray, axis: np.ndarray, low: bool, spacing: float,
                    tilt: float = END_FACE_TILT) -> np.ndarray:
    """The cap-like points ``members`` (n, 3; m) that can lie on the end face at the low
    (``low``) or high end of the unit ``axis``: within extent × sin(``tilt``) + 4 ``spacing``
    (m) of the extreme end (the 1st / 99th percentile of height, clear of stray points), the
    extent being the points' reach across the axis."""
    if len(members) < 3:
        return members
    height = members @ axis
    across = members - np.outer(height, axis)
    extent = float(np.linalg.norm(np.ptp(across, axis=0)))
    reach = extent * math.sin(tilt) + 4.0 * spacing
    end = np.percentile(height, 1.0 if low else 99.0)
    return members[np.abs(height - end) <= reach]
