"""Measured fidelity: deviation from the exact blade and row metrics, as JSON and CSV.

A reconstruction lives in the frame of the first scan view; it is first best-fitted to the
nominal blade (the design surface from the spec, as an inspection compares a part with its CAD):
principal axes of the complete cloud for a coarse pose (the four proper sign choices), then
point-to-plane ICP against the nominal surface. Deviations are distances to the exact surface
(:func:`~steamtwin.geometry.profile.reference_surface`, < 0.4 µm from it); row metrics are
measured on the section at the mean radius with the same algorithms for truth and measurement.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from matplotlib.path import Path as MplPath
from scipy.optimize import minimize
from scipy.spatial import ConvexHull, cKDTree

from steamtwin.geometry.profile import Blade, reference_surface
from steamtwin.geometry.registration import degeneracy_aware_icp
from steamtwin.geometry.rigid import transform
from steamtwin.geometry.volume_mesh import REGIONS

METRICS = ("chord", "stagger", "max_thickness", "throat")
METRIC_UNITS = {"chord": "mm", "stagger": "deg", "max_thickness": "mm", "throat": "mm"}


@dataclass(frozen=True)
class Deviation:
    """Distances (m) of a measured surface from the exact one (``p95``: 95th percentile of the
    measured points' distances, robust to the outliers that survive cleaning)."""

    mean: float
    rms: float
    max: float
    hausdorff: float
    count: int
    p95: float = float("nan")


@dataclass(frozen=True)
class SectionMetrics:
    """Row metrics of one section: chord (m), stagger (rad from axial), max thickness (m),
    throat (m)."""

    chord: float
    stagger: float
    max_thickness: float
    throat: float


def _scene(vertices: np.ndarray, triangles: np.ndarray) -> object:
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(vertices, np.float32)),
                        o3d.core.Tensor(np.asarray(triangles, np.uint32)))
    return scene


def distances_to_mesh(points: np.ndarray, vertices: np.ndarray,
                      triangles: np.ndarray) -> np.ndarray:
    """Unsigned distances (m) of points to a triangle mesh (exact point-triangle distance).

    Coordinates are shifted to the mesh centre before the single-precision query, so the
    rounding stays below 10 nm for parts up to a metre.
    """
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    centre = vertices.mean(axis=0)
    scene = _scene(vertices - centre, triangles)
    query = o3d.core.Tensor(np.asarray(points - centre, np.float32))
    return scene.compute_distance(query).numpy().astype(np.float64)


def blade_distance(blade: Blade, points: np.ndarray) -> np.ndarray:
    """Unsigned distance (m) of points to the exact blade surface.

    The sides come from the fine reference triangulation (well-shaped 0.05 × 0.5 mm triangles);
    the flat root and tip caps are measured analytically in double precision (their ear-clipped
    triangles are slivers that single-precision queries resolve only to ~10 µm).
    """

    vertices, triangles, regions = reference_surface(blade)
    caps = (regions == REGIONS.index("root")) | (regions == REGIONS.index("tip"))
    distance = distances_to_mesh(points, vertices, triangles[~caps])
    outline, _ = blade.profile.sample(5e-5)
    for radius in (blade.design.hub_radius, blade.design.tip_radius):
        section = blade.place(outline, radius)[:, :2]
        near = np.abs(points[:, 2] - radius) < distance
        if not np.any(near):
            continue
        inside = MplPath(section).contains_points(points[near, :2])
        dz = np.abs(points[near, 2] - radius)
        edge = cKDTree(section).query(points[near, :2])[0]
        cap = np.where(inside, dz, np.hypot(dz, edge))
        distance[near] = np.minimum(distance[near], cap)
    return distance


def surface_samples(vertices: np.ndarray, triangles: np.ndarray, count: int,
                    random_state: np.random.Generator | int | None = 0) -> np.ndarray:
    """``count`` points uniformly distributed over a triangle mesh's area."""
    return sample_triangles(vertices, triangles, count, random_state)[0]


