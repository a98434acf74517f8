"""The geometry chain as a user runs it — scan a row, preprocess a scan, reconstruct a blade in its
frame, report — written once for the ``steamtwin geometry`` commands, the demo pipeline and
Python users.

- :func:`scan_row`: the virtual scanner on a row's blade, the views written as a scan folder.
- :func:`read_scan_folder` / :func:`preprocess_scan`: a scan folder's (or an in-memory scan's)
  views cleaned, registered and fused (:func:`~steamtwin.geometry.preprocess.preprocess_views`),
  with the reference-sphere radius the scan recorded.
- :func:`load_cloud`: a scan folder, a fused cloud (.ply, .pcd, .xyz) or a fused mesh (.stl,
  .obj, .ply with faces) as one cloud (m).
- :func:`reconstruct_cloud`: the cloud brought into the blade frame — best-fitted to the row's
  nominal blade, or in the frame found from the data — and reconstructed.
- :func:`reconstruct_source`: all of it from a file or folder to the STL, CAD files and reports.
- :func:`write_blade_mesh`, :func:`write_turbine_assembly`, :func:`row_uncertainty`: a blade's
  tetrahedral mesh, the turbine's STL assembly and a row's scan uncertainty, each to its files.

Lengths in m unless a name says otherwise.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from steamtwin.errors import GeometryAreaError
from steamtwin.geometry.assembly import Component, build_assembly, write_assembly
from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.cad_export import CadExport, write_cad
from steamtwin.geometry.fidelity import (
    Deviation,
    FidelityReport,
    align_to_nominal,
    surface_deviation,
)
from steamtwin.geometry.frame import BladeFrame, estimate_blade_frame, nominal_starts
from steamtwin.geometry.mesh_io import MeshSampling, is_mesh_file, read_mesh_cloud, write_stl
from steamtwin.geometry.meshing import MeshQuality, blade_volume_mesh, mesh_quality, mesh_stl
from steamtwin.geometry.pointcloud import read_point_cloud
from steamtwin.geometry.preprocess import preprocess_views
from steamtwin.geometry.preprocess_settings import PreprocessReport, PreprocessSettings
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.reconstruct import Reconstruction, ReconstructionSettings, reconstruct_blade
from steamtwin.geometry.reconstruction_report import (
    reconstruction_fidelity,
    write_deviation_map,
    write_reconstruction_report,
)
from steamtwin.geometry.rigid import transform
from steamtwin.geometry.row_metrics import (
    RowSection,
    append_report_rows,
    blade_row_metrics,
    design_edge_rows,
    write_row_metrics,
)
from steamtwin.geometry.row_sizing import ROWS
from steamtwin.geometry.scanner import Scan, ScannerSettings, planned_points, scan_blade, write_scan
from steamtwin.geometry.uncertainty import UncertaintyResult, scan_uncertainty
from steamtwin.geometry.volume_mesh import write_volume_mesh
from steamtwin.model.fom import FullOrderModel
from steamtwin.progress import ProgressCallback, scaled
from steamtwin.spec import TurbineSpec

#: Largest RMS of the best fit to a row's nominal blade (m) for the cloud to count as that
#: row's blade: 20× the handheld scanner's ±0.05 mm bound (VDI/VDE 2634-2); a blade of another
#: row or design fits to millimetres (hp1's nominal to a foreign blade: 205 mm, issue 19).
MAX_BEST_FIT_RMS = 1.0e-3
#: File of a scan folder that lists its views (written by :func:`~.scanner.write_scan`).
MANIFEST = "scan.json"
#: Frames an STL can be written in: the blade frame (z along the span) or the cloud's own.
STL_FRAMES = ("blade", "scan")


class ScanFolderError(GeometryAreaError):
    """A folder that is not a readable scan folder; the message names the manifest."""


class RowMismatchError(ReconstructionError):
    """A cloud whose best fit to the row's nominal blade is worse than :data:`MAX_BEST_FIT_RMS`."""

    def __init__(self, row: str, fit_rms: float) -> None:
        self.row, self.fit_rms = row, fit_rms
        super().__init__(f"the cloud does not match row {row}'s nominal blade (best fit RMS "
                         f"{fit_rms * 1e3:.4g} mm); reconstruct it without a row, in a frame "
                         "from the data")


