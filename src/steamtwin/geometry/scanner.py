"""A virtual handheld laser scanner: partial, noisy, outlier-ridden views of a blade.

Each view looks at the ground-truth blade from one camera position; rays are cast against the
exact surface (a fine triangulation, open3d ``RaycastingScene``), so the blade hides parts of
itself (self-occlusion). Every hit is displaced along its ray by a truncated Gaussian error,
σ = 0.025 mm cut at ±0.05 mm: a scanner specified at ±0.05 mm as a 2σ bound (the way handheld
scanners state volumetric accuracy, VDI/VDE 2634-2). A share of outliers (1–3 %) is scattered
uniformly through the view's bounding box, and every view is expressed in its own unknown frame
(a random rigid motion), as a handheld scanner does before registration.

Matte reference spheres on the fixture (the sphere standards of VDI/VDE 2634-2/-3, the datums
that link the views of a multi-view scan) are part of the scene by default: they are hit by the
same rays, hide parts of the blade and are hidden by it, and get the same range error.

How many points a blade needs is planned from its nominal geometry (:func:`planned_points`),
as a metrology engineer sets a scanner's resolution from the smallest feature to capture: the
method's ~150k points per blade, more where the fused cloud would otherwise put too few points
across the blade's edges to reconstruct them (every row but hp1 of the reference unit).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from steamtwin.geometry.pointcloud import write_point_cloud
from steamtwin.geometry.preprocess_settings import KEPT_SHARE
from steamtwin.geometry.profile import Blade, reference_surface
from steamtwin.geometry.rigid import rotation_about
from steamtwin.progress import ProgressCallback

#: Files of a scan folder: views as ``view_00.ply`` …, settings in ``scan.json`` and the hidden
#: truth (view poses, reference-sphere centres) in ``truth/poses.json``; reconstruction must not
#: read ``truth/``.
MANIFEST = "scan.json"

#: Reference-sphere positions around the blade, fixed in the blade frame: azimuth about the span
#: axis (deg), distance from the span axis through the blade's centre and height above its
#: mid-span, both as multiples of the blade's bounding-sphere radius. Chosen unequal in all
#: three so that no two spheres (or sub-configurations) are related by a symmetry — the centres
#: fix a view's pose uniquely —, outside the blade's bounding sphere (1.25–1.55 radii) so that
#: the blade hides only part of a sphere from a camera on the other side, and within 0.45 radii
#: of mid-span so that the cameras 35° above and 35° below both see them.
SPHERE_LAYOUT = ((17.0, 1.25, -0.30), (103.0, 1.40, 0.18), (196.0, 1.30, -0.08),
                 (284.0, 1.45, 0.34), (58.0, 1.55, 0.45), (241.0, 1.35, -0.42))


#: The method's scan size: ~150k points per blade, the fewest :func:`planned_points` plans.
METHOD_SCAN_POINTS = 150_000

#: Points of the fused cloud across an edge's half circle (π·r) that reconstruction needs to
#: hold the edge within the 0.1 mm limit (docs/benchmarks.md, "Scan density"). At 150k points,
#: seed 0: ip9 with 2.5 points across its trailing edge is 0.47 mm off at the edge; ip8 (2.65)
#: and ip6 (2.93) 0.067 / 0.066 mm, at the margin. At 3.5 points, hp13 (3.6 at 150k) missed
#: the limit on 1 seed of 8 (0.19 mm where a random gap in the points, 0.5 × 4 mm, meets the
#: trailing edge at the tip) and ip4 on seed 0 (0.11 mm, same place); at 4.5 hp13 met it on
#: every seed tried (max 0.035–0.048 mm).
EDGE_SAMPLES = 4.5


def planned_points(blade: Blade, edge_samples: float = EDGE_SAMPLES,
                   kept_share: float = KEPT_SHARE, minimum: int = METHOD_SCAN_POINTS) -> int:
    """Scan points (all views, with outliers) that resolve ``blade``'s edges after fusion.

    The fused cloud keeps ``kept_share`` of the N scanned points over the blade's surface area
    A, so its mean spacing is h = sqrt(A / (kept_share·N)); ``edge_samples`` points on the half
    circle π·r of the smaller edge radius r (at the narrowest section) need
    h = π·r / edge_samples, i.e. N = A·edge_samples² / (kept_share·(π·r)²). Never fewer than
    ``minimum`` (the method's ~150k per blade).
    """
    if not (edge_samples > 0.0 and 0.0 < kept_share <= 1.0 and minimum > 0):
        raise ValueError("edge_samples and minimum must be > 0 and kept_share within (0, 1]")
    vertices, triangles, _ = reference_surface(blade)
    corners = vertices[triangles]
    area = 0.5 * float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                               corners[:, 2] - corners[:, 0]), axis=1).sum())
    params, design = blade.profile.params, blade.design
    narrowest = float(np.min(design.chord_scale(np.array([design.hub_radius,
                                                         design.tip_radius]))))
    edge = min(params.leading_edge_radius, params.trailing_edge_radius) * narrowest
    needed = area * edge_samples**2 / (kept_share * (math.pi * edge) ** 2)
    return max(minimum, math.ceil(needed))


#: Reference-sphere diameter as a share of the blade's bounding diameter: VDI/VDE 2634-2 sizes
#: its sphere standard at 0.1–0.2 of the measuring volume's length L0; 1/7 keeps hp1's 10 mm.
SPHERE_DIAMETER_SHARE = 1.0 / 7.0


def planned_sphere_radius(bounding_radius: float) -> float:
    """Reference-sphere radius (m) for a blade of ``bounding_radius`` (m): the diameter
    :data:`SPHERE_DIAMETER_SHARE` of the blade's bounding diameter, rounded to whole mm as sphere
    standards come, at least 1 mm. Measured on ip9 (2026-11-25): 5 mm spheres on its 360 mm
    left view poses 0.039 mm off (too few sphere points, centres to 0.03 mm), 20 mm 0.003 mm."""
    if not bounding_radius > 0.0:
        raise ValueError(f"bounding_radius = {bounding_radius} m (expected > 0)")
    return max(1, round(SPHERE_DIAMETER_SHARE * bounding_radius * 1e3)) / 1e3


@dataclass(frozen=True)
class ScannerSettings:
    """Scanner hyper-parameters (lengths in m).

    ``points`` is the total number of points over all views; ``noise_sigma`` and ``noise_bound``
    the range error's standard deviation and truncation; ``outlier_share`` the share of points
    that are outliers (1–3 % for handheld scanners on shiny metal); ``distance`` the camera
    stand-off as a multiple of the blade's bounding-sphere radius. ``tracking_angle`` and
    ``tracking_offset`` bound the error of the pose the scanner reports for each view (its
    positioning-target tracking, before any registration): a rotation of that angle about a
    random axis and a shift of that length in a random direction. The defaults (0.5 mrad, i.e.
    0.05 mm at the 0.1 m stand-off, and 0.05 mm) are the order of the volumetric accuracy that
    positioning-target tracking of metrology handheld scanners is accepted at (VDI/VDE 2634-3).

    ``reference_spheres`` (0–6) matte spheres of radius ``sphere_radius`` stand on the fixture
    at the fixed places :data:`SPHERE_LAYOUT`. None (the default) sizes them to the blade
    (:func:`planned_sphere_radius`): VDI/VDE 2634-2 sizes its sphere standard at 0.1–0.2 of the
    measuring volume's length L0, here the blade's bounding diameter — 5 mm radius for hp1's
    ~73 mm, 26 mm for ip9's ~360 mm; large enough that a partly hidden sphere still holds
    hundreds of points (centre to ~µm), small enough to hide little of the blade. The sphere
    points come on top of ``points`` (the blade keeps its budget), at the same sampling density;
    outliers stay a share of the blade points (reflections of the shiny blade, not of the matte
    spheres). ``reference_spheres = 0`` is the scanner without spheres, point for point.
    """

    views: int = 8
    points: int = 150_000
    noise_sigma: float = 0.025e-3
    noise_bound: float = 0.05e-3
    outlier_share: float = 0.02
    distance: float = 3.0
    tracking_angle: float = 5e-4  # rad, error of the scanner's own pose estimate
    tracking_offset: float = 0.05e-3  # m
    reference_spheres: int = 4
    sphere_radius: float | None = None  # m; None: sized to the blade

    def validate(self) -> None:
        problems = []
        if not 0 <= self.reference_spheres <= len(SPHERE_LAYOUT):
            problems.append(f"reference_spheres = {self.reference_spheres} "
                            f"(expected 0-{len(SPHERE_LAYOUT)})")
        if self.sphere_radius is not None and not 1e-3 <= self.sphere_radius <= 50e-3:
            problems.append(f"sphere_radius = {self.sphere_radius} m (expected 1-50 mm)")
        if self.views < 2:
            problems.append(f"views = {self.views} (need >= 2)")
        if self.points < 100 * self.views:
            problems.append(f"points = {self.points} (need >= 100 per view)")
        if not 0.0 <= self.outlier_share <= 0.2:
            problems.append(f"outlier_share = {self.outlier_share} (expected 0-0.2)")
        if not 0.0 <= self.noise_sigma <= 1e-3 or not 0.0 <= self.noise_bound <= 1e-3:
            problems.append(f"noise {self.noise_sigma}/{self.noise_bound} m (expected <= 1 mm)")
        if problems:
            raise ValueError("invalid scanner settings: " + "; ".join(problems))


@dataclass(frozen=True)
class ScanView:
    """One view: points (n, 3) in the view's own frame and its hidden pose.

    The view frame is the scanner's: camera at the origin, viewing along +z. ``pose`` (4×4) maps
    view-frame points to the blade frame; ``is_outlier`` marks the injected
    outliers and ``sphere_index`` the reference sphere a point lies on (−1: blade or outlier;
    both truth, for tests); ``camera`` is the camera position in the blade frame (m).
    ``tracked_pose`` is the scanner's own, erroneous estimate of ``pose`` (the user sees it).
    """

    points: np.ndarray
    pose: np.ndarray
    tracked_pose: np.ndarray
    is_outlier: np.ndarray
    camera: np.ndarray
    sphere_index: np.ndarray


@dataclass(frozen=True)
class Scan:
    """All views of one blade and the settings that made them; ``sphere_centres`` (k, 3) are
    the reference spheres' centres in the blade frame (m; hidden truth)."""

    row: str
    views: tuple[ScanView, ...]
    settings: ScannerSettings
    seed: int | None = None
    extra: dict = field(default_factory=dict)
    sphere_centres: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))


