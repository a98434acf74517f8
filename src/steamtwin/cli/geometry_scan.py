"""``steamtwin geometry scan`` and ``geometry preprocess``: the virtual scanner and the fused
cloud of a scan folder."""

from __future__ import annotations

from pathlib import Path

import typer

from steamtwin.cli.geometry_common import fail, load_turbine, point_cloud_out
from steamtwin.cli.paths import prepare_output_file, prepare_output_folder


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
    from steamtwin.geometry.workflow import scan_row

    if file_format not in ("ply", "pcd"):
        fail(f"--file-format must be 'ply' or 'pcd' (got {file_format!r})")
    prepare_output_folder(out, "--out")
    spec = load_turbine(turbine)
    try:
        result = scan_row(spec, row, out, points=points, views=views, outliers=outliers,
                          spheres=spheres, file_format=file_format, random_state=seed)
    except ValueError as error:  # GeometryError and the scanner's settings errors
        fail(str(error))
    typer.echo(f"wrote {len(result.paths)} views of row {row} ({result.points} points) to {out}")


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
    from steamtwin.geometry.pointcloud import write_point_cloud
    from steamtwin.geometry.profile import make_blade
    from steamtwin.geometry.workflow import (
        preprocess_scan,
        read_scan_folder,
        write_preprocess_report,
    )

    point_cloud_out(out)
    if report is not None:
        prepare_output_file(report.with_suffix(".json"), "--report")
    try:
        scan_folder = read_scan_folder(folder)
    except ValueError as error:  # ScanFolderError, a view's PointCloudError
        fail(str(error))
    blade = None
    if report is not None:
        try:
            blade = make_blade(load_turbine(turbine), str(scan_folder.row))
        except ValueError as error:  # GeometryError
            fail(f"--report: {folder / 'scan.json'}: {error}")
    try:
        fused = preprocess_scan(scan_folder, target_points)
    except ValueError as error:  # views that cannot be registered, unmatched spheres
        fail(str(error))
    write_point_cloud(fused.cloud, out)
    steps = fused.report
    typer.echo(f"fused {sum(steps.input_points)} points of {len(scan_folder.views)} views into "
               f"{len(fused.cloud)} points: {out}")
    typer.echo(f"  outliers removed per view: {steps.outliers_removed}")
    if any(steps.spheres_found):
        typer.echo(f"  reference spheres: {steps.spheres_matched} matched across views, "
                   f"points removed per view: {steps.sphere_points_removed}")
    if blade is not None:
        path, deviation = write_preprocess_report(report.with_suffix(".json"), fused, blade)
        typer.echo(f"  deviation from the nominal blade: mean {deviation.mean * 1e3:.4f} mm, "
                   f"RMS {deviation.rms * 1e3:.4f} mm, max {deviation.max * 1e3:.4f} mm; "
                   f"report {path}")
