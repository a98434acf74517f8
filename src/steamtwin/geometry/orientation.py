"""Outward orientation of the normals of a closed surface's cloud by ray parity.

Normal propagation over a spanning tree (Hoppe et al. 1992) leaves one consistent orientation
per connected part of the tree, but not which of the two is outward. A vote of the normals
against the cloud's centroid decides that only where the centroid lies inside the surface and
"in view" of the part: on a thin, cambered and twisted blade the centroid of the cloud lies
outside most sections (beyond the concave pressure side), and a whole pressure side was turned
inward (issue 19: a 250 mm blade, 25° camber, 7 % thick at the tip, twisted 40°).

The parity test of a closed surface does not depend on its shape: a ray from a point of the
surface along its outward normal crosses the surface an even number of times (0, 2, …), along
the inward normal an odd number (the Jordan–Brouwer separation theorem; the crossing-number
point-in-polygon test, Shimrat 1962, "Algorithm 112: position of point relative to polygon",
CACM 5:434, and Haines 1994, "Point in polygon strategies", Graphics Gems IV). On a cloud a
crossing is a cluster of points within a tube round the ray: :func:`ray_crossings` counts the
clusters along ``±n`` from sample points of low surface variation (where the own surface stays
within the tube's start distance), and :func:`parity_votes` gives +1 (outward), −1 (inward) or
0 (the two directions disagree, e.g. a crossing missed in a hole) per sample; a clear majority
of its samples' votes decides the outward side of each part of the tree
(:func:`part_orientation`). For the parts to be faces, the tree must not join the opposite
faces of a thin edge, whose normals are antiparallel while the chord between them can lie
close to both tangent planes: :func:`sheet_offset_bound` is how far a neighbour on the same
sheet may lie off a point's tangent plane.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from steamtwin.geometry.filters import local_frames, median_spacing

#: Tube radius round a ray, in median nearest-neighbour spacings h: a surface crossed by the
#: ray leaves about ln 2 · 2.5² = 4.3 points of a Poisson sample of that spacing in the tube's
#: cross-section (density ln 2 / (π h²)), so a crossing is missed with probability e^−4.3 ≈ 1 %.
TUBE = 2.5
#: The ray starts this many spacings from its point: beyond the noise and the curvature of the
#: own surface within the tube at the sample points (low surface variation), short of the
#: opposite face of a thin edge.
START = 0.5
#: Samples per part of the tree that vote (spread over the part); fewer in a smaller part.
SAMPLES_PER_PART = 60
#: Fewest points of a part of the tree that votes, fewest votes cast that decide a part, and
#: the share of them that must agree.
MIN_PART, MIN_VOTES, MAJORITY = 50, 10, 2.0 / 3.0
#: Offset bound of two neighbours on one sheet (:func:`sheet_offset_bound`): in nearest-neighbour
#: spacings — a chord of one spacing bends off the tangent plane by 0.25 spacing on a radius of
#: 2 spacings — and in noise standard deviations (the offset of two noisy points has σ√2; 4σ
#: keeps 99 % of them).
SHEET_SPACINGS, SHEET_NOISE = 0.25, 4.0
#: Median absolute value of a standard normal variable.
MAD_NORMAL = 0.6745
#: Nearest neighbours whose offsets from a point's tangent plane measure the noise.
NOISE_NEIGHBOURS = 4
#: Largest surface variation of a sample point, as a quantile of the cloud's: flat points only.
FLAT_QUANTILE = 0.5
#: Nearest neighbours joined in the graph of :func:`section_turn`: few enough that an edge does
#: not reach across a thin trailing edge (~1.4 point spacings), many enough to join all points.
GRAPH_NEIGHBOURS = 8


def ray_crossings(points: np.ndarray, origins: np.ndarray, directions: np.ndarray,
                  spacing: float, length: float, tree: object | None = None) -> np.ndarray:
    """Number of times each ray ``origins + t · directions`` (t from :data:`START` × ``spacing``
    to ``length``, m) crosses the surface sampled by ``points`` (m): the hits are the points
    within :data:`TUBE` × ``spacing`` of the ray, and hits closer than twice the tube radius
    along the ray count as one crossing."""
    tree = tree if tree is not None else cKDTree(points)
    radius = TUBE * spacing
    steps = np.arange(START * spacing, length + radius, radius)
    counts = np.zeros(len(origins), dtype=np.int64)
    for k, (origin, direction) in enumerate(zip(origins, directions, strict=True)):
        probes = origin + steps[:, None] * direction
        near = np.unique(np.concatenate(tree.query_ball_point(probes, radius)).astype(np.int64))
        if near.size == 0:
            continue
        offset = points[near] - origin
        along = offset @ direction
        across = np.linalg.norm(offset - along[:, None] * direction, axis=1)
        t = np.sort(along[(along > START * spacing) & (across <= radius)])
        if t.size:
            counts[k] = 1 + int(np.sum(np.diff(t) > 2.0 * radius))
    return counts


def parity_votes(points: np.ndarray, normals: np.ndarray, samples: np.ndarray, spacing: float,
                 length: float, tree: object | None = None) -> np.ndarray:
    """+1 where the normal of each sample point (indices ``samples``) points outward by ray
    parity (even crossings along +n, odd along −n), −1 where it points inward, 0 where the two
    rays disagree; rays ``length`` (m) long."""
    origins, directions = points[samples], normals[samples]
    forward = ray_crossings(points, origins, directions, spacing, length, tree) % 2
    backward = ray_crossings(points, origins, -directions, spacing, length, tree) % 2
    return np.where((forward == 0) & (backward == 1), 1,
                    np.where((forward == 1) & (backward == 0), -1, 0))


def part_orientation(points: np.ndarray, normals: np.ndarray, variation: np.ndarray,
                     part: np.ndarray, spacing: float, length: float,
                     random_state: np.random.Generator | int = 0) -> np.ndarray:
    """Per part of ``part`` (connected parts of consistently oriented normals): +1 where its
    normals point outward, −1 where they point inward, 0 undecided, by the parity votes
    (rays ``length``, m) of up to :data:`SAMPLES_PER_PART` of its points in the flatter half
    of the cloud. A part is decided when at least :data:`MIN_VOTES` samples vote and
    :data:`MAJORITY` of those agree; smaller parts (below :data:`MIN_PART` points) and
    undecided ones are left to the caller."""
    rng = np.random.default_rng(random_state)
    parts = int(part.max()) + 1
    sizes = np.bincount(part, minlength=parts)
    flat = variation <= np.quantile(variation, FLAT_QUANTILE)
    chosen = []
    for k in np.flatnonzero(sizes >= MIN_PART):
        members = np.flatnonzero((part == k) & flat)
        if members.size:
            chosen.append(rng.choice(members, min(SAMPLES_PER_PART, members.size),
                                     replace=False))
    if not chosen:
        return np.zeros(parts, dtype=np.int64)
    samples = np.concatenate(chosen)
    votes = parity_votes(points, normals, samples, spacing, length, cKDTree(points))
    outward = np.bincount(part[samples], weights=votes > 0, minlength=parts)
    inward = np.bincount(part[samples], weights=votes < 0, minlength=parts)
    cast = outward + inward
    decided = (cast >= MIN_VOTES) & (np.maximum(outward, inward) >= MAJORITY * cast)
    return np.where(decided, np.where(outward > inward, 1, -1), 0)


def sheet_offset_bound(points: np.ndarray, normals: np.ndarray, index: np.ndarray) -> float:
    """Largest offset (m) along the normals between two neighbours of one sheet of the surface:
    :data:`SHEET_SPACINGS` × the median nearest-neighbour spacing or :data:`SHEET_NOISE` × the
    noise σ (the offsets of the :data:`NOISE_NEIGHBOURS` nearest neighbours from each point's
    tangent plane have σ√2; their median absolute value is 0.6745 σ√2 for Gaussian noise;
    ``index`` the k-NN rows), whichever is larger. Neighbours offset further lie on the other
    face of a thin edge (or across a sharp crease): joining them in the orientation tree
    passes the orientation of one face to the other, inverted."""
    gap = float(np.median(np.linalg.norm(points[index[:, 1]] - points, axis=1)))
    # the nearest few neighbours stay on the point's own face where the k-NN straddle a thin
    # edge; their offsets from its tangent plane have σ√2
    offsets = np.einsum("nki,ni->nk", points[index[:, 1:NOISE_NEIGHBOURS + 1]]
                        - points[:, None, :], normals)
    noise = float(np.median(np.abs(offsets))) / (MAD_NORMAL * math.sqrt(2.0))
    return max(SHEET_SPACINGS * gap, SHEET_NOISE * noise)


def neighbour_chords(points: np.ndarray, index: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Candidate graph edges: every point ``i`` with each of its :data:`GRAPH_NEIGHBOURS`
    nearest neighbours ``j`` (``index`` row 0 is the point itself), the chord p_j − p_i and its
    length (m)."""
    nearest = index[:, 1:GRAPH_NEIGHBOURS + 1]
    i = np.repeat(np.arange(len(points)), nearest.shape[1])
    j = nearest.ravel()
    chord = points[j] - points[i]
    return i, j, chord, np.linalg.norm(chord, axis=1)


