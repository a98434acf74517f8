"""``steamtwin dcs``: plant historian data — quality check of an export against its tag map."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from steamtwin.cli.paths import prepare_output_file
from steamtwin.dcs.history import check_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.simulator import INPUT_SIGNALS

dcs_app = typer.Typer(help="Plant historian (DCS) data.", no_args_is_help=True)


@dcs_app.command("check")
def check(
    data: Path = typer.Argument(..., help="Historian export: CSV or Parquet, wide or long."),
    tags: Path = typer.Option(..., help="Tag map (TOML): column/tag, unit, range per signal."),
    json_out: Path | None = typer.Option(None, "--json", help="Also write the report as JSON."),
    require: str = typer.Option(
        ",".join(INPUT_SIGNALS), help="Comma-separated canonical signals that must be present."
    ),
) -> None:
    """Print the data-quality report of a historian export; exit code 1 if it has errors.

    Example: steamtwin dcs check history.parquet --tags tags.toml --json quality.json
    """
    if json_out is not None:
        prepare_output_file(json_out, "--json")
    required = tuple(name.strip() for name in require.split(",") if name.strip())
    try:
        historian, report = check_history(data, tags, required)
    except (TagMapError, HistorianFormatError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    if historian.dialect:
        typer.echo("read as: " + ", ".join(
            f"{key} {historian.dialect[key]!r} ({historian.dialect[f'{key}_source']})"
            for key in ("delimiter", "decimal", "encoding") if key in historian.dialect))
    marked = {name: int(mask.sum()) for name, mask in historian.bad_quality.items()
              if mask.any()}
    if marked:
        typer.echo("historian quality marks excluded: " + ", ".join(
            f"{name} {count}" for name, count in marked.items()))
    typer.echo(report.to_text())
    if json_out is not None:
        json_out.write_text(json.dumps(report.to_dict(), indent=2) + "\n", encoding="utf-8")
    if not report.ok:
        raise typer.Exit(code=1)
