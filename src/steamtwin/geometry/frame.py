"""The blade frame from the data: span axis, hub and tip ends, chordwise direction, origin.

:func:`~steamtwin.geometry.reconstruct.reconstruct_blade` needs the cloud in a blade frame (m; z
along the span, sections z = const). A scan arrives in whatever pose the scanner's software
chose, so :func:`estimate_blade_frame` finds one from the cloud itself:

1. **Span axis.** A blade is close to a surface of linear extrusion closed by two planar end
   faces: the side's normals are perpendicular to the span axis (its Gaussian image is a great
   circle whose pole is the axis) and the caps' normals are parallel to it. The axis is the
   eigenvector of the smallest eigenvalue of the side normals' scatter matrix Σ n nᵀ — the
   Gaussian-image axis estimate of extrusions and cylinders (Chaperon & Goulette 2001,
   "Extracting cylinders in full 3D data using a random sampling method and the Gaussian
   image", VMV; Pottmann & Wallner, *Computational Line Geometry*, 2001, §7: the normals of a
   cylinder surface are orthogonal to its rulings) — with the cap-like normals (within
   :data:`SIDE_ANGLE` of the axis) iteratively left out, started from every principal axis of
   the normals and of the points; the start whose result explains most normals (side or cap
   within :data:`FIT_ANGLE`) wins. It is cross-checked against the two planar end patches:
   when both are found, parallel and within :data:`CAP_AGREEMENT` of the side's axis, their
   common normal (least-squares planes through thousands of points) is taken.
2. **Hub and tip.** ``hub_end`` when given; otherwise the taper rule — HP rotor blades are
   tapered towards the tip to relieve the root of centrifugal load (Traupel,
   *Thermische Turbomaschinen*, 2001, §19; tip/hub chord 0.8–1.0), so the end whose section is
   longer (robust Feret diameter at 10 % / 90 % span) is the hub when the two differ by more
   than :data:`TAPER_MARGIN`; otherwise, with ``suction_side`` given, the handedness rule below;
   otherwise the end the scan's own axes point away from, flagged ``hub_tip_ambiguous``.
3. **Chordwise direction** from the mid-span section: the chord line is the pressure-side
   bitangent (:func:`~steamtwin.geometry.fidelity.chord_line`); x runs along it from the
   leading edge — the blunter end, larger section width near it (Dixon & Hall, *Fluid
   Mechanics and Thermodynamics of Turbomachinery*, ch. 3: the rounded nose faces the flow, the
   trailing edge is thin to limit its wake) — to the trailing edge, y = z × x.
4. **Origin** on the span axis through the mid-span chord's midpoint, at the hub cap: z is the
   height above the hub cap (the reconstruction needs no absolute radius; the row metrics
   that do are measured after the best fit to a nominal row).

Handedness: a blade and its mirror image are not congruent, so with x from the leading to the
trailing edge and z from hub to tip the convex suction side of a cambered section lies on a
fixed side, ``suction_side``: +y for a turbine rotor blade in this package's blade frame (y the
direction of motion: the steam pushes the blade from its pressure towards its suction side)
and for the stators too, whose tangential axis :mod:`~steamtwin.geometry.ip_rows` mirrors to
keep Pritchard's sign convention; −y for a stator scanned as it is. Given it, an untapered
cambered blade's hub end follows (``"handedness"`` rule).

A cloud already in a blade frame — its span axis within :data:`KEEP_ANGLE` of the scan's +z,
hub at the low end — keeps the scan frame (``kept_scan_frame``): that frame carries the radius
and the axial direction, which a frame from the data cannot know, and a cloud in the blade frame
reconstructs exactly as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import ConvexHull, cKDTree
from threadpoolctl import threadpool_limits

from steamtwin.geometry.blade_cloud import ReconstructionError, check_blade_cloud
from steamtwin.geometry.end_face import end_face_points
from steamtwin.geometry.end_face_density import end_face_need
from steamtwin.geometry.fidelity import chord_line, farthest_pair, surface_samples
from steamtwin.geometry.filters import local_frames, plane_basis
from steamtwin.geometry.profile import Blade, reference_surface
from steamtwin.geometry.reconstruct import (
    BLAS_THREADS,
    Reconstruction,
    ReconstructionSettings,
    reconstruct_blade,
)

#: Points whose normals are estimated (a random subset of larger clouds): enough for an axis
#: to 0.01° (the scatter matrix averages thousands of side normals), seconds of k-NN PCA.
SAMPLE_POINTS = 30_000
#: Neighbours of the k-NN PCA normals (as :class:`~steamtwin.geometry.segmentation.
#: SegmentationSettings`).
NEIGHBOURS = 20
#: Normals farther than this from perpendicular to the axis are left out of the side's scatter
#: (cap-like): halfway between side and cap, room for twist and taper to tilt side normals.
SIDE_ANGLE = math.radians(45.0)
#: A normal within this of perpendicular to (side) or parallel to (cap) a candidate axis counts
#: as explained by it (scores the starts; a wrong axis, e.g. the chord, leaves the leading and
#: trailing edges' normals unexplained).
FIT_ANGLE = math.radians(15.0)
#: Normals within this of the axis are cap-like (segmentation's caps use the same 20°).
CAP_ANGLE = math.radians(20.0)
#: Cap points are looked for within this share of the span from each end.
CAP_BAND = 0.1
#: Fewest cap-like points that make a planar end patch (a plane's three parameters, ten times
#: over).
MIN_CAP_POINTS = 30
#: The end planes must be parallel within this angle to give the axis (the twist and taper of
#: our rows tilt the side normals' axis by up to 2.3°, hp5).
CAP_AGREEMENT = math.radians(5.0)
#: ... and within this angle of the side normals' axis (:data:`FIT_ANGLE`: the tilt the axis
#: score allows a side normal): a strongly twisted blade tilts the side normals' axis by more
#: than CAP_AGREEMENT (issue 19's compressor blade, 60°→70° stagger over 60 mm: 4.8–7.2°),
#: while its end planes, where found, are parallel within 0.6°.
CAP_TO_SIDE = math.radians(15.0)
#: Sections whose robust Feret diameters differ by less than this share count as untapered
#: (the 0.9 taper of reaction blading gives 8 % between 10 % and 90 % span).
TAPER_MARGIN = 0.02
#: Ends whose widths differ by less than this share cannot be told apart as leading/trailing.
BLUNTNESS_MARGIN = 0.1
#: A section whose points lie on average less than this share of the chord off the chord line
#: counts as uncambered (no handedness).
CAMBER_MARGIN = 0.005
#: The scan frame is kept when the span axis is within this angle of its +z (hub at the low
#: end): 20× the largest span-axis error on our rows in random poses (0.026°,
#: benchmarks/bench_frame.py), far below any tilt a reconstruction in the scan frame would need.
KEEP_ANGLE = math.radians(0.5)
#: Section slabs are this many nearest-neighbour distances thick (~4 mean point spacings: a
#: few hundred points round a section).
SLAB_SPACINGS = 8.0
#: Hub-end overrides: the hub at the end towards which the given scan axis points.
HUB_ENDS = ("+x", "-x", "+y", "-y", "+z", "-z")
#: Sides of the suction face in the blade frame (handedness rule, module docstring).
SUCTION_SIDES = ("+y", "-y")


@dataclass(frozen=True)
class BladeFrame:
    """A rigid transformation from the scan frame into a blade frame (m).

    ``rotation`` (3×3) and ``translation`` (3,): blade = rotation · scan + translation; its rows
    are ``x_axis`` (chordwise, leading to trailing edge, unless the scan frame was kept),
    ``y_axis`` and ``z_axis`` (hub to tip) in scan coordinates. ``span_axis`` (hub to tip) and
    ``chord_direction`` are what the data gave, in scan coordinates, also when the scan frame is
    kept; ``span`` (m) is the distance between the end planes; ``rules`` say which rule decided
    each choice; ``hub_tip_ambiguous`` / ``edges_ambiguous`` flag choices the data could not
    make (the scan's sense, or the larger-width end, was taken).
    """

    rotation: np.ndarray
    translation: np.ndarray
    span_axis: np.ndarray
    chord_direction: np.ndarray
    span: float
    rules: dict[str, str]
    hub_tip_ambiguous: bool
    edges_ambiguous: bool
    kept_scan_frame: bool
    checks: dict[str, float] = field(default_factory=dict)

    @property
    def x_axis(self) -> np.ndarray:
        """The blade's x axis in scan coordinates (unit)."""
        return self.rotation[0]

    @property
    def y_axis(self) -> np.ndarray:
        """The blade's y axis in scan coordinates (unit)."""
        return self.rotation[1]

    @property
    def z_axis(self) -> np.ndarray:
        """The blade's z axis (hub to tip) in scan coordinates (unit)."""
        return self.rotation[2]

    @property
    def matrix(self) -> np.ndarray:
        """4×4 homogeneous scan → blade transformation (m)."""
        matrix = np.eye(4)
        matrix[:3, :3] = self.rotation
        matrix[:3, 3] = self.translation
        return matrix

    def to_blade(self, points: np.ndarray) -> np.ndarray:
        """Scan-frame points (n, 3; m) in the blade frame (m)."""
        return np.asarray(points, dtype=np.float64) @ self.rotation.T + self.translation

    def to_scan(self, points: np.ndarray) -> np.ndarray:
        """Blade-frame points (n, 3; m) in the scan frame (m)."""
        return (np.asarray(points, dtype=np.float64) - self.translation) @ self.rotation

    def as_dict(self) -> dict:
        """JSON-able summary; lengths in mm, angles in degrees."""
        return {
            "rotation": self.rotation.tolist(),
            "translation_mm": (self.translation * 1e3).tolist(),
            "matrix_scan_to_blade_m": self.matrix.tolist(),
            "x_axis": self.x_axis.tolist(), "y_axis": self.y_axis.tolist(),
            "z_axis": self.z_axis.tolist(),
            "span_axis": self.span_axis.tolist(),
            "chord_direction": self.chord_direction.tolist(),
            "span_mm": self.span * 1e3,
            "rules": dict(self.rules),
            "hub_tip_ambiguous": self.hub_tip_ambiguous,
            "edges_ambiguous": self.edges_ambiguous,
            "kept_scan_frame": self.kept_scan_frame,
            "checks": dict(self.checks),
        }


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (rad) between two directions, sign ignored."""
    return math.acos(min(1.0, abs(float(np.dot(_unit(a), _unit(b))))))


def _side_axis(normals: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Smallest-eigenvalue eigenvector of the scatter of the normals within SIDE_ANGLE of
    perpendicular to the axis, iterated from ``start``."""
    axis = _unit(start)
    limit = math.sin(SIDE_ANGLE)
    for _ in range(20):
        side = normals[np.abs(normals @ axis) < limit]
        if len(side) < 3:
            return axis
        new = np.linalg.eigh(side.T @ side)[1][:, 0]
        new = new if np.dot(new, axis) >= 0.0 else -new
        if np.dot(new, axis) > math.cos(1e-7):
            return new
        axis = new
    return axis


def _explained(normals: np.ndarray, axis: np.ndarray) -> float:
    """Share of normals perpendicular (side) or parallel (cap) to ``axis`` within FIT_ANGLE."""
    along = np.abs(normals @ axis)
    return float(np.mean((along < math.sin(FIT_ANGLE)) | (along > math.cos(FIT_ANGLE))))


def _plane_normal(points: np.ndarray, spacing: float) -> tuple[np.ndarray, float]:
    """Normal and RMS (m) of the least-squares plane through ``points``, refitted twice without
    the points beyond 4 robust standard deviations (or two point spacings)."""
    keep = np.ones(len(points), dtype=bool)
    for _ in range(3):
        centre = points[keep].mean(axis=0)
        normal = np.linalg.svd(points[keep] - centre, full_matrices=False)[2][2]
        distance = (points - centre) @ normal
        scale = 1.4826 * np.median(np.abs(distance[keep])) + 1e-12
        keep = np.abs(distance) < max(4.0 * scale, 2.0 * spacing)
    return normal, float(np.sqrt(np.mean(distance[keep] ** 2)))


def _slab(points: np.ndarray, height: np.ndarray, at: float, thickness: float,
          basis: np.ndarray, spacing: float) -> np.ndarray:
    """In-plane coordinates (n, 2; m) of the points within ``thickness`` / 2 of ``at`` along the
    axis, without isolated points (fewer than 4 others within 4 spacings: stray points)."""
    chosen = points[np.abs(height - at) < 0.5 * thickness] @ basis.T
    if len(chosen) < 20:
        raise ReconstructionError(f"only {len(chosen)} points in the section at "
                                  f"{at * 1e3:.4g} mm along the span axis: too sparse to find "
                                  "the blade frame")
    counts = cKDTree(chosen).query_ball_point(chosen, 4.0 * spacing, return_length=True)
    return chosen[counts >= 5]


def _feret(section: np.ndarray) -> float:
    """Robust largest width (m) of a section: the range of its points' projections on the
    line of the farthest pair, without the two most extreme points at each end."""

    hull = section[ConvexHull(section).vertices]
    a, b = farthest_pair(hull)
    along = np.sort(section @ _unit(b - a))
    return float(along[-3] - along[2])


def _end_width(section: np.ndarray, end: np.ndarray, inward: np.ndarray, chord: float) -> float:
    """Width (m) of the section across the chord line between 2 % and 8 % of the chord from
    ``end`` (the thickness of the nose or tail there: larger at the blunter end)."""
    relative = section - end
    along = relative @ inward
    across = relative @ np.array([-inward[1], inward[0]])
    near = (along > 0.02 * chord) & (along < 0.08 * chord)
    return float(np.ptp(across[near])) if np.sum(near) >= 4 else 0.0


def estimate_blade_frame(points: np.ndarray, *, hub_end: str | None = None,
                         suction_side: str | None = None, keep_scan_frame: bool = True,
                         random_state: np.random.Generator | int | None = 0) -> BladeFrame:
    """Blade frame of a blade cloud (n, 3; m) in any pose.

    ``hub_end`` (one of :data:`HUB_ENDS`) overrides the hub/tip rules: the hub is the end the
    given scan axis points towards; ``suction_side`` (``"+y"`` or ``"-y"``, see the module
    docstring) lets the handedness decide hub and tip of an untapered, cambered blade;
    ``keep_scan_frame`` keeps a scan frame that is already a blade frame (see the module
    docstring); ``random_state`` (a seed or a Generator) draws the :data:`SAMPLE_POINTS`
    whose normals are estimated. Raises
    :class:`~steamtwin.geometry.blade_cloud.ReconstructionError` naming the problem (bad
    cloud, no planar end faces).
    """
    if hub_end is not None and hub_end not in HUB_ENDS:
        raise ValueError(f"hub_end must be one of {', '.join(HUB_ENDS)} (got {hub_end!r})")
    if suction_side is not None and suction_side not in SUCTION_SIDES:
        raise ValueError(f"suction_side must be '+y' or '-y' (got {suction_side!r})")
    points = check_blade_cloud(points)
    rng = np.random.default_rng(random_state)
    sample = points[rng.permutation(len(points))[:SAMPLE_POINTS]]
    index, normals, _ = local_frames(sample, NEIGHBOURS)
    spacing = float(np.median(np.linalg.norm(sample[index[:, 1]] - sample, axis=1)))
    spacing *= math.sqrt(len(sample) / len(points))  # the full cloud's spacing

    # 1. span axis: side normals' pole, from every principal axis of normals and points
    starts = np.concatenate([np.linalg.eigh(normals.T @ normals)[1].T,
                             np.linalg.eigh(np.cov((sample - sample.mean(axis=0)).T))[1].T])
    candidates = [_side_axis(normals, start) for start in starts]
    scores = [_explained(normals, axis) for axis in candidates]
    side_axis = candidates[int(np.argmax(scores))]
    height = points @ side_axis
    low, high = np.percentile(height, [0.1, 99.9])
    along = np.abs(normals @ side_axis)
    cap_like = along > math.cos(CAP_ANGLE)
    sample_height = sample @ side_axis
    caps = {}
    checks: dict[str, float] = {}
    for name, near in (("low", sample_height < low + CAP_BAND * (high - low)),
                       ("high", sample_height > high - CAP_BAND * (high - low))):
        members = end_face_points(sample[cap_like & near], side_axis, name == "low",
                                  spacing, CAP_AGREEMENT)
        if len(members) >= MIN_CAP_POINTS:
            normal, rms = _plane_normal(members, spacing)
            caps[name] = (normal if np.dot(normal, side_axis) >= 0.0 else -normal, members)
            checks[f"{name}_end_plane_rms_mm"] = rms * 1e3
    if len(caps) < 2:
        missing = [n for n in ("low", "high") if n not in caps]
        needs = [end_face_need(points, side_axis, low if n == "low" else high, spacing,
                               NEIGHBOURS) for n in missing]
        raise ReconstructionError(
            f"no planar end face found at the {' and '.join(n + ' end' for n in missing)} of "
            f"the span axis (fewer than {MIN_CAP_POINTS} points with normals within "
            f"{math.degrees(CAP_ANGLE):.0f}° of the axis there): is it a blade with both end "
            "faces scanned?" + "".join(f"; at the {n} end {need}"
                                      for n, need in zip(missing, needs, strict=True) if need))
    rules: dict[str, str] = {}
    ends_angle = _angle(caps["low"][0], caps["high"][0])
    cap_axis = _unit(caps["low"][0] + caps["high"][0])
    side_cap = _angle(cap_axis, side_axis)
    checks["end_planes_angle_deg"] = math.degrees(ends_angle)
    checks["side_axis_to_end_planes_deg"] = math.degrees(side_cap)
    checks["normals_explained"] = float(max(scores))
    if ends_angle < CAP_AGREEMENT and side_cap < CAP_TO_SIDE:
        axis = cap_axis
        rules["span_axis"] = (f"common normal of the two parallel end planes "
                              f"({math.degrees(side_cap):.2f}° from the side normals' axis)")
    else:
        axis = side_axis
        rules["span_axis"] = (f"side normals' axis (end planes {math.degrees(ends_angle):.2f}° "
                              f"apart, {math.degrees(side_cap):.2f}° from it)")
    height = points @ axis
    end_height = {name: float(np.median(members @ axis)) for name, (_, members) in caps.items()}
    span = end_height["high"] - end_height["low"]
    basis = plane_basis(axis)
    thickness = max(SLAB_SPACINGS * spacing, 0.002 * span)

    # 3. chordwise direction, leading edge first (independent of the hub/tip choice)
    mid = _slab(points, height, end_height["low"] + 0.5 * span, thickness, basis, spacing)
    first, second, _ = chord_line(mid)
    chord = float(np.linalg.norm(second - first))
    direction = (second - first) / chord
    # the widths at the section's ends, its farthest pair: where the pressure side is convex
    # over part of the chord the bitangent's touch points need not be the ends (slender 80k
    # seed 1, 65-series, 2026-11-27: a 25.5-mm bitangent of a 37.5-mm section, the ends
    # judged from it the wrong way round)
    ends = farthest_pair(mid[ConvexHull(mid).vertices])
    length = float(np.linalg.norm(ends[1] - ends[0]))
    widths = (_end_width(mid, ends[0], (ends[1] - ends[0]) / length, length),
              _end_width(mid, ends[1], (ends[0] - ends[1]) / length, length))
    if (widths[1] > widths[0]) == (direction @ (ends[1] - ends[0]) > 0.0):
        first, second, direction = second, first, -direction
    widths = (max(widths), min(widths))
    edges_ambiguous = widths[0] < (1.0 + BLUNTNESS_MARGIN) * widths[1]
    rules["chord"] = (f"mid-span chord line (pressure-side bitangent), {chord * 1e3:.3f} mm; "
                      f"leading edge = the blunter end (width {widths[0] * 1e3:.3f} mm against "
                      f"{widths[1] * 1e3:.3f} mm at 2–8 % of the section's length from its ends)"
                      + ("; ambiguous: the ends are alike" if edges_ambiguous else ""))
    chord_direction = basis.T @ direction  # in scan coordinates, ⊥ axis

    # 2. hub and tip: override, taper, handedness, or the scan's sense
    feret = {name: _feret(_slab(points, height, end_height["low"] + fraction * span,
                                thickness, basis, spacing))
             for name, fraction in (("low", 0.1), ("high", 0.9))}
    checks["feret_low_mm"], checks["feret_high_mm"] = feret["low"] * 1e3, feret["high"] * 1e3
    ratio = feret["low"] / feret["high"]
    y_up = np.cross(axis, chord_direction)  # y if the hub is at the low end
    offset = float(np.mean((mid - first) @ (basis @ y_up))) / chord
    checks["camber_offset_chord_share"] = offset
    hub_tip_ambiguous = False
    if hub_end is not None:
        sign = -1.0 if hub_end.startswith("+") else 1.0
        hub_low = sign * axis["xyz".index(hub_end[1])] > 0.0
        rules["hub_tip"] = f"given: the hub towards {hub_end} of the scan"
    elif abs(math.log(ratio)) > TAPER_MARGIN:
        hub_low = ratio > 1.0
        rules["hub_tip"] = (f"taper: the hub section is the longer ({max(feret.values()) * 1e3:.3f}"
                            f" mm against {min(feret.values()) * 1e3:.3f} mm at 10 %/90 % span)")
    elif suction_side is not None and abs(offset) > CAMBER_MARGIN:
        # the section lies off its pressure-side chord line towards its suction side
        hub_low = (offset > 0.0) == (suction_side == "+y")
        rules["hub_tip"] = (f"handedness: the suction side towards {suction_side} (untapered: "
                            f"sections {feret['low'] * 1e3:.3f} / {feret['high'] * 1e3:.3f} mm "
                            "at 10 %/90 % span)")
    else:
        hub_tip_ambiguous = True
        largest = int(np.argmax(np.abs(axis)))
        hub_low = axis[largest] > 0.0
        reason = ("untapered and uncambered" if suction_side is not None
                  else "untapered, the suction side not given")
        towards = f"{'-' if hub_low else '+'}{'xyz'[largest]}"
        rules["hub_tip"] = (f"ambiguous ({reason}; sections {feret['low'] * 1e3:.3f} / "
                            f"{feret['high'] * 1e3:.3f} mm at 10 %/90 % span): the hub taken "
                            f"towards {towards} of the scan (hub_end overrides)")
    z_axis = axis if hub_low else -axis
    hub_height = end_height["low"] if hub_low else end_height["high"]
    x_axis = chord_direction
    y_axis = np.cross(z_axis, x_axis)
    centre = basis.T @ (0.5 * (first + second))
    origin = centre - (centre @ axis) * axis + hub_height * axis
    rotation = np.array([x_axis, y_axis, z_axis])
    translation = -rotation @ origin
    span_axis = z_axis.copy()
    kept = bool(keep_scan_frame and _angle(span_axis, np.eye(3)[2]) < KEEP_ANGLE
                and span_axis[2] > 0.0)
    if kept:
        rotation, translation = np.eye(3), np.zeros(3)
        rules["frame"] = (f"the scan frame, already a blade frame (span axis "
                          f"{math.degrees(_angle(span_axis, np.eye(3)[2])):.3f}° from +z, hub "
                          "at the low end)")
    else:
        rules["frame"] = "x along the mid-span chord, z from the hub cap (z = 0) to the tip"
    return BladeFrame(rotation=rotation, translation=translation, span_axis=span_axis,
                      chord_direction=chord_direction, span=span, rules=rules,
                      hub_tip_ambiguous=hub_tip_ambiguous, edges_ambiguous=edges_ambiguous,
                      kept_scan_frame=kept, checks=checks)


def reconstruct_in_any_pose(points: np.ndarray, settings: ReconstructionSettings | None = None,
                            *, frame: BladeFrame | None = None, hub_end: str | None = None,
                            suction_side: str | None = None
                            ) -> tuple[Reconstruction, BladeFrame]:
    """Reconstruct a blade cloud (n, 3; m) in any pose: the blade frame from the data
    (:func:`estimate_blade_frame`, or ``frame`` when given), then
    :func:`~steamtwin.geometry.reconstruct.reconstruct_blade` in it.

    Returns the reconstruction in the blade frame (m) and the frame; ``frame.to_scan`` takes
    its vertices back to the scan frame. A cloud already in a blade frame is reconstructed as
    it is (``kept_scan_frame``). Both steps run with ``reconstruct.BLAS_THREADS`` BLAS
    thread(s).
    """
    with threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        if frame is None:
            frame = estimate_blade_frame(points, hub_end=hub_end, suction_side=suction_side)
        return reconstruct_blade(frame.to_blade(points), settings), frame


#: Rotation about the blade's x axis by 180°: the same frame with hub and tip swapped.
_FLIP = np.diag([1.0, -1.0, -1.0])


def nominal_starts(points: np.ndarray, blade: Blade, *, hub_end: str | None = None
                   ) -> list[np.ndarray]:
    """Coarse poses (4×4, scan → the nominal blade's frame) of a cloud (m) of ``blade``'s row:
    the cloud's frame from the data onto the nominal blade's, both estimated the same way (this
    package's rows have their suction side towards +y); with hub and tip swapped as well when
    the cloud's ends are ambiguous. Starting poses for
    :func:`~steamtwin.geometry.fidelity.align_to_nominal`."""
    vertices, triangles, _ = reference_surface(blade)
    nominal_points = surface_samples(vertices, triangles, SAMPLE_POINTS, np.random.default_rng(0))
    nominal = estimate_blade_frame(nominal_points, suction_side="+y", keep_scan_frame=False)
    measured = estimate_blade_frame(points, hub_end=hub_end, suction_side="+y",
                                    keep_scan_frame=False)
    to_nominal = np.linalg.inv(nominal.matrix)
    starts = [to_nominal @ measured.matrix]
    if measured.hub_tip_ambiguous:
        flip = np.eye(4)
        flip[:3, :3] = _FLIP
        flip[2, 3] = measured.span  # the tip cap onto z = 0
        starts.append(to_nominal @ flip @ measured.matrix)
    return starts