def oriented_normals(points: np.ndarray, neighbours: int = 20
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbour indices (n, k), outward unit normals (n, 3) and surface variation (n,).

    Orientation: Hoppe et al. (1992) propagation over a minimum spanning tree with weights
    1 − |n_i·n_j| (:func:`_propagate`), restricted to tangential neighbour pairs (the chord
    between them within 30° of both tangent planes); every connected part of the tree then
    points the majority of its normals away from the cloud's centroid. That vote fails where
    the tree joins the opposite faces of a thin edge (it passes one face's orientation to the
    other, inverted) or the centroid lies outside the section: a second, strict tree also
    leaves out the pairs farther than
    :func:`~steamtwin.geometry.orientation.sheet_offset_bound` from each other's tangent
    plane, and each of its parts that ray parity decides
    (:func:`~steamtwin.geometry.orientation.part_orientation`, rays over the section plane's
    extent) and that the first orientation inverted for the most part is turned as parity
    says; the other points keep the first orientation.
    """
    index, normals, variation = local_frames(points, neighbours)
    count = len(points)
    i, j, chord, length = neighbour_chords(points, index)
    along_i = np.abs(np.einsum("ij,ij->i", normals[i], chord))
    along_j = np.abs(np.einsum("ij,ij->i", normals[j], chord))
    tangential = (length > 0.0) & (along_i < 0.5 * length) & (along_j < 0.5 * length)
    # the strict tree does not join the opposite faces of a thin edge either (normals
    # antiparallel, the chord tangential, but each point off the other's tangent plane by the
    # edge's thickness)
    # every part of the tangential tree points the majority of its normals away from the
    # cloud's centroid
    flip, part = _propagate(normals, i[tangential], j[tangential], count)
    by_centroid = np.where(flip[:, None], -normals, normals)
    outward = np.einsum("ij,ij->i", by_centroid, points - points.mean(axis=0)) > 0.0
    votes = np.bincount(part, weights=np.where(outward, 1.0, -1.0))
    by_centroid = np.where((votes[part] < 0.0)[:, None], -by_centroid, by_centroid)
    # the strict tree does not join the opposite faces of a thin edge (normals antiparallel,
    # the chord tangential, but each point off the other's tangent plane by the edge's
    # thickness); its parts that ray parity decides are turned by it (a thin cambered
    # section's pressure side faces the cloud's centroid, issue 19)
    bound = sheet_offset_bound(points, normals, index)
    strict = tangential & (along_i < bound) & (along_j < bound)
    flip, part = _propagate(normals, i[strict], j[strict], count)
    by_parts = np.where(flip[:, None], -normals, normals)
    sign = part_orientation(points, by_parts, variation, part, median_spacing(points),
                            float(np.linalg.norm(np.ptp(points[:, :2], axis=0))))
    # a decided part overrides the centroid vote only where that inverted most of it (a whole
    # face): elsewhere the two differ at a few points of uncertain orientation, which keep the
    # first
    agree = np.einsum("ij,ij->i", by_parts * sign[part, None], by_centroid) > 0.0
    inverted = np.bincount(part, weights=~agree, minlength=len(sign)) > 0.5 * np.bincount(
        part, minlength=len(sign))
    override = (sign != 0) & inverted
    normals = np.where(override[part, None], by_parts * sign[part, None], by_centroid)
    return index, normals, variation


def _propagate(normals: np.ndarray, i: np.ndarray, j: np.ndarray, count: int
               ) -> tuple[np.ndarray, np.ndarray]:
    """Hoppe et al. (1992) orientation propagation over the minimum spanning tree of the
    neighbour pairs ``(i, j)`` with weights 1 − |n_i·n_j|: which normals to turn so that each
    agrees with its parent in the tree, and the connected part of every point."""
    lo, hi = np.minimum(i, j), np.maximum(i, j)
    _, unique = np.unique(lo * count + hi, return_index=True)
    lo, hi = lo[unique], hi[unique]
    weight = 1.0 - np.abs(np.einsum("ij,ij->i", normals[lo], normals[hi])) + 1e-9
    tree = minimum_spanning_tree(coo_array((weight, (lo, hi)), shape=(count, count)).tocsr())
    parts, part = connected_components(tree, directed=False)
    # one breadth-first pass over the forest: a virtual root joined to one node of every part
    first = np.unique(part, return_index=True)[1]
    tree = tree.tocoo()
    rows = np.concatenate([tree.row, np.full(parts, count)])
    cols = np.concatenate([tree.col, first])
    forest = coo_array((np.ones(len(rows)), (rows, cols)), shape=(count + 1, count + 1)).tocsr()
    order, predecessor = breadth_first_order(forest, count, directed=False)
    order = order[1:]
    parent = predecessor[order]
    agree = np.ones(len(order), dtype=bool)
    inner = parent != count
    agree[inner] = np.einsum("ij,ij->i", normals[order[inner]], normals[parent[inner]]) >= 0.0
    flipped = [False] * (count + 1)  # parents come before their children in ``order``
    for node, up, same in zip(order.tolist(), parent.tolist(), agree.tolist(), strict=True):
        flipped[node] = flipped[up] != (not same)
    return np.array(flipped[:count]), part
