"""``steamtwin calibrate``: fit the model parameters to plant historian data with the GA."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.calibration import Calibrator
from steamtwin.dcs.quality import clean
from steamtwin.dcs.readers import HistorianFormatError, read_historian
from steamtwin.dcs.tagmap import TagMapError, load_tag_map
from steamtwin.dcs.windows import find_steady_windows, select_window
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec


def _pick_windows(data: pd.DataFrame, window: list[str] | None, rated_load_w: float
                  ) -> list[pd.DataFrame]:
    if window:
        picked = []
        for text in window:
            start, sep, end = text.partition("/")
            if not sep or not start or not end:
                raise ValueError(f"--window {text!r}: expected START/END (ISO 8601 times)")
            try:
                bounds = pd.Timestamp(start), pd.Timestamp(end)
            except ValueError as error:
                raise ValueError(f"--window {text!r}: {error} (expected ISO 8601 times)") from None
            picked.append(select_window(data, *bounds))
        return picked
    if "load" not in data.columns:
        raise ValueError(
            "no --window given and the data have no 'load' signal, which the automatic search "
            "for steady 2-h windows needs; map the generator load in the tag map or pass "
            "--window START/END"
        )
    steady = find_steady_windows(data, duration_s=7200.0, rated_load_w=rated_load_w)
    if not steady:
        raise ValueError("no steady 2-h window found in the data; pass --window START/END")
    return [select_window(data, w.start, w.end) for w in steady]


def calibrate(
    data: Path = typer.Option(..., help="Historian export: CSV or Parquet, wide or long."),
    tags: Path = typer.Option(..., help="Tag map (TOML) of the historian export."),
    out: Path = typer.Option(..., help="Parameter JSON to write (history CSV alongside)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    population: int = typer.Option(50, help="GA population size."),
    generations: int = typer.Option(200, help="GA generations."),
    seed: int = typer.Option(0, help="Seed of the GA's random generator."),
    window: list[str] | None = typer.Option(
        None, help="START/END (ISO 8601) of a window to fit; repeatable. Default: steady 2-h "
        "windows of 'load'."),
    workers: int | None = typer.Option(
        None, min=1, help="Local worker processes evaluating the GA's candidates (default: "
        "every core; 1 = no pool)."),
    scheduler: str | None = typer.Option(
        None, help="Dask scheduler address (e.g. tcp://10.0.0.5:8786): evaluate on that "
        "cluster instead of local processes."),
    resume: bool = typer.Option(
        False, "--resume", help="Continue from the checkpoint a killed run left "
        "(<out stem>.checkpoint next to --out); same settings and data give the same result."),
) -> None:
    """Calibrate flow, friction and heat-transfer coefficients against DCS temperatures.

    Reads and cleans the historian export, picks the windows, runs the genetic algorithm and
    writes the parameters (readable by 'steamtwin simulate --params') plus the per-generation
    history, then prints the RMSE before (empirical parameters) and after calibration. A
    checkpoint is rewritten after every generation; --resume continues a killed run.

    Example: steamtwin calibrate --data plant-data/historian.parquet --tags plant-data/tags.toml --out params.json
    """  # noqa: E501
    console = Console(stderr=True)
    try:
        spec = load_spec(turbine)
        tag_map = load_tag_map(tags)
        historian = read_historian(data, tag_map)
        specs = tag_map.signals.values()
        cleaned = clean(
            historian.signals,
            required=INPUT_SIGNALS,
            ranges={s.signal: s.valid_range_si for s in specs if s.valid_range_si is not None},
            declared_units={s.signal: s.unit for s in specs},
            tag_names={s.signal: s.column for s in specs},
            source=str(data),
        ).data
        windows = _pick_windows(cleaned, window, spec.design.generator_power)
        model = FullOrderModel(spec)
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task("calibrating", total=1.0)

            def progress(fraction: float, message: str) -> None:
                bar.update(task, completed=fraction, description=message)

            calibrator = Calibrator(model, population=population, generations=generations,
                                    seed=seed, progress=progress, workers=workers,
                                    scheduler=scheduler,
                                    checkpoint=out.with_name(f"{out.stem}.checkpoint"))
            before = calibrator.rmse(windows, ModelParameters())
            calibrator.fit(windows, resume=resume)
    except (SpecError, TagMapError, HistorianFormatError, ValueError, KeyError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    params_path, history_path = calibrator.save(out)
    p = calibrator.params_
    typer.echo(f"windows: {len(windows)} ({sum(len(w) for w in windows)} samples); "
               f"evaluations: {calibrator.n_evaluations_}")
    typer.echo(f"parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    typer.echo(f"RMSE before (empirical 1, 1, 1): {before:.3f} K; after: {calibrator.rmse_:.3f} K")
    typer.echo(f"wrote {params_path} and {history_path}")
