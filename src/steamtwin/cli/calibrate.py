"""``steamtwin calibrate``: fit the model parameters to plant historian data with the GA.

Parsing and printing over :meth:`steamtwin.Twin.calibrate` (windows, sensors, calibrators) and
:meth:`~steamtwin.Twin.calibration_report`.

Several historian files calibrate jointly (``--data A --data B``, one ``--tags`` for all or one
per file): windows at every steady load and on ramps, weighted by load band
(:mod:`steamtwin.calibration.windowset`); the fit is the MAP under the parameters' priors with
95 % intervals (:mod:`steamtwin.calibration.posterior`).
"""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.calibration import CalibrationError
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.online import OnlineCalibrator, ParameterStore
from steamtwin.calibration.report import trajectory_figure
from steamtwin.calibration.tracking import ParameterTracker, tracking_sigma
from steamtwin.cli.paths import OutputPathError, prepare_output_file, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError, History, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    ModelParameters,
    ParameterError,
    ParameterPrior,
    parse_prior,
    priors_from_dict,
    sensor_offsets_from_json,
)
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import SpecError, load_spec
from steamtwin.textfile import read_utf8_text
from steamtwin.twin import PRESSURE_WITNESS, Twin, sensor_model


def _read_cleaned(data: Path, tags: Path, accept_errors: bool, console: Console
                  ) -> History:
    """The export through the quality gate (bad samples excluded); prints what it excluded."""
    history = load_history(data, tags, required=INPUT_SIGNALS, accept_errors=accept_errors)
    excluded = {name: n for name, n in history.excluded.items() if n}
    if excluded:
        console.print(f"{data}: data quality: excluded {sum(excluded.values())} sample(s) "
                      f"({', '.join(f'{name} {n}' for name, n in excluded.items())}); "
                      "'steamtwin dcs check' lists why")
    for finding in history.report.errors:
        console.print(f"accepted data-quality error: {finding.message}")
    return history


def _read_histories(data: list[Path], tags: list[Path], accept_errors: bool, console: Console
                    ) -> list[History]:
    """Every --data file through the quality gate with its tag map; errors name the file."""
    if len(tags) not in (1, len(data)):
        raise ValueError(f"give one --tags for all {len(data)} --data files or one per file "
                         f"in the same order (got {len(tags)})")
    result = []
    for k, path in enumerate(data):
        tag_path = tags[0] if len(tags) == 1 else tags[k]
        try:
            result.append(_read_cleaned(path, tag_path, accept_errors, console))
        except DataQualityError:
            raise
        except (TagMapError, HistorianFormatError, ValueError, KeyError) as error:
            raise ValueError(f"--data {path} (with --tags {tag_path}): {error}") from None
    return result


def _priors(no_priors: bool, priors_file: Path | None, prior: list[str] | None
            ) -> dict[str, ParameterPrior] | None:
    """Default priors, overridden by --priors FILE then by each --prior; None for --no-priors."""
    if no_priors:
        if priors_file is not None or prior:
            raise ValueError("--no-priors contradicts --priors/--prior")
        return None
    result = dict(DEFAULT_PRIORS)
    if priors_file is not None:
        document = json.loads(read_utf8_text(priors_file, "priors file", "JSON", ParameterError))
        if not isinstance(document, dict) or "priors" not in document:
            raise ParameterError(f"{priors_file}: expected a JSON object with a 'priors' "
                                 "section (as calibrate writes into params.json)")
        result = priors_from_dict(document["priors"], str(priors_file), result)
    for text in prior or []:
        name, value = parse_prior(text)
        result[name] = value
    return result


