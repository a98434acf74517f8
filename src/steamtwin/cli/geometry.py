"""``steamtwin geometry``: virtual blade scans, scan preprocessing, surface reconstruction and
blade meshes."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import NoReturn

import numpy as np
import typer

from steamtwin.cli.paths import prepare_output_file, prepare_output_folder

geometry_app = typer.Typer(
    help="Blade geometry: virtual scans, scan preprocessing, reconstruction, simulation meshes.",
    no_args_is_help=True,
)


#: Largest RMS of the best fit to a row's nominal blade (m) for the cloud to count as that
#: row's blade: 20× the handheld scanner's ±0.05 mm bound (VDI/VDE 2634-2); a blade of another
#: row or design fits to millimetres (hp1's nominal to a foreign blade: 205 mm, issue 19).
MAX_BEST_FIT_RMS = 1.0e-3


def _fail(message: str) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def _spec(turbine: str):  # returns a steamtwin.spec.TurbineSpec
    from steamtwin.spec import SpecError, load_spec

    try:
        return load_spec(turbine)
    except (SpecError, OSError, ValueError) as error:
        _fail(f"cannot load turbine {turbine!r}: {error}")


def _preprocess_settings(manifest: dict, target_points: int | None):  # -> PreprocessSettings
    """Preprocessing settings for a scan folder: the reference spheres' radius from
    ``scan.json`` (null: no spheres), the default radius when the manifest does not say."""
    from steamtwin.geometry.preprocess import PreprocessSettings

    if "sphere_radius" not in manifest:
        return PreprocessSettings(target_points=target_points)
    return PreprocessSettings(target_points=target_points,
                              sphere_radius=manifest["sphere_radius"])


def _read_scan(folder: Path) -> tuple[list, dict]:
    """The views (m) and the manifest of a 'geometry scan' folder."""
    from steamtwin.geometry.pointcloud import read_point_cloud

    manifest_path = folder / "scan.json"
    if not manifest_path.is_file():
        _fail(f"{manifest_path}: no scan manifest (is {folder} a 'geometry scan' folder?)")
    try:
        manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
        views = [read_point_cloud(folder / name) for name in manifest["views"]]
    except KeyError as error:
        _fail(f"{manifest_path}: no key {error} (is {folder} a 'geometry scan' folder?)")
    except (ValueError, OSError, TypeError) as error:  # PointCloudError is a ValueError
        _fail(f"{manifest_path}: {error}")
    return views, manifest


def _point_cloud_out(path: Path) -> Path:
    """``--out`` of a point cloud: a known format, a writable file."""
    from steamtwin.geometry.pointcloud import SUFFIXES

    if path.suffix.lower() not in SUFFIXES:
        _fail(f"--out {path}: unknown point-cloud format {path.suffix!r}; use "
              f"{', '.join(SUFFIXES)}")
    return prepare_output_file(path, "--out")


@geometry_app.command()
def scan(
    row: str = typer.Option("hp1", help="Blade row: hp1…hp13 (HP rotor) or ip1…ip9 (IP stator)."),
    out: Path = typer.Option(..., help="Folder for view_NN.ply, scan.json and truth/."),
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path."),
    points: int | None = typer.Option(
        None, help="Total blade points (with outliers) over all views; the spheres' points come "
                   "on top. Default: planned from the blade, the method's 150000 or more where "
                   "a blade needs them to resolve its edges (hp13: 234321)."),
    views: int = typer.Option(8, help="Number of partial views."),
    outliers: float = typer.Option(0.02, help="Share of outliers (0.01-0.03 typical)."),
    seed: int = typer.Option(0, help="Seed of the scanner's random generator."),
    file_format: str = typer.Option("ply", help="'ply' or 'pcd'."),
    spheres: int = typer.Option(4, help="Reference spheres on the fixture, 0-6, sized to the "
                                        "blade (5 mm radius on hp1); 0 scans the blade alone."),
) -> None:
    """Scan the ground-truth blade of ROW with the virtual handheld scanner (±0.05 mm).

    Each view is in the scanner's own frame; the true poses and sphere centres go to
    OUT/truth/ (do not read them when reconstructing). The reference spheres link the views
    in the registration; their points are removed before the blade is fused.

    Example: steamtwin geometry scan --row hp1 --points 150000 --seed 1 --out scan-hp1
    Example: steamtwin geometry scan --row ip9 --out scan-ip9   (planned: ~485000 points)
    Example: steamtwin geometry scan --row hp1 --spheres 0 --out scan-hp1-blade-only
    """
    from steamtwin.geometry.profile import GeometryError, make_blade
    from steamtwin.geometry.scanner import (
        ScannerSettings,
        planned_points,
        scan_blade,
        write_scan,
    )

    if file_format not in ("ply", "pcd"):
        _fail(f"--file-format must be 'ply' or 'pcd' (got {file_format!r})")
    prepare_output_folder(out, "--out")
    spec = _spec(turbine)
    try:
        blade = make_blade(spec, row)
        if points is None:
            points = planned_points(blade)
        settings = ScannerSettings(views=views, points=points, outlier_share=outliers,
                                   reference_spheres=spheres)
        result = scan_blade(blade, settings, rng=seed)
    except (GeometryError, ValueError) as error:
        _fail(str(error))
    paths = write_scan(result, out, file_format=file_format)
    total = sum(len(v.points) for v in result.views)
    typer.echo(f"wrote {len(paths)} views of row {row} ({total} points) to {out}")


@geometry_app.command()
def preprocess(
    folder: Path = typer.Argument(..., help="Scan folder written by 'geometry scan'."),
    out: Path = typer.Option(..., help="Fused, downsampled cloud (.ply, .pcd or .xyz)."),
    target_points: int | None = typer.Option(
        None, help="Points kept after downsampling. Default: 8/15 of the scanned blade points "
                   "(the method's 150k → 80k)."),
    report: Path | None = typer.Option(None, help="Report base path (writes .json)."),
    turbine: str = typer.Option("reference", help="Turbine of the nominal blade (report)."),
) -> None:
    """Clean, smooth, register and fuse the views of a scan folder into one cloud.

    With --report, the fused cloud is best-fitted to the nominal blade of the scanned row and
    its deviation (mean, RMS, max, Hausdorff) is reported with what each step removed.

    Example: steamtwin geometry preprocess scan-hp1 --out hp1-fused.ply --report hp1-report
    """
    from steamtwin.geometry.fidelity import align_to_nominal, surface_deviation
    from steamtwin.geometry.pointcloud import write_point_cloud
    from steamtwin.geometry.preprocess import preprocess_views, transform
    from steamtwin.geometry.profile import GeometryError, make_blade

    _point_cloud_out(out)
    if report is not None:
        prepare_output_file(report.with_suffix(".json"), "--report")
    views, manifest = _read_scan(folder)
    if report is not None:
        try:
            blade = make_blade(_spec(turbine), str(manifest.get("row")))
        except GeometryError as error:
            _fail(f"--report: {folder / 'scan.json'}: {error}")
    tracked = manifest.get("tracked_poses")
    try:
        fused, _, steps = preprocess_views(views, _preprocess_settings(manifest, target_points),
                                           initial_poses=tracked)
    except ValueError as error:
        _fail(str(error))
    write_point_cloud(fused, out)
    typer.echo(f"fused {sum(steps.input_points)} points of {len(views)} views into "
               f"{len(fused)} points: {out}")
    typer.echo(f"  outliers removed per view: {steps.outliers_removed}")
    if any(steps.spheres_found):
        typer.echo(f"  reference spheres: {steps.spheres_matched} matched across views, "
                   f"points removed per view: {steps.sphere_points_removed}")
    if report is not None:
        pose, fit_rms = align_to_nominal(fused, blade)
        deviation = surface_deviation(blade, transform(fused, pose))
        document = {"row": manifest["row"], "steps": steps.as_dict(),
                    "best_fit_rms_mm": fit_rms * 1e3,
                    "deviation_mm": {"mean": deviation.mean * 1e3, "rms": deviation.rms * 1e3,
                                     "max": deviation.max * 1e3,
                                     "hausdorff": deviation.hausdorff * 1e3,
                                     "p95": deviation.p95 * 1e3}}
        path = report.with_suffix(".json")
        path.write_text(json.dumps(document, indent=2), encoding="utf-8")
        typer.echo(f"  deviation from the nominal blade: mean {deviation.mean * 1e3:.4f} mm, "
                   f"RMS {deviation.rms * 1e3:.4f} mm, max {deviation.max * 1e3:.4f} mm; "
                   f"report {path}")


@geometry_app.command()
def reconstruct(
    source: Path = typer.Argument(..., help="Scan folder ('geometry scan'), fused cloud "
                                           "(.ply, .pcd, .xyz) or fused mesh (.stl, .obj, "
                                           ".ply with faces); m unless --unit-scale."),
    out: Path = typer.Option(..., help="Watertight blade STL (binary, m; the region of each "
                                       "triangle in its attribute word)."),
    report: Path | None = typer.Option(None, help="Report base path: writes .json, .csv and a "
                                                  ".png deviation map (against the nominal "
                                                  "blade with a row, else the fit residuals)."),
    row: str | None = typer.Option(None, help="Row of the blade (default: from scan.json). "
                                              "With a row the cloud is best-fitted to its "
                                              "nominal blade; without, it is reconstructed in "
                                              "a blade frame found from the data."),
    turbine: str = typer.Option("reference", help="Turbine of the nominal blade."),
    target_points: int | None = typer.Option(
        None, help="Points kept by preprocessing (scan folders). Default: 8/15 of the scanned "
                   "blade points (the method's 150k → 80k)."),
    tolerance: float = typer.Option(0.02, help="RMS fit residual aimed at by knot insertion, "
                                               "mm."),
    frame: str = typer.Option(
        "blade", help="Frame of the STL: 'blade' (default: z along the span, the frame the mesh "
                      "command, the FEM and the reports use; the nominal row's frame with a "
                      "row, else the frame from the data) or 'scan' (the cloud's own frame, to "
                      "overlay the STL on the scan)."),
    hub_end: str | None = typer.Option(
        None, help="The hub end, as the scan axis pointing towards it (+x, -x, +y, -y, +z, -z), "
                   "when the data cannot tell hub from tip (an untapered blade)."),
    unit_scale: float = typer.Option(1.0, help="Factor from the cloud's or mesh's unit to "
                                               "metres (1e-3 for a file in mm)."),
    mesh_samples: int = typer.Option(80_000, help="Points sampled uniformly over a mesh source "
                                                  "(.stl, .obj, .ply with faces)."),
    mesh_vertices: bool = typer.Option(False, help="Add a mesh source's vertices to its "
                                                   "samples."),
    step: Path | None = typer.Option(None, help="Also write the B-spline side and the cap "
                                                "planes as a STEP solid (mm, blade frame)."),
    iges: Path | None = typer.Option(None, help="Also write them as IGES surfaces (mm, blade "
                                                "frame)."),
    blade_count: int | None = typer.Option(None, help="Blades in the row, for the throat "
                                                      "(2πr/N) when there is no --row."),
) -> None:
    """Reconstruct a watertight blade surface (STL) from a scan folder, a fused cloud or mesh.

    A scan folder is preprocessed first (as 'geometry preprocess'); a fused mesh (.stl, .obj,
    .ply with faces) is sampled into a cloud. The blade frame is found from the data (span
    axis from the side and end-face normals, hub at the longer end section, chord from the
    leading to the trailing edge at mid span) and printed; with a row the cloud is then
    best-fitted to the row's nominal blade (refused when it does not match it). The cloud is
    segmented by region growing into root, tip, pressure side, suction side, leading and
    trailing edge; the side is fitted by a periodic B-spline surface refined by knot
    insertion, the caps by planes. --step/--iges export those surfaces for CAD. With --report:
    deviation from the nominal blade, row metrics at hub, mid and tip and the transformations;
    with no row, the row metrics alone (chord, stagger, thickness, edge radii; the throat with
    --blade-count).

    Example: steamtwin geometry reconstruct scan-hp1 --out hp1.stl --report hp1-reconstruction
    Example: steamtwin geometry reconstruct foreign.ply --out foreign.stl --frame scan
    Example: steamtwin geometry reconstruct prismatic.ply --out prismatic.stl --hub-end -z
    Example: steamtwin geometry reconstruct fused-mm.stl --unit-scale 1e-3 --out blade.stl
             --step blade.step --iges blade.igs --report blade --blade-count 60
    """
    from steamtwin.geometry.cad_export import CAD_SUFFIXES, CadExportError, write_cad
    from steamtwin.geometry.fidelity import align_to_nominal
    from steamtwin.geometry.frame import HUB_ENDS, estimate_blade_frame, nominal_starts
    from steamtwin.geometry.mesh_input import is_mesh_file, read_mesh_cloud
    from steamtwin.geometry.pointcloud import PointCloudError, read_point_cloud
    from steamtwin.geometry.preprocess import preprocess_views, transform
    from steamtwin.geometry.profile import GeometryError, make_blade
    from steamtwin.geometry.reconstruct import (
        ReconstructionSettings,
        reconstruct_blade,
        reconstruction_fidelity,
        write_deviation_map,
        write_reconstruction_report,
        write_stl,
    )
    from steamtwin.geometry.row_metrics import append_report_rows, design_edge_rows
    from steamtwin.geometry.segmentation import ReconstructionError

    if not 0.0 < tolerance <= 1.0:
        _fail(f"--tolerance must lie within (0, 1] mm (got {tolerance})")
    if frame not in ("blade", "scan"):
        _fail(f"--frame must be 'blade' or 'scan' (got {frame!r})")
    if hub_end is not None and hub_end not in HUB_ENDS:
        _fail(f"--hub-end must be one of {', '.join(HUB_ENDS)} (got {hub_end!r})")
    prepare_output_file(out, "--out")
    if report is not None:
        for suffix in (".json", ".csv", ".png"):
            prepare_output_file(report.with_suffix(suffix), "--report")
    cad = [p for p in (step, iges) if p is not None]
    for path, option, kind in ((step, "--step", "STEP"), (iges, "--iges", "IGES")):
        if path is not None:
            if CAD_SUFFIXES.get(path.suffix.lower()) != kind:
                _fail(f"{option} {path}: expected a {kind} file name ("
                      f"{', '.join(k for k, v in CAD_SUFFIXES.items() if v == kind)})")
            prepare_output_file(path, option)
    if blade_count is not None and blade_count < 1:
        _fail(f"--blade-count must be a positive count (got {blade_count})")
    scan = _read_scan(source) if source.is_dir() else None
    if scan is not None:
        row = row or scan[1].get("row")
    if row is not None:
        try:
            blade = make_blade(_spec(turbine), row)
        except GeometryError as error:
            _fail(str(error))
    if scan is not None:
        views, manifest = scan
        try:
            cloud, _, steps = preprocess_views(
                views, _preprocess_settings(manifest, target_points),
                initial_poses=manifest.get("tracked_poses"))
        except ValueError as error:
            _fail(str(error))
        typer.echo(f"fused {sum(steps.input_points)} points of {len(views)} views into "
                   f"{len(cloud)} points")
    else:
        try:
            if is_mesh_file(source):
                cloud, sampling = read_mesh_cloud(source, mesh_samples, mesh_vertices,
                                                  unit_scale)
                typer.echo(f"sampled {sampling.samples} points over the {sampling.triangles} "
                           f"triangles of {source} ({sampling.area * 1e6:.1f} mm², "
                           f"{sampling.degenerate} degenerate left out, "
                           f"{sampling.vertices_added} vertices added)")
            else:
                cloud = read_point_cloud(source, unit_scale)
        except (PointCloudError, OSError) as error:
            _fail(str(error))
    frames: dict = {"stl_frame": frame}
    if row is not None:
        try:
            starts = nominal_starts(cloud, blade, hub_end=hub_end)
        except ReconstructionError as error:  # the principal axes alone start the best fit
            typer.echo(f"no blade frame from the data ({error}); best fit from the principal "
                       "axes alone")
            starts = []
        pose, fit_rms = align_to_nominal(cloud, blade, starts=starts)
        if fit_rms > MAX_BEST_FIT_RMS:
            _fail(f"the cloud does not match row {row}'s nominal blade (best fit RMS "
                  f"{fit_rms * 1e3:.4g} mm); leave out --row to reconstruct in a frame from "
                  "the data")
        cloud = transform(cloud, pose)
        typer.echo(f"best fit to the nominal blade {row}: RMS {fit_rms * 1e3:.4f} mm")
        frames["best_fit_scan_to_blade_m"] = pose.tolist()
    else:
        try:
            found = estimate_blade_frame(cloud, hub_end=hub_end)
        except ReconstructionError as error:
            _fail(str(error))
        _echo_frame(found)
        pose = found.matrix
        cloud = found.to_blade(cloud)
        frames["estimated"] = found.as_dict()
    try:
        result = reconstruct_blade(cloud, ReconstructionSettings(tolerance=tolerance * 1e-3))
    except ReconstructionError as error:
        _fail(str(error))
    if frame == "scan":
        scan_vertices = transform(result.vertices, np.linalg.inv(pose))
        write_stl(dataclasses.replace(result, vertices=scan_vertices), out)
    else:
        write_stl(result, out)
    summary = result.summary()
    counts = ", ".join(f"{k} {v}" for k, v in summary["patch_points"].items())
    typer.echo(f"wrote {out}: {summary['triangles']} triangles, watertight, volume "
               f"{summary['volume_cm3']:.4f} cm³")
    typer.echo(f"  points per patch: {counts}; left out by the fit: "
               f"{summary['trimmed_by_fit']}")
    typer.echo(f"  side fit: RMS {summary['side_fit_rms_mm']:.4f} mm, max "
               f"{summary['side_fit_max_mm']:.4f} mm, {summary['breakpoints']} knots round "
               "the profile")
    if cad:
        try:
            exported = write_cad(result.surface, result.root, result.tip, cad)
        except CadExportError as error:
            _fail(str(error))
        shape = "a solid" if exported.solid else "surfaces only (the kernel did not close them)"
        typer.echo(f"  CAD: {', '.join(str(p) for p in cad)}: {shape}, {exported.faces} faces, "
                   f"{exported.control_points[0]}×{exported.control_points[1]} control points "
                   f"(mm, blade frame)")
    if report is not None and row is None:
        _report_without_row(result, report, blade_count, {"reconstruction": summary,
                                                          "frame": frames})
    if report is not None and row is not None:
        extra = {"reconstruction": summary, "best_fit_rms_mm": fit_rms * 1e3,
                 "frame": frames}
        fidelity = reconstruction_fidelity(blade, result.vertices, result.triangles,
                                           extra=extra)
        json_path, csv_path = write_reconstruction_report(fidelity, report)
        png_path = write_deviation_map(result, report.with_suffix(".png"), blade)
        d = fidelity.deviation
        typer.echo(f"  deviation from the nominal blade: mean {d.mean * 1e3:.4f} mm, RMS "
                   f"{d.rms * 1e3:.4f} mm, max {d.max * 1e3:.4f} mm, Hausdorff "
                   f"{d.hausdorff * 1e3:.4f} mm")
        throat = fidelity.extra["throat_area"]
        typer.echo(f"  throat area N·∫o dr: {throat['measured_mm2']:.1f} mm² against the "
                   f"design blade's {throat['design_mm2']:.1f} mm² (ratio "
                   f"{throat['ratio']:.5f})")
        for section in fidelity.extra["sections"]:
            errors = ", ".join(f"{m['metric']} {m['error']:+.4f} {m['unit']}"
                               for m in section["metrics"])
            typer.echo(f"  {section['section']} ({section['radius_mm']:.1f} mm): {errors}")
        try:
            edges = design_edge_rows(blade, result.vertices, result.triangles)
        except ValueError as error:
            _fail(f"--report: edge radii: {error}")
        append_report_rows(json_path, csv_path, "edge_radii", edges)
        typer.echo(f"  reports {json_path}, {csv_path}, {png_path}")


def _echo_frame(found) -> None:  # found: steamtwin.geometry.frame.BladeFrame
    """Print a blade frame from the data: axes, transformation, the rule behind each choice."""
    def vector(v) -> str:
        return "(" + ", ".join(f"{c:+.5f}" for c in v) + ")"

    typer.echo(f"blade frame from the data: span axis (hub → tip) {vector(found.span_axis)}, "
               f"chord (leading → trailing edge) {vector(found.chord_direction)}, span "
               f"{found.span * 1e3:.3f} mm")
    for name, rule in found.rules.items():
        typer.echo(f"  {name}: {rule}")
    typer.echo("  scan → blade: rotation " + ", ".join(vector(r) for r in found.rotation)
               + f", translation {vector(found.translation * 1e3)} mm")
    if found.hub_tip_ambiguous:
        typer.echo("  hub and tip AMBIGUOUS: the data cannot tell them apart; check, or give "
                   "--hub-end")
    if found.edges_ambiguous:
        typer.echo("  leading and trailing edge AMBIGUOUS: the section's ends are alike")


def _report_without_row(result, report: Path, blade_count: int | None,  # a Reconstruction
                        extra: dict) -> None:
    """Row metrics (json/csv) and the fit-residual map (png) of a blade with no nominal row."""
    import math

    from steamtwin.geometry.reconstruct import write_deviation_map
    from steamtwin.geometry.row_metrics import blade_row_metrics, write_row_metrics

    try:
        sections = blade_row_metrics(result.vertices, result.triangles, blade_count=blade_count)
    except ValueError as error:
        _fail(f"--report: {error}")
    json_path, csv_path = write_row_metrics(sections, report, extra)
    png_path = write_deviation_map(result, report.with_suffix(".png"))
    for section in sections:
        values = ", ".join(f"{r['metric']} {r['measured']:.4f} {r['unit']}"
                           for r in section.rows() if math.isfinite(r["measured"]))
        typer.echo(f"  {section.name} ({section.radius * 1e3:.1f} mm): {values}")
    typer.echo(f"  reports {json_path}, {csv_path}, {png_path}")


@geometry_app.command()
def mesh(
    row: str = typer.Option("hp1", help="Blade row to mesh (hp1…hp13, ip1…ip9)."),
    out: Path = typer.Option(..., help="Volume mesh file (.msh gmsh 4.1 or .vtu)."),
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path."),
    element_size: float | None = typer.Option(None, help="Target element size in mm."),
    stl: Path | None = typer.Option(None, help="Mesh this blade STL (from 'geometry "
                                               "reconstruct') instead of the row's "
                                               "ground truth."),
) -> None:
    """Tetrahedral (gmsh HXT) mesh of the blade of ROW or of a reconstructed STL, with a
    quality report.

    Boundary faces carry the regions root, tip, pressure_side, suction_side, leading_edge and
    trailing_edge (from the STL's region attributes, or segmented when it has none).

    Example: steamtwin geometry mesh --row hp1 --out blade.msh
    Example: steamtwin geometry mesh --stl hp1.stl --out hp1-measured.msh
    """
    from steamtwin.geometry.meshing import blade_volume_mesh, mesh_quality, mesh_stl
    from steamtwin.geometry.profile import GeometryError
    from steamtwin.geometry.volume_mesh import MeshError, write_volume_mesh

    if out.suffix.lower() not in (".msh", ".vtu"):
        _fail(f"--out {out}: unknown mesh format {out.suffix!r}; use .msh or .vtu")
    prepare_output_file(out, "--out")
    size = None if element_size is None else element_size * 1e-3
    try:
        if stl is not None:
            volume_mesh = mesh_stl(stl, element_size=size)
        else:
            volume_mesh = blade_volume_mesh(_spec(turbine), row, element_size=size)
        write_volume_mesh(volume_mesh, out)
    except (GeometryError, MeshError) as error:
        _fail(str(error))
    quality = mesh_quality(volume_mesh)
    typer.echo(f"wrote {out}: {quality.node_count} nodes, {quality.tetrahedron_count} tetrahedra")
    typer.echo(f"  min dihedral angle {quality.min_dihedral_angle:.1f}°, max aspect ratio "
               f"{quality.max_aspect_ratio:.2f}, volume {quality.total_volume * 1e6:.3f} cm³")


@geometry_app.command()
def assemble(
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path."),
    out: Path = typer.Option(..., help="Assembly STL; per-component STLs are written beside it."),
    rows: str = typer.Option("all", help="Comma-separated rows (e.g. hp1,hp2) or 'all'."),
    spacing: float = typer.Option(2.0, help="Blade triangulation spacing in mm."),
) -> None:
    """Place blade rows, rotor and casing on the turbine centreline and write STL files.

    Example: steamtwin geometry assemble --turbine reference --rows hp1,hp2 --out assembly.stl
    """
    from steamtwin.geometry.assembly import build_assembly, write_assembly
    from steamtwin.geometry.profile import ROWS

    chosen = ROWS if rows == "all" else tuple(r.strip() for r in rows.split(","))
    unknown = [r for r in chosen if r not in ROWS]
    if unknown:
        _fail(f"unknown row(s) {unknown}; known rows: {', '.join(ROWS)}")
    if not 0.1 <= spacing <= 20.0:
        _fail(f"--spacing must lie within 0.1-20 mm (got {spacing})")
    prepare_output_file(out, "--out")
    spec = _spec(turbine)
    components = build_assembly(spec, rows=chosen, spacing=spacing * 1e-3)
    paths = write_assembly(components, out)
    triangles = sum(len(c.triangles) for c in components)
    typer.echo(f"wrote {len(components)} components ({triangles} triangles): "
               + ", ".join(str(p) for p in paths))


@geometry_app.command()
def uncertainty(
    row: str = typer.Option("hp1", help="Blade row whose scan error is studied (hp1…hp13)."),
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path."),
    samples: int = typer.Option(20, help="Monte Carlo samples."),
    bound: float = typer.Option(0.05, help="Scan error bound in mm (uniform within ±bound)."),
    seed: int = typer.Option(0, help="Seed of the random generator."),
    out: Path | None = typer.Option(None, help="JSON file for the result."),
) -> None:
    """Propagate ±BOUND scan errors through the row's throat area into its own stage's flow
    capacity and report the HP-exhaust temperature spread at the design point.

    Row hpK scales pressure stage K−1 alone; hp1, the control-stage rotor, sets no flow in the
    model (nozzle governing): its throat-area spread is reported without a temperature.

    Example: steamtwin geometry uncertainty --row hp1 --samples 20 --out uncertainty.json
    """
    from steamtwin.geometry.profile import GeometryError, make_blade
    from steamtwin.geometry.uncertainty import scan_uncertainty
    from steamtwin.model.fom import FullOrderModel

    if samples < 2 or not 0.0 < bound <= 1.0:
        _fail(f"--samples must be >= 2 and --bound within (0, 1] mm (got {samples}, {bound})")
    if out is not None:
        prepare_output_file(out, "--out")
    spec = _spec(turbine)
    try:
        blade = make_blade(spec, row)
        result = scan_uncertainty(blade, FullOrderModel(spec), samples=samples,
                                  bound=bound * 1e-3, rng=seed)
    except GeometryError as error:
        _fail(str(error))
    document = result.as_dict()
    if out is not None:
        out.write_text(json.dumps(document, indent=2), encoding="utf-8")
    typer.echo(f"{row}: throat-area multiplier {document['throat_area_ratio_min']:.5f}…"
               f"{document['throat_area_ratio_max']:.5f} over {samples} samples")
    if result.stage is None:
        typer.echo(f"  HP-exhaust temperature: {result.propagation}")
    else:
        typer.echo(f"  through stage {result.stage}'s flow capacity alone: HP-exhaust "
                   f"temperature spread {document['hp_exhaust_temperature_spread_K']:.3f} K "
                   "(largest deviation from the exact blade's "
                   f"{document['hp_exhaust_temperature_max_deviation_K']:.3f} K)")
