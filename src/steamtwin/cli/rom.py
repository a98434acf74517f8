"""``steamtwin rom build | predict | info``: the blade-temperature reduced-order model."""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.blade.mesh import MeshError
from steamtwin.cli.paths import OutputPathError, prepare_output_file, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ModelParameters, ParameterError, sensor_offsets_from_json
from steamtwin.model.sensor_setup import sensor_setup
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.provenance import check_parameters, resolve_spec
from steamtwin.rom.reconstruction import (
    DISTANCE,
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
    MAX_EXTRAPOLATION,
)
from steamtwin.rom.romfile import RomFileError, load_rom, save_rom
from steamtwin.rom.snapshots import ROM_INPUTS
from steamtwin.spec import SpecError, load_spec
from steamtwin.spec.fingerprint import load_spec_and_text, short_hash

rom_app = typer.Typer(help="Build and use the blade-temperature ROM (POD + RBF).",
                      no_args_is_help=True)


def _progress_bar(console: Console, description: str):
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    bar = Progress(*columns, console=console, transient=True)
    task = bar.add_task(description, total=1.0)
    return bar, lambda fraction: bar.update(task, completed=fraction)


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
    from steamtwin.geometry.meshing import blade_volume_mesh
    from steamtwin.geometry.volume_mesh import read_volume_mesh
    from steamtwin.rom.build import build_rom
    from steamtwin.rom.envelope import parse_parameter_interval

    if (data is None) != (tags is None):
        typer.echo("error: --data and --tags go together", err=True)
        raise typer.Exit(code=2)
    console = Console(stderr=True)
    try:
        prepare_output_file(out, "--out")
        spec, spec_toml = load_spec_and_text(turbine)
        parameters = ModelParameters.from_json(params) if params else ModelParameters()
        intervals = dict(parse_parameter_interval(text) for text in param_interval)
        observed = None
        if data is not None and tags is not None:
            observed = load_history(data, tags, required=list(ROM_INPUTS),
                                    accept_errors=accept_quality_errors).data
        with console.status("meshing the control-stage blade"):
            volume = (read_volume_mesh(mesh) if mesh is not None
                      else blade_volume_mesh(spec, "hp1", element_size=element_size))
        bar, progress = _progress_bar(console, f"{snapshots} snapshots")
        with bar:
            bundle, _ = build_rom(spec, volume, parameters, n_snapshots=snapshots,
                                  energy=energy, max_workers=workers, scheduler=scheduler,
                                  seed=seed, layout=layout, progress=progress,
                                  projection_tolerance=projection_tolerance or None,
                                  physics_features=physics_features, spec_toml=spec_toml,
                                  params_file=params, parameter_intervals=intervals or None,
                                  observed=observed)
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
               f"{_spec_label(bundle.provenance)}")


def _spec_label(provenance: dict) -> str:
    """``'name' (sha256 0123456789ab)`` of the ROM's turbine, or that it records none."""
    record = provenance.get("spec")
    if not isinstance(record, dict):
        return "not recorded (format 2 file)"
    return f"{record.get('name')!r} (sha256 {short_hash(str(record.get('sha256')))})"


_WIRE = {"K": ("degC", lambda v: v - 273.15), "Pa": ("MPa", lambda v: v / 1e6),
         "W": ("MW", lambda v: v / 1e6)}


def _si_unit(name: str) -> str:
    if name.endswith("pressure"):
        return "Pa"
    if name.endswith("power") or name == "load":
        return "W"
    return "K"


