"""``steamtwin validate``: the blade-temperature ROM against plant data, as an HTML report."""

from __future__ import annotations

import dataclasses
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import typer
from rich.console import Console

from steamtwin.cli.paths import OutputPathError, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, load_history
from steamtwin.dcs.quality import QualityReport
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMap, TagMapError, load_tag_map
from steamtwin.dcs.windows import find_steady_windows, parse_window, select_window
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import (
    ModelParameters,
    ParameterError,
    sensor_offsets_from_json,
)
from steamtwin.model.sensor_setup import sensor_setup
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.provenance import check_parameters, resolve_spec
from steamtwin.rom.romfile import BladeRom, RomFileError, load_rom
from steamtwin.rom.snapshots import SnapshotSet, generate_snapshots
from steamtwin.spec import SpecError, TurbineSpec, load_spec
from steamtwin.spec.fingerprint import short_hash, spec_hash
from steamtwin.validation.monitor import rom_parameters
from steamtwin.validation.monitor import validate as run_validation
from steamtwin.validation.tables import quality_section

STEADY_TOLERANCE = 0.02  # ± fraction of rated load for the automatic window search


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
        True, "--sensor-offsets/--no-sensor-offsets", help="With --params and --monitor fom: "
        "read the model through the sensors' offsets the calibration estimated (the same "
        "plant's instruments; leave them out after the thermocouples were recalibrated)."),
    monitor: str = typer.Option(
        "fom", help="What monitors the steam-path temperatures: 'fom' (the full-order model of "
        "--turbine with the ROM's parameters; metal dynamics included) or 'rom' (the ROM's "
        "steady map)."),
    sensor_lag: bool = typer.Option(
        True, help="With --monitor fom: compare what the thermocouples read — the model's "
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
            if sensor_offsets and monitor == "fom":
                offsets = sensor_offsets_from_json(params)
        timings["load ROM and turbine"] = time.perf_counter() - clock
        clock = time.perf_counter()
        tag_map = load_tag_map(tags)
        needed = _needed_signals(bundle, field_check or monitor == "fom")
        signals, quality = _read_cleaned(data, tag_map, needed, accept_quality_errors)
        if tag_map.time_zone:  # windows named and reported in the data's own time zone
            signals = signals.set_axis(signals.index.tz_convert(tag_map.time_zone))
        timings["read and clean data"] = time.perf_counter() - clock
        clock = time.perf_counter()
        windows = _pick_windows(signals, window, hours, spec.design.generator_power)
        _check_windows(bundle, windows)
        timings["window selection"] = time.perf_counter() - clock
        reference = None
        if field_check:
            clock = time.perf_counter()
            with console.status("solving the FOM blade field at each window's conditions"):
                reference = _reference_fields(bundle, spec, windows)
            timings["FOM blade fields (Figure 9)"] = time.perf_counter() - clock
        rated_mw = spec.design.generator_power / 1e6
        settings = {
            "ROM file": str(rom), "data": str(data), "tag map": str(tags),
            "tag map layout": tag_map.layout,
            "turbine": f"{spec.name} (sha256 {short_hash(spec_hash(spec))}; "
                       + (f"--turbine {turbine})" if turbine else "the ROM's own spec)"),
            "windows from": "--window" if window else (
                f"steady load (± {STEADY_TOLERANCE:.0%} of rated {rated_mw:g} MW) over "
                f"≥ {hours:g} h, the last {hours:g} h of each span"),
            "samples read": len(signals),
            "sensor offsets (measured − model)": ", ".join(
                f"{name} {value:+.2f} K" for name, value in offsets.items())
            or "none (--params without sensor_offsets, or not given)",
        }
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExtrapolationWarning)
            with console.status("monitoring the windows and writing the report"):
                result = run_validation(bundle, windows, report, settings=settings,
                                        timings=timings, field_check=reference,
                                        simulator=_monitoring_model(spec, monitor,
                                                                    sensor_lag, tag_map,
                                                                    offsets),
                                        time_zone=tag_map.time_zone,
                                        extra_sections=[quality_section(
                                            quality, "Data quality of the export (whole "
                                            "file, before windowing)")])
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


