"""``steamtwin serve``: the live twin of one or several units."""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path

import typer

from steamtwin.live.config import ServiceConfig, load_config
from steamtwin.live.runner import run_service, stop_on_signals
from steamtwin.live.service import LiveSummary


def serve(
    config: Path = typer.Option(..., help="Service configuration (TOML): database, [[units]] "
                                "with turbine, tag map, params, ROM and source."),
    log_level: str = typer.Option("info", help="Log level: debug, info, warning, error."),
) -> None:
    """Run the live twin: read each unit's DCS (OPC UA or a replayed historian), gate the
    samples, advance the full-order model and the ROM, store measured, twin and residual series
    with the gate's flags, alarms and state in the service's DuckDB file. Ctrl-C or SIGTERM
    stops it cleanly; a restart continues after the last stored sample.

    Example: steamtwin serve --config unit.toml
    """
    level = getattr(logging, log_level.upper(), None)
    if not isinstance(level, int):
        raise typer.BadParameter(f"{log_level!r}: expected debug, info, warning or error",
                                 param_hint="--log-level")
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    logging.getLogger("asyncua").setLevel(logging.WARNING)
    settings = load_config(config)
    summaries = asyncio.run(_serve(settings))
    for name, summary in summaries.items():
        typer.echo(f"{name}: {summary.samples} samples stored ({summary.without_twin} without a "
                   f"twin value), {summary.alarms} alarm(s), {summary.findings} finding(s)")
    typer.echo(f"database: {settings.database}")


async def _serve(settings: ServiceConfig) -> dict[str, LiveSummary]:
    return await run_service(settings, stop_on_signals())
