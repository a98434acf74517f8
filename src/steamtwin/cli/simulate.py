"""``steamtwin simulate``: run the full-order model over a CSV of boundary conditions."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.dcs.canonical_csv import CsvFormatError, read_canonical_csv, write_canonical_csv
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.parameters import ModelParameters, ParameterError
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec


def simulate(
    inputs: Path = typer.Option(..., help="CSV: 'time' + canonical inputs in MPa, °C, t/h."),
    out: Path = typer.Option(..., help="Output CSV of predicted signals (MPa, °C, MW)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    params: Path | None = typer.Option(None, help="Parameter JSON (default: empirical)."),
) -> None:
    """Simulate the HP section over a time series of boundary conditions.

    The inputs CSV has a 'time' column (ISO 8601 or seconds) and the columns
    main_steam_pressure [MPa], main_steam_temperature [°C], main_steam_flow [t/h],
    hp_exhaust_pressure [MPa].

    Example: steamtwin simulate --turbine reference --inputs inputs.csv --out outputs.csv
    """
    console = Console(stderr=True)
    try:
        spec = load_spec(turbine)
        parameters = ModelParameters.from_json(params) if params else ModelParameters()
        frame = read_canonical_csv(inputs, required=INPUT_SIGNALS)
        model = FullOrderModel(spec)
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        with console.status(f"simulating {len(frame)} samples"):
            outputs = model.simulate(frame, parameters)
    except (SpecError, ParameterError, CsvFormatError, InputError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    write_canonical_csv(outputs, out)
    typer.echo(f"wrote {len(outputs)} samples of {', '.join(outputs.columns)} to {out}")
