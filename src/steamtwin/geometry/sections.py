"""Order round the sections where the ring of a blade's side is broken at a thin edge.

:func:`~steamtwin.geometry.sections.section_turn` measures the turn fraction round each
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
faces — at the median slab or in a slab next to either end of the span.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.orientation import neighbour_chords

#: A θ order whose median :func:`tour_ratio` exceeds this is broken (an order that follows the
#: section zig-zags by 1.2–1.6 on 80k-point clouds with σ 0.017 mm noise; a broken one by 5–13).
BROKEN_TOUR = 2.0
#: Fewest points of a face reached from both ends for the order by faces.
MIN_FACE_POINTS = 100
#: Thin slabs along the span in which :func:`tour_ratio` is measured.
TOUR_SLABS = 12
#: Slabs next to each end of the span judged one by one in :func:`tour_ratio` (the outer
#: sixth of the span at each end).
END_SLABS = 2
#: Passes of neighbour averaging of the path lengths in :func:`section_turn`.
SMOOTHING_PASSES = 3
#: Reach of :func:`nose_directions` round the front end, in seed radii (about three k-th
#: neighbour distances: points of both faces, short of a blade's mid-chord).
NOSE_REACH = 3.0
#: Fewest points round the front end of a slab for :func:`nose_directions`.
MIN_NOSE_POINTS = 10


def tour_ratios(points: np.ndarray, mask: np.ndarray, turn: np.ndarray, perimeter: np.ndarray,
                height: float) -> np.ndarray:
    """In :data:`TOUR_SLABS` slabs ``height`` (m) thick, spread over the span of the points
    under ``mask`` (from the low end up), the closed polyline length through the slab's points
    in ``turn`` order over the slab's median ``perimeter`` (m); NaN in slabs with fewer than 20
    points."""
    z = points[:, 2]
    ratios = np.full(TOUR_SLABS, np.nan)
    for slab, centre in enumerate(np.linspace(np.percentile(z[mask], 2.0),
                                              np.percentile(z[mask], 98.0), TOUR_SLABS)):
        members = np.flatnonzero(mask & (np.abs(z - centre) < 0.5 * height)
                                 & np.isfinite(turn) & np.isfinite(perimeter))
        if len(members) < 20:
            continue
        xy = points[members[np.argsort(turn[members])], :2]
        length = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1).sum()
        ratios[slab] = length / float(np.median(perimeter[members]))
    return ratios


def tour_ratio(points: np.ndarray, mask: np.ndarray, turn: np.ndarray, perimeter: np.ndarray,
               height: float) -> float:
    """How broken an order is: the larger of the median of :func:`tour_ratios` and of the
    largest in the :data:`END_SLABS` slabs next to either end of the span (ratio 1 when no slab
    has points). A ring broken at a thin edge is broken over the whole span (the median) or
    from the end where the edge is thinnest inwards (issue 19, lean-sweep 80k seeds 2–3:
    4.2 and 2.2 next to one end, 1.5 at the median); a single slab up to 2.3 in mid-span is the
    zig-zag of a sparse scan's noisy points (the hp1 quick scan, 10k points), not a break."""
    ratios = tour_ratios(points, mask, turn, perimeter, height)
    if np.all(np.isnan(ratios)):
        return 1.0
    ends = np.concatenate([ratios[:END_SLABS], ratios[-END_SLABS:]])
    return float(max(np.nanmedian(ratios), np.nanmax(ends) if np.any(np.isfinite(ends))
                     else 0.0))


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
        face_length[face] = slab_median(points[chosen, 2], total[chosen], points[:, 2], slab)
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


