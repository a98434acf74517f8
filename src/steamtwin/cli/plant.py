"""``steamtwin plant [serve]``: the virtual plant of the reference unit, as historian files or
live over OPC UA (``serve``: :mod:`steamtwin.cli.plant_serve`)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.cli.paths import prepare_output_folder
from steamtwin.cli.plant_options import (
    FAULT_HELP,
    check_scenario,
    fail,
    parse_faults,
    run_with_bar,
)
from steamtwin.cli.plant_serve import serve
from steamtwin.dcs.plant import SCENARIOS, write_plant

plant_app = typer.Typer(invoke_without_command=True)


@plant_app.callback()
def plant(
    ctx: typer.Context,
    scenario: str | None = typer.Option(
        None, help=f"Load programme: {', '.join(SCENARIOS)}."),
    out: Path | None = typer.Option(None, help="Folder for historian.*, tags.toml and truth/."),
    hours: float | None = typer.Option(None, help="Length of the long hold (h)."),
    seed: int = typer.Option(0, help="Seed of the instruments' random generator."),
    layout: str = typer.Option("wide", help="Historian layout: 'wide' or 'long'."),
    file_format: str = typer.Option("parquet", help="'parquet' or 'csv'."),
    sensor_fault: list[str] | None = typer.Option(None, help=FAULT_HELP),
) -> None:
    """Generate DCS historian data of the virtual 600 MW plant (hidden truth in OUT/truth/).

    The plant differs from the twin in its parameters and structure (its own graded metal and
    bored rotors, gland and tip leakage, overlapping valves, boiler temperature schedule and
    dynamics, a deeper casing thermocouple, real instruments; docs/plant.md); the twin must not
    read truth/. 'steamtwin plant serve' publishes the same data live over OPC UA.

    Example: steamtwin plant --scenario deep-peak-50 --hours 2 --seed 1 --out plant-data
    """
    if ctx.invoked_subcommand is not None:
        return
    problems = check_scenario(scenario, hours)
    if out is None:
        problems.append("--out is required (the folder for the historian files)")
    if layout not in ("wide", "long"):
        problems.append(f"--layout must be 'wide' or 'long' (got {layout!r})")
    if file_format not in ("parquet", "csv"):
        problems.append(f"--file-format must be 'parquet' or 'csv' (got {file_format!r})")
    if problems:
        fail(problems)
    assert scenario is not None and out is not None
    faults = parse_faults(sensor_fault)
    prepare_output_folder(out, "--out")
    console = Console(stderr=True)
    run = run_with_bar(scenario, hours, seed, console, faults)
    paths = write_plant(run, out, layout=layout, file_format=file_format)
    typer.echo(f"wrote {len(run.measured)} samples of {len(run.measured.columns)} tags:")
    for name, path in paths.items():
        typer.echo(f"  {name}: {path}")


plant_app.command("serve")(serve)