@rom_app.command("predict")
def predict(
    rom: Path = typer.Option(..., help="ROM file (.npz) from 'steamtwin rom build'."),
    data: Path = typer.Option(..., help="Historian export: CSV or Parquet, wide or long."),
    tags: Path = typer.Option(..., help="Tag map (TOML) of the historian export."),
    out: Path = typer.Option(..., help="CSV of predictions per sample (°C, MPa, MW + flags)."),
    turbine: str | None = typer.Option(
        None, help="'reference' or a turbine spec TOML: checked to be the ROM's own (refused "
        "if it differs); default: the ROM's own spec."),
    params: Path | None = typer.Option(
        None, help="Parameter JSON: checked to hold the ROM's own parameters (refused if "
        "they differ)."),
    fields_every: int | None = typer.Option(None, help="Also reconstruct the field every N "
                                            "samples (needs --vtu-dir)."),
    vtu_dir: Path | None = typer.Option(None, help="Folder for the fields as VTU (ParaView)."),
    max_extrapolation: float = typer.Option(
        MAX_EXTRAPOLATION, min=0.0, help="Farthest a sample may lie outside the snapshots "
        "and still be predicted, in snapshot spans of each input."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings; the "
        "bad samples stay excluded."),
    readings: bool = typer.Option(
        True, "--readings/--steady-values", help="Write the temperature sensors as the DCS "
        "reads them (each thermocouple's lag from the tag map, else typical, and with "
        "--params the sensor offsets the calibration estimated) or the ROM's steady "
        "steam and metal values."),
) -> None:
    """Predict steam-path sensors and blade temperatures for every sample of DCS data.

    The data pass the quality gate first: samples outside the tag map's valid range, spikes,
    stuck runs and samples the historian marks Bad/Uncertain are excluded (and counted), and
    error-level findings (e.g. a unit mix-up) stop the command unless
    --accept-quality-errors. Samples with missing or excluded inputs, or outside the physical
    domain (main steam not superheated, farther than --max-extrapolation outside the
    snapshots), are flagged (rom_invalid_input, rom_out_of_domain) and left empty; samples
    outside the snapshots' range but within the limit are flagged (rom_extrapolated) with
    their distance. A --turbine or --params other than those the ROM was built from is
    refused (exit 2). The temperature sensors are written as the DCS reads them, through
    the same sensor models calibrate and validate use: each thermocouple's first-order lag
    (tag map time constant, else typical) and, when --params holds a joint calibration's
    sensor_offsets, that offset (--steady-values: the ROM's values as they are).

    Example: steamtwin rom predict --rom rom.npz --data plant-data/historian.parquet --tags plant-data/tags.toml --out monitored.csv --fields-every 600 --vtu-dir fields
    """  # noqa: E501
    from steamtwin.rom.reconstruction import predict_series, read_through, write_vtu

    if (fields_every is None) != (vtu_dir is None):
        typer.echo("error: --fields-every and --vtu-dir go together", err=True)
        raise typer.Exit(code=2)
    try:
        prepare_output_file(out, "--out")
        if vtu_dir is not None:
            prepare_output_folder(vtu_dir, "--vtu-dir")
        bundle = load_rom(rom)
        spec = resolve_spec(bundle, None if turbine is None else load_spec(turbine),
                            f"--turbine {turbine}", rom)
        offsets: dict[str, float] = {}
        if params is not None:
            check_parameters(bundle, ModelParameters.from_json(params), f"--params {params}",
                             rom)
            offsets = sensor_offsets_from_json(params)
        history = load_history(data, tags, required=[str(n) for n in bundle.rom.input_names_],
                               accept_errors=accept_quality_errors)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExtrapolationWarning)
            result = predict_series(bundle, history.data, fields_every=fields_every,
                                    max_extrapolation=max_extrapolation)
        setup = dataclasses.replace(sensor_setup(spec, history.historian.tag_map),
                                    offsets=offsets)
        table = read_through(result.sensors, setup) if readings else result.sensors
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (RomFileError, SpecError, ParameterError, TagMapError, HistorianFormatError,
            OutputPathError, ValueError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    excluded = {name: n for name, n in history.excluded.items() if n}
    if excluded:
        typer.echo(f"data quality: excluded {sum(excluded.values())} sample(s) ("
                   + ", ".join(f"{name} {n}" for name, n in excluded.items())
                   + "); 'steamtwin dcs check' lists why", err=True)
    for warning in caught:
        typer.echo(f"warning: {warning.message}", err=True)
    if readings:
        typer.echo("sensors as read: " + "; ".join(setup.describe()), err=True)
    wire = pd.DataFrame(index=table.index)
    for name in table.columns:
        if name in (FLAG_INVALID, FLAG_OUT_OF_DOMAIN, FLAG_EXTRAPOLATED, DISTANCE):
            wire[name] = table[name]
            continue
        unit, convert = _WIRE[_si_unit(name)]
        wire[f"{name} [{unit}]"] = convert(table[name])
    wire.index.name = "time"
    wire.to_csv(out)
    typer.echo(f"wrote {len(wire)} samples to {out} ({int(table[FLAG_INVALID].sum())} invalid, "
               f"of which {int(table[FLAG_OUT_OF_DOMAIN].sum())} outside the physical domain; "
               f"{int(table[FLAG_EXTRAPOLATED].sum())} extrapolated)")
    if vtu_dir is not None:
        for row, field in result.fields.items():
            stamp = pd.Timestamp(table.index[row]).strftime("%Y%m%dT%H%M%S")
            write_vtu(bundle.mesh, {"temperature_K": field}, vtu_dir / f"field_{row:06d}_"
                      f"{stamp}.vtu")
        typer.echo(f"wrote {len(result.fields)} field(s) to {vtu_dir}")


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
    typer.echo(f"turbine: {_spec_label(bundle.provenance)}, spec TOML "
               f"{'recorded' if bundle.spec_toml else 'not recorded'}")
    typer.echo(f"mesh: {bundle.mesh.points.shape[0]} nodes, {bundle.mesh.tetrahedra.shape[0]} "
               f"tetrahedra; field range over the snapshots {model.field_range_:.2f} K")
    for name, low, span in zip(model.input_names_, model.input_min_, model.input_span_,
                               strict=True):
        unit, convert = _WIRE[_si_unit(name)]
        typer.echo(f"input {name}: {convert(low):.3f} … {convert(low + span):.3f} {unit}")
    typer.echo(f"steam-path sensors: {', '.join(model.sensor_names_) or '-'}")
    typer.echo(f"blade probes: {', '.join(f'{k} (node {v})' for k, v in bundle.probes.items())}")
    singular = np.array2string(model.singular_values_[: model.n_modes_ + 2], precision=4)
    typer.echo(f"singular values: {singular}")
    typer.echo("provenance: " + json.dumps(bundle.provenance, indent=2, sort_keys=True))
