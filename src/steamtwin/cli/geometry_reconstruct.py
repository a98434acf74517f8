"""``steamtwin geometry reconstruct``: a watertight blade STL (and CAD, reports) from a scan
folder, a fused cloud or a fused mesh; what it did is printed by :mod:`.geometry_output`."""

from __future__ import annotations

from pathlib import Path

import typer

from steamtwin.cli.geometry_common import fail, load_turbine
from steamtwin.cli.geometry_output import echo_reconstruction
from steamtwin.cli.paths import prepare_output_file


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
    from steamtwin.geometry.cad_export import CAD_SUFFIXES
    from steamtwin.geometry.frame import HUB_ENDS
    from steamtwin.geometry.workflow import RowMismatchError, reconstruct_source

    if not 0.0 < tolerance <= 1.0:
        fail(f"--tolerance must lie within (0, 1] mm (got {tolerance})")
    if frame not in ("blade", "scan"):
        fail(f"--frame must be 'blade' or 'scan' (got {frame!r})")
    if hub_end is not None and hub_end not in HUB_ENDS:
        fail(f"--hub-end must be one of {', '.join(HUB_ENDS)} (got {hub_end!r})")
    prepare_output_file(out, "--out")
    if report is not None:
        for suffix in (".json", ".csv", ".png"):
            prepare_output_file(report.with_suffix(suffix), "--report")
    for path, option, kind in ((step, "--step", "STEP"), (iges, "--iges", "IGES")):
        if path is not None:
            if CAD_SUFFIXES.get(path.suffix.lower()) != kind:
                fail(f"{option} {path}: expected a {kind} file name ("
                     f"{', '.join(k for k, v in CAD_SUFFIXES.items() if v == kind)})")
            prepare_output_file(path, option)
    if blade_count is not None and blade_count < 1:
        fail(f"--blade-count must be a positive count (got {blade_count})")
    try:
        run = reconstruct_source(
            source, out, spec=load_turbine(turbine), row=row, stl_frame=frame, hub_end=hub_end,
            tolerance=tolerance * 1e-3, target_points=target_points, mesh_samples=mesh_samples,
            mesh_vertices=mesh_vertices, unit_scale=unit_scale,
            cad=[p for p in (step, iges) if p is not None], report=report,
            blade_count=blade_count)
    except RowMismatchError as error:
        fail(f"the cloud does not match row {error.row}'s nominal blade (best fit RMS "
             f"{error.fit_rms * 1e3:.4g} mm); leave out --row to reconstruct in a frame from "
             "the data")
    except (ValueError, OSError) as error:  # the geometry errors are ValueErrors
        fail(str(error))
    echo_reconstruction(run, source)