def section_chords(points: np.ndarray, mask: np.ndarray, slab: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Front and rear ends (x-y) of the sections, at every point's z.

    The ends are the most upstream and the most downstream points (smallest and largest axial
    x): on a Pritchard section they lie on the leading- and trailing-edge circles whatever the
    stagger and camber (each edge arc faces through the axial direction), where the farthest
    pair of points may end on the bulge of a strongly cambered suction side. The points under
    ``mask`` are cut into slabs ``slab`` (m) high; in each, stray points (the 4th nearest
    neighbour in the slab farther than 4 × the slab's median) are set aside and each end is the
    mean of the three extreme points. The ends of all slabs are then fitted by cubics in z,
    dropping slabs more than 3 robust standard deviations off (a hole in the scan or a stray
    point moves one slab's end). Returns ``(front (n, 2), rear (n, 2), slab centres)``.
    """
    z = points[mask, 2]
    edges = np.arange(z.min(), z.max() + slab, slab)
    centres, ends = [], []
    for lo, hi in itertools.pairwise(edges):
        xy = points[mask][(z >= lo) & (z < hi), :2]
        if len(xy) < 20:
            continue
        fourth = cKDTree(xy).query(xy, k=5)[0][:, -1]
        xy = xy[fourth < 4.0 * np.median(fourth)]
        order = np.argsort(xy[:, 0])
        centres.append(0.5 * (lo + hi))
        ends.append(np.concatenate([xy[order[:3]].mean(axis=0), xy[order[-3:]].mean(axis=0)]))
    if len(centres) < 2:
        raise ReconstructionError("too few side points to find the sections' chords")
    centres, ends = np.array(centres), np.array(ends)
    scale = max(float(np.ptp(centres)), 1e-9)
    u = (centres - centres.mean()) / scale
    degree = min(3, len(centres) - 1)
    keep = np.ones(len(centres), dtype=bool)
    for _ in range(4):
        coef = np.polynomial.polynomial.polyfit(u[keep], ends[keep], degree)
        miss = np.linalg.norm(ends - np.polynomial.polynomial.polyval(u, coef).T, axis=1)
        bound = 3.0 * 1.4826 * np.median(miss[keep]) + 1e-6 * scale
        if np.array_equal(miss < bound, keep) or (miss < bound).sum() <= degree:
            break
        keep = miss < bound
    fitted = np.polynomial.polynomial.polyval((points[:, 2] - centres.mean()) / scale, coef).T
    return fitted[:, :2], fitted[:, 2:], centres


def nose_directions(points: np.ndarray, mask: np.ndarray, front: np.ndarray,
                    offset: np.ndarray, seed_radius: float, slab: float) -> np.ndarray:
    """Unit x-y direction (n, 2) from the sections' front end into the nose at every point's
    z: the bisector of the directions in which the two faces leave the front end. Per slab
    ``slab`` (m) high along the span, the directions from the front end to the points under
    ``mask`` between 1 and :data:`NOSE_REACH` ``seed_radius`` (m) from it (``offset``, m)
    span an angle from one face to the other (5th to 95th percentile, so stray points and
    unequal numbers on the faces do not move it); its middle is the bisector, interpolated
    along the span. It is +x on a round nose, and runs between the faces where the axial
    direction runs along one: at high stagger both faces leave the most upstream point upwards
    (or downwards), and a line y = y_front through it crosses the lower face again within a
    millimetre (issue 19, a slender blade 50° staggered at the tip). +x where no slab has
    :data:`MIN_NOSE_POINTS` such points."""
    relative = points[:, :2] - front
    angle = np.arctan2(relative[:, 1], relative[:, 0])
    # points upstream of the front end are strays (it is the most upstream point)
    near = (mask & (offset > seed_radius) & (offset < NOSE_REACH * seed_radius)
            & (np.abs(angle) < 0.5 * math.pi))
    z, angle = points[near, 2], angle[near]
    centres, bisectors = [], []
    if z.size:
        for lo, hi in itertools.pairwise(np.arange(z.min(), z.max() + slab, slab)):
            inside = angle[(z >= lo) & (z < hi)]
            if inside.size >= MIN_NOSE_POINTS:
                centres.append(0.5 * (lo + hi))
                bisectors.append(0.5 * float(np.sum(np.percentile(inside, [5.0, 95.0]))))
    if not centres:
        return np.tile([1.0, 0.0], (len(points), 1))
    bisector = np.interp(points[:, 2], centres, bisectors)
    return np.column_stack([np.cos(bisector), np.sin(bisector)])


def section_turn(points: np.ndarray, normals: np.ndarray, index: np.ndarray, mask: np.ndarray,
                 front: np.ndarray, rear: np.ndarray, seed_radius: float, slab: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Turn fraction θ ∈ [0, 1) of the points under ``mask`` round their section (arc length
    anticlockwise, seen from the tip, from the section's rear end, over the perimeter) and the
    perimeter (m) at every point; NaN elsewhere. ``front`` and ``rear`` are the sections' most
    upstream and most downstream points (x-y at every point's z, m); ``seed_radius`` (m) is
    about the k-th neighbour distance, ``slab`` (m) the height of the slabs along the span.

    Arc lengths are geodesic distances on the surface, approximated by shortest paths through
    a neighbour graph (Dijkstra 1959; graph distances converge to geodesic ones on densely
    sampled surfaces, Tenenbaum, de Silva & Langford 2000, Science 290). Edges join each point
    to those of its :data:`GRAPH_NEIGHBOURS` nearest neighbours whose outward normals,
    projected on the section plane, agree within 75° and whose chord lies within 45° of both
    tangent planes. The front end's outward normal is −x, so the points to the right of the
    line from it into the nose (:func:`nose_directions`, between the two faces) come first
    anticlockwise round the section: the graph is cut along that line within
    2 ``seed_radius`` of the front end (the section crosses it there once; a line y = y_front
    can cross a face leaving the front end upwards again within a millimetre, at high stagger),
    and the paths start from the points within ``seed_radius`` to the right of the cut, run
    once round the section and end at those to its left. The distance d from the start (averaged
    :data:`SMOOTHING_PASSES` times over each point and its graph neighbours) is the arc length
    anticlockwise from the front end; the perimeter P is d plus the distance to the front end
    at the end points (median per slab along the span). From θ' = d / P and the rear end's θ'_r
    (median of the points within ``seed_radius`` of it, per slab: it moves with the twist),
    θ = (θ' − θ'_r) / (1 − θ'_r) · (1 − a) on the suction side and 1 − a + θ' / θ'_r · a on the
    pressure side, a the median θ'_r: each face keeps a fixed share of the turn along the span,
    the rear end at θ = 0 and the front end at 1 − a, as the chordwise turn fraction kept them
    at 0 and 0.5. The cut is at the leading edge, whose circle spans several point spacings;
    at a thin trailing edge k-NN normals straddle both faces and an edge may cut across, which
    only shortens the paths beyond it by part of the circle. Unlike the chordwise position, θ
    is monotone round any section, however strongly cambered, and unchanged by twist and
    taper. Points the graph does not reach (strays) take the θ of their nearest reached point.
    Where the ring is broken — no seam across y = y_front at the front end (high stagger), the
    paths do not come back, or the order jumps between the faces over the span or next to one
    end of it (:func:`~steamtwin.geometry.sections.tour_ratio` above
    :data:`~steamtwin.geometry.sections.BROKEN_TOUR`), as at a thin edge sampled too sparsely
    for the graph to go round it — the order by faces
    (:func:`~steamtwin.geometry.sections.two_face_turn`) is taken instead, when it follows the
    sections better. A ring broken next to one end only is broken all the same (issue 19,
    lean-sweep 80k seed 2: a 0.2 mm trailing edge at the tip): kept, the side's fit folds there
    and is stiffened everywhere.
    """

    count = len(points)
    i, j, chord, length = neighbour_chords(points, index)
    # the normals' directions in the section plane: next to the cap rims the k-NN normals of
    # both faces tilt towards ±z, where they would agree across a thin trailing edge
    flat = np.column_stack([normals[:, :2], np.zeros(count)])
    flat /= np.maximum(np.linalg.norm(flat, axis=1, keepdims=True), 1e-12)
    along_i = np.abs(np.einsum("ij,ij->i", flat[i], chord))
    along_j = np.abs(np.einsum("ij,ij->i", flat[j], chord))
    agree = np.einsum("ij,ij->i", flat[i], flat[j]) > math.cos(math.radians(75.0))
    tangential = (along_i < math.sqrt(0.5) * length) & (along_j < math.sqrt(0.5) * length)
    edge = mask[i] & mask[j] & (length > 0.0) & agree & tangential
    pair = np.minimum(i, j)[edge] * count + np.maximum(i, j)[edge]
    _, unique = np.unique(pair, return_index=True)  # a mutual neighbour pair once
    lo, hi, length = i[edge][unique], j[edge][unique], length[edge][unique]
    graph_edges = (lo, hi, length)  # for the order by faces, should the ring be broken
    offset = np.linalg.norm(points[:, :2] - front, axis=1)
    # cut the ring along the line from the front end into the nose, between its two faces
    inward = nose_directions(points, mask, front, offset, seed_radius, slab)
    relative = points[:, :2] - front
    below = inward[:, 0] * relative[:, 1] - inward[:, 1] * relative[:, 0] < 0.0
    cut = (below[lo] != below[hi]) & (np.minimum(offset[lo], offset[hi]) < 2.0 * seed_radius)
    lo, hi, length = lo[~cut], hi[~cut], length[~cut]
    seam = mask & (offset < seed_radius)
    start, end = np.flatnonzero(seam & below), np.flatnonzero(seam & ~below)
    if start.size == 0 or end.size == 0:
        # no seam across the cut line (a nose too sparse for points on both sides of it
        # within a seed radius): the order by faces, cut along the chord
        return two_face_turn(points, normals, mask, *graph_edges, front, rear, seed_radius,
                             slab)
    origin = count  # a virtual source joined to the seam points below the cut
    rows = np.concatenate([lo, hi, np.full(start.size, origin)])
    cols = np.concatenate([hi, lo, start])
    weights = np.concatenate([length, length, offset[start] + 1e-12])
    graph = coo_array((weights, (rows, cols)), shape=(count + 1, count + 1)).tocsr()
    distance = dijkstra(graph, indices=origin)[:count]
    reached = mask & np.isfinite(distance)
    # the zig-zag of the paths through noisy points varies from point to point: average d over
    # each point and its graph neighbours (d is linear along the surface, the mean keeps it)
    near = reached[lo] & reached[hi]
    adjacency = coo_array((np.ones(2 * near.sum()), (np.concatenate([lo[near], hi[near]]),
                                                     np.concatenate([hi[near], lo[near]]))),
                          shape=(count, count)).tocsr()
    degree = np.asarray(adjacency.sum(axis=1)).ravel() + 1.0
    smooth = np.where(reached, distance, 0.0)
    for _ in range(SMOOTHING_PASSES):
        smooth = (smooth + adjacency @ smooth) / degree
    distance = np.where(reached, smooth, np.inf)
    closing = end[np.isfinite(distance[end])]
    if closing.size == 0 or np.mean(reached[mask]) < 0.9:
        return two_face_turn(points, normals, mask, *graph_edges, front, rear, seed_radius,
                             slab)
    perimeter = np.full(count, np.nan)
    perimeter[mask] = slab_median(points[closing, 2], distance[closing] + offset[closing],
                                   points[mask, 2], slab)
    turn = np.full(count, np.nan)
    turn[reached] = np.mod(distance[reached] / perimeter[reached], 1.0)
    missed = mask & ~reached
    if np.any(missed):
        _, nearest = cKDTree(points[reached]).query(points[missed])
        turn[missed] = turn[reached][nearest]
    near_rear = mask & (np.linalg.norm(points[:, :2] - rear, axis=1) < seed_radius)
    if not np.any(near_rear):
        raise ReconstructionError("no side points at the rear end of the sections: is the "
                                  "trailing edge scanned?")
    # the rear end's turn along the span (it moves with the twist), then both faces stretched
    # to fixed shares so that the rear end is at θ = 0 and the front end at 1 − share
    rear_turn = np.clip(slab_median(points[near_rear, 2], turn[near_rear], points[mask, 2],
                                     slab), 0.05, 0.95)
    share = float(np.median(rear_turn))
    front_based = turn[mask]
    turn[mask] = np.where(front_based >= rear_turn,
                          (front_based - rear_turn) / (1.0 - rear_turn) * (1.0 - share),
                          1.0 - share + front_based / rear_turn * share)
    # a ring broken at a thin, sparse edge leaves the order jumping between the faces, over the
    # span or next to one end: then the order by faces, when it follows the sections better
    ratio = tour_ratio(points, mask, turn, perimeter, seed_radius)
    if ratio > BROKEN_TOUR:
        try:
            by_faces = two_face_turn(points, normals, mask, *graph_edges, front, rear,
                                     seed_radius, slab)
        except ReconstructionError:
            return turn, perimeter
        if tour_ratio(points, mask, *by_faces, seed_radius) < ratio:
            return by_faces
    return turn, perimeter


def slab_median(z: np.ndarray, values: np.ndarray, at: np.ndarray, slab: float) -> np.ndarray:
    """Medians of ``values`` in slabs ``slab`` (m) high along z, interpolated linearly (held
    beyond the end slabs) at the heights ``at``; slabs with fewer than 3 values are skipped."""
    edges = np.arange(z.min(), z.max() + slab, slab)
    which = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, len(edges) - 1)
    counts = np.bincount(which, minlength=len(edges))
    full = np.flatnonzero(counts >= 3)
    if full.size == 0:
        return np.full(len(at), float(np.median(values)))
    medians = [float(np.median(values[which == k])) for k in full]
    return np.interp(at, edges[full] + 0.5 * slab, medians)
