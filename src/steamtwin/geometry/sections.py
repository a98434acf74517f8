"""Order round the sections where the ring of a blade's side is broken at a thin edge.

:func:`~steamtwin.geometry.segmentation.section_turn` measures the turn fraction round each
section by geodesic paths that start below the leading edge, run once round the section
through the trailing edge and come back above it. At a thin, sparsely sampled edge (a
0.15 mm radius at 0.23 mm spacing, issue 19's slender blade) the neighbour graph does not go
round the edge — neighbours there have normals more than 75° apart — and the paths reach the
far face only through holes and stray links, out of order: the fit of such a parametrisation
folds. This module gives an order that needs no path round either edge:

- the points are split into the two faces by their outward normals — the pressure face's
  point to the right of the section's own chord line (front to rear end, whatever the
  stagger), the suction face's to the left — and the graph keeps the edges within a face;
- on each face the geodesic distances d_f from the front end and d_r from the rear end
  (Dijkstra 1959 on the neighbour graph, as section_turn; graph distances converge to
  geodesic ones, Tenenbaum, de Silva & Langford 2000) give the arc-length fraction along the
  face, φ = d_f / (d_f + d_r), monotone from one end to the other;
- the faces' lengths L = d_f + d_r (medians in slabs along the span) give their shares of the
  perimeter, and θ follows section_turn's convention: the rear end at 0, the suction face
  (above the ends, +y) anticlockwise to the front end at 1 − a, the pressure face on to 1,
  a the pressure face's median share.

:func:`tour_ratio` says whether an order is broken: the length of the closed polyline through
a thin slab's points in θ order over the slab's perimeter, ≈ 1–1.5 when the order follows the
section (noise makes the polyline zig-zag) and several times that when it jumps between the
faces.
"""

from __future__ import annotations

import numpy as np

from steamtwin.geometry.segmentation import ReconstructionError, _slab_median

#: A θ order whose median :func:`tour_ratio` exceeds this is broken (an order that follows the
#: section zig-zags by 1.2–1.6 on 80k-point clouds with σ 0.017 mm noise; a broken one by 5–13).
BROKEN_TOUR = 2.0
#: Fewest points of a face reached from both ends for the order by faces.
MIN_FACE_POINTS = 100
#: Thin slabs along the span in which :func:`tour_ratio` is measured.
TOUR_SLABS = 12


def tour_ratio(points: np.ndarray, mask: np.ndarray, turn: np.ndarray, perimeter: np.ndarray,
               height: float) -> float:
    """Median over :data:`TOUR_SLABS` slabs ``height`` (m) thick, spread over the span of the
    points under ``mask``, of the closed polyline length through the slab's points in ``turn``
    order over the slab's median ``perimeter`` (m); slabs with fewer than 20 points are
    skipped (ratio 1 when none is left)."""
    z = points[:, 2]
    ratios = []
    for centre in np.linspace(np.percentile(z[mask], 2.0), np.percentile(z[mask], 98.0),
                              TOUR_SLABS):
        members = np.flatnonzero(mask & (np.abs(z - centre) < 0.5 * height)
                                 & np.isfinite(turn) & np.isfinite(perimeter))
        if len(members) < 20:
            continue
        xy = points[members[np.argsort(turn[members])], :2]
        length = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1).sum()
        ratios.append(length / float(np.median(perimeter[members])))
    return float(np.median(ratios)) if ratios else 1.0


def two_face_turn(points: np.ndarray, normals: np.ndarray, mask: np.ndarray, lo: np.ndarray,
                  hi: np.ndarray, length: np.ndarray, front: np.ndarray, rear: np.ndarray,
                  seed_radius: float, slab: float) -> tuple[np.ndarray, np.ndarray]:
    """Turn fraction θ ∈ [0, 1) of the points under ``mask`` and their section's perimeter (m;
    NaN elsewhere), from the faces between the front and rear ends (module docstring).

    ``normals``: outward unit normals (n, 3); ``lo``, ``hi``, ``length``: the neighbour
    graph's edges and their lengths (m), as section_turn builds them (normals agreeing, chords
    tangential); ``front``, ``rear``: the sections' ends (x-y at every point's z, m);
    ``seed_radius`` (m): the reach of the seeds at the ends; ``slab`` (m): the slabs along the
    span of the face lengths. Raises :class:`ReconstructionError` when a face is not reached
    from both ends.
    """
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    count = len(points)
    chord = rear - front
    left = np.column_stack([-chord[:, 1], chord[:, 0]])
    # the faces by their outward normals: the pressure face's point right of the chord line
    # (seen from the front end), the suction face's left; edges join points of one face only
    pressure = np.einsum("ij,ij->i", normals[:, :2], left) < 0.0
    same = pressure[lo] == pressure[hi]
    graph = coo_array((np.concatenate([length[same], length[same]]),
                       (np.concatenate([lo[same], hi[same]]),
                        np.concatenate([hi[same], lo[same]]))), shape=(count, count)).tocsr()
    distance = {}
    for name, end in (("front", front), ("rear", rear)):
        seed = mask & (np.linalg.norm(points[:, :2] - end, axis=1) < seed_radius)
        for face, side in (("pressure", pressure), ("suction", ~pressure)):
            sources = np.flatnonzero(seed & side)
            if sources.size == 0:
                raise ReconstructionError(
                    f"no side points at the {name} end of the sections on the {face} side: is "
                    f"the {'leading' if name == 'front' else 'trailing'} edge scanned?")
            distance[name, face] = np.where(side, dijkstra(graph, indices=sources,
                                                           min_only=True), np.inf)
    total = np.where(pressure, distance["front", "pressure"] + distance["rear", "pressure"],
                     distance["front", "suction"] + distance["rear", "suction"])
    reached = mask & np.isfinite(total)
    if np.mean(reached[mask]) < 0.9:
        raise ReconstructionError("the side points do not join the sections' ends: the faces "
                                  "are not reached from both the leading and the trailing edge "
                                  "(a hole across the whole span?)")
    face_length = {}
    for face, on in (("pressure", pressure), ("suction", ~pressure)):
        chosen = reached & on
        if np.sum(chosen) < MIN_FACE_POINTS:
            raise ReconstructionError(
                f"only {int(np.sum(chosen))} side points on the {face} side are reached from "
                "both the leading and the trailing edge: the sections cannot be ordered by "
                "their faces")
        face_length[face] = _slab_median(points[chosen, 2], total[chosen], points[:, 2], slab)
    perimeter = np.full(count, np.nan)
    perimeter[mask] = (face_length["pressure"] + face_length["suction"])[mask]
    share = float(np.median((face_length["pressure"] / perimeter)[mask]))
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.where(pressure, distance["front", "pressure"],
                            distance["rear", "suction"]) / total
    turn = np.full(count, np.nan)
    turn[reached] = np.where(pressure[reached], 1.0 - share + fraction[reached] * share,
                             fraction[reached] * (1.0 - share))
    turn[reached] = np.mod(turn[reached], 1.0)
    missed = mask & ~reached
    if np.any(missed):
        _, nearest = cKDTree(points[reached]).query(points[missed])
        turn[missed] = turn[reached][nearest]
    return turn, perimeter
