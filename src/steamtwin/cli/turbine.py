"""``steamtwin turbine show``: the design heat balance and stage table of a turbine spec."""

from __future__ import annotations

import math

import typer
from rich.console import Console
from rich.table import Table

from steamtwin.spec import SpecError, TurbineSpec, load_spec

turbine_app = typer.Typer(help="Inspect turbine specs.", no_args_is_help=True)


@turbine_app.command("show")
def show(
    turbine: str = typer.Argument(..., help="'reference' or a path to a turbine spec TOML."),
) -> None:
    """Print the design heat balance and the stage table.

    Example: steamtwin turbine show reference
    """
    try:
        spec = load_spec(turbine)
    except SpecError as error:
        raise typer.BadParameter(str(error), param_hint="TURBINE") from None
    console = Console()
    console.print(f"[bold]{spec.name}[/bold]: {spec.description}")
    console.print(_heat_balance_table(spec))
    console.print(_valve_table(spec))
    console.print(_stage_table(spec))


def _heat_balance_table(spec: TurbineSpec) -> Table:
    design = spec.design
    table = Table(title="Design heat balance (rated load)")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    rows = [
        ("main-steam pressure", f"{design.main_steam_pressure / 1e6:.2f} MPa"),
        ("main-steam temperature", f"{design.main_steam_temperature - 273.15:.1f} °C"),
        ("main-steam flow", f"{design.main_steam_flow * 3.6:.0f} t/h"),
        ("control-stage pressure", f"{design.control_stage_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust pressure", f"{design.hp_exhaust_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust temperature", f"{design.hp_exhaust_temperature - 273.15:.1f} °C"),
        ("HP power", f"{design.hp_power / 1e6:.1f} MW"),
        ("generator power", f"{design.generator_power / 1e6:.0f} MW"),
        ("speed", f"{design.rotational_speed * 60 / (2 * math.pi):.0f} rpm"),
    ]
    for extraction in spec.extractions:
        rows.append((f"bleed '{extraction.name}' after stage {extraction.after_stage}",
                     f"{extraction.design_flow * 3.6:.0f} t/h at "
                     f"{extraction.design_pressure / 1e6:.2f} MPa"))
    for name, value in rows:
        table.add_row(name, value)
    return table


def _valve_table(spec: TurbineSpec) -> Table:
    table = Table(title="Governing valves (nozzle governing)")
    for column in ("valve", "opening order", "admission arc", "open at design"):
        table.add_column(column, justify="right")
    for valve in spec.control_stage.valves:
        table.add_row(valve.name, str(valve.opening_order), f"{valve.admission_arc:.2f}",
                      "yes" if valve.open_at_design else "no")
    return table


def _stage_table(spec: TurbineSpec) -> Table:
    table = Table(title="Stages")
    for column in ("stage", "d (m)", "l (mm)", "blades", "reaction", "α1 (°)",
                   "η peak", "flow capacity K (cm²)"):
        table.add_column(column, justify="right")
    cs = spec.control_stage
    rows = [("control", cs.blading, "nozzle groups")]
    rows += [(str(i), stage.blading, f"{stage.flow_capacity * 1e4:.1f}")
             for i, stage in enumerate(spec.stages, start=1)]
    for name, blading, capacity in rows:
        table.add_row(name, f"{blading.mean_diameter:.4f}", f"{blading.blade_height * 1e3:.1f}",
                      str(blading.blade_count), f"{blading.reaction:.2f}",
                      f"{math.degrees(blading.nozzle_exit_angle):.1f}",
                      f"{blading.peak_blade_efficiency:.3f}", capacity)
    return table
