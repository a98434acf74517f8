"""``steamtwin rom predict``: the ROM over a historian export, one call into
:func:`steamtwin.rom.workflow.predict_history`; the CSV in °C, MPa and MW with the flags."""

from __future__ import annotations

from pathlib import Path

import typer

from steamtwin.cli.paths import OutputPathError, prepare_output_file, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.parameters import ParameterError
from steamtwin.rom.reconstruction import (
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
    MAX_EXTRAPOLATION,
)
from steamtwin.rom.romfile import RomFileError
from steamtwin.rom.workflow import predict_history
from steamtwin.spec import SpecError
from steamtwin.spec.fingerprint import short_hash

__all__ = ["predict", "spec_label"]


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
    if (fields_every is None) != (vtu_dir is None):
        typer.echo("error: --fields-every and --vtu-dir go together", err=True)
        raise typer.Exit(code=2)
    try:
        prepare_output_file(out, "--out")
        if vtu_dir is not None:
            prepare_output_folder(vtu_dir, "--vtu-dir")
        result = predict_history(rom, data, tags, turbine=turbine, params_file=params,
                                 fields_every=fields_every, max_extrapolation=max_extrapolation,
                                 accept_quality_errors=accept_quality_errors, readings=readings)
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (RomFileError, SpecError, ParameterError, TagMapError, HistorianFormatError,
            OutputPathError, ValueError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    if result.excluded:
        typer.echo(f"data quality: excluded {sum(result.excluded.values())} sample(s) ("
                   + ", ".join(f"{name} {n}" for name, n in result.excluded.items())
                   + "); 'steamtwin dcs check' lists why", err=True)
    for warning in result.warnings:
        typer.echo(f"warning: {warning}", err=True)
    if readings:
        typer.echo("sensors as read: " + "; ".join(result.sensors_as_read), err=True)
    result.in_wire_units().to_csv(out)
    table = result.table
    typer.echo(f"wrote {len(table)} samples to {out} ({int(table[FLAG_INVALID].sum())} invalid, "
               f"of which {int(table[FLAG_OUT_OF_DOMAIN].sum())} outside the physical domain; "
               f"{int(table[FLAG_EXTRAPOLATED].sum())} extrapolated)")
    if vtu_dir is not None:
        result.write_fields(vtu_dir)
        typer.echo(f"wrote {len(result.fields)} field(s) to {vtu_dir}")


def spec_label(provenance: dict) -> str:
    """``'name' (sha256 0123456789ab)`` of the ROM's turbine, or that it records none."""
    record = provenance.get("spec")
    if not isinstance(record, dict):
        return "not recorded (format 2 file)"
    return f"{record.get('name')!r} (sha256 {short_hash(str(record.get('sha256')))})"