def sample_triangles(vertices: np.ndarray, triangles: np.ndarray, count: int,
                     random_state: np.random.Generator | int | None = 0
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``count`` points (m) uniformly distributed over a triangle mesh's area, the triangle
    each lies on and that triangle's unit normal (by the vertex order: outward on a
    consistently wound closed mesh). Triangle by area, then uniform barycentric coordinates
    with the reflection trick (Turk 1990, *Graphics Gems* I, "Generating random points in
    triangles")."""
    p = vertices[triangles]
    cross = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    rng = np.random.default_rng(random_state)
    pick = rng.choice(len(triangles), size=count, p=area / area.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    a, b, c = p[pick, 0], p[pick, 1], p[pick, 2]
    normals = cross[pick] / np.linalg.norm(cross[pick], axis=1, keepdims=True)
    return a + u[:, None] * (b - a) + v[:, None] * (c - a), pick, normals


def surface_deviation(blade: Blade, points: np.ndarray, vertices: np.ndarray | None = None,
                      triangles: np.ndarray | None = None, samples: int = 200_000,
                      random_state: np.random.Generator | int | None = 0) -> Deviation:
    """Deviation of measured ``points`` (blade frame, m) from the exact blade surface.

    mean/RMS/max are over the points; the Hausdorff distance also takes the exact surface's
    distance to the measured one, from ``samples`` points spread over the exact surface, to the
    measured mesh (``vertices``, ``triangles``) or, without a mesh, to the nearest point.
    """
    rng = np.random.default_rng(random_state)
    ref_v, ref_t, _ = reference_surface(blade)
    forward = blade_distance(blade, points)
    truth_points = surface_samples(ref_v, ref_t, samples, rng)
    if vertices is not None and triangles is not None:
        backward = distances_to_mesh(truth_points, vertices, triangles)
    else:
        backward = cKDTree(points).query(truth_points)[0]
    return Deviation(mean=float(forward.mean()), rms=float(np.sqrt(np.mean(forward**2))),
                     max=float(forward.max()),
                     hausdorff=float(max(forward.max(), backward.max())), count=len(points),
                     p95=float(np.percentile(forward, 95.0)))


# --- best fit to the nominal blade -----------------------------------------------------------


def align_to_nominal(points: np.ndarray, blade: Blade, distance: float = 1.0e-3,
                     starts: Sequence[np.ndarray] = ()) -> tuple[np.ndarray, float]:
    """Rigid transformation (4×4) taking a complete measured cloud onto the nominal blade, and
    the RMS point-to-plane residual (m) of the fit.

    Coarse: principal axes of the cloud onto those of the nominal surface, trying the four
    proper sign choices, and the given ``starts`` (4×4 poses, e.g. the blade frames from the
    data, :func:`~steamtwin.geometry.frame.nominal_starts`); fine: point-to-plane ICP against
    the nominal; the lowest RMS distance to the exact blade wins (all candidates measured in one
    query: building the exact surface's search structure costs far more than the points).
    """
    ref_v, ref_t, _ = reference_surface(blade)
    rng = np.random.default_rng(0)
    nominal, _, nominal_normals = sample_triangles(ref_v, ref_t, 30_000, rng)
    sub = points[rng.permutation(len(points))[:10_000]]

    def axes(cloud: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        centre = cloud.mean(axis=0)
        _, vectors = np.linalg.eigh(np.cov((cloud - centre).T))
        return centre, vectors

    c_meas, v_meas = axes(sub)
    c_nom, v_nom = axes(nominal)
    guesses = []
    for signs in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
        rotation = v_nom @ np.diag(signs) @ v_meas.T
        if np.linalg.det(rotation) < 0.0:
            rotation = v_nom @ np.diag(signs) @ np.diag([1, 1, -1]) @ v_meas.T
        guess = np.eye(4)
        guess[:3, :3] = rotation
        guess[:3, 3] = c_nom - rotation @ c_meas
        guesses.append(guess)
    poses = []
    for pose in [*guesses, *starts]:
        for scale in (8.0, 4.0, 2.0, 1.0):
            pose, _, _, _ = degeneracy_aware_icp(sub, nominal, nominal_normals, pose,
                                                 scale * distance, stability=0.0)
        poses.append(pose)
    moved = np.concatenate([transform(sub, pose) for pose in poses])
    rms = np.sqrt(np.mean(blade_distance(blade, moved).reshape(len(poses), -1) ** 2, axis=1))
    best = int(np.argmin(rms))
    return poses[best], float(rms[best])


# --- row metrics ---------------------------------------------------------------------------------


def _densify(polygon: np.ndarray, spacing: float) -> np.ndarray:
    """Closed polyline with points at most ``spacing`` apart."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    counts = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(int))
    t = np.concatenate([np.arange(c) / c for c in counts])
    start = np.repeat(np.arange(len(a)), counts)
    return a[start] + t[:, None] * (b[start] - a[start])


def chord_line(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """The chord line of a closed section polyline (n, 2; m): its leading and trailing touch
    points (m, the leading one upstream) and whether the section has a concave side to rest on.

    The chord line is the double tangent (bitangent) of the section on its concave (pressure)
    side: the line a straight edge laid against the pressure side touches at the leading and
    trailing edges — the "caliper" chord line of blade inspection (Hexagon PC-DMIS Blade 6.0
    help, *Chord Angle*, method CALIPER: "the line that will touch the CCV [concave] curve in two
    places"; *Terms and Definitions*, chord line: "a line that is tangential to the concave side
    of a blade section"). It is the longest edge of the section's convex hull, the one bridging
    the concave side. It is well conditioned: an error ε of the surface at a touch point moves the
    line by ε there, so its direction by ε / (distance between the touch points), where the
    farthest pair of points slides round the edge circles by √(2 r ε).

    A section without a concave side (its longest hull edge shorter than half its diameter:
    a convex polygon such as a circle) has no bitangent; the farthest pair of points stands in.
    """
    polygon = np.asarray(polygon, dtype=np.float64)
    hull = polygon[ConvexHull(polygon).vertices]
    edges = np.roll(hull, -1, axis=0) - hull
    length = np.linalg.norm(edges, axis=1)
    longest = int(np.argmax(length))
    first, second = hull[longest], hull[(longest + 1) % len(hull)]
    diameter = farthest_pair(hull)
    concave = bool(length[longest] >= 0.5 * np.linalg.norm(diameter[1] - diameter[0]))
    if not concave:
        first, second = diameter
    if first[0] > second[0]:
        first, second = second, first
    return first, second, concave


def farthest_pair(hull: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two hull points farthest apart: on a thinned hull first, then among the neighbours
    of that pair."""
    k = max(1, len(hull) // 800)
    coarse = hull[::k]
    d = np.linalg.norm(coarse[:, None] - coarse[None], axis=2)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    near_i = hull[np.arange(i * k - k, i * k + k + 1) % len(hull)]
    near_j = hull[np.arange(j * k - k, j * k + k + 1) % len(hull)]
    d = np.linalg.norm(near_i[:, None] - near_j[None], axis=2)
    a, b = np.unravel_index(np.argmax(d), d.shape)
    return near_i[a], near_j[b]


def section_metrics(polygon: np.ndarray, pitch: float | None) -> SectionMetrics:
    """Row metrics of a closed section polyline (n, 2) in the unrolled x (axial) - y
    (tangential) plane, with the neighbouring blade ``pitch`` (m) away in +y (None: unknown,
    the throat is NaN).

    The chord line is the bitangent on the pressure side (:func:`chord_line`); stagger is its
    angle from the axial direction, the normal of the cascade front (rad, positive towards +y;
    Dixon & Hall, *Fluid Mechanics and Thermodynamics of Turbomachinery*, ch. 3, cascade
    geometry); chord is the length of the section's projection onto the chord line (the
    distance between the two perpendiculars to it that touch the leading and the trailing
    edge: the caliper chord of PC-DMIS Blade 6.0, *Chord Length*). Max thickness = diameter of
    the largest inscribed circle; throat = shortest distance from the neighbour's trailing-edge
    region (its last 6 % of axial chord) to this section (the cascade throat, Pritchard 1985).
    """
    polygon = np.asarray(polygon, dtype=np.float64)
    lead, trail, _ = chord_line(polygon)
    direction = (trail - lead) / np.linalg.norm(trail - lead)
    stagger = math.atan2(direction[1], direction[0])
    chord = float(np.ptp(polygon @ direction))
    dense = _densify(polygon, chord / 20_000)
    tree = cKDTree(dense)
    # largest inscribed circle: best of a grid inside the section, then refined
    lo, hi = polygon.min(axis=0), polygon.max(axis=0)
    step = chord / 150.0
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0], step), np.arange(lo[1], hi[1], step))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    outline = polygon[:: max(1, len(polygon) // 2000)]
    inside = grid[MplPath(outline).contains_points(grid)]
    depth = tree.query(inside)[0]
    start = inside[np.argmax(depth)]
    result = minimize(lambda c: -tree.query(c)[0], start, method="Nelder-Mead",
                      options={"xatol": 1e-8, "fatol": 1e-10})
    thickness = 2.0 * float(-result.fun)
    throat = float("nan") if pitch is None else _throat(dense, tree, pitch)
    return SectionMetrics(chord=chord, stagger=stagger, max_thickness=thickness, throat=throat)


def _throat(dense: np.ndarray, tree: cKDTree, pitch: float) -> float:
    lo, hi = dense[:, 0].min(), dense[:, 0].max()
    neighbour = dense + np.array([0.0, pitch])
    trailing = neighbour[neighbour[:, 0] > hi - 0.06 * (hi - lo)]
    return float(tree.query(trailing)[0].min())


def section_throat(polygon: np.ndarray, pitch: float) -> float:
    """The throat (m) of :func:`section_metrics` alone (faster)."""
    polygon = np.asarray(polygon, dtype=np.float64)
    extent = float(np.ptp(polygon[:, 0]))
    dense = _densify(polygon, extent / 20_000)
    return _throat(dense, cKDTree(dense), pitch)


def truth_section(blade: Blade, radius: float | None = None) -> np.ndarray:
    """The exact section polyline (≈ 5 µm spacing) at ``radius`` (default: mean), x-y in m."""
    radius = blade.design.mean_radius if radius is None else radius
    return blade.place(blade.profile.dense[0], radius)[:, :2]


def section_pitch(blade: Blade, radius: float | None = None) -> float:
    """Blade pitch 2πr/N (m) at ``radius`` (default: mean)."""
    radius = blade.design.mean_radius if radius is None else radius
    return 2.0 * math.pi * radius / blade.profile.params.blade_count


# --- reports -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FidelityReport:
    """Deviation and row-metric errors of one reconstructed blade."""

    row: str
    deviation: Deviation
    truth: SectionMetrics
    measured: SectionMetrics
    extra: dict

    def metric_rows(self) -> list[dict[str, float | str]]:
        """One row per metric, in engineering units (mm, deg)."""
        rows = []
        for name in METRICS:
            factor = math.degrees(1.0) if name == "stagger" else 1e3
            truth = getattr(self.truth, name) * factor
            measured = getattr(self.measured, name) * factor
            rows.append({"metric": name, "unit": METRIC_UNITS[name], "truth": truth,
                         "measured": measured, "error": measured - truth})
        return rows

    def as_dict(self) -> dict:
        deviation = {k: (v * 1e3 if k != "count" else v)
                     for k, v in asdict(self.deviation).items()}
        return {"row": self.row, "deviation_mm": deviation, "metrics": self.metric_rows(),
                **self.extra}


def write_report(report: FidelityReport, path: str | Path) -> tuple[Path, Path]:
    """Write ``report`` as ``<path>.json`` and ``<path>.csv`` (metrics and deviations)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    json_path, csv_path = path.with_suffix(".json"), path.with_suffix(".csv")
    json_path.write_text(json.dumps(report.as_dict(), indent=2, default=float),
                         encoding="utf-8")
    with csv_path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=["metric", "unit", "truth", "measured",
                                                    "error"])
        writer.writeheader()
        for row in report.metric_rows():
            writer.writerow(row)
        for key, value in asdict(report.deviation).items():
            if key != "count":
                writer.writerow({"metric": f"deviation_{key}", "unit": "mm", "truth": 0.0,
                                 "measured": value * 1e3, "error": value * 1e3})
    return json_path, csv_path
