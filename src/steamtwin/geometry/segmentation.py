"""Normals, curvature and region growing of a blade cloud into labelled surface patches.

The cloud is in the blade frame (m): x axial, y tangential, z = radius, sections are planes
z = const. Steps:

1. k-NN PCA per point (:func:`~steamtwin.geometry.preprocess.local_frames`, the estimate of
   open3d's ``estimate_normals``): normal and surface variation λ0 / (λ0 + λ1 + λ2) (Pauly, Gross
   & Kobbelt 2002). Normals are oriented by propagation along a minimum spanning tree
   (Hoppe et al. 1992, SIGGRAPH) whose edges join only *tangential* neighbours — on a thin
   trailing edge the nearest points of the opposite face lie along the normal and must not pass
   their orientation on — then each connected part is turned outward by a majority vote.
2. Largest principal curvature (1/m) from the least-squares shape operator that maps position
   differences to normal differences over the neighbours (Kalogerakis et al. 2007, "Robust
   statistical estimation of curvature on discretized surfaces", SGP).
3. Region growing (Rabbani, van den Heuvel & Vosselman 2006, ISPRS V/5; PCL's
   ``RegionGrowing``): seeds in order of increasing surface variation, a region grows to the
   neighbours whose normal deviates less than the smoothness angle from the current point's and
   continues from those below the curvature threshold.
4. Labels (:data:`~steamtwin.geometry.volume_mesh.REGIONS`): the large segments with normals
   along ∓z at the low/high end of the span are the root (hub) and tip caps; a plane fitted to
   each, and every point on it, gives the cap patches. On a blade the side is one smooth segment
   (neighbouring normals turn by less than the smoothness angle round the leading edge), so the
   side points are labelled one by one, by their turn fraction round the section
   (:func:`section_turn`: geodesic arc length from the section's most upstream point, its
   front end, round to its most downstream point, the rear end, and back): leading or trailing
   edge where the curvature radius is below ``edge_radius_ratio`` × chord within a share of
   the chord (the distance between the ends) of arc length from the front or rear end,
   otherwise suction side (from the rear end anticlockwise to the front end) or pressure side.
   Next to the cap rims, where neighbourhoods straddle the crease, a point takes the label (and
   the turn fraction) of the nearest point further along the span. Isolated points and points
   beyond the cap planes stay unassigned; :meth:`Segmentation.counts` accounts for every
   point.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.pointcloud import PointCloudError, check_point_cloud
from steamtwin.geometry.volume_mesh import REGIONS

#: Label of points that belong to no patch.
UNASSIGNED = -1
#: Fewest points a blade cloud must have to be reconstructed.
MIN_POINTS = 2000
SIDE_REGIONS = ("pressure_side", "suction_side", "leading_edge", "trailing_edge")
#: A point whose k-th neighbour is farther than this multiple of the median is isolated.
ISOLATED = 3.0
#: Nearest neighbours joined in the graph of :func:`section_turn`: few enough that an edge does
#: not reach across a thin trailing edge (~1.4 point spacings), many enough to join all points.
GRAPH_NEIGHBOURS = 8
#: Passes of neighbour averaging of the path lengths in :func:`section_turn`.
SMOOTHING_PASSES = 3


class ReconstructionError(GeometryAreaError):
    """A cloud that cannot be segmented or reconstructed; the message names the problem."""


@dataclass(frozen=True)
class SegmentationSettings:
    """Hyper-parameters of :func:`segment_blade` (angles in rad, lengths in m).

    ``curvature_threshold`` bounds the surface variation of seed points (PCL's
    ``setCurvatureThreshold``); ``edge_radius_ratio`` × chord is the largest radius of curvature
    counted as leading/trailing edge; edges are looked for within ``leading_band`` × chord of
    arc length from the front end and ``1 − trailing_band`` × chord from the rear end.
    ``min_segment_size`` is the smallest smooth segment kept (−1 below); cap patches may be
    smaller, down to :func:`cap_patch_minimum` of the cloud.
    """

    neighbours: int = 20
    smoothness_angle: float = math.radians(8.0)
    curvature_threshold: float = 0.02
    min_segment_size: int = 50
    edge_radius_ratio: float = 0.1
    leading_band: float = 0.2
    trailing_band: float = 0.9


@dataclass(frozen=True)
class CapPlane:
    """A flat end face z = a + b·x + c·y (a in m) and the RMS of its points about it (m)."""

    coefficients: np.ndarray
    rms: float

    def height(self, xy: np.ndarray) -> np.ndarray:
        """z (m) of the plane above the points ``xy`` (n, 2)."""
        a, b, c = self.coefficients
        return a + b * xy[:, 0] + c * xy[:, 1]


@dataclass(frozen=True)
class Segmentation:
    """Per-point results of :func:`segment_blade`.

    ``normals`` outward (n, 3); ``variation`` surface variation; ``curvature`` largest principal
    curvature (1/m); ``segments`` region-growing segment (largest first, −1 for points of
    segments below the minimum size); ``labels`` index into REGIONS or −1 (unassigned);
    ``spacing`` median distance to the nearest point (m); ``chord`` median distance between
    the sections' front and rear ends (:func:`section_chords`, m);
    ``turn`` the arc-length fraction of each side point round its section, anticlockwise from
    the rear end (:func:`section_turn`), and ``perimeter`` its section's perimeter (m), both NaN
    off the side.
    """

    normals: np.ndarray
    variation: np.ndarray
    curvature: np.ndarray
    segments: np.ndarray
    labels: np.ndarray
    root: CapPlane
    tip: CapPlane
    spacing: float
    chord: float
    turn: np.ndarray
    perimeter: np.ndarray
    extra: dict = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        """Points per patch and unassigned points (they add up to the cloud size)."""
        counts = {name: int(np.sum(self.labels == k)) for k, name in enumerate(REGIONS)}
        counts["unassigned"] = int(np.sum(self.labels == UNASSIGNED))
        return counts


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
    from steamtwin.geometry.orientation import (
        median_spacing,
        part_orientation,
        sheet_offset_bound,
    )
    from steamtwin.geometry.preprocess import local_frames

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
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import (
        breadth_first_order,
        connected_components,
        minimum_spanning_tree,
    )

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


def principal_curvature(points: np.ndarray, normals: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Largest absolute principal curvature (1/m) of every point.

    Least-squares shape operator S (2×2, tangent plane) with Δn ≈ S Δp over the neighbours
    (Kalogerakis et al. 2007), symmetrised; its largest absolute eigenvalue.
    """
    neighbour = index[:, 1:]
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(normals, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    curvature = np.empty(len(points))
    for start in range(0, len(points), 20_000):  # bounded memory
        sl = slice(start, start + 20_000)
        dp = points[neighbour[sl]] - points[sl, None, :]
        dn = normals[neighbour[sl]] - normals[sl, None, :]
        basis = np.stack([t1[sl], t2[sl]], axis=2)  # (m, 3, 2)
        u = np.einsum("mki,mij->mkj", dp, basis)
        w = np.einsum("mki,mij->mkj", dn, basis)
        gram = np.einsum("mki,mkj->mij", u, u) + 1e-30 * np.eye(2)
        shape = np.linalg.solve(gram, np.einsum("mki,mkj->mij", u, w))
        shape = 0.5 * (shape + np.transpose(shape, (0, 2, 1)))
        curvature[sl] = np.abs(np.linalg.eigvalsh(shape)).max(axis=1)
    return curvature


def region_growing(normals: np.ndarray, variation: np.ndarray, index: np.ndarray,
                   smoothness_angle: float = math.radians(8.0),
                   curvature_threshold: float = 0.02, min_size: int = 50) -> np.ndarray:
    """Segment per point (largest segment 0, …), −1 for points of segments below ``min_size``.

    PCL's region growing (Rabbani et al. 2006): unlabelled points start regions in order of
    increasing surface variation; a point's neighbours (``index``) join its region when their
    oriented normals deviate less than ``smoothness_angle`` (rad) from its own, and those with
    surface variation below ``curvature_threshold`` continue the growth.
    """
    neighbour = index[:, 1:]
    smooth = np.einsum("ij,ikj->ik", normals, normals[neighbour]) > math.cos(smoothness_angle)
    allowed = [row[mask].tolist() for row, mask in zip(neighbour, smooth, strict=True)]
    grows = (variation < curvature_threshold).tolist()
    segment = [-1] * len(normals)
    current = 0
    for start in np.argsort(variation, kind="stable").tolist():
        if segment[start] >= 0:
            continue
        segment[start] = current
        queue = [start]  # the first point of a region is a seed whatever its curvature
        while queue:
            point = queue.pop()
            for other in allowed[point]:
                if segment[other] < 0:
                    segment[other] = current
                    if grows[other]:
                        queue.append(other)
        current += 1
    segment = np.array(segment)
    sizes = np.bincount(segment)
    rank = np.full(len(sizes), -1)
    big = np.flatnonzero(sizes >= min_size)
    rank[big[np.argsort(-sizes[big], kind="stable")]] = np.arange(len(big))
    return rank[segment]


def fit_cap_plane(points: np.ndarray) -> CapPlane:
    """Least-squares plane z = a + b x + c y through cap points, refitted without the points
    beyond 4 robust standard deviations (1.4826 × median absolute residual)."""
    design = np.column_stack([np.ones(len(points)), points[:, 0], points[:, 1]])
    keep = np.ones(len(points), dtype=bool)
    for _ in range(3):
        coef = np.linalg.lstsq(design[keep], points[keep, 2], rcond=None)[0]
        residual = points[:, 2] - design @ coef
        scale = 1.4826 * np.median(np.abs(residual[keep])) + 1e-9
        keep = np.abs(residual) < 4.0 * scale
    return CapPlane(coefficients=coef, rms=float(np.sqrt(np.mean(residual[keep] ** 2))))


def segment_blade(points: np.ndarray, settings: SegmentationSettings | None = None
                  ) -> Segmentation:
    """Normals, curvature, region-growing segments and patch labels of a blade cloud (m, blade
    frame). Raises :class:`ReconstructionError` when the cloud is empty, too small, flat, or
    shows no root or tip cap."""
    from scipy.spatial import cKDTree

    settings = settings or SegmentationSettings()
    points = check_blade_cloud(points)
    index, normals, variation = oriented_normals(points, settings.neighbours)
    curvature = principal_curvature(points, normals, index)
    spacing = float(np.median(cKDTree(points).query(points[:: max(1, len(points) // 5000)],
                                                    k=2)[0][:, 1]))
    cap_size = min(settings.min_segment_size, cap_patch_minimum(points, spacing))
    grown = region_growing(normals, variation, index, settings.smoothness_angle,
                           settings.curvature_threshold, cap_size)
    root, tip = _caps(points, normals, grown)
    # ranks follow size: the segments of at least min_segment_size points keep theirs
    sizes = np.bincount(grown[grown >= 0])
    segments = grown.copy()
    segments[segments >= int(np.sum(sizes >= settings.min_segment_size))] = -1
    labels = np.full(len(points), UNASSIGNED)
    band = {name: max(4.0 * plane.rms, 0.25 * spacing) for name, plane in
            (("root", root), ("tip", tip))}
    above_root = points[:, 2] - root.height(points[:, :2])
    below_tip = tip.height(points[:, :2]) - points[:, 2]
    labels[np.abs(above_root) <= band["root"]] = REGIONS.index("root")
    labels[np.abs(below_tip) <= band["tip"]] = REGIONS.index("tip")
    side = (above_root > band["root"]) & (below_tip > band["tip"])
    reach = np.linalg.norm(points[index[:, -1]] - points, axis=1)
    side &= reach < ISOLATED * np.median(reach)  # isolated points stay unassigned
    # next to the cap rims the neighbourhoods straddle the crease: normals and curvature there
    # are blends; those points take the label of the nearest side point beyond the rim zone
    rim = side & (np.minimum(above_root, below_tip) < np.median(reach))
    chord, turn, perimeter = _label_sides(points, normals, curvature, segments, index,
                                          float(np.median(reach)), side, rim, labels, settings)
    _smooth_labels(labels, index, side & ~rim)
    _label_rims(points, labels, side & ~rim, rim)
    return Segmentation(normals=normals, variation=variation, curvature=curvature,
                        segments=segments, labels=labels, root=root, tip=tip, spacing=spacing,
                        chord=chord, turn=turn, perimeter=perimeter,
                        extra={"segments": int(segments.max() + 1),
                               "fragment_points": int(np.sum(segments < 0))})


#: Share of a cap's expected points the smallest accepted cap patch must hold: noise splits a
#: small cap into several smooth patches (a 2.45 mm cap of ~290 points fell into patches
#: below 50 points in 2 of 4 clouds, issue 19), 5 % keeps patches of 15 points there.
CAP_SHARE = 0.05
#: Fewest points of a cap patch, whatever the cloud: the plane of a patch needs a few.
MIN_CAP_PATCH = 10


def cap_patch_minimum(points: np.ndarray, spacing: float) -> int:
    """Smallest segment (points) accepted as part of a cap: :data:`CAP_SHARE` of the points
    expected on the smaller end face, at least :data:`MIN_CAP_PATCH`.

    Expected points = section area near the end × density. The area is the convex hull of the
    x-y of the points within 3 ``spacing`` (m) of the end (the 0.5th / 99.5th percentile of z,
    clear of stray points; points whose 5th neighbour in the slab lies beyond 4 × the median
    set aside), which outlines the section there; the density is ln 2 / (π h²) for a median
    nearest-neighbour distance h, the fewest points per m² that give that median (a Poisson
    sample; a regular one has more) — so the minimum errs small.
    """
    from scipy.spatial import ConvexHull, QhullError, cKDTree

    z = points[:, 2]
    density = math.log(2.0) / (math.pi * spacing**2)
    expected = []
    for end in (np.percentile(z, 0.5), np.percentile(z, 99.5)):
        xy = points[np.abs(z - end) < 3.0 * spacing, :2]
        if len(xy) < 10:
            return MIN_CAP_PATCH
        fifth = cKDTree(xy).query(xy, k=6)[0][:, -1]
        xy = xy[fifth < 4.0 * np.median(fifth)]
        try:
            expected.append(ConvexHull(xy).volume * density)  # a 2-D hull's volume is its area
        except QhullError:
            return MIN_CAP_PATCH
    return max(MIN_CAP_PATCH, math.floor(CAP_SHARE * min(expected)))


def _caps(points: np.ndarray, normals: np.ndarray, segments: np.ndarray
          ) -> tuple[CapPlane, CapPlane]:
    """Planes of the root and tip caps: the large segments whose mean normal is within 20° of
    the z axis (either way), below mid-span (root) or above (tip)."""
    count = int(segments.max()) + 1 if np.any(segments >= 0) else 0
    big = segments >= 0
    mean_normal = np.zeros((count, 3))
    np.add.at(mean_normal, segments[big], normals[big])
    mean_normal /= np.maximum(np.linalg.norm(mean_normal, axis=1, keepdims=True), 1e-300)
    mean_z = np.bincount(segments[big], weights=points[big, 2], minlength=count)
    mean_z /= np.maximum(np.bincount(segments[big], minlength=count), 1)
    middle = 0.5 * (np.percentile(points[:, 2], 1.0) + np.percentile(points[:, 2], 99.0))
    along = math.cos(math.radians(20.0))
    planes = []
    for name, sign, side in (("root", -1.0, mean_z < middle), ("tip", 1.0, mean_z > middle)):
        # either orientation: on a long blade the propagation can cross the rim's blended
        # normals and turn a whole cap inward (issue 19: a 250 mm blade)
        chosen = np.flatnonzero((np.abs(mean_normal[:, 2]) > along) & side)
        if chosen.size == 0:
            raise ReconstructionError(
                f"no {name} cap found: no smooth patch with normals along z at the "
                f"{'low' if sign < 0 else 'high'} end of the "
                "span (is the cloud in the blade frame, z along the span, and are both end "
                "faces scanned?)")
        planes.append(fit_cap_plane(points[np.isin(segments, chosen)]))
    return planes[0], planes[1]


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
    from scipy.spatial import cKDTree

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


def _label_sides(points: np.ndarray, normals: np.ndarray, curvature: np.ndarray,
                 segments: np.ndarray, index: np.ndarray, reach: float, side: np.ndarray,
                 rim: np.ndarray, labels: np.ndarray, settings: SegmentationSettings
                 ) -> tuple[float, np.ndarray, np.ndarray]:
    """Label the side points off the rims in place (edges, suction, pressure).

    The suction side runs anticlockwise from the rear end of the section to its front end, the
    pressure side on from there (:func:`section_turn`); edges are looked for within
    ``leading_band`` × chord of arc length from the front end and ``1 − trailing_band`` × chord
    from the rear end; ``reach`` (m) is the typical distance to the k-th neighbour. Returns the
    median chord (m), every side point's turn fraction and its section's perimeter (m; NaN
    elsewhere).
    """
    if np.sum(side & (segments >= 0)) < MIN_POINTS // 4:
        raise ReconstructionError(f"only {int(np.sum(side & (segments >= 0)))} points between "
                                  "the caps lie in smooth patches: too few to reconstruct the "
                                  "blade's sides")
    extent = float(np.ptp(points[side, 2]))
    slab = max(extent / 40.0, 1e-4)
    front, rear, _ = section_chords(points, side, slab)
    chord = np.linalg.norm(rear - front, axis=1)
    inner = side & ~rim
    turn, perimeter = section_turn(points, normals, index, inner, front, rear, reach, slab)
    if np.any(rim):  # as the labels: from the nearest point further along the span
        nearest = _nearest_along_span(points, inner, rim)
        turn[rim], perimeter[rim] = turn[nearest], perimeter[nearest]
    near_front = side & (np.linalg.norm(points[:, :2] - front, axis=1) < reach)
    front_turn = float(np.median(turn[near_front]))  # away from the seam at θ = 0
    from_rear = perimeter * np.minimum(turn, 1.0 - turn)
    from_front = perimeter * np.abs(np.mod(turn - front_turn + 0.5, 1.0) - 0.5)
    edge = inner & (curvature > 1.0 / (settings.edge_radius_ratio * chord))
    leading = edge & (from_front < settings.leading_band * chord)
    trailing = edge & (from_rear < (1.0 - settings.trailing_band) * chord)
    # neighbourhoods reaching onto an edge circle blend its curvature in: keep the points above
    # half the edge's typical (upper-quartile) curvature
    for band in (leading, trailing):
        if np.any(band):
            band &= curvature > 0.5 * np.percentile(curvature[band], 75.0)
    sides = inner & ~leading & ~trailing
    suction = turn < front_turn
    labels[sides & suction] = REGIONS.index("suction_side")
    labels[sides & ~suction] = REGIONS.index("pressure_side")
    labels[leading] = REGIONS.index("leading_edge")
    labels[trailing] = REGIONS.index("trailing_edge")
    return float(np.median(chord[side])), turn, perimeter


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
    tangent planes. The front end's outward normal is −x, so the points just below it (smaller
    y) lie anticlockwise of it: the graph is cut along the line y = y_front within
    2 ``seed_radius`` of the front end (the section crosses it there once, at right angles), and
    the paths start from the points within ``seed_radius`` below the cut, run once round the
    section and end at those above it. The distance d from the start (averaged
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
    paths do not come back, or the order jumps between the faces
    (:func:`~steamtwin.geometry.sections.tour_ratio` above
    :data:`~steamtwin.geometry.sections.BROKEN_TOUR`), as at a thin edge sampled too sparsely
    for the graph to go round it — the order by faces
    (:func:`~steamtwin.geometry.sections.two_face_turn`) is taken instead, when it follows the
    sections better.
    """
    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    from steamtwin.geometry.sections import BROKEN_TOUR, tour_ratio, two_face_turn

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
    below = points[:, 1] < front[:, 1]
    # cut the ring along the line y = y_front across the leading edge
    cut = (below[lo] != below[hi]) & (np.minimum(offset[lo], offset[hi]) < 2.0 * seed_radius)
    lo, hi, length = lo[~cut], hi[~cut], length[~cut]
    seam = mask & (offset < seed_radius)
    start, end = np.flatnonzero(seam & below), np.flatnonzero(seam & ~below)
    if start.size == 0 or end.size == 0:
        # no seam across the line y = y_front (a section staggered so far that both faces
        # leave the front end upwards or downwards): the order by faces, cut along the chord
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
    perimeter[mask] = _slab_median(points[closing, 2], distance[closing] + offset[closing],
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
    rear_turn = np.clip(_slab_median(points[near_rear, 2], turn[near_rear], points[mask, 2],
                                     slab), 0.05, 0.95)
    share = float(np.median(rear_turn))
    front_based = turn[mask]
    turn[mask] = np.where(front_based >= rear_turn,
                          (front_based - rear_turn) / (1.0 - rear_turn) * (1.0 - share),
                          1.0 - share + front_based / rear_turn * share)
    # a ring broken at a thin, sparse edge leaves the order jumping between the faces: then
    # the order by faces, when it follows the sections better
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


def _slab_median(z: np.ndarray, values: np.ndarray, at: np.ndarray, slab: float) -> np.ndarray:
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


def _smooth_labels(labels: np.ndarray, index: np.ndarray, side: np.ndarray) -> None:
    """One majority vote of the side labels over each side point's neighbours (in place)."""
    side_ids = np.array([REGIONS.index(name) for name in SIDE_REGIONS])
    labelled = side & np.isin(labels, side_ids)
    onehot = np.zeros((len(labels), len(REGIONS)))
    onehot[np.flatnonzero(labelled), labels[labelled]] = 1.0
    votes = onehot[index].sum(axis=1)
    best = np.argmax(votes, axis=1)
    change = labelled & (votes[np.arange(len(labels)), best] > 0)
    labels[change] = best[change]


def _label_rims(points: np.ndarray, labels: np.ndarray, inner: np.ndarray,
                rim: np.ndarray) -> None:
    """Give the rim-zone points the label of the nearest labelled side point (in place), with
    z shrunk tenfold so that the same place of the section a little further along the span
    wins."""
    source = inner & (labels >= 0)
    if not np.any(rim) or not np.any(source):
        return
    labels[rim] = labels[_nearest_along_span(points, source, rim)]


def _nearest_along_span(points: np.ndarray, source: np.ndarray, target: np.ndarray
                        ) -> np.ndarray:
    """Index of the nearest ``source`` point of every ``target`` point, with z shrunk tenfold
    so that the same place of the section a little further along the span wins."""
    from scipy.spatial import cKDTree

    scale = np.array([1.0, 1.0, 0.1])
    _, nearest = cKDTree(points[source] * scale).query(points[target] * scale)
    return np.flatnonzero(source)[nearest]
