"""``steamtwin history export``: the live twin's database as files people open."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import typer

from steamtwin.cli.paths import prepare_output_file
from steamtwin.live.historian import export_history

history_app = typer.Typer(help="The live twin's embedded historian (DuckDB).",
                          no_args_is_help=True)


def _time(text: str | None, option: str) -> pd.Timestamp | None:
    if text is None:
        return None
    try:
        stamp = pd.Timestamp(text)
    except ValueError:
        raise typer.BadParameter(f"{text!r}: expected an ISO 8601 time with its zone, e.g. "
                                 "2026-03-01T08:00+08:00", param_hint=option) from None
    if stamp.tzinfo is None:
        raise typer.BadParameter(f"{text!r} has no time zone; add one (e.g. Z or +08:00)",
                                 param_hint=option)
    return stamp


@history_app.command("export")
def export(
    db: Path = typer.Option(..., help="The service's DuckDB file."),
    out: Path = typer.Option(..., help="Output file: .parquet or .csv."),
    unit: str | None = typer.Option(None, help="Unit name (needed for --layout wide when the "
                                    "database holds several)."),
    start: str | None = typer.Option(None, "--from", help="First time (ISO 8601 with zone)."),
    end: str | None = typer.Option(None, "--to", help="Last time (ISO 8601 with zone)."),
    layout: str = typer.Option("wide", help="'wide': one row per time, <source>/<signal> "
                               "columns (SI) and flag/<signal>; 'long': one row per value."),
) -> None:
    """Export measured, twin and residual series (SI, canonical names) from the live twin's
    database.

    Example: steamtwin history export --db twin.duckdb --unit unit1 --from 2026-03-01T08:00+08:00 --to 2026-03-01T10:00+08:00 --out window.parquet
    """  # noqa: E501
    first, last = _time(start, "--from"), _time(end, "--to")
    prepare_output_file(out, "--out")
    rows = export_history(db, out, unit=unit, start=first, end=last, layout=layout)
    typer.echo(f"wrote {rows} rows to {out}")
