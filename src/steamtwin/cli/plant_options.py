"""What ``steamtwin plant`` and ``plant serve`` share: checking the scenario and --hours,
reading --sensor-fault, and running the virtual plant under a progress bar."""

from __future__ import annotations

from typing import NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.dcs.plant import SCENARIOS, PlantRun, run_plant
from steamtwin.dcs.sensor_faults import SensorFault, parse_sensor_fault

__all__ = ["FAULT_HELP", "check_scenario", "fail", "parse_faults", "run_with_bar"]

FAULT_HELP = ("A sensor fault to inject after the instruments, SIGNAL:KIND[:SIZE]@STARTh[-ENDh] "
              "(kinds drift [SI per hour], bias_step [SI], stuck; hours from the first "
              "sample), e.g. hp_exhaust_temperature:drift:2@6h; repeatable.")


def check_scenario(scenario: str | None, hours: float | None) -> list[str]:
    """What is wrong with --scenario and --hours (empty: nothing)."""
    problems = []
    if scenario is None:
        problems.append(f"--scenario is required (one of: {', '.join(SCENARIOS)})")
    elif scenario not in SCENARIOS:
        problems.append(f"unknown scenario {scenario!r}; choose one of: {', '.join(SCENARIOS)}")
    if hours is not None and not hours > 0.0:
        problems.append(f"--hours must be positive (got {hours!r})")
    return problems


def fail(problems: list[str]) -> NoReturn:
    """Print each problem as ``error: ...`` on stderr and exit 2."""
    for problem in problems:
        typer.echo(f"error: {problem}", err=True)
    raise typer.Exit(code=2)


def parse_faults(texts: list[str] | None) -> list[SensorFault]:
    """The faults of --sensor-fault (exit 2 naming the bad one)."""
    try:
        return [parse_sensor_fault(text) for text in texts or []]
    except ValueError as error:
        fail([f"--sensor-fault: {error}"])


def run_with_bar(scenario: str, hours: float | None, seed: int, console: Console,
                 faults: list[SensorFault]) -> PlantRun:
    """``dcs.plant.run_plant`` under a transient progress bar on ``console``."""
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(f"plant {scenario}", total=1.0)

        def progress(fraction: float, message: str) -> None:
            bar.update(task, completed=fraction, description=f"plant {scenario}: {message}")

        try:
            return run_plant(scenario, hours=hours, random_state=seed, progress=progress,
                             sensor_faults=faults)
        except ValueError as error:
            fail([str(error)])
