"""``steamtwin plant serve``: the virtual plant's historian tags published live over OPC UA
(``live.plant_server``); Ctrl-C or SIGTERM stops it (``live.runner.stop_on_signals``)."""

from __future__ import annotations

import asyncio
import contextlib
from pathlib import Path

import typer
from rich.console import Console

from steamtwin.cli.paths import prepare_output_file
from steamtwin.cli.plant_options import (
    FAULT_HELP,
    check_scenario,
    fail,
    parse_faults,
    run_with_bar,
)
from steamtwin.dcs.plant import SCENARIOS, plant_tag_map
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.plant_server import CLOCKS, PlantServer, PlantServerSettings, plant_node_ids
from steamtwin.live.runner import stop_on_signals

__all__ = ["serve"]


def _speed(text: str) -> float | None:
    if text.strip().lower() == "max":
        return None
    try:
        return float(text)
    except ValueError:
        fail([f"--speed {text!r}: expected a factor of real time (e.g. 10) or 'max'"])


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
    sensor_fault: list[str] | None = typer.Option(None, help=FAULT_HELP),
) -> None:
    """Publish the virtual plant's historian tags live over OPC UA.

    Runs the scenario first (as 'steamtwin plant' does), then serves each KKS tag as an OPC
    UA variable (namespace urn:steamtwin:virtual-plant, node id s=<tag>) in its wire unit
    (MPa, degC, t/h, MW) with the sample's source timestamp and status (Bad where the
    historian has a dropout), and HistoryRead of the recent past. No security: a test plant,
    on loopback unless --host says otherwise. Ctrl-C or SIGTERM stops it cleanly.

    Example: steamtwin plant serve --scenario day --speed 10 --port 4840 --tags-out live-tags.toml
    """
    problems = check_scenario(scenario, hours)
    if clock not in CLOCKS:
        problems.append(f"--clock must be one of {', '.join(CLOCKS)} (got {clock!r})")
    rate = _speed(speed)
    if problems:
        fail(problems)
    try:
        settings = PlantServerSettings(host=host, port=port, speed=rate, clock=clock,
                                       history_samples=history_samples)
    except ValueError as error:
        fail([str(error)])
    faults = parse_faults(sensor_fault)
    if tags_out is not None:
        prepare_output_file(tags_out, "--tags-out")
    run = run_with_bar(scenario, hours, seed, Console(stderr=True), faults)
    tag_map = plant_tag_map()
    if tags_out is not None:
        write_tag_map(plant_node_ids(tag_map), tags_out)
        typer.echo(f"wrote {tags_out} (tag map with OPC UA node ids)")
    asyncio.run(_serve(PlantServer(run.measured, tag_map, settings), exit_at_end))


async def _serve(server: PlantServer, exit_at_end: bool) -> None:
    """Publish until done (and, without exit_at_end, until SIGINT/SIGTERM)."""
    stop = stop_on_signals()
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
