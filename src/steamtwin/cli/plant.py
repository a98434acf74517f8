"""``steamtwin plant``: historian data of the virtual plant of the reference unit."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.cli.paths import prepare_output_folder
from steamtwin.dcs.plant import SCENARIOS, run_plant, write_plant


def plant(
    scenario: str = typer.Option(
        ..., help=f"Load programme: {', '.join(SCENARIOS)}."),
    out: Path = typer.Option(..., help="Folder for historian.*, tags.toml and truth/."),
    hours: float | None = typer.Option(None, help="Length of the long hold (h)."),
    seed: int = typer.Option(0, help="Seed of the instruments' random generator."),
    layout: str = typer.Option("wide", help="Historian layout: 'wide' or 'long'."),
    file_format: str = typer.Option("parquet", help="'parquet' or 'csv'."),
) -> None:
    """Generate DCS historian data of the virtual 600 MW plant (hidden truth in OUT/truth/).

    The plant differs from the twin in its parameters and structure (its own graded metal and
    bored rotors, gland and tip leakage, overlapping valves, boiler temperature schedule and
    dynamics, a deeper casing thermocouple, real instruments; docs/plant.md); the twin must not
    read truth/.

    Example: steamtwin plant --scenario deep-peak-50 --hours 2 --seed 1 --out plant-data
    """
    console = Console(stderr=True)
    problems = []
    if scenario not in SCENARIOS:
        problems.append(f"unknown scenario {scenario!r}; choose one of: {', '.join(SCENARIOS)}")
    if layout not in ("wide", "long"):
        problems.append(f"--layout must be 'wide' or 'long' (got {layout!r})")
    if file_format not in ("parquet", "csv"):
        problems.append(f"--file-format must be 'parquet' or 'csv' (got {file_format!r})")
    if hours is not None and not hours > 0.0:
        problems.append(f"--hours must be positive (got {hours!r})")
    if problems:
        for problem in problems:
            typer.echo(f"error: {problem}", err=True)
        raise typer.Exit(code=2)
    prepare_output_folder(out, "--out")
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(f"plant {scenario}", total=1.0)

        def progress(fraction: float, message: str) -> None:
            bar.update(task, completed=fraction, description=f"plant {scenario}: {message}")

        try:
            run = run_plant(scenario, hours=hours, seed=seed, progress=progress)
        except ValueError as error:
            typer.echo(f"error: {error}", err=True)
            raise typer.Exit(code=2) from None
        bar.update(task, description=f"plant {scenario}: writing")
        paths = write_plant(run, out, layout=layout, file_format=file_format)
    typer.echo(f"wrote {len(run.measured)} samples of {len(run.measured.columns)} tags:")
    for name, path in paths.items():
        typer.echo(f"  {name}: {path}")