@dataclass(frozen=True)
class ScanFolder:
    """The views (m, each in its scanner frame) and the ``scan.json`` manifest of a scan."""

    folder: Path
    manifest: dict
    views: list[np.ndarray]

    @property
    def row(self) -> str | None:
        return self.manifest.get("row")


def read_scan_folder(folder: str | Path) -> ScanFolder:
    """Read a scan folder written by :func:`scan_row` (or a real scanner's export in that
    layout). Raises :class:`ScanFolderError` naming the manifest, or the point-cloud reader's
    error naming the view file."""
    folder = Path(folder)
    path = folder / MANIFEST
    if not path.is_file():
        raise ScanFolderError(f"{path}: no scan manifest (is {folder} a 'geometry scan' folder?)")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
        views = [read_point_cloud(folder / name) for name in manifest["views"]]
    except KeyError as error:
        raise ScanFolderError(f"{path}: no key {error} (is {folder} a 'geometry scan' "
                              "folder?)") from None
    except (ValueError, OSError, TypeError) as error:  # PointCloudError is a ValueError
        raise ScanFolderError(f"{path}: {error}") from None
    return ScanFolder(folder, manifest, views)


def scan_settings(manifest: dict, target_points: int | None = None) -> PreprocessSettings:
    """Preprocessing settings for a scan: the reference spheres' radius (m) from its manifest
    (``sphere_radius``; null: no spheres), the default radius when the manifest does not say."""
    if "sphere_radius" not in manifest:
        return PreprocessSettings(target_points=target_points)
    return PreprocessSettings(target_points=target_points, sphere_radius=manifest["sphere_radius"])


@dataclass(frozen=True)
class RowScan:
    """A virtual scan of a row's blade and the files it was written to."""

    blade: Blade
    scan: Scan
    paths: list[Path]

    @property
    def points(self) -> int:
        return sum(len(view.points) for view in self.scan.views)


def scan_row(spec: TurbineSpec, row: str, out: str | Path, *, points: int | None = None,
             views: int = 8, outliers: float = 0.02, spheres: int = 4, file_format: str = "ply",
             random_state: int | None = 0, progress: ProgressCallback | None = None) -> RowScan:
    """Scan the ground-truth blade of ``row`` with the virtual scanner and write the scan folder
    ``out`` (views, ``scan.json``, hidden ``truth/``). ``points`` defaults to
    :func:`~steamtwin.geometry.scanner.planned_points`; see
    :class:`~steamtwin.geometry.scanner.ScannerSettings` for the others."""
    if file_format not in ("ply", "pcd"):
        raise ValueError(f"file_format must be 'ply' or 'pcd' (got {file_format!r})")
    blade = make_blade(spec, row)
    settings = ScannerSettings(views=views, points=planned_points(blade) if points is None
                               else points, outlier_share=outliers, reference_spheres=spheres)
    scan = scan_blade(blade, settings, random_state=random_state, progress=progress)
    return RowScan(blade, scan, write_scan(scan, out, file_format=file_format))


@dataclass(frozen=True)
class PreprocessedScan:
    """A scan's fused, downsampled cloud (m, frame of view 0), the view poses and the report."""

    cloud: np.ndarray
    poses: list[np.ndarray]
    report: PreprocessReport
    row: str | None


def preprocess_scan(scan: str | Path | ScanFolder | Scan, target_points: int | None = None,
                    progress: ProgressCallback | None = None) -> PreprocessedScan:
    """Clean, register and fuse the views of a scan folder (a path or :class:`ScanFolder`) or of
    an in-memory :class:`~steamtwin.geometry.scanner.Scan`, starting from the scanner's tracked
    poses and with the reference-sphere radius the scan recorded."""
    if isinstance(scan, Scan):
        manifest = {"row": scan.row, "sphere_radius": scan.settings.sphere_radius
                    if scan.settings.reference_spheres > 0 else None}
        views = [view.points for view in scan.views]
        tracked = [view.tracked_pose for view in scan.views]
    else:
        folder = scan if isinstance(scan, ScanFolder) else read_scan_folder(scan)
        manifest, views, tracked = folder.manifest, folder.views, folder.manifest.get(
            "tracked_poses")
    cloud, poses, report = preprocess_views(views, scan_settings(manifest, target_points),
                                            initial_poses=tracked, progress=progress)
    return PreprocessedScan(cloud, poses, report, manifest.get("row"))


