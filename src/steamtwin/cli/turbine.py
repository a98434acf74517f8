"""``steamtwin turbine show|check|derive|fit|update``: a turbine spec, the model's own design
point and line, a spec derived from a heat balance, its part-load laws fitted to it and the
throat areas of scanned rows taken into it.

``show`` and ``check`` run the full-order model on the spec (``model.design_check``); ``derive``
writes a spec built from an OEM thermal kit (``spec.derive``); ``fit`` adjusts the spec's
``[part_load]`` laws to the kit (``model.design_fit``); ``update`` scales the flow capacities of
the stages whose rotor rows were reconstructed (``geometry.into_spec``); those three are in
:mod:`steamtwin.cli.turbine_spec`, the tables in :mod:`steamtwin.cli.turbine_tables` and
:mod:`steamtwin.cli.kit_tables`.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.cli import turbine_tables
from steamtwin.cli.kit_tables import kit_table
from steamtwin.cli.paths import prepare_output_file
from steamtwin.cli.turbine_options import (
    KIT_HELP,
    TURBINE_ARGUMENT,
    fail,
    load_kit,
    load_turbine,
    parse_loads,
    say_outside,
)
from steamtwin.cli.turbine_spec import derive, fit, update
from steamtwin.model.design_check import (
    DEFAULT_LOADS,
    DesignError,
    check_design,
    design_point,
    line_in_engineering_units,
)
from steamtwin.model.design_fit import DesignFitError

turbine_app = typer.Typer(help="Inspect and check turbine specs.", no_args_is_help=True)

_PREPARING = "running the model's design step (the first run compiles it, ~20 s)"


@turbine_app.command("show")
def show(turbine: str = TURBINE_ARGUMENT) -> None:
    """Print the design heat balance beside the model's own design point, the valves, the
    stage table and the drawn HP rotor section (when the spec has ``[rotor]``).
    Exit code 1, with the reason, if the model cannot run the spec.

    Example: steamtwin turbine show reference
    """
    spec, _ = load_turbine(turbine)
    console = Console()
    console.print(f"[bold]{spec.name}[/bold]: {spec.description}")
    reason = None
    try:
        with Console(stderr=True).status(_PREPARING):
            model_point = design_point(spec)
    except DesignError as error:
        model_point, reason = None, str(error)
    console.print(turbine_tables.heat_balance_table(spec, model_point))
    console.print(turbine_tables.valve_table(spec))
    console.print(turbine_tables.stage_table(spec))
    rotor = turbine_tables.rotor_table(spec)
    if rotor is not None:
        console.print(rotor)
    if reason is not None:
        fail(f"the model cannot run this spec: {reason}", 1)


@turbine_app.command("check")
def check(
    turbine: str = TURBINE_ARGUMENT,
    loads: str = typer.Option(
        ",".join(f"{load:g}" for load in DEFAULT_LOADS), "--loads",
        help="Comma-separated fractions of rated load along the sliding-pressure line "
             "(0.2 up to the line's end)."),
    csv: Path | None = typer.Option(
        None, "--csv", help="Also write the design line to this CSV (engineering units, the "
                            "unit in each column name)."),
    heat_balance: Path | None = typer.Option(
        None, "--heat-balance", help=f"{KIT_HELP}: also run the model at every point's inputs "
        "and put it beside the kit's figures."),
) -> None:
    """Check that the model can pass the spec's rated flow, then print its design point beside
    the heat balance and its steady off-design line (MPa, °C, t/h, MW, %).

    With --heat-balance the model runs at each point's main-steam pressure, temperature and flow
    and HP-exhaust pressure, beside the kit's control-stage pressure and temperature and
    HP-exhaust temperature; points outside ±0.5 % / ±1.0 K are marked.

    Exit code 1 with the reason when the spec cannot pass its rated flow (e.g. every governing
    valve open at design) or the model cannot run one of the loads or points.

    Example: steamtwin turbine check unit.toml --heat-balance kit.toml --csv line.csv
    """
    if csv is not None:
        prepare_output_file(csv, "--csv")
    spec, _ = load_turbine(turbine)
    load_values = parse_loads(spec, loads)
    kit = load_kit(heat_balance) if heat_balance is not None else None
    try:
        with Console(stderr=True).status(_PREPARING):
            result = check_design(spec, load_values, kit)
    except (DesignError, DesignFitError) as error:
        fail(str(error), 1)
    if result.problems:
        typer.echo(f"{spec.name}: cannot pass its rated flow", err=True)
        fail("\nerror: ".join(result.problems), 1)
    assert result.point is not None and result.line is not None
    console = Console()
    console.print(f"{spec.name}: consistent: the model passes the rated flow "
                  f"({spec.design.main_steam_flow * 3.6:.0f} t/h) with a governing valve "
                  "left for overload")
    console.print(turbine_tables.design_point_table(result.point))
    console.print(turbine_tables.line_table(spec, result.line))
    if csv is not None:
        line_in_engineering_units(spec, result.line).to_csv(csv, float_format="%.6g")
        console.print(f"wrote the design line ({len(result.line)} loads) to {csv}")
    if kit is not None and result.residuals is not None:
        console.print(kit_table(kit, result.residuals,
                                           f"The model at the points of {kit.source}"))
        say_outside(result.residuals)


turbine_app.command("fit")(fit)
turbine_app.command("derive")(derive)
turbine_app.command("update")(update)
