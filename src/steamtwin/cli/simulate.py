"""``steamtwin simulate``: run the full-order model over a CSV of boundary conditions.

Errors name the inputs file, the column and the row as a data row (1-based, the header not
counted) with its line in the file (data row + 1), and values in the file's units.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NoReturn

import numpy as np
import pandas as pd
import typer
from rich.console import Console

from steamtwin.cli.paths import prepare_output_file
from steamtwin.dcs.canonical_csv import (
    CsvFormatError,
    parse_time_zone,
    read_canonical_csv,
    write_canonical_csv,
)
from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.parameters import ModelParameters, ParameterError
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec
from steamtwin.units import convert

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
    try:
        zone = None if time_zone is None else parse_time_zone(time_zone)
    except ValueError as error:
        _fail(f"--time-zone {error}")
    console = Console(stderr=True)
    try:
        spec = load_spec(turbine)
        parameters = ModelParameters.from_json(params) if params else ModelParameters()
    except (SpecError, ParameterError) as error:
        _fail(str(error))
    try:
        frame = read_canonical_csv(inputs, required=INPUT_SIGNALS, time_zone=zone)
    except CsvFormatError as error:
        _fail(str(error))
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
