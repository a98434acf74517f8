"""Reading and writing point clouds (PLY, PCD, XYZ), with checks that name the file.

Clouds are (n, 3) float64 arrays in metres. A file in millimetres is read with
``unit_scale=1e-3``; a cloud whose size is implausible for a turbine part in metres is refused
with a hint rather than silently misread.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

SUFFIXES = (".ply", ".pcd", ".xyz")
#: Plausible bounding-box diagonal of a scanned turbine part, m (a 1 mm chip to a 10 m casing).
MIN_EXTENT, MAX_EXTENT = 1e-3, 10.0
MIN_POINTS = 100


class PointCloudError(ValueError):
    """An unreadable, empty, non-finite, degenerate or implausibly scaled point cloud."""


def read_point_cloud(path: str | Path, unit_scale: float = 1.0) -> np.ndarray:
    """Read the points (n, 3) of a PLY, PCD or XYZ file, times ``unit_scale`` (to metres).

    Raises :class:`PointCloudError` naming the file when it is missing, unreadable, empty, holds
    NaN/inf coordinates, is degenerate (fewer than 100 points, all on a line) or its bounding box
    diagonal is outside 1 mm – 10 m (wrong units).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PointCloudError(f"{path}: unknown point-cloud format {suffix!r}; "
                              f"expected one of {', '.join(SUFFIXES)}")
    if not path.is_file():
        raise PointCloudError(f"{path}: no such file")
    points = _read_xyz(path) if suffix == ".xyz" else _read_open3d(path)
    return check_point_cloud(points * unit_scale, str(path))


def _read_xyz(path: Path) -> np.ndarray:
    try:
        data = np.loadtxt(path, ndmin=2, comments="#")
    except ValueError as error:
        raise PointCloudError(f"{path}: not a whitespace-separated x y z table: {error}") from None
    if data.size == 0:
        raise PointCloudError(f"{path}: the file holds no points")
    if data.shape[1] < 3:
        raise PointCloudError(f"{path}: expected at least 3 columns (x y z), got {data.shape[1]}")
    return data[:, :3].astype(np.float64)


def _read_open3d(path: Path) -> np.ndarray:
    import open3d as o3d

    if path.stat().st_size == 0:
        raise PointCloudError(f"{path}: the file is empty")
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        cloud = o3d.io.read_point_cloud(str(path), remove_nan_points=False,
                                        remove_infinite_points=False)
    points = np.asarray(cloud.points, dtype=np.float64)
    if len(points) == 0:
        head = path.read_bytes()[:3].lower()
        kind = "PLY" if path.suffix.lower() == ".ply" else "PCD"
        if kind == "PLY" and head != b"ply":
            raise PointCloudError(f"{path}: not a PLY file (no 'ply' header)")
        raise PointCloudError(f"{path}: no points could be read (empty or malformed {kind})")
    return points


def check_point_cloud(points: np.ndarray, source: str = "point cloud") -> np.ndarray:
    """Validate an (n, 3) cloud in metres; return it as float64 or raise naming ``source``."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise PointCloudError(f"{source}: expected an (n, 3) array of points, got {points.shape}")
    if len(points) == 0:
        raise PointCloudError(f"{source}: the cloud is empty")
    bad = ~np.all(np.isfinite(points), axis=1)
    if np.any(bad):
        raise PointCloudError(f"{source}: {int(bad.sum())} of {len(points)} points have NaN or "
                              f"infinite coordinates (first at index {int(np.argmax(bad))})")
    if len(points) < MIN_POINTS:
        raise PointCloudError(f"{source}: only {len(points)} points (need >= {MIN_POINTS})")
    extent = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    if extent < MIN_EXTENT or extent > MAX_EXTENT:
        hint = (" — is the file in millimetres? read it with unit_scale=1e-3"
                if MAX_EXTENT < extent <= 1e4 else "")
        raise PointCloudError(f"{source}: bounding-box diagonal {extent:.4g} m is outside the "
                              f"plausible {MIN_EXTENT:g}–{MAX_EXTENT:g} m{hint}")
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred[:: max(1, len(points) // 20000)], compute_uv=False)
    if singular[1] < 1e-6 * singular[0]:
        raise PointCloudError(f"{source}: degenerate cloud, all points lie on a line")
    return points


def write_point_cloud(points: np.ndarray, path: str | Path) -> None:
    """Write an (n, 3) cloud (m) as binary PLY, binary PCD or text XYZ, by the suffix."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise PointCloudError(f"{path}: unknown point-cloud format {suffix!r}")
    points = np.asarray(points, dtype=np.float64)
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".xyz":
        np.savetxt(path, points, fmt="%.9e")
        return
    import open3d as o3d

    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        ok = o3d.io.write_point_cloud(str(path), cloud, write_ascii=False)
    if not ok:
        raise PointCloudError(f"{path}: open3d could not write the file")
