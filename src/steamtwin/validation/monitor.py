"""Monitoring over validation windows and the validation report used by the CLI and the demo.

:func:`monitor_windows` replays the ROM over each window of DCS data (canonical SI);
:func:`validate` compares the monitored steam-path temperatures with the measured ones and
writes the report: Table 5 (operating conditions), Table 8 (deviations of the steam-path
temperatures and of every measured pressure the twin models, definitions in
:mod:`steamtwin.validation.tables`), the per-sample series (one Parquet file per window),
Figure 10 (HP-exhaust tracking), optionally Figure 9 (ROM vs FOM blade field at reference
conditions) and the ROM's provenance — times in the data's own time zone.
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from steamtwin.calibration.windowprep import prepare_window
from steamtwin.model.sensor_setup import SensorSetup
from steamtwin.model.simulator import Simulator
from steamtwin.rom.figure import field_comparison_figure
from steamtwin.rom.provenance import rom_parameters
from steamtwin.rom.reconstruction import (
    FLAG_INVALID,
    predict_field,
    predict_series,
    read_through,
)
from steamtwin.rom.romfile import BladeRom
from steamtwin.rom.snapshots import SnapshotSet
from steamtwin.units import convert
from steamtwin.validation.figures import exhaust_tracking_figure
from steamtwin.validation.html import Section, ValidationReport
from steamtwin.validation.replay import replay
from steamtwin.validation.tables import (
    deviation_table,
    operating_table,
    rom_provenance_table,
    series_frame,
)

__all__ = ["COMPARED_PRESSURES", "COMPARED_SIGNALS", "monitor_windows", "rom_parameters",
           "validate", "write_series"]

COMPARED_SIGNALS = (
    "hp_exhaust_temperature",
    "control_stage_temperature",
    "hp_inner_casing_temperature",
)
"""Steam-path temperatures Table 8 compares when the twin predicts them and the data hold them."""

COMPARED_PRESSURES = (
    "main_steam_pressure",
    "control_stage_pressure",
    "hp_exhaust_pressure",
)
"""Pressures Table 8 compares (after the temperatures) when the twin models them — an output of
the monitoring model, not one of its inputs — and the data hold them: the control-stage
pressure, the most sensitive witness of the flow coefficient, with the full-order model."""

_DEFINITIONS = (
    "Deviation d = monitored (twin) − measured (DCS), in the row's unit (K for temperatures, "
    "MPa for pressures), over the samples where both are finite and the ROM input is valid. "
    "mean |d|, max |d| and RMSE = sqrt(mean d²); mean d is the bias.",
    "In % of the measured value (temperatures in °C, the °C scale; pressures absolute, MPa): "
    "mean_deviation_pct = 100 · mean d / mean measured, relative_error_pct = 100 · mean |d| / "
    "mean measured, rmse_pct = 100 · RMSE / mean measured, max_relative_error_pct = 100 · max "
    "over samples of |d| / measured.",
    "Samples not used are counted: n_skipped_rom_invalid (ROM input missing or not finite), "
    "n_skipped_missing (measured or monitored value missing, e.g. a dropout or a rejected "
    "spike); n_used + n_skipped_missing + n_skipped_rom_invalid = n_samples. n_extrapolated: "
    "used samples outside the snapshots' range (flagged, included in the metrics).",
)


def monitor_windows(bundle: BladeRom, windows: Mapping[str, pd.DataFrame],
                    simulator: Simulator | None = None,
                    sensors: SensorSetup | None = None,
                    replay_over: pd.DataFrame | None = None) -> dict[str, pd.DataFrame]:
    """Monitored values (SI) with their flags for every sample of every window.

    Each frame is :attr:`SeriesPrediction.sensors` of
    :func:`~steamtwin.rom.reconstruction.predict_series`: the ROM's steam-path sensors, blade
    probes, ``rom_invalid_input``, ``rom_extrapolated`` and ``rom_extrapolation_distance``.
    The ROM's inputs are used as measured (no filling); an ``ExtrapolationWarning`` per window
    that leaves the snapshots' range.

    With ``simulator`` (the full-order model of the ROM's turbine), the steam-path signals it
    outputs come from it instead, run over the window with the parameters the ROM was built
    with (``provenance["model_parameters"]``): the FOM carries the metal's heat storage and
    takes the HP-exhaust pressure, which the ROM's steady map from (p0, T0, p1) cannot. Its
    inputs are gap-filled as in calibration (≤ 60 s held, longer gaps raise); rows before the
    first complete input row are flagged ``rom_invalid_input``.

    ``sensors`` (ROM monitoring only; a ``simulator`` reads through its own): the ROM's steady
    temperatures read as the DCS reads them — each thermocouple's lag and the calibration's
    offsets (:func:`~steamtwin.rom.reconstruction.read_through`).

    ``replay_over`` (with a ``simulator``): the whole file the windows were cut from
    (canonical SI, the windows' time index). The simulator then runs once, continuously over
    all of it (:func:`~steamtwin.validation.replay.replay`: the metal's and the thermowells'
    state carried through the ramps between the windows), and each window takes that run's
    samples, instead of a fresh run from steady state at the window's first sample.
    """
    if replay_over is not None and simulator is None:
        raise ValueError("replay_over needs a simulator: the ROM is a steady map, it has no "
                         "state to carry")
    if simulator is not None and sensors is not None:
        raise ValueError("sensors apply to ROM monitoring; a simulator reads through its own "
                         "sensor models")
    params = rom_parameters(bundle) if simulator is not None else None
    replayed = (None if replay_over is None
                else replay(simulator, replay_over, params, name="the whole file"))
    monitored = {}
    for name, frame in windows.items():
        missing = [str(s) for s in bundle.rom.input_names_ if s not in frame.columns]
        if missing:
            raise ValueError(f"window {name!r} lacks the ROM input signal(s) {missing}")
        predicted = predict_series(bundle, frame).sensors
        if sensors is not None:
            predicted = read_through(predicted, sensors)
        if replayed is not None:
            outputs = replayed.loc[replayed.index.intersection(frame.index)].dropna(
                subset=list(simulator.output_signals))
            for column in simulator.output_signals:
                predicted[column] = outputs[column].reindex(predicted.index)
            predicted[FLAG_INVALID] |= ~predicted.index.isin(outputs.index)
        elif simulator is not None:
            prepared = prepare_window(frame, simulator, (), name=f"window {name!r}",
                                      min_samples=1)
            outputs = simulator.simulate(prepared.inputs, params)
            for column in simulator.output_signals:
                predicted[column] = outputs[column].reindex(predicted.index)
            predicted[FLAG_INVALID] |= ~predicted.index.isin(outputs.index)
        monitored[name] = predicted
    return monitored


def validate(bundle: BladeRom, windows: Mapping[str, pd.DataFrame], out_dir: str | Path, *,
             title: str = "Blade-temperature ROM against DCS data: validation report",
             settings: Mapping[str, object] | None = None,
             timings: Mapping[str, float] | None = None,
             versions: Mapping[str, str] | None = None,
             field_check: SnapshotSet | None = None,
             extra_sections: Sequence[Section] = (),
             simulator: Simulator | None = None,
             sensors: SensorSetup | None = None,
             time_zone: str | None = None,
             replay_over: pd.DataFrame | None = None) -> ValidationReport:
    """Compare the ROM with measured windows and write the report into ``out_dir``.

    ``windows`` maps a name (e.g. "50 % load") to canonical SI data. ``settings``,
    ``timings`` (stage → s, e.g. reading the data) and ``versions`` (extra packages) of the
    caller head the report; ``field_check`` (FOM fields, e.g. from
    :func:`~steamtwin.rom.snapshots.generate_snapshots` on the ROM's mesh) adds Figure 9 per
    field with a table of its errors; ``extra_sections`` follow the validation's own.
    ``simulator`` / ``sensors`` / ``replay_over``: see :func:`monitor_windows`.
    ``time_zone`` (IANA name, e.g. "Asia/Shanghai"; the tag map's ``historian.time_zone``):
    the zone the report's times are given in (default: the windows' own).
    Writes ``report.html``, ``report.json``, the CSV tables, the per-sample series
    (``series_<n>_<window>.parquet``, :func:`write_series`) and PNG figures; returns the report.
    """
    if not windows:
        raise ValueError("no validation windows given")
    for name, frame in windows.items():
        if frame.empty:
            raise ValueError(f"window {name!r} holds no sample")
    if time_zone is not None:
        windows = {name: _in_zone(frame, time_zone, name) for name, frame in windows.items()}
        if replay_over is not None:
            replay_over = _in_zone(replay_over, time_zone, "the whole file")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    stages = dict(timings or {})
    clock = time.perf_counter()
    monitored = monitor_windows(bundle, windows, simulator, sensors, replay_over)
    stages["ROM prediction over the windows"] = time.perf_counter() - clock

    clock = time.perf_counter()
    predicted = set(bundle.sensor_names) | set(simulator.output_signals if simulator else ())
    # a pressure the monitoring model takes as input is not modelled: nothing to compare
    inputs = set(simulator.input_signals if simulator else bundle.rom.input_names_)

    def held(signal: str) -> bool:
        return all(signal in frame.columns for frame in windows.values())

    signals = [s for s in COMPARED_SIGNALS if s in predicted and held(s)]
    if not signals:
        raise ValueError(f"the data hold none of the ROM's steam-path temperatures "
                         f"{[s for s in COMPARED_SIGNALS if s in bundle.sensor_names]} in "
                         "every window; nothing to compare")
    signals += [s for s in COMPARED_PRESSURES
                if s in predicted and s not in inputs and held(s)]
    table5 = operating_table(windows)
    table8 = deviation_table({name: (windows[name], monitored[name]) for name in windows},
                             signals)
    stages["tables"] = time.perf_counter() - clock
    zone = time_zone or str(next(iter(windows.values())).index.tz or "as in the data")

    report = ValidationReport(title, settings={
        **(settings or {}),
        "windows": list(windows),
        "times in": zone,
        "compared signals": signals,
        "ROM inputs": [str(name) for name in bundle.rom.input_names_],
        "steam-path temperatures monitored by": (
            "the full-order model with the ROM's parameters (metal dynamics, exhaust pressure)"
            + (", run once over the whole file (state carried between the windows)"
               if replay_over is not None else ", started at steady state in each window")
            if simulator is not None else "the ROM's steady map from (p0, T0, p1)"),
        "blade temperatures monitored by": "the ROM",
    })
    report.versions |= dict(versions or {})
    report.add_table("table5_operating", table5,
                     f"Table 5 — operating conditions of the validation windows (DCS; MW, MPa, "
                     f"°C, t/h; times in {zone})")
    report.add_table("table8_deviation", table8,
                     "Table 8 — monitored (twin) vs measured temperatures and pressures per "
                     "measurement point and window (K or MPa as the unit column says, %)")
    report.add_notes("Table 8: definitions", _DEFINITIONS)
    series = write_series(windows, monitored, signals, out_dir)
    report.add_files("Per-sample series (Parquet): measured, twin and residual per signal", [
        (path, f"{name}: {len(windows[name])} samples of {', '.join(signals)}; units in the "
         f"column names and the file's metadata; times in {zone}")
        for name, path in series.items()])
    clock = time.perf_counter()
    if "hp_exhaust_temperature" in signals:
        path = exhaust_tracking_figure(windows, monitored,
                                       out_dir / "figure10_exhaust_tracking.png")
        report.add_figure(path, "Figure 10 — HP-exhaust steam temperature, monitored vs "
                          "measured, and their deviation")
    else:
        report.add_notes("Figure 10", ("not drawn: hp_exhaust_temperature is missing from the "
                                       "data or not predicted by the ROM.",))
    if field_check is not None:
        errors, figures = _field_check(bundle, field_check, out_dir)
        report.add_table("figure9_field_error", errors,
                         "Blade field, ROM vs FOM at the reference conditions (Figure 9; K; "
                         "relative error over the snapshots' field range)")
        for path, caption in figures:  # under the table's heading
            report.add_figure(path, caption)
    stages["figures"] = time.perf_counter() - clock
    report.add_table("rom_provenance", rom_provenance_table(bundle),
                     "The ROM: format, snapshots, modes, settings and provenance")
    report.add_notes("Sample accounting", _accounting(table8))
    for section in extra_sections:
        report.add(section)
    report.timings = stages
    report.write(out_dir)
    return report


def write_series(windows: Mapping[str, pd.DataFrame], monitored: Mapping[str, pd.DataFrame],
                 signals: Sequence[str], out_dir: str | Path) -> dict[str, Path]:
    """One Parquet file per window of :func:`~steamtwin.validation.tables.series_frame`.

    Named ``series_<n>_<window>.parquet`` (n from 1, the window name reduced to letters,
    digits and ``_``); the schema metadata key ``steamtwin`` holds JSON with the window name,
    its time zone, each column's unit and the residual's definition. Returns name → path.
    """
    out_dir = Path(out_dir)
    written = {}
    for number, (name, frame) in enumerate(windows.items(), start=1):
        series = series_frame(frame, monitored[name], signals, name)
        slug = re.sub(r"[^A-Za-z0-9]+", "_", name.replace("%", "pct")).strip("_")
        path = out_dir / f"series_{number}_{slug}.parquet"
        table = pa.Table.from_pandas(series, preserve_index=True)
        metadata = {"window": name, "time_zone": str(series.index.tz),
                    "units": series.attrs["units"],
                    "residual": "twin − measured, in the residual column's unit"}
        table = table.replace_schema_metadata({**(table.schema.metadata or {}),
                                               b"steamtwin": json.dumps(metadata).encode()})
        pq.write_table(table, path)
        written[name] = path
    return written


def _in_zone(frame: pd.DataFrame, time_zone: str, name: str) -> pd.DataFrame:
    """``frame`` with its time index converted to ``time_zone`` (a naive index is refused)."""
    index = frame.index
    if not isinstance(index, pd.DatetimeIndex) or index.tz is None:
        raise ValueError(f"window {name!r}: times without a time zone cannot be shown in "
                         f"{time_zone}")
    return frame.set_axis(index.tz_convert(time_zone))


def _field_check(bundle: BladeRom, reference: SnapshotSet, out_dir: Path
                 ) -> tuple[pd.DataFrame, list[tuple[Path, str]]]:
    """A table of the field errors per reference field and its Figure 9 (path, caption)."""
    rom = bundle.rom
    rows = []
    figures = []
    for i in range(reference.fields.shape[0]):
        condition = {name: float(reference.conditions[name].iloc[i])
                     for name in rom.input_names_}
        rom_field = predict_field(bundle, condition)
        error = np.abs(rom_field - reference.fields[i])
        suffix = "" if reference.fields.shape[0] == 1 else f"_{i + 1}"
        p0 = float(convert(condition["main_steam_pressure"], "Pa", "MPa"))
        t0 = float(convert(condition["main_steam_temperature"], "K", "degC"))
        p1 = float(convert(condition["control_stage_pressure"], "Pa", "MPa"))
        label = f"p0 {p0:.2f} MPa, T0 {t0:.1f} °C, p1 {p1:.2f} MPa"
        path = field_comparison_figure(bundle.mesh, reference.fields[i], rom_field,
                                       out_dir / f"figure9_field{suffix}.png", title=label)
        figures.append((path, "Figure 9 — blade temperature field (pressure side), FOM | ROM | "
                        f"ROM − FOM ({label})"))
        rows.append({"main_steam_pressure_MPa": p0, "main_steam_temperature_degC": t0,
                     "control_stage_pressure_MPa": p1,
                     "max_abs_error_K": float(error.max()),
                     "mean_abs_error_K": float(error.mean()),
                     "max_relative_error_pct": 100.0 * float(error.max()) / rom.field_range_})
    return pd.DataFrame(rows), figures


def _accounting(table8: pd.DataFrame) -> list[str]:
    lines = []
    for row in table8.itertuples(index=False):
        lines.append(f"{row.signal}, {row.window}: {row.n_used} of {row.n_samples} samples used "
                     f"({row.n_skipped_missing} missing, {row.n_skipped_rom_invalid} with invalid "
                     f"ROM input); {row.n_extrapolated} extrapolated")
    return lines