def _monitoring_model(spec: TurbineSpec, monitor: str, sensor_lag: bool, tag_map: TagMap,
                      offsets: dict[str, float]) -> FullOrderModel | None:
    """The FOM that monitors the steam path (None: the ROM does), read through the plant's
    sensors as every mode reads it (:func:`~steamtwin.model.sensor_setup.sensor_setup`: the
    tag map's time constants and thermocouple depth, typical thermowells' otherwise) and the
    calibration's sensor ``offsets`` (K)."""
    if monitor != "fom":
        return None
    setup = dataclasses.replace(sensor_setup(spec, tag_map), offsets=offsets)
    if not sensor_lag:
        return FullOrderModel(setup.spec_for(spec), sensor_offsets=offsets or None)
    return setup.model(spec)


def _needed_signals(bundle: BladeRom, with_model: bool) -> tuple[str, ...]:
    """Signals the run cannot do without: the ROM's inputs (+ the FOM's when it runs)."""
    needed = [str(name) for name in bundle.rom.input_names_]
    if with_model:
        needed += [name for name in INPUT_SIGNALS if name not in needed]
    return tuple(needed)


def _read_cleaned(data: Path, tag_map: TagMap, needed: tuple[str, ...], accept_errors: bool
                  ) -> tuple[pd.DataFrame, QualityReport]:
    """The export through the quality gate: cleaned SI signals (bad samples NaN) and report."""
    history = load_history(data, tag_map, required=needed, accept_errors=accept_errors)
    return history.data, history.report


def _pick_windows(data: pd.DataFrame, window: list[str] | None, hours: float,
                  rated_load_w: float) -> dict[str, pd.DataFrame]:
    """Named windows: given START/END pairs, or the last ``hours`` of each steady-load span."""
    picked: list[pd.DataFrame] = []
    if window:
        for text in window:
            bounds = parse_window(text)
            try:
                picked.append(select_window(data, *bounds))
            except ValueError as error:
                raise ValueError(f"--window {text!r}: {error}") from None
    else:
        if "load" not in data.columns:
            raise ValueError("no --window given and the data have no 'load' signal, which the "
                             "search for steady windows needs; map the generator load in the "
                             "tag map or pass --window START/END")
        duration = hours * 3600.0
        steady = find_steady_windows(data, duration_s=duration, rated_load_w=rated_load_w,
                                     tolerance=STEADY_TOLERANCE,
                                     sub_window_s=min(600.0, duration / 4.0))
        if not steady:
            raise ValueError(f"no steady-load span of {hours:g} h found in the data; pass "
                             "--window START/END")
        for span in sorted(steady, key=lambda w: w.start):
            end = pd.Timestamp(span.end)
            picked.append(select_window(data, end - pd.Timedelta(seconds=duration), end))
    return _named(picked, rated_load_w)


def _named(frames: list[pd.DataFrame], rated_load_w: float) -> dict[str, pd.DataFrame]:
    """Names by mean load ("50 % load"), told apart by start time when two share one."""
    names = []
    for i, frame in enumerate(frames):
        load = frame["load"].to_numpy(dtype=float) if "load" in frame.columns else np.array([])
        finite = load[np.isfinite(load)]
        names.append(f"{100.0 * finite.mean() / rated_load_w:.0f} % load" if finite.size
                     else f"window {i + 1}")
    named = {}
    for name, frame in zip(names, frames, strict=True):
        if names.count(name) > 1:
            name = f"{name}, {frame.index[0]:%Y-%m-%d %H:%M}"
        named[name] = frame
    return named


def _check_windows(bundle: BladeRom, windows: dict[str, pd.DataFrame]) -> None:
    """Every window needs at least one sample with all ROM inputs present."""
    inputs = [str(name) for name in bundle.rom.input_names_]
    for name, frame in windows.items():
        if not np.isfinite(frame[inputs].to_numpy(dtype=float)).all(axis=1).any():
            raise ValueError(f"window {name!r} ({frame.index[0]} … {frame.index[-1]}): no "
                             f"sample has all ROM inputs {inputs} valid")


def _reference_fields(bundle: BladeRom, spec: TurbineSpec,
                      windows: dict[str, pd.DataFrame]) -> SnapshotSet:
    """FOM blade fields at each window's mean boundary conditions, with the ROM's parameters."""
    params = rom_parameters(bundle)
    conditions = pd.DataFrame([frame[list(INPUT_SIGNALS)].mean() for frame in windows.values()])
    if conditions.isna().any().any():
        raise ValueError("--field-check: a window has no valid sample of "
                         f"{list(INPUT_SIGNALS)}")
    return generate_snapshots(spec, bundle.mesh, conditions, params, max_workers=1)
