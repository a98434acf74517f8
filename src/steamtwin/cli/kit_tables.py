"""The tables ``steamtwin turbine check|fit`` print for a thermal kit: the kit's figures beside
the model's at every point (MPa, °C, with the difference in % or K) and the fitted part-load
laws with the points that identify them."""

from __future__ import annotations

import math

import pandas as pd
from rich.markup import escape
from rich.table import Table

from steamtwin.model.design_fit import ACCEPTANCE_BAND, RESIDUALS, DesignFit, given_value
from steamtwin.spec import HeatBalance

__all__ = ["fit_table", "kit_table"]

_KELVIN = 273.15


def kit_table(kit: HeatBalance, residuals: pd.DataFrame, title: str) -> Table:
    """Kit vs model per point: p1 (MPa), T1 and T ex (°C) with the difference; '!' outside the
    acceptance band."""
    table = Table(title=title)
    table.add_column("point")
    table.add_column("load (MW)", justify="right")
    for header in ("p1 (MPa)", "T1 (°C)", "T ex (°C)"):
        table.add_column(f"{header} kit → model", justify="right")
    for point, (label, row) in zip(kit.points, residuals.iterrows(), strict=True):
        cells = [str(label), f"{point.load_w / 1e6:.1f}"]
        for column in RESIDUALS:
            given, difference = given_value(point, column), float(row[column])
            if given is None or not math.isfinite(difference):
                cells.append("–")
                continue
            flag = " !" if abs(difference) > ACCEPTANCE_BAND[column] else ""
            if column == "control_stage_pressure_pct":
                given /= 1e6
                model = given * (1.0 + difference / 100.0)
                cells.append(f"{given:.3f} → {model:.3f} ({difference:+.2f} %){flag}")
            else:
                given -= _KELVIN
                cells.append(f"{given:.1f} → {given + difference:.1f} ({difference:+.2f} K)"
                             f"{flag}")
        table.add_row(*cells)
    return table


def fit_table(result: DesignFit) -> Table:
    """Fitted laws, their start values and the points that pin each one down (share ≥ 20 %)."""
    table = Table(title=escape("Fitted [part_load] laws (docs/spec.md)"))
    for header in ("law", "spec", "fitted", "identified mostly by"):
        table.add_column(header, justify="left" if header in ("law", "identified mostly by")
                         else "right")
    for name in result.parameters:
        shares = result.identified_share[name]
        strong = ", ".join(f"{label} {share:.0%}" for label, share
                           in shares.sort_values(ascending=False).items() if share >= 0.2)
        bound = result.bound_reached(name)
        if bound is not None:
            strong = f"at its {bound} bound: the points push it further ({strong or '–'})"
        elif name in result.unidentified:
            strong = "not identified by these points (kept near its start)"
        table.add_row(name, f"{getattr(result.initial_part_load, name):.4g}",
                      f"{getattr(result.part_load, name):.4g}", strong or "–")
    return table