def blade_raycasting_scene(blade: Blade) -> object:
    """An open3d ``RaycastingScene`` holding the exact blade surface (see
    :func:`~steamtwin.geometry.profile.reference_surface`)."""
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    vertices, triangles, _ = reference_surface(blade)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(vertices.astype(np.float32)),
                        o3d.core.Tensor(triangles.astype(np.uint32)))
    return scene


def _look_at(camera: np.ndarray, target: np.ndarray, roll: float) -> np.ndarray:
    """Rotation whose columns are the camera axes (x, y, z = viewing direction) in the blade
    frame, rolled by ``roll`` rad about the viewing direction."""
    z = (target - camera) / np.linalg.norm(target - camera)
    x = np.cross(z, [0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    c, s = math.cos(roll), math.sin(roll)
    return np.column_stack([c * x + s * y, -s * x + c * y, z])


def camera_positions(centre: np.ndarray, radius: float, count: int) -> np.ndarray:
    """``count`` camera positions around the blade: a ring around the span axis (z) at
    alternating ±35° elevation, so both caps and every side are seen by some view."""
    azimuth = 2.0 * math.pi * (np.arange(count) + 0.5) / count
    elevation = np.radians(np.where(np.arange(count) % 2 == 0, 35.0, -35.0))
    direction = np.column_stack([np.cos(elevation) * np.cos(azimuth),
                                 np.cos(elevation) * np.sin(azimuth), np.sin(elevation)])
    return centre + radius * direction


def reference_sphere_centres(centre: np.ndarray, radius: float, count: int) -> np.ndarray:
    """Centres (count, 3; m) of the first ``count`` reference spheres of :data:`SPHERE_LAYOUT`
    around a blade whose bounding sphere has ``centre`` and ``radius`` (m)."""
    layout = np.array(SPHERE_LAYOUT[:count], dtype=np.float64).reshape(-1, 3)
    azimuth = np.radians(layout[:, 0])
    offset = np.column_stack([layout[:, 1] * np.cos(azimuth), layout[:, 1] * np.sin(azimuth),
                              layout[:, 2]])
    return np.asarray(centre, dtype=np.float64) + radius * offset


def ray_sphere_hits(origin: np.ndarray, directions: np.ndarray, centres: np.ndarray,
                    radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact (analytic) first intersection of unit rays from ``origin`` with spheres of
    ``radius`` (m) at ``centres``: the distance along each ray (m; inf for a miss) and the index
    of the sphere hit (−1 for a miss)."""
    distance = np.full(len(directions), np.inf)
    index = np.full(len(directions), -1, dtype=np.int64)
    for k, centre in enumerate(np.asarray(centres, dtype=np.float64)):
        offset = centre - origin
        along = directions @ offset
        discriminant = along * along - (offset @ offset - radius * radius)
        t = along - np.sqrt(np.maximum(discriminant, 0.0))
        t = np.where((discriminant >= 0.0) & (t > 0.0), t, np.inf)
        closer = t < distance
        distance[closer] = t[closer]
        index[closer] = k
    return distance, index


def _sphere_discs(camera: np.ndarray, centre: np.ndarray, spheres: np.ndarray, radius: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Discs in the target plane (through ``centre``, normal to the viewing axis) that hold
    each sphere's outline seen from ``camera``: their centres (k, 3) and radii (k,), m.

    The outline is a cone of half-angle α = asin(r / d) about the direction to the sphere, at
    θ from the axis; its section with the plane lies within plane distance × (tan(θ + α) −
    tan θ) of where the sphere's centre projects (2 % margin)."""
    axis = (centre - camera) / np.linalg.norm(centre - camera)
    plane = float(np.linalg.norm(centre - camera))
    towards = spheres - camera
    length = np.linalg.norm(towards, axis=1)
    depth = towards @ axis
    theta = np.arccos(np.clip(depth / length, -1.0, 1.0))
    alpha = np.arcsin(np.minimum(radius / length, 1.0))
    if np.any(theta + alpha >= math.radians(80.0)):
        raise ValueError("a reference sphere lies too far off the viewing direction of a camera")
    projected = camera + towards * (plane / depth)[:, None]
    radii = 1.02 * plane * (np.tan(theta + alpha) - np.tan(theta))
    return projected, radii


def scan_blade(blade: Blade, settings: ScannerSettings | None = None,
               random_state: np.random.Generator | int | None = None,
               progress: ProgressCallback | None = None) -> Scan:
    """Scan ``blade`` with the virtual scanner (seeded by ``random_state``: a Generator or a seed).

    Rays aim at random points, uniformly distributed over the target plane's disc that holds
    the blade and over the discs that hold the reference spheres' outlines; each ray ends at
    the nearest of the blade (open3d ray casting) and the spheres (exact intersection). Rays
    are cast until the blade has its points; a sphere keeps the hits of the same rays.
    """
    import open3d as o3d  # deferred: heavy import (~2 s), only the steps that use it pay

    settings = settings or ScannerSettings()
    settings.validate()
    seed = random_state if isinstance(random_state, int) else None
    rng = np.random.default_rng(random_state)
    scene = blade_raycasting_scene(blade)
    vertices, _, _ = blade.surface_mesh(2e-3)
    centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
    sphere = float(np.linalg.norm(vertices - centre, axis=1).max())
    if settings.sphere_radius is None:
        settings = replace(settings, sphere_radius=planned_sphere_radius(sphere))
    cameras = camera_positions(centre, settings.distance * sphere, settings.views)
    spheres = reference_sphere_centres(centre, sphere, settings.reference_spheres)
    per_view = settings.points // settings.views
    views = []
    for k, camera in enumerate(cameras):
        inliers_wanted = round(per_view * (1.0 - settings.outlier_share))
        axis = (centre - camera) / np.linalg.norm(centre - camera)
        e1 = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis, e1)
        discs = _sphere_discs(camera, centre, spheres, settings.sphere_radius)
        batches, batch_labels = [], []
        blade_hits = rays_cast = 0
        while blade_hits < inliers_wanted:
            # rays towards random points of the bounding sphere's disc facing the camera
            count = max(1000, int(1.3 * (inliers_wanted - blade_hits) * (rays_cast + 1000)
                                  / max(blade_hits, 1000)))
            rho = sphere * np.sqrt(rng.random(count))
            phi = 2.0 * math.pi * rng.random(count)
            targets = centre + (rho * np.cos(phi))[:, None] * e1 + (rho * np.sin(phi))[:, None] * e2
            if len(spheres):
                targets = _with_sphere_targets(targets, rng, centre, sphere, *discs, e1, e2)
            dirs = targets - camera
            dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
            rays = np.column_stack([np.repeat(camera[None], len(dirs), axis=0), dirs])
            answer = scene.cast_rays(o3d.core.Tensor(rays.astype(np.float32)))
            t_hit = answer["t_hit"].numpy().astype(np.float64)
            label = np.full(len(dirs), -1, dtype=np.int64)
            if len(spheres):
                t_sphere, which = ray_sphere_hits(camera, dirs, spheres, settings.sphere_radius)
                nearer = t_sphere < t_hit
                t_hit = np.where(nearer, t_sphere, t_hit)
                label = np.where(nearer, which, -1)
            ok = np.isfinite(t_hit)
            error = _truncated_normal(rng, int(ok.sum()), settings.noise_sigma,
                                      settings.noise_bound)
            batches.append(camera + dirs[ok] * (t_hit[ok] + error)[:, None])
            batch_labels.append(label[ok])
            blade_hits += int(np.sum(label[ok] < 0))
            rays_cast += count
        # keep the rays up to the one that gives the blade its last point
        labels = np.concatenate(batch_labels)
        last = int(np.flatnonzero(labels < 0)[inliers_wanted - 1]) + 1
        hits, labels = np.concatenate(batches)[:last], labels[:last]
        outlier_count = per_view - inliers_wanted
        lo, hi = hits[labels < 0].min(axis=0), hits[labels < 0].max(axis=0)
        margin = 0.05 * (hi - lo)
        outliers = rng.uniform(lo - margin, hi + margin, size=(outlier_count, 3))
        points = np.concatenate([hits, outliers])
        is_outlier = np.concatenate([np.zeros(len(hits), bool), np.ones(outlier_count, bool)])
        sphere_index = np.concatenate([labels, np.full(outlier_count, -1, dtype=np.int64)])
        order = rng.permutation(len(points))
        points, is_outlier, sphere_index = points[order], is_outlier[order], sphere_index[order]
        # the view's frame is the scanner's own: camera at the origin looking along +z, with a
        # random roll about the viewing axis; its pose in the blade frame is unknown to the user
        rotation = _look_at(camera, centre, float(rng.uniform(0.0, 2.0 * math.pi)))
        pose = np.eye(4)  # view frame -> blade frame: x_blade = R x_view + camera
        pose[:3, :3] = rotation
        pose[:3, 3] = camera
        local = (points - camera) @ rotation
        tracked = _perturbed(pose, settings.tracking_angle, settings.tracking_offset, rng)
        views.append(ScanView(points=local, pose=pose, tracked_pose=tracked,
                              is_outlier=is_outlier, camera=camera, sphere_index=sphere_index))
        if progress is not None:
            progress((k + 1) / len(cameras), f"view {k + 1}/{len(cameras)} scanned")
    return Scan(row=blade.row, views=tuple(views), settings=settings, seed=seed,
                sphere_centres=spheres)


def _with_sphere_targets(targets: np.ndarray, rng: np.random.Generator, centre: np.ndarray,
                         radius: float, disc_centres: np.ndarray, disc_radii: np.ndarray,
                         e1: np.ndarray, e2: np.ndarray) -> np.ndarray:
    """``targets`` (uniform on the blade's disc of ``radius`` about ``centre``) joined by
    targets on the spheres' discs at the same density, each disc's samples falling in the
    blade's disc or an earlier disc dropped: uniform over the union. Shuffled, so that the
    first rays of a batch are a uniform sample too."""
    density = len(targets) / (math.pi * radius**2)
    joined = [targets]
    for k, (middle, size) in enumerate(zip(disc_centres, disc_radii, strict=True)):
        count = round(density * math.pi * size**2)
        rho = size * np.sqrt(rng.random(count))
        phi = 2.0 * math.pi * rng.random(count)
        new = middle + (rho * np.cos(phi))[:, None] * e1 + (rho * np.sin(phi))[:, None] * e2
        covered = np.linalg.norm(new - centre, axis=1) < radius
        for before, size_before in zip(disc_centres[:k], disc_radii[:k], strict=True):
            covered |= np.linalg.norm(new - before, axis=1) < size_before
        joined.append(new[~covered])
    targets = np.concatenate(joined)
    return targets[rng.permutation(len(targets))]


def _perturbed(pose: np.ndarray, angle: float, offset: float,
               rng: np.random.Generator) -> np.ndarray:
    """``pose`` rotated by ``angle`` about a random axis and shifted by ``offset`` (m)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rotation = rotation_about(axis, angle)
    direction = rng.normal(size=3)
    out = pose.copy()
    out[:3, :3] = rotation @ pose[:3, :3]
    out[:3, 3] = pose[:3, 3] + offset * direction / np.linalg.norm(direction)
    return out


def _truncated_normal(rng: np.random.Generator, count: int, sigma: float,
                      bound: float) -> np.ndarray:
    """Normal samples N(0, σ²) redrawn until they lie within ±bound."""
    values = rng.normal(0.0, sigma, count) if sigma > 0.0 else np.zeros(count)
    bad = np.abs(values) > bound
    while np.any(bad):
        values[bad] = rng.normal(0.0, sigma, int(bad.sum()))
        bad = np.abs(values) > bound
    return values


def write_scan(scan: Scan, folder: str | Path, file_format: str = "ply") -> list[Path]:
    """Write the views as ``view_NN.ply``/``.pcd``, ``scan.json`` (settings, the scanner's
    tracked poses and the nominal ``sphere_radius``, m, null without spheres) and the hidden
    ``truth/poses.json`` (poses, sphere centres in the blade frame, points per sphere)."""
    if file_format not in ("ply", "pcd"):
        raise ValueError(f"file_format must be 'ply' or 'pcd' (got {file_format!r})")
    folder = Path(folder)
    (folder / "truth").mkdir(parents=True, exist_ok=True)
    paths = []
    for k, view in enumerate(scan.views):
        path = folder / f"view_{k:02d}.{file_format}"
        write_point_cloud(view.points, path)
        paths.append(path)
    spheres = scan.settings.reference_spheres > 0
    manifest = {"row": scan.row, "seed": scan.seed, "units": "m",
                "views": [p.name for p in paths], "settings": asdict(scan.settings),
                "tracked_poses": [v.tracked_pose.tolist() for v in scan.views],
                "sphere_radius": scan.settings.sphere_radius if spheres else None}
    (folder / MANIFEST).write_text(json.dumps(manifest, indent=2), encoding="utf-8")
    truth = {"poses": [v.pose.tolist() for v in scan.views],
             "outliers": [int(v.is_outlier.sum()) for v in scan.views],
             "cameras": [v.camera.tolist() for v in scan.views],
             "sphere_centres": scan.sphere_centres.tolist(),
             "sphere_points": [int(np.sum(v.sphere_index >= 0)) for v in scan.views]}
    (folder / "truth" / "poses.json").write_text(json.dumps(truth), encoding="utf-8")
    return paths
