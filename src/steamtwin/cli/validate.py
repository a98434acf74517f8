"""``steamtwin validate``: the blade-temperature ROM against plant data, as an HTML report."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import typer
from rich.console import Console

from steamtwin.cli.paths import OutputPathError, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError, load_tag_map
from steamtwin.dcs.windows import name_windows
from steamtwin.model.parameters import (
    ModelParameters,
    ParameterError,
    sensor_offsets_from_json,
)
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.provenance import check_parameters, resolve_spec
from steamtwin.rom.romfile import RomFileError, load_rom
from steamtwin.spec import SpecError, load_spec
from steamtwin.spec.fingerprint import short_hash, spec_hash
from steamtwin.twin import Twin, monitoring_model

# the window names and the monitoring model are the library's; the names this module gave them
# stay for the callers that import them
_named = name_windows
_monitoring_model = monitoring_model


def validate(
    rom: Path = typer.Option(..., help="ROM file (.npz) from 'steamtwin rom build'."),
    data: Path = typer.Option(..., help="Historian export: CSV or Parquet, wide or long."),
    tags: Path = typer.Option(..., help="Tag map (TOML) of the historian export (columns/tags "
                              "and their units)."),
    report: Path = typer.Option(..., help="Folder for report.html, report.json, CSV tables "
                                "and PNG figures."),
    window: list[str] | None = typer.Option(
        None, help="START/END (ISO 8601) of a validation window; repeatable. Default: the "
        "last --hours of every steady-load span of at least --hours."),
    hours: float = typer.Option(2.0, min=0.05, help="Length of the automatically found "
                                "windows (h)."),
    turbine: str | None = typer.Option(
        None, help="'reference' or a turbine spec TOML (rated load for the window search; the "
        "FOM). Default: the spec the ROM was built from; one that differs is refused."),
    params: Path | None = typer.Option(
        None, help="Parameter JSON, checked to hold the parameters the ROM was built with "
        "(refused if they differ); the twin always runs with the ROM's own. Its sensor "
        "offsets (a calibration with --sensor-bias writes them) are added to what the "
        "monitoring model's sensors read, unless --no-sensor-offsets."),
    sensor_offsets: bool = typer.Option(
        True, "--sensor-offsets/--no-sensor-offsets", help="With --params: "
        "read the model through the sensors' offsets the calibration estimated (the same "
        "plant's instruments; leave them out after the thermocouples were recalibrated)."),
    monitor: str = typer.Option(
        "fom", help="What monitors the steam-path temperatures: 'fom' (the full-order model of "
        "--turbine with the ROM's parameters; metal dynamics included) or 'rom' (the ROM's "
        "steady map)."),
    sensor_lag: bool = typer.Option(
        True, help="Compare what the thermocouples read — the model's (FOM or ROM) "
        "temperatures through first-order lags: the tag map's time_constant per signal where "
        "given, else typical thermowells (control stage 20 s, HP exhaust 30 s, casing metal "
        "5 s)."),
    field_check: bool = typer.Option(
        False, "--field-check", help="Also solve the FOM blade field at each window's mean "
        "conditions and compare it with the ROM's (Figure 9)."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings; the "
        "bad samples stay excluded (and are counted in the report)."),
) -> None:
    """Compare the ROM's monitored temperatures with measured DCS data and write a report.

    Reads the historian export with its tag map (units converted to SI there), cleans it
    (spikes and out-of-range values rejected and counted, nothing filled), picks the windows,
    replays the twin over them — blade temperatures from the ROM, steam-path temperatures from
    the full-order model with the ROM's parameters (--monitor fom) or the ROM (--monitor rom) —
    and writes Table 5 (operating conditions), Table 8 (mean/max
    absolute deviation, RMSE, absolute and in %, per steam-path temperature and modelled
    pressure — the control-stage pressure with --monitor fom — and window), Figure 10 (HP-exhaust
    tracking), the per-sample series (Parquet) and the ROM's provenance, times in the tag
    map's time zone. Prints one line per window. The turbine is the one
    the ROM records; a --turbine or --params other than those the ROM was built from is
    refused (exit 2) with both named.

    Example: steamtwin validate --rom rom.npz --data plant-data/historian.parquet --tags plant-data/tags.toml --report validation
    """  # noqa: E501
    if monitor not in ("fom", "rom"):
        typer.echo(f"error: --monitor must be 'fom' or 'rom' (got {monitor!r})", err=True)
        raise typer.Exit(code=2)
    console = Console(stderr=True)
    timings: dict[str, float] = {}
    try:
        prepare_output_folder(report, "--report")
        clock = time.perf_counter()
        bundle = load_rom(rom)
        spec = resolve_spec(bundle, None if turbine is None else load_spec(turbine),
                            f"--turbine {turbine}", rom)
        offsets: dict[str, float] = {}
        if params is not None:
            check_parameters(bundle, ModelParameters.from_json(params), f"--params {params}",
                             rom)
            if sensor_offsets:
                offsets = sensor_offsets_from_json(params)
        twin = Twin(spec, rom=bundle, sensor_offsets=offsets)
        timings["load ROM and turbine"] = time.perf_counter() - clock
        clock = time.perf_counter()
        tag_map = load_tag_map(tags)
        history = load_history(data, tag_map, accept_errors=accept_quality_errors,
                               required=twin.signals_needed(monitor=monitor,
                                                            field_check=field_check))
        timings["read and clean data"] = time.perf_counter() - clock
        settings = {
            "ROM file": str(rom), "data": str(data), "tag map": str(tags),
            "tag map layout": tag_map.layout,
            "turbine": f"{spec.name} (sha256 {short_hash(spec_hash(spec))}; "
                       + (f"--turbine {turbine})" if turbine else "the ROM's own spec)"),
        }
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExtrapolationWarning)
            with console.status("monitoring the windows and writing the report") as status:
                result = twin.validate(history, report, windows=window or (), hours=hours,
                                       monitor=monitor, sensor_lag=sensor_lag,
                                       field_check=field_check, settings=settings,
                                       timings=timings,
                                       progress=lambda _f, message: status.update(message))
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (RomFileError, SpecError, TagMapError, HistorianFormatError, ParameterError,
            OutputPathError, ValueError, OSError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    for warning in caught:
        typer.echo(f"warning: {warning.message}", err=True)
    table8 = result.tables["table8_deviation"]
    shown = table8["signal"].iloc[0]  # the HP exhaust when the data hold it
    for row in table8[table8["signal"] == shown].itertuples(index=False):
        if row.n_used == 0:
            typer.echo(f"{row.window}: {shown}: no usable sample ({row.n_samples} missing, "
                       "excluded by the quality gate or flagged by the ROM); nothing to compare")
            continue
        typer.echo(f"{row.window}: {shown} mean abs deviation {row.mean_abs_deviation:.2f} "
                   f"{row.unit}, max {row.max_abs_deviation:.2f} {row.unit}, RMSE "
                   f"{row.rmse:.2f} {row.unit} ({row.n_used} of {row.n_samples} samples used)")
    typer.echo(f"wrote {report / 'report.html'} (+ report.json, "
               f"{len(result.tables)} CSV tables, figures)")
