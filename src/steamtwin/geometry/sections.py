"""Order round a blade's sections: the turn fraction θ of every side point.

:func:`~steamtwin.geometry.sections.section_turn` measures each face from the leading edge
alone: geodesic paths from the points just below the leading edge run along the pressure face,
those from the points just above it along the suction face, and neither has to go round the
trailing edge. At a thin, sparsely sampled trailing edge (0.2 mm radius at 0.14 mm spacing) the
neighbour graph does not go round the edge — neighbours there have normals more than 75°
apart — or links the faces across it, and a single path round the section reached the far
face by detours, 3–5 mm too long next to the edge, where the side's fit then folded (issue 19).
Where the nose itself is too sparse for seeds on both sides of it (a 0.15 mm radius at
0.23 mm spacing, issue 19's slender blade), or the order jumps between the faces,
:func:`two_face_turn` gives an order that needs no path round either edge:

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
#: :func:`lower_envelope`: the percentile of each slab's values, the smoothing weight, the
#: weight of the values above the curve, the reweighting rounds and the order of the
#: differences penalised (on lines lengthened in up to half of 40 slabs by 5–30 mm, in runs,
#: the envelope stays within 0.3 mm of a quadratic; with second differences or a weight of
#: 0.05 above, 4–12 mm off it). The 25th percentile, not the median: in slabs where most of
#: a face's points next to the rear end are reached by detours (issue 19's slender blade, 80k
#: seeds 6 and 7) the median is a detour's length, and the fit was refused.
ENVELOPE_PERCENTILE = 25.0
ENVELOPE_SMOOTHING = 1000.0
ENVELOPE_ASYMMETRY = 0.001
ENVELOPE_ITERATIONS = 30
ENVELOPE_ORDER = 3
#: Round the rear end the turn is the rear path's, within this many seed radii of it along the
#: surface less one, blended linearly into the front paths' over the next seed radius.
REAR_ZONE = 2.0


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
    tangent planes. The graph is cut along the line from the front end into the nose
    (:func:`nose_directions`, between the two faces) within 2 ``seed_radius`` of the front end
    (the section crosses it there once; a line y = y_front can cross a face leaving the front
    end upwards again within a millimetre, at high stagger). Each face is then measured from
    the front end alone: d_p from the points within ``seed_radius`` to the right of the cut
    (the pressure face, first anticlockwise), each starting at its straight distance from the
    front end, and d_s from those to its left, each averaged
    :data:`SMOOTHING_PASSES` times over each point and its graph neighbours. No path has to go
    round the rear end: a thin trailing edge whose k-NN normals straddle both faces keeps the
    graph from going round it, or links the faces across it, and a single path round the
    section then reached the far face by a detour along the span (3–5 mm too long near the
    edge, issue 19 lean-sweep 80k seed 5), which folded the side's fit.

    Each face's length L(z) is read 1–3 ``seed_radius`` short of the rear end, as d plus the
    way on to the rear end along the surface, on that face's points only (split by the
    bisector of the faces round the rear end, :func:`nose_directions` mirrored): the points at
    the edge itself are reached by detours where the edge is thin. The way on is a third
    path's, from the points within ``seed_radius`` of the rear end, each starting at its
    straight distance: the straight distance itself is up to π/2 times shorter round a thick
    edge's circle, and the reference unit's hp8 (a 0.6 mm trailing edge at a 1 mm seed radius)
    had its faces' lengths summing about 1 mm short of the perimeter the paths measure — its
    turn stepped by 1.2 mm at the trailing edge and the row was refused. Along the span L(z)
    is the lower envelope of those values (:func:`lower_envelope`): a face cut off from its
    own seam next to the rear end, over part of the span (k-NN normals turned at a thin edge),
    is reached round the cut, 20–30 mm too long on issue 19's slender blade. A point belongs to
    the face whose distance, less that face's length, is smaller (a detour only lengthens a
    path), and θ = 1 − a + a · d_p / L_p on the pressure face, (1 − d_s / L_s)(1 − a) on the
    suction face: the rear end at θ = 0, the front end at 1 − a, a the median of
    L_p / (L_p + L_s), each face keeping a fixed share of the turn along the span.

    Round the rear end the turn is the third path's instead: −a · r / L_p on the pressure side
    of the faces' bisector, (1 − a) · r / L_s on the other, r the third path's length less its
    smooth floor along the span, alone up to :data:`REAR_ZONE` − 1 ``seed_radius`` of the rear
    end and blended linearly into the front paths' turn over the next ``seed_radius``. Where a
    sparse scan's edge circle is wider than the point spacing, the rear end (the most
    downstream point) can lie at one end of the circle and the whole circle belong to one
    face; the third path starts from the far side of the circle at the straight distance
    across it, that face's length comes out short, and the circle's points wrapped onto the
    other face (the reference unit's hp1 at 0.64 mm spacing and a 2.5 mm seed radius: L_p
    2.4–2.7 mm short, each half of its 0.82 mm trailing edge mirrored, the fit refused). The
    floor is the :func:`lower_envelope` of the slabs' least values within ``seed_radius`` of
    the rear end: the rear end itself may lie off a sparse edge, and the slabs' own least
    values jump with the sampling (0.37–0.94 mm on a noise-free 25k-point hp1 cloud, up to
    0.39 mm from slab to slab; their median over five slabs cost its fit 45 more knots and 34 µm
    RMS at the hub rim). The perimeter is L_p + L_s. Unlike
    the chordwise position, θ is monotone round any section, however strongly cambered, and
    unchanged by twist and taper. Points neither path reaches (strays) take the θ of their
    nearest reached point. Where there is no seam across the cut (a nose too sparse for points
    on both sides of it within a seed radius), the paths reach too few points, or the order
    jumps between the faces over the span or next to one end of it
    (:func:`~steamtwin.geometry.sections.tour_ratio` above
    :data:`~steamtwin.geometry.sections.BROKEN_TOUR`), the order by faces split by their normals
    (:func:`~steamtwin.geometry.sections.two_face_turn`) is taken instead, when it follows the
    sections better.
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
    below = _right_of(points, nose_directions(points, mask, front, offset, seed_radius, slab),
                      front)
    cut = (below[lo] != below[hi]) & (np.minimum(offset[lo], offset[hi]) < 2.0 * seed_radius)
    lo, hi, length = lo[~cut], hi[~cut], length[~cut]
    seam = mask & (offset < seed_radius)
    start, end = np.flatnonzero(seam & below), np.flatnonzero(seam & ~below)
    if start.size == 0 or end.size == 0:
        # no seam across the cut line (a nose too sparse for points on both sides of it
        # within a seed radius): the order by faces, cut along the chord
        return two_face_turn(points, normals, mask, *graph_edges, front, rear, seed_radius,
                             slab)
    # two virtual sources, joined to the seam points right and left of the cut, each at its
    # straight distance from the front end, and a third joined to the points round the rear end
    behind = np.linalg.norm(points[:, :2] - rear, axis=1)
    tail = np.flatnonzero(mask & (behind < seed_radius))
    if tail.size == 0:
        raise ReconstructionError("no side points at the rear end of the sections: is the "
                                  "trailing edge scanned?")
    rows = np.concatenate([lo, hi, np.full(start.size, count), np.full(end.size, count + 1),
                           np.full(tail.size, count + 2)])
    cols = np.concatenate([hi, lo, start, end, tail])
    weights = np.concatenate([length, length, offset[start] + 1e-12, offset[end] + 1e-12,
                              behind[tail] + 1e-12])
    graph = coo_array((weights, (rows, cols)), shape=(count + 3, count + 3)).tocsr()
    pressure_path, suction_path, rear_path = (
        _smoothed(d, mask & np.isfinite(d), lo, hi)
        for d in dijkstra(graph, indices=[count, count + 1, count + 2])[:, :count])
    reached = mask & (np.isfinite(pressure_path) | np.isfinite(suction_path))
    if np.mean(reached[mask]) < 0.9:
        return two_face_turn(points, normals, mask, *graph_edges, front, rear, seed_radius,
                             slab)
    pressure_length, suction_length, pressure_behind = _face_lengths(
        points, mask, rear, pressure_path, suction_path, rear_path, seed_radius, slab)
    perimeter = np.full(count, np.nan)
    perimeter[mask] = (pressure_length + suction_length)[mask]
    share = float(np.median((pressure_length / perimeter)[mask]))
    # a detour only lengthens a path: a point is on the face whose path, less its length, is
    # shorter (also for a point of one face reached round the rear end from the other); the
    # turn is counted here from the rear end, −share … 0 on the pressure face
    with np.errstate(invalid="ignore"):
        pressure = pressure_path - pressure_length < suction_path - suction_length
        from_front = np.where(pressure, share * (pressure_path / pressure_length - 1.0),
                              (1.0 - suction_path / suction_length) * (1.0 - share))
        # round the rear end, the way to it (from the nearest point: the rear end itself
        # may lie off a sparse edge) and the side of the faces' bisector
        near_rear = mask & (behind < seed_radius) & np.isfinite(rear_path)
        to_rear = rear_path - lower_envelope(points[near_rear, 2], rear_path[near_rear],
                                             points[:, 2], slab, percentile=0.0)
        from_rear = np.where(pressure_behind, -share * to_rear / pressure_length,
                             (1.0 - share) * to_rear / suction_length)
    rear_weight = np.clip(REAR_ZONE - rear_path[reached] / seed_radius, 0.0, 1.0)
    near_end = np.where(np.isfinite(from_rear), from_rear, 0.0)[reached]
    turn = np.full(count, np.nan)
    turn[reached] = np.mod(rear_weight * near_end + (1.0 - rear_weight) * from_front[reached],
                           1.0)
    missed = mask & ~reached
    if np.any(missed):
        _, nearest = cKDTree(points[reached]).query(points[missed])
        turn[missed] = turn[reached][nearest]
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


def _right_of(points: np.ndarray, direction: np.ndarray, through: np.ndarray) -> np.ndarray:
    """Whether each point lies right of the line along ``direction`` (n, 2) through
    ``through`` (x-y, m), seen from the tip."""
    relative = points[:, :2] - through
    return direction[:, 0] * relative[:, 1] - direction[:, 1] * relative[:, 0] < 0.0


def _smoothed(distance: np.ndarray, reached: np.ndarray, lo: np.ndarray, hi: np.ndarray
              ) -> np.ndarray:
    """Path lengths ``distance`` (m) averaged :data:`SMOOTHING_PASSES` times over each reached
    point and its graph neighbours (edges ``lo``–``hi``): the zig-zag of the paths through
    noisy points varies from point to point, and d is linear along the surface, so the mean
    keeps it. ∞ where not reached."""
    near = reached[lo] & reached[hi]
    adjacency = coo_array((np.ones(2 * near.sum()), (np.concatenate([lo[near], hi[near]]),
                                                     np.concatenate([hi[near], lo[near]]))),
                          shape=(len(distance), len(distance))).tocsr()
    degree = np.asarray(adjacency.sum(axis=1)).ravel() + 1.0
    smooth = np.where(reached, distance, 0.0)
    for _ in range(SMOOTHING_PASSES):
        smooth = (smooth + adjacency @ smooth) / degree
    return np.where(reached, smooth, np.inf)


def _face_lengths(points: np.ndarray, mask: np.ndarray, rear: np.ndarray,
                  pressure_path: np.ndarray, suction_path: np.ndarray, rear_path: np.ndarray,
                  seed_radius: float, slab: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lengths (m) of the pressure and suction faces from the front end to the rear end at
    every point's z (:func:`section_turn`): the path from the front end plus the path on to
    the rear end (``rear_path``, m), on each face's points 1–3 ``seed_radius`` (m) short of
    it; and whether each point under ``mask`` lies on the pressure face's side of the faces'
    bisector round the rear end."""
    behind = np.linalg.norm(points[:, :2] - rear, axis=1)
    mirror = np.array([-1.0, 1.0, 1.0])  # the rear end is the front end of the mirrored blade
    tail = nose_directions(points * mirror, mask, rear * mirror[:2], behind, seed_radius,
                           slab) * mirror[:2]
    right = _right_of(points, tail, rear)
    short = mask & (behind >= seed_radius) & (behind < NOSE_REACH * seed_radius)
    missing = ReconstructionError("no side points on both faces next to the rear end of the "
                                  "sections reached from the front end: is the trailing edge "
                                  "scanned?")
    if not (np.any(short & right) and np.any(short & ~right)):
        raise missing
    # the face the pressure paths reach sooner is the pressure face, whichever side it lies
    # (a point no path reaches counts as ∞ in the medians)
    pressure_side = right if (np.median(pressure_path[short & right])
                              < np.median(pressure_path[short & ~right])) else ~right
    lengths = []
    for path, on in ((pressure_path, pressure_side), (suction_path, ~pressure_side)):
        chosen = short & on & np.isfinite(path)
        if not np.any(chosen):
            raise missing
        lengths.append(lower_envelope(points[chosen, 2], path[chosen] + rear_path[chosen],
                                      points[:, 2], slab))
    return lengths[0], lengths[1], mask & pressure_side