def write_preprocess_report(path: str | Path, fused: PreprocessedScan, blade: Blade
                            ) -> tuple[Path, Deviation]:
    """The JSON report of a preprocessed scan: what each step did, and the deviation (mm) of
    the fused cloud from the nominal ``blade`` after the best fit to it; returns the path and
    that deviation."""
    pose, fit_rms = align_to_nominal(fused.cloud, blade)
    deviation = surface_deviation(blade, transform(fused.cloud, pose))
    document = {"row": fused.row, "steps": fused.report.as_dict(),
                "best_fit_rms_mm": fit_rms * 1e3,
                "deviation_mm": {"mean": deviation.mean * 1e3, "rms": deviation.rms * 1e3,
                                 "max": deviation.max * 1e3,
                                 "hausdorff": deviation.hausdorff * 1e3,
                                 "p95": deviation.p95 * 1e3}}
    path = Path(path)
    path.write_text(json.dumps(document, indent=2), encoding="utf-8")
    return path, deviation


@dataclass(frozen=True)
class LoadedCloud:
    """A source as one cloud (m, in its own frame): ``fused`` for a scan folder, ``sampling``
    for a mesh file, neither for a cloud file; ``row`` from a scan folder's manifest."""

    cloud: np.ndarray
    row: str | None = None
    fused: PreprocessedScan | None = None
    sampling: MeshSampling | None = None


def load_cloud(source: str | Path | ScanFolder, *, target_points: int | None = None,
               mesh_samples: int = 80_000, mesh_vertices: bool = False, unit_scale: float = 1.0,
               progress: ProgressCallback | None = None) -> LoadedCloud:
    """A scan folder (a path or :class:`ScanFolder`; preprocessed, :func:`preprocess_scan`), a
    fused mesh (sampled,
    :func:`~steamtwin.geometry.mesh_io.read_mesh_cloud`) or a cloud file as one cloud;
    ``unit_scale`` converts a file's unit to m."""
    source = source if isinstance(source, ScanFolder) else Path(source)
    if isinstance(source, ScanFolder) or source.is_dir():
        fused = preprocess_scan(source, target_points, progress)
        return LoadedCloud(fused.cloud, fused.row, fused=fused)
    if is_mesh_file(source):
        cloud, sampling = read_mesh_cloud(source, mesh_samples, mesh_vertices, unit_scale)
        return LoadedCloud(cloud, sampling=sampling)
    return LoadedCloud(read_point_cloud(source, unit_scale))


@dataclass(frozen=True)
class BladeReconstruction:
    """A reconstruction in the blade frame and how the cloud got there: ``pose`` (4×4, scan ->
    blade frame), ``fit_rms`` (m) of the best fit to the nominal blade of ``row`` or ``frame``
    found from the data, ``notes`` on fallbacks taken, ``frames`` for the report."""

    reconstruction: Reconstruction
    pose: np.ndarray
    row: str | None = None
    fit_rms: float | None = None
    frame: BladeFrame | None = None
    notes: list[str] = field(default_factory=list)
    frames: dict = field(default_factory=dict)


def reconstruct_cloud(cloud: np.ndarray, blade: Blade | None = None, *,
                      hub_end: str | None = None, tolerance: float = 0.02e-3
                      ) -> BladeReconstruction:
    """Reconstruct a blade cloud given in any frame (m).

    With the nominal ``blade`` the cloud is best-fitted to it (started from the frames found
    from the data, :func:`~steamtwin.geometry.frame.nominal_starts`, or from the principal axes
    alone when there are none) and refused by :class:`RowMismatchError` beyond
    :data:`MAX_BEST_FIT_RMS`; without, it is reconstructed in the blade frame found from the
    data (:func:`~steamtwin.geometry.frame.estimate_blade_frame`; ``hub_end`` when the data
    cannot tell hub from tip). ``tolerance`` is the RMS fit residual (m) knot insertion aims at.
    """
    notes: list[str] = []
    if blade is not None:
        try:
            starts = nominal_starts(cloud, blade, hub_end=hub_end)
        except ReconstructionError as error:  # the principal axes alone start the best fit
            notes.append(f"no blade frame from the data ({error}); best fit from the principal "
                         "axes alone")
            starts = []
        pose, fit_rms = align_to_nominal(cloud, blade, starts=starts)
        if fit_rms > MAX_BEST_FIT_RMS:
            raise RowMismatchError(blade.row, fit_rms)
        frame, frames = None, {"best_fit_scan_to_blade_m": pose.tolist()}
    else:
        frame = estimate_blade_frame(cloud, hub_end=hub_end)
        pose, fit_rms, frames = frame.matrix, None, {"estimated": frame.as_dict()}
    reconstruction = reconstruct_blade(transform(cloud, pose),
                                       ReconstructionSettings(tolerance=tolerance))
    return BladeReconstruction(reconstruction, pose, None if blade is None else blade.row,
                               fit_rms, frame, notes, frames)