def calibrate(
    data: list[Path] = typer.Option(
        ..., help="Historian export: CSV or Parquet, wide or long; repeat for a joint "
        "calibration over several files."),
    tags: list[Path] = typer.Option(
        ..., help="Tag map (TOML): one for every --data, or one per --data in the same order."),
    out: Path = typer.Option(..., help="Parameter JSON to write (history CSV alongside)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec TOML."),
    population: int = typer.Option(50, help="GA population size."),
    generations: int = typer.Option(200, help="GA generations."),
    seed: int = typer.Option(0, help="Seed of the GA's random generator."),
    window: list[str] | None = typer.Option(
        None, help="START/END (ISO 8601) of a window to fit, taken from every file covering "
        "it; repeatable. Default: the steady windows at every load and the load ramps."),
    min_steady_minutes: float = typer.Option(
        60.0, min=1.0, help="Shortest steady hold taken as a window (min)."),
    max_steady_minutes: float = typer.Option(
        120.0, min=1.0, help="Longest steady window (min; the last part of a longer hold)."),
    ramps: bool = typer.Option(
        True, "--ramps/--no-ramps", help="Also fit the load ramps (they show the "
        "heat-transfer coefficient)."),
    prior: list[str] | None = typer.Option(
        None, help="A parameter's prior NAME=normal|lognormal:CENTER:SPREAD, e.g. "
        "flow_coefficient=normal:1.0:0.03; repeatable; overrides --priors and the defaults."),
    priors_file: Path | None = typer.Option(
        None, "--priors", help="JSON file whose 'priors' section overrides the default priors "
        "(e.g. a params.json calibrate wrote)."),
    no_priors: bool = typer.Option(
        False, "--no-priors", help="Plain RMSE fit without priors (the method's original; no "
        "intervals)."),
    sensor_bias: bool = typer.Option(
        False, "--sensor-bias/--no-sensor-bias", help="Integrate out each thermocouple's "
        "constant bias per file (IEC 60584-1 class 1 tolerance): the fit then learns from how "
        "the temperatures change with load, not from their level; for a twin that already "
        "matches the level within a few K."),
    pressure_witness: bool | None = typer.Option(
        None, "--pressure-witness/--no-pressure-witness", help="Also fit the control-stage "
        "pressure (σ from the tag map's noise, else 25 kPa), the flow coefficient's most "
        "direct witness (Stodola's cone law); on the virtual plant's unseen day it put the "
        "flow coefficient within 0.011 of the truth against 0.020 without "
        "(docs/benchmarks.md). Default: when every file maps it."),
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
        priors = _priors(no_priors, priors_file, prior)
        histories = _read_histories(data, tags, accept_quality_errors, console)
        if pressure_witness is None and not all(PRESSURE_WITNESS in h.data.columns
                                                for h in histories):
            console.print(f"no {PRESSURE_WITNESS} in the data: the temperatures alone are "
                          "fitted")
        twin = Twin(spec)
        columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task("preparing the model (the first run compiles it, ~20 s)",
                                total=1.0)

            def progress(fraction: float, message: str) -> None:
                bar.update(task, completed=fraction, description=message)

            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", IdentifiabilityWarning)
                twin.calibrate(
                    histories, method="surrogate" if surrogate else "ga",
                    windows=window or (), ramps=ramps,
                    min_steady_s=60.0 * min_steady_minutes,
                    max_steady_s=60.0 * max_steady_minutes,
                    pressure_witness=pressure_witness, sensor_bias=sensor_bias,
                    priors=priors, population=population, generations=generations,
                    max_evaluations=max_evaluations, random_state=seed, workers=workers,
                    scheduler=scheduler, progress=progress, resume=resume,
                    checkpoint=None if surrogate else out.with_name(f"{out.stem}.checkpoint"))
        calibrator, windows = twin.calibrator_, twin.windows_
        if report is not None:
            with console.status("writing the report") as status:
                written = twin.calibration_report(report, sensitivity=sensitivity,
                                                  progress=lambda _, message: status.update(message))
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
    bands = windows.bands()
    typer.echo(f"windows: {len(windows)} ({sum(len(w.data) for w in windows)} samples) from "
               f"{len(data)} file(s) in {len(set(bands))} load band(s) "
               f"({', '.join(sorted(set(bands)))}); evaluations: {calibrator.n_evaluations_}")
    typer.echo(f"parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    if calibrator.posterior_ is not None:
        typer.echo(f"MAP under the priors, likelihood tempered by κ = {calibrator.tempering_:.3g} "
                   "(the residuals' autocorrelation and the model's misfit)")
        for name, row in calibrator.posterior_.table().iterrows():
            typer.echo(f"  {name}: {row['map']:.4f}, 95 % interval [{row['low']:.4f}, "
                       f"{row['high']:.4f}] (prior [{row['prior_low']:.3f}, "
                       f"{row['prior_high']:.3f}])")
    before = twin.initial_rmse_
    typer.echo(f"RMSE before (empirical 1, 1, 1): {before:.3f} K; after: {calibrator.rmse_:.3f} K"
               " (load-band weighted)")
    typer.echo(f"wrote {params_path} and {history_path}")
    if report is not None:
        typer.echo(f"wrote {', '.join(str(path) for path in written)}")


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
        spec = load_spec(turbine)
        history = _read_cleaned(data, tags, accept_quality_errors, console)
        model = sensor_model(spec, [history])
        start = ModelParameters()
        if params is not None:
            start = ModelParameters.from_json(params)
            offsets = sensor_offsets_from_json(params)
            if offsets:
                model = FullOrderModel(model.spec, sensor_offsets=offsets,
                                       sensor_time_constants=model.sensor_time_constants)
        with console.status("preparing the model (the first run compiles it, ~20 s)"):
            _ = model.design_
        columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
        if method not in ("ga", "track"):
            raise ValueError(f"--method {method!r}: expected 'ga' or 'track'")
        tag_map = history.historian.tag_map
        if method == "track":
            with console.status("tracking the coefficients step by step"):
                centred = {name: dataclasses.replace(prior, center=getattr(start, name))
                           for name, prior in DEFAULT_PRIORS.items()}
                online = ParameterTracker(
                    model, sigma=tracking_sigma(tag_map), step_s=every_minutes * 60.0,
                    priors=centred,
                    store=ParameterStore(start, path=out / "params.json")).run(history.data)
        else:
            with Progress(*columns, console=console, transient=True) as bar:
                task = bar.add_task("online calibration", total=1.0)
                online = OnlineCalibrator(
                    model, window_s=window_minutes * 60.0, every_s=every_minutes * 60.0,
                    population=population, generations=generations,
                    first_generations=first_generations, random_state=seed, workers=workers,
                    scheduler=scheduler, store=ParameterStore(start, path=out / "params.json"),
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
    if tag_map.time_zone:  # the trajectory in the data's own time zone
        trajectory = trajectory.set_axis(trajectory.index.tz_convert(tag_map.time_zone))
    trajectory.to_csv(out / "trajectory.csv")
    figure = trajectory_figure(trajectory, out / "trajectory.png")
    failed = int((trajectory["error"] != "").sum())
    p = online.params_
    runs = f"; model runs: {online.n_evaluations_}" if method == "ga" else ""
    typer.echo(f"updates: {len(trajectory)} ({failed} could not run){runs}")
    typer.echo(f"live parameters: flow {p.flow_coefficient:.4f}, friction "
               f"{p.friction_coefficient:.4f}, heat transfer {p.heat_transfer_coefficient:.4f}")
    typer.echo(f"wrote {out / 'params.json'}, {out / 'trajectory.csv'} and {figure}")
