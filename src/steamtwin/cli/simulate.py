"""``steamtwin simulate``: run the full-order model over a CSV of boundary conditions.

Errors name the inputs file, the column and the row as a data row (1-based, the header not
counted) with its line in the file (data row + 1), and values in the file's units.
"""

from __future__ import annotations

import math
import re
from datetime import timedelta, timezone, tzinfo
from pathlib import Path
from typing import NoReturn
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

import numpy as np
import pandas as pd
import typer
from rich.console import Console

from steamtwin.cli.paths import prepare_output_file
from steamtwin.dcs.canonical_csv import CsvFormatError, read_canonical_csv, write_canonical_csv
from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.parameters import ModelParameters, ParameterError
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec
from steamtwin.units import convert

# An ISO 8601 time of day followed by its UTC offset: 'Z' or ±hh[[:]mm].
_WITH_OFFSET = re.compile(r"\d{2}:\d{2}(?::\d{2}(?:[.,]\d+)?)?\s*(?:[Zz]|[+-]\d{2}(?::?\d{2})?)$")
_FIXED_OFFSET = re.compile(r"([+-])(\d{2}):?(\d{2})")
_DISPLAY_UNITS = {"degC": "°C"}


def simulate(
    inputs: Path = typer.Option(..., help="CSV: 'time' + canonical inputs in MPa, °C, t/h."),
    out: Path = typer.Option(..., help="Output CSV of predicted signals (MPa, °C, MW)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    params: Path | None = typer.Option(None, help="Parameter JSON (default: empirical)."),
    time_zone: str | None = typer.Option(
        None, help="Zone of timestamps written without a UTC offset: an IANA name "
                   "(Asia/Shanghai, UTC) or a fixed offset (+08:00). Without it such "
                   "timestamps are refused."),
) -> None:
    """Simulate the HP section over a time series of boundary conditions.

    The inputs CSV has a 'time' column (ISO 8601 with a UTC offset, e.g.
    2026-03-01T10:00:00+08:00 or ...Z, or seconds) and the columns
    main_steam_pressure [MPa], main_steam_temperature [°C], main_steam_flow [t/h],
    hp_exhaust_pressure [MPa]. Errors give the data row (1-based, header not counted) and its
    line in the file (data row + 1).

    Example: steamtwin simulate --turbine reference --inputs inputs.csv --out outputs.csv

    Example: steamtwin simulate --inputs dcs-local.csv --time-zone Asia/Shanghai --out o.csv
    """
    prepare_output_file(out, "--out")
    zone = None if time_zone is None else _zone(time_zone)
    console = Console(stderr=True)
    try:
        spec = load_spec(turbine)
        parameters = ModelParameters.from_json(params) if params else ModelParameters()
    except (SpecError, ParameterError) as error:
        _fail(str(error))
    try:
        frame = read_canonical_csv(inputs, required=INPUT_SIGNALS)
    except CsvFormatError as error:
        _fail(str(error))
    except UnicodeDecodeError as error:  # the CSV reader leaves the encoding to pandas
        _fail(f"{inputs}: not UTF-8 text (byte 0x{error.object[error.start]:02x} at offset "
              f"{error.start}); save the inputs CSV as UTF-8")
    if isinstance(frame.index, pd.DatetimeIndex):
        frame.index = _explicit_times(frame.index, inputs, zone, time_zone)
    model = FullOrderModel(spec)
    try:
        checked = model.check_inputs(frame)  # before the model is prepared: bad rows fail fast
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        with console.status(f"simulating {len(frame)} samples"):
            outputs = pd.DataFrame(model.simulate_checked(checked, parameters),
                                   index=frame.index, columns=list(model.output_signals))
    except InputError as error:
        _fail(in_file_terms(error, inputs))
    write_canonical_csv(outputs, out)
    typer.echo(f"wrote {len(outputs)} samples of {', '.join(outputs.columns)} to {out}")


def in_file_terms(error: InputError, path: Path) -> str:
    """The model's input error re-worded for the CSV it came from: the file, the column, the
    data row (1-based) with its line (data row + 1) and, for a range error, the value and the
    limits in the file's units (MPa, °C, t/h)."""
    if error.row is None:
        return f"{path}: {error}"
    where = f"column {error.column!r} " if error.column else ""
    where += f"data row {error.row + 1} (line {error.row + 2})"
    signal = SIGNALS.get(error.column or "")
    if error.limits is None or error.value is None or signal is None:
        return f"{path}: {where}: {error.reason}"
    value, low, high = convert(np.array([error.value, *error.limits]), signal.si_unit,
                               signal.wire_unit)
    unit = _DISPLAY_UNITS.get(signal.wire_unit, signal.wire_unit)
    shown = "an empty cell" if math.isnan(value) else f"{value:g} {unit}"
    rows = "1 bad row" if error.count == 1 else f"{error.count} bad rows"
    return (f"{path}: {where}: {shown} is not a number within [{low:g}, {high:g}] {unit} "
            f"({rows})")


def _fail(message: str) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def _zone(name: str) -> tzinfo:
    """The zone of ``--time-zone``: a fixed offset (``+08:00``) or an IANA name."""
    fixed = _FIXED_OFFSET.fullmatch(name.strip())
    if fixed:
        sign, hours, minutes = fixed.groups()
        offset = timedelta(hours=int(hours), minutes=int(minutes))
        if offset > timedelta(hours=14):
            _fail(f"--time-zone {name}: offsets lie within ±14:00")
        return timezone(-offset if sign == "-" else offset)
    try:
        return ZoneInfo(name.strip())
    except (ZoneInfoNotFoundError, ValueError):
        _fail(f"--time-zone {name!r}: not a time zone; give an IANA name such as "
              "Asia/Shanghai or Europe/Berlin, UTC, or an offset such as +08:00")


def _explicit_times(index: pd.DatetimeIndex, path: Path, zone: tzinfo | None,
                    zone_name: str | None) -> pd.DatetimeIndex:
    """The time index with every timestamp written without a UTC offset read in ``zone``.

    The CSV reader takes such timestamps as UTC; without ``--time-zone`` they are refused,
    naming the first one.
    """
    raw = pd.read_csv(path, usecols=["time"], dtype=str, keep_default_na=False)["time"]
    naive = ~raw.str.strip().str.contains(_WITH_OFFSET).to_numpy()
    if not naive.any():
        return index
    first = int(np.flatnonzero(naive)[0])
    where = f"{path}: column 'time' data row {first + 1} (line {first + 2})"
    if zone is None:
        _fail(f"{where}: {raw.iloc[first]!r} has no UTC offset ({int(naive.sum())} such rows); "
              "write the offset (e.g. 2026-03-01T10:00:00+08:00, or Z for UTC) or give the "
              "zone of the plant's clock with --time-zone (e.g. --time-zone Asia/Shanghai)")
    wall_clock = index[naive].tz_localize(None)
    local = wall_clock.tz_localize(zone, ambiguous="NaT", nonexistent="NaT")
    if local.isna().any():
        bad = int(np.flatnonzero(naive)[int(np.flatnonzero(local.isna())[0])])
        _fail(f"{path}: column 'time' data row {bad + 1} (line {bad + 2}): "
              f"{raw.iloc[bad]!r} is ambiguous or does not exist in {zone_name} (a "
              "daylight-saving change); write these timestamps with their UTC offset")
    utc = index.tz_convert("UTC").tz_localize(None).to_numpy().copy()
    utc[naive] = local.tz_convert("UTC").tz_localize(None).to_numpy()
    return pd.DatetimeIndex(utc, name=index.name).tz_localize("UTC")