def write_blade_stl(result: BladeReconstruction, path: str | Path, frame: str = "blade") -> Path:
    """The reconstruction's STL in the blade frame or, ``frame="scan"``, in the cloud's own."""
    if frame not in STL_FRAMES:
        raise ValueError(f"frame must be 'blade' or 'scan' (got {frame!r})")
    mesh = result.reconstruction
    if frame == "scan":
        mesh = replace(mesh, vertices=transform(mesh.vertices, np.linalg.inv(result.pose)))
    return write_stl(mesh, path)


@dataclass(frozen=True)
class ReconstructionReport:
    """The report files and what they hold: ``fidelity`` against the nominal blade, or the row
    ``sections`` of a blade without one."""

    json: Path
    csv: Path
    png: Path
    fidelity: FidelityReport | None = None
    sections: list[RowSection] | None = None


def report_reconstruction(result: BladeReconstruction, base: str | Path,
                          blade: Blade | None = None, *, blade_count: int | None = None,
                          extra_fields: dict | None = None) -> ReconstructionReport:
    """Write ``base``.json/.csv/.png: with the nominal ``blade``, the deviation and row metrics
    against it, the edge radii against the design and the deviation map; without, the row
    metrics alone (the throat with ``blade_count``) and the fit-residual map. ``extra_fields``
    go into the JSON after the reconstruction's summary and best-fit RMS."""
    base = Path(base)
    extra = {"reconstruction": result.reconstruction.summary()}
    if blade is not None and result.fit_rms is not None:
        extra["best_fit_rms_mm"] = result.fit_rms * 1e3
    extra.update(extra_fields or {})
    mesh = result.reconstruction
    if blade is None:
        sections = blade_row_metrics(mesh.vertices, mesh.triangles, blade_count=blade_count)
        json_path, csv_path = write_row_metrics(sections, base, extra)
        png = write_deviation_map(mesh, base.with_suffix(".png"))
        return ReconstructionReport(json_path, csv_path, png, sections=sections)
    fidelity = reconstruction_fidelity(blade, mesh.vertices, mesh.triangles, extra=extra)
    json_path, csv_path = write_reconstruction_report(fidelity, base)
    png = write_deviation_map(mesh, base.with_suffix(".png"), blade)
    edges = design_edge_rows(blade, mesh.vertices, mesh.triangles)
    append_report_rows(json_path, csv_path, "edge_radii", edges)
    return ReconstructionReport(json_path, csv_path, png, fidelity=fidelity)


@dataclass(frozen=True)
class ReconstructionRun:
    """Everything :func:`reconstruct_source` made."""

    loaded: LoadedCloud
    result: BladeReconstruction
    stl: Path
    cad: CadExport | None = None
    report: ReconstructionReport | None = None


