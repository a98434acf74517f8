"""``steamtwin turbine fit|derive|update``: the commands that write a turbine spec: its
part-load laws fitted to a thermal kit (``model.design_fit``), a spec derived from a kit
(``spec.derive``) and the flow capacities of scanned rows taken into it
(``geometry.into_spec``). Registered on ``turbine_app`` by :mod:`steamtwin.cli.turbine`."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.cli.kit_tables import fit_table, kit_table
from steamtwin.cli.paths import prepare_output_file
from steamtwin.cli.turbine_options import KIT_HELP, fail, load_kit, load_turbine, say_outside
from steamtwin.model.design_fit import DesignFitError, fit_design
from steamtwin.spec import DeriveError, HeatBalanceError, derive_spec, load_heat_balance
from steamtwin.spec.loader import parse_spec

__all__ = ["derive", "fit", "update"]


def fit(
    turbine: str = typer.Argument(..., help="'reference' or a path to a turbine spec TOML "
                                  "(e.g. from 'steamtwin turbine derive')."),
    heat_balance: Path = typer.Option(..., "--heat-balance", help=f"{KIT_HELP} whose points the "
                                      "model must meet."),
    out: Path = typer.Option(..., "--out", help="Spec TOML to write: the input with its "
                             "[part_load] table replaced by the fitted laws."),
    parameters: str | None = typer.Option(
        None, "--parameters", help="Comma-separated [part_load] fields to fit (default: all; "
        "see docs/spec.md)."),
) -> None:
    """Fit the spec's part-load laws so the model meets every point of a thermal kit.

    Bounded least squares on the model − kit residuals (control-stage pressure %, control-stage
    and HP-exhaust temperature K) weighted by the acceptance band ±0.5 % / ±1.0 K; prints the
    residuals before and after, the fitted laws and which points pin each one down, and writes
    the fitted spec. Exit code 1 when a residual stays outside the band (the spec is written).

    Example: steamtwin turbine fit unit.toml --heat-balance kit.toml --out fitted.toml
    """
    prepare_output_file(out, "--out")
    spec, text = load_turbine(turbine)
    kit = load_kit(heat_balance)
    names = {} if parameters is None else {"parameters": tuple(
        name.strip() for name in parameters.split(",") if name.strip())}
    try:
        with Console(stderr=True).status(f"fitting the part-load laws to {len(kit.points)} "
                                         "points"):
            result = fit_design(spec, kit, **names)
    except DesignFitError as error:
        fail(str(error), 2)
    out.write_text(result.spec_toml(text), encoding="utf-8")
    console = Console()
    console.print(kit_table(kit, result.initial_residuals, "Before the fit"))
    console.print(kit_table(kit, result.residuals, "After the fit"))
    console.print(fit_table(result))
    typer.echo(f"{result.evaluations} model evaluations in {result.wall_time_s:.1f} s; "
               f"wrote {out}")
    say_outside(result.residuals)


def derive(
    heat_balance: Path = typer.Argument(..., help="Heat-balance TOML (the OEM thermal kit, "
                                        "see docs/heat-balance.md), or 'example-600mw' (the "
                                        "shipped kit of an independent unit)."),
    out: Path = typer.Option(..., "--out", help="Spec TOML to write."),
    name: str | None = typer.Option(None, "--name", help="Name of the unit in the spec "
                                    "(default: the heat balance's name)."),
) -> None:
    """Build a complete turbine spec from a heat balance, every derived figure commented with
    how it was obtained (docs/heat-balance.md, 'Deriving a spec from a heat balance').

    Exit code 2, with the point and field named, if no valid spec can be derived.

    Example: steamtwin turbine derive heat-balance.toml --out unit.toml --name "Unit 3"
    """
    prepare_output_file(out, "--out")
    try:
        derived = derive_spec(load_heat_balance(heat_balance), name=name)
    except (HeatBalanceError, DeriveError) as error:
        fail(str(error), 2)
    out.write_text(derived.toml, encoding="utf-8")
    for note in derived.notes:
        typer.echo(f"note: {note}")
    spec = parse_spec(derived.toml, str(out))
    typer.echo(f"wrote {out}: {spec.name!r}, {len(spec.stages)} pressure stages, "
               f"{len(spec.control_stage.valves)} governing valves, design "
               f"{spec.design.generator_power / 1e6:.0f} MW at "
               f"{spec.design.main_steam_flow * 3.6:.0f} t/h; check it with "
               f"'steamtwin turbine check {out}'")


def update(
    turbine: str = typer.Argument(..., help="Spec TOML to update (or a built-in name)."),
    scans: Path = typer.Option(..., "--scans", help="Folder of reconstruction reports "
                               "('geometry reconstruct … --report BASE' writes BASE.json)."),
    out: Path = typer.Option(..., "--out", help="Updated spec TOML to write."),
) -> None:
    """Take the throat areas of reconstructed rows into the spec: the measured / design
    throat-area ratio of rotor row hpK scales stages[K−1].flow_capacity, each changed line
    commented with the row, the report file and the ratio (docs/geometry.md).

    hp1 (the control-stage rotor) sets no flow in the model and IP rows are not in it: they
    are listed, not applied. Exit code 2, naming the file and row, for a ratio outside
    0.8–1.2, a report of another design blade or without the throat area.

    Example: steamtwin turbine update unit.toml --scans scans/ --out updated.toml
    """
    from steamtwin.geometry.into_spec import ScanUpdateError, update_spec_from_scans

    prepare_output_file(out, "--out")
    spec, text = load_turbine(turbine)
    try:
        result = update_spec_from_scans(text, spec, scans, source=turbine)
    except ScanUpdateError as error:
        fail(str(error), 2)
    out.write_text(result.toml, encoding="utf-8")
    for row, stage, path, ratio, old, new in result.applied:
        typer.echo(f"{row}: stages[{stage}].flow_capacity {old:.6g} → {new:.6g} m² (throat-area "
                   f"ratio {ratio:.5f}, {path})")
    for row, reason in result.not_applied.items():
        typer.echo(f"{row}: {reason}")
    if result.missing:
        typer.echo(f"no report for: {', '.join(result.missing)} (flow capacities unchanged)")
    typer.echo(f"wrote {out}: {len(result.applied)} flow capacities from {scans}")
