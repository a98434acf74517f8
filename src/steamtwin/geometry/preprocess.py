"""Point-cloud preprocessing, the orchestration: reference spheres -> outliers -> MLS smoothing
-> registration -> fusion -> downsampling (:func:`preprocess_views`).

The steps live in their own modules — the filters in :mod:`~steamtwin.geometry.filters`, the
sphere targets in :mod:`~steamtwin.geometry.targets`, the registration in
:mod:`~steamtwin.geometry.registration` and :mod:`~steamtwin.geometry.multiview`, the settings
and report in :mod:`~steamtwin.geometry.preprocess_settings`. Every step returns its result and
what it removed or changed, so the report can account for each point.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from steamtwin.geometry.filters import (
    feature_preserving_downsample,
    mls_smooth,
    remove_statistical_outliers,
)
from steamtwin.geometry.pointcloud import check_point_cloud
from steamtwin.geometry.preprocess_settings import KEPT_SHARE, PreprocessReport, PreprocessSettings
from steamtwin.geometry.registration import register_views
from steamtwin.geometry.rigid import transform
from steamtwin.geometry.targets import SphereFit, detect_spheres, fit_sphere, match_spheres
from steamtwin.progress import ProgressCallback, scaled


def _remove_sphere_remnants(views: list[np.ndarray], spheres: Sequence[Sequence[SphereFit]],
                            poses: Sequence[np.ndarray], settings: PreprocessSettings,
                            report: PreprocessReport, widen: float) -> list[np.ndarray]:
    """Remove from each view the points of the reference spheres it did not find (too few
    points, e.g. mostly hidden by the blade), counted in ``report.sphere_points_removed``.

    A sphere's centre is the mean of its placements by ``poses`` (view -> a common frame),
    carried into the view; the view's points within 0.5 mm of that sphere's surface (the poses
    may be off by the tracking error) refit the centre with the known radius (kept if it moves
    less than 0.5 mm), and the points on the shell (``sphere_tolerance`` + ``widen``, m) or
    inside it are removed.
    """
    groups = match_spheres(spheres, poses, settings.sphere_match_distance)
    radius = settings.sphere_radius
    band = 0.5e-3
    kept = []
    for k, (view, pose) in enumerate(zip(views, poses, strict=True)):
        remnant = np.zeros(len(view), dtype=bool)
        for group in groups:
            if any(j == k for j, _ in group):
                continue  # found in this view: its points are gone already
            placed = np.mean([transform(spheres[j][i].centre[None], np.asarray(poses[j]))[0]
                              for j, i in group], axis=0)
            centre = transform(placed[None], np.linalg.inv(np.asarray(pose)))[0]
            distance = np.linalg.norm(view - centre, axis=1)
            candidates = np.abs(distance - radius) <= band
            if candidates.sum() >= 4:
                refit = fit_sphere(view[candidates], radius, centre)[0]
                if np.linalg.norm(refit - centre) < band:
                    distance = np.linalg.norm(view - refit, axis=1)
            remnant |= distance <= radius + settings.sphere_tolerance + widen
        report.sphere_points_removed[k] += int(remnant.sum())
        kept.append(view[~remnant])
    return kept



def preprocess_views(views: Sequence[np.ndarray], settings: PreprocessSettings | None = None,
                     initial_poses: Sequence[np.ndarray] | None = None,
                     progress: ProgressCallback | None = None
                     ) -> tuple[np.ndarray, list[np.ndarray], PreprocessReport]:
    """Reference spheres -> outliers -> MLS smoothing -> registration -> fusion ->
    downsampling.

    With ``settings.sphere_radius``, the reference spheres of that radius are found in each
    view (:func:`detect_spheres`) and their points removed before anything else, so that the
    fused cloud holds the blade only; their centres link the views in the registration. The
    few points of a sphere that a view saw too little of to find it are removed as well
    (:func:`_remove_sphere_remnants`): before the outlier removal when ``initial_poses`` place
    the spheres, else after the registration.
    ``initial_poses`` are the scanner's tracking estimates (see :func:`register_views`).
    Returns ``(fused cloud in the frame of view 0, per-view poses, report)``.
    """
    settings = settings or PreprocessSettings()
    if settings.target_points is not None and settings.target_points < 1:
        raise ValueError(f"target_points = {settings.target_points} (expected a count >= 1, "
                         "or None for 8/15 of the scanned blade points)")
    report = PreprocessReport()
    blade_views, spheres = [], []
    for k, view in enumerate(views):
        view = check_point_cloud(view, f"view {k}")
        report.input_points.append(len(view))
        found = [] if settings.sphere_radius is None else detect_spheres(
            view, settings.sphere_radius, settings.sphere_tolerance, settings.sphere_min_points)
        on_sphere = np.zeros(len(view), dtype=bool)
        for fit in found:
            on_sphere[fit.points] = True
        spheres.append(found)
        report.spheres_found.append(len(found))
        report.sphere_points_removed.append(int(on_sphere.sum()))
        blade_views.append(view[~on_sphere])
    if any(spheres) and initial_poses is not None:
        if len(initial_poses) != len(views):
            raise ValueError(f"{len(initial_poses)} initial poses for {len(views)} views")
        blade_views = _remove_sphere_remnants(blade_views, spheres, initial_poses, settings,
                                              report, 0.0)
    cleaned = []
    for k, view in enumerate(blade_views):
        kept, mask = remove_statistical_outliers(view, settings.outlier_neighbours,
                                                 settings.outlier_std_ratio)
        report.outliers_removed.append(int((~mask).sum()))
        smooth = mls_smooth(kept, settings.mls_neighbours, settings.mls_max_shift)
        report.smoothing_mean_shift.append(float(np.linalg.norm(smooth - kept, axis=1).mean()))
        cleaned.append(smooth)
        if progress is not None:
            progress(0.2 * (k + 1) / len(views), f"view {k + 1}/{len(views)} cleaned")
    poses = register_views(cleaned, settings, report, initial_poses,
                           scaled(progress, 0.2, 0.9, "register: "),
                           spheres)
    if any(spheres) and initial_poses is None:
        cleaned = _remove_sphere_remnants(cleaned, spheres, poses, settings, report,
                                          settings.mls_max_shift)
    fused = np.concatenate([transform(v, p) for v, p in zip(cleaned, poses, strict=True)])
    report.fused_points = len(fused)
    target = settings.target_points
    if target is None:
        target = round(KEPT_SHARE * (sum(report.input_points) - sum(report.sphere_points_removed)))
    fused = feature_preserving_downsample(fused, target, settings.feature_share)
    report.downsampled_points = len(fused)
    if progress is not None:
        progress(1.0, f"{len(fused)} points fused and downsampled")
    return fused, poses, report