def reconstruct_source(source: str | Path, out: str | Path, *, spec: TurbineSpec | None = None,
                       row: str | None = None, stl_frame: str = "blade",
                       hub_end: str | None = None, tolerance: float = 0.02e-3,
                       target_points: int | None = None, mesh_samples: int = 80_000,
                       mesh_vertices: bool = False, unit_scale: float = 1.0,
                       cad: list[Path] | None = None, report: str | Path | None = None,
                       blade_count: int | None = None,
                       progress: ProgressCallback | None = None) -> ReconstructionRun:
    """Scan folder, fused cloud or fused mesh -> cloud -> blade frame -> watertight STL ``out``
    (and ``cad`` files, ``report`` base path).

    ``row`` (default: a scan folder's own) names the nominal blade of ``spec`` to best-fit to;
    without one the frame comes from the data. The rest as :func:`load_cloud`,
    :func:`reconstruct_cloud`, :func:`write_blade_stl` and :func:`report_reconstruction`.
    """
    if stl_frame not in STL_FRAMES:
        raise ValueError(f"stl_frame must be 'blade' or 'scan' (got {stl_frame!r})")
    if Path(source).is_dir():
        source = read_scan_folder(source)
        row = row or source.row
    blade = None if row is None or spec is None else make_blade(spec, row)
    if row is not None and spec is None:
        raise ValueError(f"row {row!r} needs the turbine spec of its nominal blade")
    loaded = load_cloud(source, target_points=target_points, mesh_samples=mesh_samples,
                        mesh_vertices=mesh_vertices, unit_scale=unit_scale,
                        progress=scaled(progress, 0.0, 0.5, "preprocess: "))
    result = reconstruct_cloud(loaded.cloud, blade, hub_end=hub_end, tolerance=tolerance)
    stl = write_blade_stl(result, out, stl_frame)
    exported = None
    if cad:
        mesh = result.reconstruction
        exported = write_cad(mesh.surface, mesh.root, mesh.tip, cad)
    files = None
    if report is not None:
        frames = {"stl_frame": stl_frame, **result.frames}
        files = report_reconstruction(result, report, blade, blade_count=blade_count,
                                      extra_fields={"frame": frames})
    if progress is not None:
        progress(1.0, f"wrote {stl}")
    return ReconstructionRun(loaded, result, stl, exported, files)


def write_blade_mesh(out: str | Path, *, spec: TurbineSpec | None = None, row: str = "hp1",
                     stl: str | Path | None = None, element_size: float | None = None,
                     progress: ProgressCallback | None = None) -> MeshQuality:
    """Tetrahedral mesh of a reconstructed blade ``stl`` (:func:`~.meshing.mesh_stl`) or of the
    ground-truth blade of ``row`` of ``spec`` (:func:`~.meshing.blade_volume_mesh`), written to
    ``out`` (.msh or .vtu); returns its quality. ``element_size`` in m (None: the default)."""
    if stl is not None:
        mesh = mesh_stl(stl, element_size=element_size, progress=progress)
    elif spec is not None:
        mesh = blade_volume_mesh(spec, row, element_size=element_size, progress=progress)
    else:
        raise ValueError("a blade mesh needs either an STL or the turbine spec of the row")
    write_volume_mesh(mesh, out)
    return mesh_quality(mesh)


def write_turbine_assembly(spec: TurbineSpec, out: str | Path, rows: tuple[str, ...] = ROWS,
                           spacing: float = 2e-3, progress: ProgressCallback | None = None
                           ) -> tuple[list[Component], list[Path]]:
    """Rows, rotor and casing of ``spec`` (:func:`~.assembly.build_assembly`; ``spacing`` the
    blade triangulation spacing, m) written as one STL ``out`` and one per component."""
    unknown = [row for row in rows if row not in ROWS]
    if unknown:
        raise GeometryError(f"unknown row(s) {unknown}; known rows: {', '.join(ROWS)}")
    components = build_assembly(spec, rows=rows, spacing=spacing, progress=progress)
    return components, write_assembly(components, out)


def row_uncertainty(spec: TurbineSpec, row: str, *, samples: int = 20, bound: float = 0.05e-3,
                    random_state: int | None = 0, out: str | Path | None = None,
                    progress: ProgressCallback | None = None) -> UncertaintyResult:
    """Scan uncertainty of ``row`` (:func:`~.uncertainty.scan_uncertainty`: ±``bound`` m scan
    errors through the row's throat area into its own stage of the full-order model of
    ``spec``), written as JSON to ``out`` when given."""
    result = scan_uncertainty(make_blade(spec, row), FullOrderModel(spec), samples=samples,
                              bound=bound, random_state=random_state, progress=progress)
    if out is not None:
        Path(out).write_text(json.dumps(result.as_dict(), indent=2), encoding="utf-8")
    return result
