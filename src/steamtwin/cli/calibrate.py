"""``steamtwin calibrate``: fit the model parameters to plant historian data with the GA."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.calibration import CalibrationError, Calibrator
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.online import OnlineCalibrator, ParameterStore
from steamtwin.calibration.report import (
    convergence_figure,
    ga_sensitivity_table,
    rmse_table,
    temperature_comparison_figure,
    trajectory_figure,
)
from steamtwin.calibration.surrogate import SurrogateCalibrator
from steamtwin.cli.paths import OutputPathError, prepare_output_file, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, History, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.dcs.windows import find_steady_windows, parse_window, select_window
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, TurbineSpec, load_spec


def _read_cleaned(data: Path, tags: Path, accept_errors: bool, console: Console
                  ) -> History:
    """The export through the quality gate (bad samples excluded); prints what it excluded."""
    history = load_history(data, tags, required=INPUT_SIGNALS, accept_errors=accept_errors)
    excluded = {name: n for name, n in history.excluded.items() if n}
    if excluded:
        console.print(f"data quality: excluded {sum(excluded.values())} sample(s) "
                      f"({', '.join(f'{name} {n}' for name, n in excluded.items())}); "
                      "'steamtwin dcs check' lists why")
    for finding in history.report.errors:
        console.print(f"accepted data-quality error: {finding.message}")
    return history


def _model(spec: TurbineSpec, history: History) -> FullOrderModel:
    """The FOM, its readings lagged by the sensor time constants the tag map gives (none:
    the model's temperatures as they are)."""
    given = history.historian.tag_map.time_constants
    if not given:
        return FullOrderModel(spec)
    outputs = FullOrderModel(spec).output_signals
    return FullOrderModel(spec, sensor_time_constants={
        name: tau for name, tau in given.items() if name in outputs})


def _pick_windows(data: pd.DataFrame, window: list[str] | None, rated_load_w: float
                  ) -> list[pd.DataFrame]:
    if window:
        return [select_window(data, *parse_window(text)) for text in window]
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
    surrogate: bool = typer.Option(
        False, "--surrogate", help="Surrogate-assisted: the GA searches an RBF surrogate; the "
        "model runs only for the initial design and infill (--max-evaluations)."),
    max_evaluations: int = typer.Option(
        400, min=10, help="Model runs the surrogate mode may spend."),
    report: Path | None = typer.Option(
        None, help="Folder for the result files: Table 6 (RMSE before/after per window), "
        "Figure 7 (convergence), Figure 8 (temperatures before/after), identifiability."),
    sensitivity: bool = typer.Option(
        False, "--sensitivity", help="Also run Table 7 (GA settings varied: P 30/50/80, p_c, "
        "p_m) into --report; nine more calibrations."),
    accept_quality_errors: bool = typer.Option(
        False, OVERRIDE_OPTION, help="Go on despite error-level data-quality findings (unit "
        "mix-ups, conflicting duplicates, ...); the bad samples stay excluded."),
) -> None:
    """Calibrate flow, friction and heat-transfer coefficients against DCS temperatures.

    Reads and cleans the historian export, picks the windows, runs the genetic algorithm and
    writes the parameters (readable by 'steamtwin simulate --params') plus the per-generation
    history, then prints the RMSE before (empirical parameters) and after calibration. A
    checkpoint is rewritten after every generation; --resume continues a killed run. A warning
    names any parameter the windows cannot identify.

    Example: steamtwin calibrate --data plant-data/historian.parquet --tags plant-data/tags.toml --out params.json
    """  # noqa: E501
    console = Console(stderr=True)
    if surrogate and resume:
        typer.echo("error: --resume continues a GA run; the surrogate mode has no checkpoint",
                   err=True)
        raise typer.Exit(code=2)
    try:
        prepare_output_file(out, "--out")
        if report is not None:
            prepare_output_folder(report, "--report")
        spec = load_spec(turbine)
        history = _read_cleaned(data, tags, accept_quality_errors, console)
        windows = _pick_windows(history.data, window, spec.design.generator_power)
        model = _model(spec, history)
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task("calibrating", total=1.0)

            def progress(fraction: float, message: str) -> None:
                bar.update(task, completed=fraction, description=message)

            settings = {"population": population, "seed": seed, "workers": workers,
                        "scheduler": scheduler}
            if surrogate:
                calibrator = SurrogateCalibrator(model, max_evaluations=max_evaluations,
                                                 progress=progress, **settings)
            else:
                calibrator = Calibrator(model, generations=generations, progress=progress,
                                        checkpoint=out.with_name(f"{out.stem}.checkpoint"),
                                        **settings)
            before = Calibrator(model, workers=1).rmse(windows, ModelParameters())
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", IdentifiabilityWarning)
                if surrogate:
                    calibrator.fit(windows)
                else:
                    calibrator.fit(windows, resume=resume)
        if report is not None:
            written = _write_report(report, model, windows, calibrator, sensitivity,
                                    {**settings, "generations": generations}, console)
    except (DataQualityError, CalibrationError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (SpecError, TagMapError, HistorianFormatError, OutputPathError, ValueError,
            KeyError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    for warning in caught:
        typer.echo(f"warning: {warning.message}", err=True)
    params_path, history_path = calibrator.save(out)
    p = calibrator.params_
    typer.echo(f"windows: {len(windows)} ({sum(len(w) for w in windows)} samples); "
               f"evaluations: {calibrator.n_evaluations_}")
    typer.echo(f"parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    typer.echo(f"RMSE before (empirical 1, 1, 1): {before:.3f} K; after: {calibrator.rmse_:.3f} K")
    typer.echo(f"wrote {params_path} and {history_path}")
    if report is not None:
        typer.echo(f"wrote {', '.join(str(path) for path in written)}")


def _condition_name(window: pd.DataFrame, rated_load_w: float, index: int) -> str:
    if "load" in window.columns and window["load"].notna().any():
        return f"window {index + 1}: {100 * window['load'].mean() / rated_load_w:.0f} % load"
    return f"window {index + 1}"


def _write_report(folder: Path, model: FullOrderModel, windows: list[pd.DataFrame],
                  calibrator: Calibrator | SurrogateCalibrator, sensitivity: bool,
                  settings: dict[str, object], console: Console) -> list[Path]:
    """Table 6, Figures 7 and 8, identifiability (and Table 7) into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    rated = model.spec.design.generator_power
    names = [_condition_name(w, rated, i) for i, w in enumerate(windows)]
    table6 = rmse_table(model, {n: [w] for n, w in zip(names, windows, strict=True)},
                        calibrator.params_)
    written = [folder / "table6_rmse.csv"]
    table6.to_csv(written[-1])
    if isinstance(calibrator, Calibrator):
        written.append(convergence_figure(calibrator.history_, folder / "figure7_convergence.png"))
    loads = [abs(float(w["load"].mean()) / rated - 0.5) if "load" in w.columns else 0.0
             for w in windows]
    closest = int(np.argmin(loads))  # the method's Figure 8 is at 50 % load
    written.append(temperature_comparison_figure(
        model, windows[closest], calibrator.params_, folder / "figure8_temperatures.png",
        title=f"Predicted vs measured temperatures, {names[closest]} (Figure 8)"))
    if calibrator.identifiability_ is not None:
        written.append(folder / "identifiability.csv")
        calibrator.identifiability_.to_csv(written[-1])
    if sensitivity:
        with console.status("Table 7: GA settings varied"):
            table7 = ga_sensitivity_table(
                lambda s: Calibrator(model, **s).fit(windows), settings)
        written.append(folder / "table7_ga_sensitivity.csv")
        table7.to_csv(written[-1], index=False)
    return written


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
) -> None:
    """Keep the parameters current: recalibrate on a sliding window as the data stream in.

    The export is replayed in one-minute chunks. Every --every-minutes of data the GA refits the
    last --window-minutes, warm-started from the previous population; the live parameter file is
    replaced atomically and every update is logged (parameters, RMSE before/after, reason if it
    could not run).

    Example: steamtwin calibrate-online --data day/historian.parquet --tags day/tags.toml --out online --every-minutes 30
    """  # noqa: E501
    console = Console(stderr=True)
    try:
        prepare_output_folder(out, "--out")
        spec = load_spec(turbine)
        history = _read_cleaned(data, tags, accept_quality_errors, console)
        model = _model(spec, history)
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task("online calibration", total=1.0)
            online = OnlineCalibrator(
                model, window_s=window_minutes * 60.0, every_s=every_minutes * 60.0,
                population=population, generations=generations,
                first_generations=first_generations, seed=seed, workers=workers,
                scheduler=scheduler, store=ParameterStore(path=out / "params.json"),
                progress=lambda f, m: bar.update(task, completed=f, description=m))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", IdentifiabilityWarning)
                online.run(history.data)
    except DataQualityError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=1) from None
    except (SpecError, TagMapError, HistorianFormatError, OutputPathError, ValueError,
            KeyError) as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(code=2) from None
    trajectory = online.trajectory_
    if trajectory.empty:
        typer.echo(f"error: the data span less than one window ({window_minutes:g} min)",
                   err=True)
        raise typer.Exit(code=2)
    trajectory.to_csv(out / "trajectory.csv")
    figure = trajectory_figure(trajectory, out / "trajectory.png")
    failed = int((trajectory["error"] != "").sum())
    p = online.params_
    typer.echo(f"updates: {len(trajectory)} ({failed} could not run); model runs: "
               f"{online.n_evaluations_}")
    typer.echo(f"live parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    typer.echo(f"wrote {out / 'params.json'}, {out / 'trajectory.csv'} and {figure}")
