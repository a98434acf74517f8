"""What the ``steamtwin turbine`` commands share: reading the TURBINE argument, a thermal kit
and --loads (bad input: a usage error naming the option), and exiting with a message."""

from __future__ import annotations

from pathlib import Path
from typing import NoReturn

import numpy as np
import pandas as pd
import typer

from steamtwin.model.design_check import DesignError, checked_loads
from steamtwin.model.design_fit import outside_band
from steamtwin.spec import HeatBalance, HeatBalanceError, SpecError, TurbineSpec, load_heat_balance
from steamtwin.spec.fingerprint import load_spec_and_text

__all__ = ["KIT_HELP", "TURBINE_ARGUMENT", "fail", "load_kit", "load_turbine", "parse_loads",
           "say_outside"]

TURBINE_ARGUMENT = typer.Argument(..., help="'reference' or a path to a turbine spec TOML.")
KIT_HELP = "Thermal kit (TOML, docs/heat-balance.md, or 'example-600mw')"


def fail(message: str, code: int) -> NoReturn:
    """Print ``error: message`` on stderr and exit with ``code``."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=code)


def say_outside(residuals: pd.DataFrame) -> None:
    """Exit 1 naming the points outside the acceptance band (``model.design_fit``)."""
    outside = outside_band(residuals)
    if outside:
        typer.echo(f"outside ±0.5 % / ±1.0 K: {'; '.join(outside)}", err=True)
        raise typer.Exit(code=1)


def load_turbine(turbine: str) -> tuple[TurbineSpec, str]:
    """The spec named by the TURBINE argument and its TOML text."""
    try:
        return load_spec_and_text(turbine)
    except SpecError as error:
        raise typer.BadParameter(str(error), param_hint="TURBINE") from None


def load_kit(path: Path) -> HeatBalance:
    """The thermal kit of --heat-balance."""
    try:
        return load_heat_balance(path)
    except HeatBalanceError as error:
        raise typer.BadParameter(str(error), param_hint="--heat-balance") from None


def parse_loads(spec: TurbineSpec, text: str) -> np.ndarray:
    """The load fractions of --loads (comma-separated), checked against the spec's line."""
    try:
        return checked_loads(spec, [float(item) for item in text.split(",")])
    except DesignError as error:
        raise typer.BadParameter(str(error), param_hint="--loads") from None
    except ValueError:
        raise typer.BadParameter(f"{text!r}: expected comma-separated load fractions, e.g. "
                                 "1,0.75,0.5", param_hint="--loads") from None
