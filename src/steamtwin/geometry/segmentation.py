"""Normals, curvature and region growing of a blade cloud into labelled surface patches.

The cloud is in the blade frame (m): x axial, y tangential, z = radius, sections are planes
z = const. Steps:

1. k-NN PCA per point (:func:`~steamtwin.geometry.filters.local_frames`, the estimate of
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

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from steamtwin.geometry.blade_cloud import MIN_POINTS, ReconstructionError, check_blade_cloud
from steamtwin.geometry.end_face import end_face_points
from steamtwin.geometry.end_face_density import end_face_need
from steamtwin.geometry.orientation import oriented_normals
from steamtwin.geometry.sections import section_chords, section_turn
from steamtwin.geometry.volume_mesh import REGIONS

#: Label of points that belong to no patch.
UNASSIGNED = -1
SIDE_REGIONS = ("pressure_side", "suction_side", "leading_edge", "trailing_edge")
#: A point whose k-th neighbour is farther than this multiple of the median is isolated.
ISOLATED = 3.0


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
    settings = settings or SegmentationSettings()
    points = check_blade_cloud(points)
    index, normals, variation = oriented_normals(points, settings.neighbours)
    curvature = principal_curvature(points, normals, index)
    spacing = float(np.median(cKDTree(points).query(points[:: max(1, len(points) // 5000)],
                                                    k=2)[0][:, 1]))
    cap_size = min(settings.min_segment_size, cap_patch_minimum(points, spacing))
    grown = region_growing(normals, variation, index, settings.smoothness_angle,
                           settings.curvature_threshold, cap_size)
    root, tip = _caps(points, normals, grown, spacing, settings.neighbours, cap_size)
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


def _caps(points: np.ndarray, normals: np.ndarray, segments: np.ndarray, spacing: float,
          neighbours: int, cap_size: int) -> tuple[CapPlane, CapPlane]:
    """Planes of the root and tip caps: the large segments whose mean normal is within 20° of
    the z axis (either way), below mid-span (root) or above (tip); where none is, the plane of
    the end face's cap-like points (:func:`_aligned_cap`); a cap not found is refused with the
    density its face needs for normals from ``neighbours`` points
    (:func:`~steamtwin.geometry.end_face_density.end_face_need`; ``spacing`` in m)."""
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
        if chosen.size:
            planes.append(fit_cap_plane(points[np.isin(segments, chosen)]))
            continue
        half = points[:, 2] < middle if sign < 0 else points[:, 2] > middle
        plane = _aligned_cap(points[half & (np.abs(normals[:, 2]) > along)], sign < 0, spacing,
                             cap_size)
        if plane is None:
            end = np.percentile(points[:, 2], 0.5 if sign < 0 else 99.5)
            need = end_face_need(points, np.eye(3)[2], end, spacing, neighbours)
            raise ReconstructionError(
                f"no {name} cap found: no smooth patch and no plane of {cap_size} points "
                f"with normals along z at the "
                f"{'low' if sign < 0 else 'high'} end of the "
                "span (is the cloud in the blade frame, z along the span, and are both end "
                "faces scanned?)" + (f"; {need}" if need else ""))
        planes.append(plane)
    return planes[0], planes[1]


def _aligned_cap(aligned: np.ndarray, low: bool, spacing: float, cap_size: int
                 ) -> CapPlane | None:
    """The cap plane through the cap-like points ``aligned`` (normals within 20° of z; m) of
    the end face at the low (``low``) or high end, where no smooth patch formed: on an end
    face a few neighbourhoods wide every neighbourhood straddles a rim, so its surface variation
    is above the region growing's seed threshold (issue 19: a 2.45 mm tip cap at 80k points,
    variation 0.05 against 0.02) while its normals still point along z. The points within the
    end-face window (:func:`~steamtwin.geometry.end_face.end_face_points`) give the plane when
    at least ``cap_size`` of them lie on it (within 4 robust standard deviations) and it is
    within 20° of perpendicular to z; None otherwise."""
    members = end_face_points(aligned, np.eye(3)[2], low, spacing)
    if len(members) < cap_size:
        return None
    plane = fit_cap_plane(members)
    residual = np.abs(members[:, 2] - plane.height(members[:, :2]))
    slope = math.hypot(plane.coefficients[1], plane.coefficients[2])
    on_plane = int(np.sum(residual <= 4.0 * max(plane.rms, 1e-9)))
    if on_plane < cap_size or slope > math.tan(math.radians(20.0)):
        return None
    return plane


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
    scale = np.array([1.0, 1.0, 0.1])
    _, nearest = cKDTree(points[source] * scale).query(points[target] * scale)
    return np.flatnonzero(source)[nearest]
