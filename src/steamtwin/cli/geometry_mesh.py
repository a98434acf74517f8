"""``steamtwin geometry mesh``, ``assemble`` and ``uncertainty``: a blade's tetrahedral mesh, the
turbine's STL assembly and a row's scan uncertainty."""

from __future__ import annotations

from pathlib import Path

import typer

from steamtwin.cli.geometry_common import fail, load_turbine
from steamtwin.cli.paths import prepare_output_file


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
    from steamtwin.geometry.workflow import write_blade_mesh

    if out.suffix.lower() not in (".msh", ".vtu"):
        fail(f"--out {out}: unknown mesh format {out.suffix!r}; use .msh or .vtu")
    prepare_output_file(out, "--out")
    spec = None if stl is not None else load_turbine(turbine)
    try:
        quality = write_blade_mesh(out, spec=spec, row=row, stl=stl,
                                   element_size=None if element_size is None
                                   else element_size * 1e-3)
    except ValueError as error:  # GeometryError, MeshError, ReconstructionError of the STL
        fail(str(error))
    typer.echo(f"wrote {out}: {quality.node_count} nodes, {quality.tetrahedron_count} tetrahedra")
    typer.echo(f"  min dihedral angle {quality.min_dihedral_angle:.1f}°, max aspect ratio "
               f"{quality.max_aspect_ratio:.2f}, volume {quality.total_volume * 1e6:.3f} cm³")


def assemble(
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path."),
    out: Path = typer.Option(..., help="Assembly STL; per-component STLs are written beside it."),
    rows: str = typer.Option("all", help="Comma-separated rows (e.g. hp1,hp2) or 'all'."),
    spacing: float = typer.Option(2.0, help="Blade triangulation spacing in mm."),
) -> None:
    """Place blade rows, rotor and casing on the turbine centreline and write STL files.

    Example: steamtwin geometry assemble --turbine reference --rows hp1,hp2 --out assembly.stl
    """
    from steamtwin.geometry.row_sizing import ROWS
    from steamtwin.geometry.workflow import write_turbine_assembly

    chosen = ROWS if rows == "all" else tuple(r.strip() for r in rows.split(","))
    unknown = [r for r in chosen if r not in ROWS]
    if unknown:
        fail(f"unknown row(s) {unknown}; known rows: {', '.join(ROWS)}")
    if not 0.1 <= spacing <= 20.0:
        fail(f"--spacing must lie within 0.1-20 mm (got {spacing})")
    prepare_output_file(out, "--out")
    components, paths = write_turbine_assembly(load_turbine(turbine), out, chosen,
                                               spacing * 1e-3)
    triangles = sum(len(c.triangles) for c in components)
    typer.echo(f"wrote {len(components)} components ({triangles} triangles): "
               + ", ".join(str(p) for p in paths))


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
    from steamtwin.geometry.workflow import row_uncertainty

    if samples < 2 or not 0.0 < bound <= 1.0:
        fail(f"--samples must be >= 2 and --bound within (0, 1] mm (got {samples}, {bound})")
    if out is not None:
        prepare_output_file(out, "--out")
    try:
        result = row_uncertainty(load_turbine(turbine), row, samples=samples,
                                 bound=bound * 1e-3, random_state=seed, out=out)
    except ValueError as error:  # GeometryError: a row outside the HP model
        fail(str(error))
    document = result.as_dict()
    typer.echo(f"{row}: throat-area multiplier {document['throat_area_ratio_min']:.5f}…"
               f"{document['throat_area_ratio_max']:.5f} over {samples} samples")
    if result.stage is None:
        typer.echo(f"  HP-exhaust temperature: {result.propagation}")
    else:
        typer.echo(f"  through stage {result.stage}'s flow capacity alone: HP-exhaust "
                   f"temperature spread {document['hp_exhaust_temperature_spread_K']:.3f} K "
                   "(largest deviation from the exact blade's "
                   f"{document['hp_exhaust_temperature_max_deviation_K']:.3f} K)")
