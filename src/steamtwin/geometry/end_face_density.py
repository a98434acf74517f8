"""The density an end face needs before its normals can be found (issue 19, item 3).

An end face (hub or tip cap) is found from k-NN normals (PCA of each point's ``k`` nearest
neighbours, Hoppe et al. 1992, SIGGRAPH): a cap point's normal lies along the span only while
its neighbours lie on the cap. The cap of a thin blade is a strip as wide as the end section is
thick, t; a point on its middle line keeps its ``k`` neighbours on the strip only when they
reach no farther than t / 2. So where the ``k``-th neighbour's distance r_k exceeds half the
end section's largest thickness, no point of the face can have a clean normal, and the cloud
must be denser by (2·r_k / t)² (the points in a disc grow with its area: r_k ∝ ρ^−½). This is a
lower bound — the face's rims, noise and outliers need more — and it is measured on the cloud
(r_k and t), not assumed.

:func:`end_face_need` gives the figure for a refusal that found no end face
(:func:`~steamtwin.geometry.frame.estimate_blade_frame`, :func:`~steamtwin.geometry.segmentation.
segment_blade`), so that a cloud refused at its caps says, like one refused at its edges
(:mod:`.edge_density`), how dense the scan must be.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.spatial import cKDTree

from steamtwin.geometry.filters import plane_basis

#: Slabs along the end section's length in which its thickness is measured (each ~1/8 of the
#: chord).
THICKNESS_BINS = 8
#: Fewest points in a slab for its thickness to count.
MIN_BIN_POINTS = 10
#: Height of the end's section band (point spacings from the extreme end): as
#: ``segmentation.cap_patch_minimum``'s outline of the section there.
END_BAND = 3.0


def section_thickness(xy: np.ndarray) -> float:
    """Largest thickness (m) of a thin section from its points (n, 2; m): a cubic through all
    points across its principal axis (the camber line: a strip along a circular arc turning
    0°–86° reads within 0.96–1.0 × its width, ``tests/geometry/test_end_face_density.py``),
    then in each of
    :data:`THICKNESS_BINS` slabs along the axis the 2nd–98th percentile width of the offsets
    from it, times the cosine of its slope there; the largest over slabs with at least
    :data:`MIN_BIN_POINTS` points (0 when none has)."""
    xy = np.asarray(xy, dtype=float)
    if len(xy) < MIN_BIN_POINTS:
        return 0.0
    centred = xy - xy.mean(axis=0)
    axes = np.linalg.svd(centred, full_matrices=False)[2]
    along, across = centred @ axes[0], centred @ axes[1]
    camber = np.polynomial.Polynomial.fit(along, across, 3)
    offset = across - camber(along)
    edges = np.linspace(along.min(), along.max(), THICKNESS_BINS + 1)
    widths = [0.0]
    for lo, hi in itertools.pairwise(edges):
        inside = (along >= lo) & (along <= hi)
        if inside.sum() < MIN_BIN_POINTS:
            continue
        low, high = np.percentile(offset[inside], [2.0, 98.0])
        slope = float(camber.deriv()(0.5 * (lo + hi)))
        widths.append(float((high - low) / math.hypot(1.0, slope)))
    return max(widths)


def end_face_need(points: np.ndarray, axis: np.ndarray, end: float, spacing: float,
                  neighbours: int) -> str:
    """A refusal's figure for an end face not found: the end section's largest thickness, the
    reach of a point's ``neighbours`` nearest neighbours there and the density the face needs
    (module docstring), e.g. "the end section is at most 2.41 mm thick and a point's 20 nearest
    neighbours reach 1.71 mm: the face's normals need ≥ 2.0 × this scan's density"; "" when the
    neighbours already fit within half the thickness (the face is missed for another reason).

    ``points`` (n, 3; m), ``axis`` the span axis (unit), ``end`` the end's height along it (m),
    ``spacing`` the cloud's point spacing (m).
    """
    points = np.asarray(points, dtype=float)
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    height = points @ axis
    band = np.abs(height - end) < END_BAND * spacing
    if band.sum() <= neighbours:
        return ""
    thickness = section_thickness(points[band] @ plane_basis(axis).T)
    near = np.abs(height - end) < END_BAND * spacing + 10.0 * spacing
    reach = float(np.median(cKDTree(points[near]).query(points[band], k=neighbours + 1)[0][:, -1]))
    if thickness <= 0.0 or 2.0 * reach <= thickness:
        return ""
    return (f"the end section is at most {thickness * 1e3:.2f} mm thick and a point's "
            f"{neighbours} nearest neighbours reach {reach * 1e3:.2f} mm: the face's normals "
            f"need ≥ {(2.0 * reach / thickness) ** 2:.1f} × this scan's density (the neighbours "
            "within half the thickness)")
