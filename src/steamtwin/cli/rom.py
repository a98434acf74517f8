"""``steamtwin rom build | predict | info``: the blade-temperature reduced-order model.

``build`` and ``predict`` each make one call into :mod:`steamtwin.rom.workflow`; ``predict``
is in :mod:`steamtwin.cli.rom_predict`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.blade.mesh import MeshError
from steamtwin.cli.paths import OutputPathError, prepare_output_file
from steamtwin.cli.rom_predict import predict, spec_label
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ParameterError
from steamtwin.rom.romfile import RomFileError, load_rom, save_rom
from steamtwin.rom.workflow import build_rom_from_files, wire_unit
from steamtwin.spec import SpecError

rom_app = typer.Typer(help="Build and use the blade-temperature ROM (POD + RBF).",
                      no_args_is_help=True)


@rom_app.command("build")
def build(
    out: Path = typer.Option(..., help="ROM file to write (.npz)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    params: Path | None = typer.Option(None, help="Parameter JSON (default: empirical)."),
    snapshots: int = typer.Option(32, help="Number of snapshots (4 load levels)."),
    energy: float = typer.Option(0.992, help="POD energy kept (0-1]."),
    mesh: Path | None = typer.Option(None, help="Blade volume mesh (.msh/.vtu); default: "
                                     "meshed from the spec."),
    element_size: float | None = typer.Option(None, help="Element size (m) when meshing."),
    workers: int | None = typer.Option(None, help="Local worker processes (default: CPUs)."),
    scheduler: str | None = typer.Option(None, help="Dask scheduler address, e.g. "
                                         "tcp://host:8786 (default: local processes)."),
    seed: int = typer.Option(0, help="Seed of the design of experiments."),
    layout: str = typer.Option("lhs", help="Design per load level: lhs, corners or bands."),
    projection_tolerance: float = typer.Option(
        0.1, help="Add POD modes until every snapshot projects within this (K); 0: energy only."),
    physics_features: bool = typer.Option(
        True, help="RBF on the governing stage's features (p0, T0, p1, T_cs, admitted arc) "
        "instead of (p0, T0, p1)."),
    param_interval: list[str] = typer.Option(
        [], "--param-interval", help="NAME=LOW:HIGH, a model parameter's interval (e.g. its "
        "calibration interval); the snapshots cover the control-stage pressure a plant "
        "anywhere in it shows. Repeatable."),
    data: Path | None = typer.Option(None, help="Historian export (CSV/Parquet) whose "
                                     "main-steam p, T and control-stage pressure the "
                                     "snapshots must cover (needs --tags)."),
    tags: Path | None = typer.Option(None, help="Tag map (TOML) of --data."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings in "
        "--data; the bad samples stay excluded."),
) -> None:
    """Generate blade-field snapshots with the FOM + FEM and fit the POD-RBF ROM.

    The snapshots cover the spec's operating envelope (sliding pressure, temperature schedule,
    valve points), widened by --param-interval and by the inputs observed in --data. A
    snapshot condition the model cannot run (e.g. more flow than the valves pass at the
    calibrated flow coefficient) is replaced by a feasible one and counted; when the operating
    line itself cannot be run, the error names the parameter.

    Example: steamtwin rom build --turbine reference --params params.json --snapshots 32 --out rom.npz
    """  # noqa: E501
    if (data is None) != (tags is None):
        typer.echo("error: --data and --tags go together", err=True)
        raise typer.Exit(code=2)
    console = Console(stderr=True)
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    try:
        prepare_output_file(out, "--out")
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task(f"{snapshots} snapshots", total=1.0)
            bundle = build_rom_from_files(
                turbine, params_file=params, mesh_file=mesh, element_size=element_size,
                history_file=data, tag_map_file=tags, accept_quality_errors=accept_quality_errors,
                parameter_intervals=param_interval, n_snapshots=snapshots, energy=energy,
                max_workers=workers, scheduler=scheduler, random_state=seed, layout=layout,
                projection_tolerance=projection_tolerance or None,
                physics_features=physics_features,
                progress=lambda fraction, message: bar.update(
                    task, completed=fraction, description=message or f"{snapshots} snapshots"))
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (SpecError, ParameterError, InputError, MeshError, OutputPathError, TagMapError,
            HistorianFormatError, ValueError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    save_rom(bundle, out)
    envelope = bundle.provenance["envelope"]
    if envelope["replaced"]:
        typer.echo(f"{envelope['replaced']} snapshot condition(s) the model cannot run were "
                   "replaced by feasible ones (e.g. the highest flow the valves pass); "
                   "'steamtwin rom info' lists them", err=True)
    coverage = envelope["observed"]
    if coverage is not None and coverage["samples"]:
        typer.echo(f"--data: {coverage['outside_hull']} of {coverage['samples']} sample(s) "
                   f"outside the snapshots' hull, {coverage['beyond_limit']} beyond the "
                   f"extrapolation limit")
    rom = bundle.rom
    typer.echo(f"wrote {out}: {rom.n_modes_} modes ({rom.energy_captured_:.6f} of the energy) "
               f"on {rom.mean_.size} nodes from {rom.centres_.shape[0]} snapshots, turbine "
               f"{spec_label(bundle.provenance)}")


rom_app.command("predict")(predict)


@rom_app.command("info")
def info(rom: Path = typer.Argument(..., help="ROM file (.npz).")) -> None:
    """Print what a ROM file holds: modes, energy, inputs and their range, sensors, provenance.

    Example: steamtwin rom info rom.npz
    """
    try:
        bundle = load_rom(rom)
    except RomFileError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    model = bundle.rom
    typer.echo(f"ROM {rom}: {model.n_modes_} modes, energy {model.energy_captured_:.6f} "
               f"(threshold {model.energy}), kernel {model.kernel}, "
               f"{model.centres_.shape[0]} snapshots")
    typer.echo(f"turbine: {spec_label(bundle.provenance)}, spec TOML "
               f"{'recorded' if bundle.spec_toml else 'not recorded'}")
    typer.echo(f"mesh: {bundle.mesh.points.shape[0]} nodes, {bundle.mesh.tetrahedra.shape[0]} "
               f"tetrahedra; field range over the snapshots {model.field_range_:.2f} K")
    for name, low, span in zip(model.input_names_, model.input_min_, model.input_span_,
                               strict=True):
        unit, convert = wire_unit(name)
        typer.echo(f"input {name}: {convert(low):.3f} … {convert(low + span):.3f} {unit}")
    typer.echo(f"steam-path sensors: {', '.join(model.sensor_names_) or '-'}")
    typer.echo(f"blade probes: {', '.join(f'{k} (node {v})' for k, v in bundle.probes.items())}")
    singular = np.array2string(model.singular_values_[: model.n_modes_ + 2], precision=4)
    typer.echo(f"singular values: {singular}")
    typer.echo("provenance: " + json.dumps(bundle.provenance, indent=2, sort_keys=True))
