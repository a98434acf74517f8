"""``steamtwin simulate``: run the full-order model over a CSV of boundary conditions
(:func:`steamtwin.model.simulate_file.simulate_csv`).

Errors name the inputs file, the column and the row as a data row (1-based, the header not
counted) with its line in the file (data row + 1), and values in the file's units.
"""

from __future__ import annotations

from pathlib import Path
from typing import NoReturn

import typer
from rich.console import Console

from steamtwin.cli.paths import prepare_output_file
from steamtwin.dcs.canonical_csv import CsvFormatError, parse_time_zone, write_canonical_csv
from steamtwin.model.parameters import ParameterError
from steamtwin.model.simulate_file import simulate_csv
from steamtwin.spec import SpecError


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
    try:
        with Console(stderr=True).status("reading the inputs") as status:
            outputs = simulate_csv(inputs, turbine=turbine, params_file=params, time_zone=zone,
                                   progress=lambda _, message: status.update(message))
    except (SpecError, ParameterError, CsvFormatError) as error:
        _fail(str(error))
    write_canonical_csv(outputs, out)
    typer.echo(f"wrote {len(outputs)} samples of {', '.join(outputs.columns)} to {out}")


def _fail(message: str) -> NoReturn:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)
