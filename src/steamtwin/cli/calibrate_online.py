"""``steamtwin calibrate-online``: keep the parameters current as the data stream in.

Parsing, one library call — :meth:`steamtwin.Twin.calibrate_online` (the sliding-window GA of
:mod:`steamtwin.calibration.online` or the recursive filter of
:mod:`steamtwin.calibration.tracking`) — and printing; the trajectory is written by
:func:`~steamtwin.calibration.report.write_trajectory`.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from steamtwin.calibration.report import write_trajectory
from steamtwin.cli.calibrate_output import print_quality, progress_bar
from steamtwin.cli.paths import OutputPathError, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.parameters import ModelParameters, sensor_offsets_from_json
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec
from steamtwin.twin import Twin

__all__ = ["calibrate_online"]


def calibrate_online(
    data: Path = typer.Option(..., help="Historian export to replay as a stream (CSV/Parquet)."),
    tags: Path = typer.Option(..., help="Tag map (TOML) of the historian export."),
    out: Path = typer.Option(..., help="Folder: live params.json, trajectory.csv and .png."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    window_minutes: float = typer.Option(60.0, min=1.0, help="Data each update fits (min)."),
    every_minutes: float = typer.Option(30.0, min=1.0, help="Data time between updates (min)."),
    population: int = typer.Option(20, help="GA population."),
    generations: int = typer.Option(8, help="Generations per warm-started update."),
    first_generations: int = typer.Option(25, help="Generations of the first update."),
    seed: int = typer.Option(0, help="Seed of the GA's random generator."),
    workers: int = typer.Option(1, min=1, help="Local worker processes per update."),
    scheduler: str | None = typer.Option(None, help="Dask scheduler address."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings; the "
        "bad samples stay excluded."),
    method: str = typer.Option(
        "ga", help="'ga': refit a sliding window with the GA; 'track': follow the flow and "
        "friction coefficients step by step with a recursive Bayesian filter "
        "(calibration.tracking; every --every-minutes of new data, the control-stage pressure "
        "used as the flow coefficient's witness)."),
    params: Path | None = typer.Option(
        None, help="A joint calibration's params.json: its coefficients start the live file "
        "and its sensor offsets are read by the model, as validate and rom predict read them."),
) -> None:
    """Keep the parameters current as the data stream in.

    The export is replayed in one-minute chunks. With --method ga, every --every-minutes of
    data the GA refits the last --window-minutes, warm-started from the previous population.
    With --method track, every --every-minutes of new data updates a recursive filter (a
    random-walk state, the step's MAP and Laplace covariance), which follows a step of a few
    per cent of the flow coefficient within half an hour. The live parameter file is replaced
    atomically and every update is logged (parameters, RMSE or interval, reason if it could not
    run); the trajectory's times are in the data's own time zone. --params starts from a joint
    calibration: its coefficients (the tracker's priors centred on them) and its sensor
    offsets, which the model reads as validate and rom predict do.

    Example: steamtwin calibrate-online --data day/historian.parquet --tags day/tags.toml --out online --every-minutes 30
    """  # noqa: E501
    console = Console(stderr=True)
    try:
        prepare_output_folder(out, "--out")
        if method not in ("ga", "track"):
            raise ValueError(f"--method {method!r}: expected 'ga' or 'track'")
        twin = Twin(load_spec(turbine),
                    None if params is None else ModelParameters.from_json(params),
                    sensor_offsets=None if params is None else sensor_offsets_from_json(params))
        history = load_history(data, tags, required=INPUT_SIGNALS,
                               accept_errors=accept_quality_errors)
        print_quality([history], console)
        settings = {"method": method, "store": out / "params.json",
                    "window_s": window_minutes * 60.0, "every_s": every_minutes * 60.0,
                    "population": population, "generations": generations,
                    "first_generations": first_generations, "random_state": seed,
                    "workers": workers, "scheduler": scheduler}
        if method == "track":
            with console.status("tracking the coefficients step by step"):
                twin.calibrate_online(history, **settings)
        else:
            with progress_bar(console, "online calibration") as progress:
                twin.calibrate_online(history, progress=progress, **settings)
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (SpecError, TagMapError, HistorianFormatError, OutputPathError, ValueError,
            KeyError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    online = twin.online_
    trajectory = online.trajectory_
    if trajectory.empty:
        typer.echo(f"error: the data span less than one window ({window_minutes:g} min)",
                   err=True)
        raise typer.Exit(code=2)
    table, figure = write_trajectory(trajectory, out, history.tag_map.time_zone)
    failed = int((trajectory["error"] != "").sum())
    p = online.params_
    runs = f"; model runs: {online.n_evaluations_}" if method == "ga" else ""
    typer.echo(f"updates: {len(trajectory)} ({failed} could not run){runs}")
    typer.echo(f"live parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    typer.echo(f"wrote {out / 'params.json'}, {table} and {figure}")
