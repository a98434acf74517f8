"""``steamtwin plant [serve]``: the virtual plant of the reference unit, as historian files or
live over OPC UA."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.cli.paths import prepare_output_file, prepare_output_folder
from steamtwin.dcs.plant import SCENARIOS, PlantRun, plant_tag_map, run_plant, write_plant
from steamtwin.dcs.sensor_faults import SensorFault, parse_sensor_fault
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.plant_server import CLOCKS, PlantServer, PlantServerSettings, plant_node_ids

plant_app = typer.Typer(invoke_without_command=True)


def _check(scenario: str | None, hours: float | None) -> list[str]:
    problems = []
    if scenario is None:
        problems.append(f"--scenario is required (one of: {', '.join(SCENARIOS)})")
    elif scenario not in SCENARIOS:
        problems.append(f"unknown scenario {scenario!r}; choose one of: {', '.join(SCENARIOS)}")
    if hours is not None and not hours > 0.0:
        problems.append(f"--hours must be positive (got {hours!r})")
    return problems


def _fail(problems: list[str]) -> None:
    for problem in problems:
        typer.echo(f"error: {problem}", err=True)
    raise typer.Exit(code=2)


_FAULT_HELP = ("A sensor fault to inject after the instruments, SIGNAL:KIND[:SIZE]@STARTh[-ENDh] "
               "(kinds drift [SI per hour], bias_step [SI], stuck; hours from the first "
               "sample), e.g. hp_exhaust_temperature:drift:2@6h; repeatable.")


def _faults(texts: list[str] | None) -> list[SensorFault]:
    try:
        return [parse_sensor_fault(text) for text in texts or []]
    except ValueError as error:
        _fail([f"--sensor-fault: {error}"])
        raise  # unreachable


def _run(scenario: str, hours: float | None, seed: int, console: Console,
         faults: list[SensorFault]) -> PlantRun:
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(f"plant {scenario}", total=1.0)

        def progress(fraction: float, message: str) -> None:
            bar.update(task, completed=fraction, description=f"plant {scenario}: {message}")

        try:
            return run_plant(scenario, hours=hours, seed=seed, progress=progress,
                             sensor_faults=faults)
        except ValueError as error:
            _fail([str(error)])
            raise  # unreachable: _fail exits


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
    sensor_fault: list[str] | None = typer.Option(None, help=_FAULT_HELP),
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
    problems = _check(scenario, hours)
    if out is None:
        problems.append("--out is required (the folder for the historian files)")
    if layout not in ("wide", "long"):
        problems.append(f"--layout must be 'wide' or 'long' (got {layout!r})")
    if file_format not in ("parquet", "csv"):
        problems.append(f"--file-format must be 'parquet' or 'csv' (got {file_format!r})")
    if problems:
        _fail(problems)
    assert scenario is not None and out is not None
    faults = _faults(sensor_fault)
    prepare_output_folder(out, "--out")
    console = Console(stderr=True)
    run = _run(scenario, hours, seed, console, faults)
    paths = write_plant(run, out, layout=layout, file_format=file_format)
    typer.echo(f"wrote {len(run.measured)} samples of {len(run.measured.columns)} tags:")
    for name, path in paths.items():
        typer.echo(f"  {name}: {path}")


def _speed(text: str) -> float | None:
    if text.strip().lower() == "max":
        return None
    try:
        return float(text)
    except ValueError:
        _fail([f"--speed {text!r}: expected a factor of real time (e.g. 10) or 'max'"])
        raise  # unreachable


@plant_app.command("serve")
def serve(
    scenario: str = typer.Option(..., help=f"Load programme: {', '.join(SCENARIOS)}."),
    hours: float | None = typer.Option(None, help="Length of the long hold (h)."),
    seed: int = typer.Option(0, help="Seed of the instruments' random generator."),
    speed: str = typer.Option("1", help="Samples go out at this multiple of real time, or "
                              "'max' for as fast as possible."),
    host: str = typer.Option("127.0.0.1", help="Address to listen on (loopback by default)."),
    port: int = typer.Option(4840, min=0, max=65535, help="OPC UA port."),
    clock: str = typer.Option("data", help="Timestamps: 'data' (the day's own, a replay) or "
                              "'now' (shifted to start now; --speed 1 only)."),
    history_samples: int = typer.Option(3600, min=1, help="Values per tag HistoryRead "
                                        "returns (the recent past)."),
    tags_out: Path | None = typer.Option(None, help="Write the tag map with each tag's OPC "
                                         "UA node id here (for 'steamtwin serve')."),
    exit_at_end: bool = typer.Option(False, "--exit-at-end", help="Stop once the last "
                                     "sample is out (default: keep serving for HistoryRead "
                                     "until Ctrl-C or SIGTERM)."),
    sensor_fault: list[str] | None = typer.Option(None, help=_FAULT_HELP),
) -> None:
    """Publish the virtual plant's historian tags live over OPC UA.

    Runs the scenario first (as 'steamtwin plant' does), then serves each KKS tag as an OPC
    UA variable (namespace urn:steamtwin:virtual-plant, node id s=<tag>) in its wire unit
    (MPa, degC, t/h, MW) with the sample's source timestamp and status (Bad where the
    historian has a dropout), and HistoryRead of the recent past. No security: a test plant,
    on loopback unless --host says otherwise. Ctrl-C or SIGTERM stops it cleanly.

    Example: steamtwin plant serve --scenario day --speed 10 --port 4840 --tags-out live-tags.toml
    """
    problems = _check(scenario, hours)
    if clock not in CLOCKS:
        problems.append(f"--clock must be one of {', '.join(CLOCKS)} (got {clock!r})")
    rate = _speed(speed)
    if problems:
        _fail(problems)
    try:
        settings = PlantServerSettings(host=host, port=port, speed=rate, clock=clock,
                                       history_samples=history_samples)
    except ValueError as error:
        _fail([str(error)])
        raise
    faults = _faults(sensor_fault)
    if tags_out is not None:
        prepare_output_file(tags_out, "--tags-out")
    console = Console(stderr=True)
    run = _run(scenario, hours, seed, console, faults)
    tag_map = plant_tag_map()
    if tags_out is not None:
        write_tag_map(plant_node_ids(tag_map), tags_out)
        typer.echo(f"wrote {tags_out} (tag map with OPC UA node ids)")
    asyncio.run(_serve(PlantServer(run.measured, tag_map, settings), exit_at_end, console))


async def _serve(server: PlantServer, exit_at_end: bool, console: Console) -> None:
    """Publish until done (and, without exit_at_end, until SIGINT/SIGTERM)."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(signum, stop.set)
    async with server:
        typer.echo(f"serving {len(server.node_ids)} tags at {server.endpoint}")
        publishing = asyncio.create_task(server.publish())
        waiting = asyncio.create_task(stop.wait())
        await asyncio.wait({publishing, waiting}, return_when=asyncio.FIRST_COMPLETED)
        if publishing.done() and not exit_at_end and not stop.is_set():
            typer.echo(f"all {server.published} samples published; serving history until "
                       "stopped")
            await waiting
        publishing.cancel()
        waiting.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await publishing
    typer.echo(f"stopped after {server.published} samples")