def lower_envelope(z: np.ndarray, values: np.ndarray, at: np.ndarray, slab: float,
                   percentile: float = ENVELOPE_PERCENTILE) -> np.ndarray:
    """A smooth lower envelope of ``values`` along z, at the heights ``at`` (held beyond the end
    slabs): the ``percentile`` th percentile (default :data:`ENVELOPE_PERCENTILE`) of the
    values in each slab ``slab``
    (m) high (slabs with fewer than 3 values skipped), then the asymmetric least-squares
    smoother of Eilers & Boelens (2005, "Baseline correction with asymmetric least squares
    smoothing", Leiden University Medical Centre report): a Whittaker smoother (penalty on the
    differences of order :data:`ENVELOPE_ORDER` — a quadratic along the span passes
    unchanged —, weight :data:`ENVELOPE_SMOOTHING`) whose values above the curve weigh
    :data:`ENVELOPE_ASYMMETRY` and those below 1 − that, reweighted
    :data:`ENVELOPE_ITERATIONS` times. Path lengths are only lengthened
    by detours (a face cut off next to the rear end over part of the span is reached round it,
    20–30 mm too long on issue 19's slender blade), so the shortest slabs are the true ones."""
    edges = np.arange(z.min(), z.max() + slab, slab)
    which = np.clip(np.searchsorted(edges, z, side="right") - 1, 0, len(edges) - 1)
    counts = np.bincount(which, minlength=len(edges))
    full = np.flatnonzero(counts >= 3)
    if full.size == 0:
        return np.full(len(at), float(np.percentile(values, percentile)))
    low = np.array([float(np.percentile(values[which == k], percentile))
                    for k in full])
    if full.size >= 3:
        count = int(full[-1] - full[0] + 1)  # every slab between the first and last filled
        observed = np.zeros(count)
        observed[full - full[0]] = low
        present = np.zeros(count)
        present[full - full[0]] = 1.0
        difference = np.diff(np.eye(count), n=ENVELOPE_ORDER, axis=0)
        penalty = ENVELOPE_SMOOTHING * difference.T @ difference
        weights = present.copy()
        for _ in range(ENVELOPE_ITERATIONS):
            curve = np.linalg.solve(np.diag(weights) + penalty, weights * observed)
            weights = present * np.where(observed > curve, ENVELOPE_ASYMMETRY,
                                         1.0 - ENVELOPE_ASYMMETRY)
        low = curve[full - full[0]]
    return np.interp(at, edges[full] + 0.5 * slab, low)


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
