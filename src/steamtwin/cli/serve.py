"""``steamtwin serve``: the live twin of one or several units, and its HTTP service."""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path

import typer

from steamtwin.live.config import ServiceConfig, load_config
from steamtwin.live.runner import Companion, run_service, stop_on_signals
from steamtwin.live.service import LiveSummary

LOG = logging.getLogger("steamtwin.live")


def serve(
    config: Path = typer.Option(..., help="Service configuration (TOML): database, [[units]] "
                                "with turbine, tag map, params, ROM and source."),
    log_level: str = typer.Option("info", help="Log level: debug, info, warning, error."),
    http_port: int | None = typer.Option(
        None, help="Serve the HTTP API (JSON, live events, /health, /metrics, /docs) on this "
        "port, e.g. 8080 (0: any free port, logged); not given: no HTTP service.",
        min=0, max=65535),
    bind: str = typer.Option("127.0.0.1", help="Address the HTTP service listens on; any "
                             "address but loopback needs --token-file."),
    token_file: Path | None = typer.Option(
        None, help="Bearer tokens (TOML: [[tokens]] name, role = \"read\" or \"ack\", token): "
        "every HTTP request must then bring one."),
    scheduler: str | None = typer.Option(
        None, help="Dask scheduler address (e.g. tcp://10.0.0.5:8786): the units' online "
        "recalibration steps run on that cluster; not given: in this process."),
) -> None:
    """Run the live twin: read each unit's DCS (OPC UA or a replayed historian), gate the
    samples, advance the full-order model and the ROM, store measured, twin and residual series
    with the gate's flags, alarms and state in the service's DuckDB file. Ctrl-C or SIGTERM
    stops it cleanly; a restart continues after the last stored sample. With --http-port the
    same process serves the database over HTTP until the service stops.

    Example: steamtwin serve --config unit.toml --http-port 8080
    """
    level = getattr(logging, log_level.upper(), None)
    if not isinstance(level, int):
        raise typer.BadParameter(f"{log_level!r}: expected debug, info, warning or error",
                                 param_hint="--log-level")
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    logging.getLogger("asyncua").setLevel(logging.WARNING)
    settings = load_config(config)
    companions: list[Companion] = []
    if http_port is not None:
        companions.append(_http(settings, http_port, bind, token_file))
    elif token_file is not None or bind != "127.0.0.1":
        raise typer.BadParameter("--bind and --token-file apply to the HTTP service: add "
                                 "--http-port", param_hint="--http-port")
    try:
        summaries = asyncio.run(_serve(settings, companions, scheduler))
    except ValueError as error:
        if scheduler is None or "Dask scheduler" not in str(error):
            raise
        raise typer.BadParameter(str(error), param_hint="--scheduler") from None
    for name, summary in summaries.items():
        typer.echo(f"{name}: {summary.samples} samples stored ({summary.without_twin} without a "
                   f"twin value), {summary.alarms} alarm(s), {summary.findings} finding(s)")
    typer.echo(f"database: {settings.database}")


def _http(settings: ServiceConfig, port: int, bind: str, token_file: Path | None) -> Companion:
    from steamtwin.web.access import AccessError, AccessPolicy, load_tokens
    from steamtwin.web.server import HttpServiceError, HttpSettings, http_companion

    try:
        access = load_tokens(token_file) if token_file is not None else AccessPolicy()
        return http_companion(HttpSettings(host=bind, port=port, access=access), settings,
                              on_bound=lambda host, bound: LOG.info(
                                  "HTTP service on http://%s:%d/ (API reference: /docs)",
                                  host, bound))
    except (AccessError, HttpServiceError) as error:
        raise typer.BadParameter(str(error), param_hint="--bind/--token-file/--http-port"
                                 ) from None


async def _serve(settings: ServiceConfig, companions: list[Companion], scheduler: str | None
                 ) -> dict[str, LiveSummary]:
    return await run_service(settings, stop_on_signals(), companions, scheduler=scheduler)
