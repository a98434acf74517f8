"""``steamtwin calibrate``: fit the model parameters to plant historian data.

Parsing, one library call — :meth:`steamtwin.Twin.calibrate` over the histories
:func:`~steamtwin.calibration.histories.load_histories` read, then
:meth:`~steamtwin.Twin.calibration_report` — and printing (:mod:`steamtwin.cli.calibrate_output`).
Several historian files calibrate jointly (``--data A --data B``, one ``--tags`` for all or one
per file): windows at every steady load and on ramps, weighted by load band
(:mod:`steamtwin.calibration.windowset`); the fit is the MAP under the parameters' priors with
95 % intervals (:mod:`steamtwin.calibration.posterior`).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import typer
from rich.console import Console

from steamtwin.calibration import CalibrationError
from steamtwin.calibration.histories import PRESSURE_WITNESS, load_histories
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.settings import load_priors
from steamtwin.cli.calibrate_output import print_calibration, print_quality, progress_bar
from steamtwin.cli.paths import OutputPathError, prepare_output_file, prepare_output_folder
from steamtwin.dcs.history import OVERRIDE_OPTION, DataQualityError
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.spec import SpecError, load_spec
from steamtwin.twin import Twin

__all__ = ["calibrate"]


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
    try:
        if surrogate and resume:
            raise ValueError("--resume continues a GA run; the surrogate mode has no checkpoint")
        if no_priors and (priors_file is not None or prior):
            raise ValueError("--no-priors contradicts --priors/--prior")
        prepare_output_file(out, "--out")
        if report is not None:
            prepare_output_folder(report, "--report")
        twin = Twin(load_spec(turbine))
        priors = None if no_priors else load_priors(priors_file, prior or ())
        histories = load_histories(data, tags, accept_errors=accept_quality_errors)
        print_quality(histories, console)
        if pressure_witness is None and not all(PRESSURE_WITNESS in h.data.columns
                                                for h in histories):
            console.print(f"no {PRESSURE_WITNESS} in the data: the temperatures alone are "
                          "fitted")
        with progress_bar(console, "preparing the model (the first run compiles it, ~20 s)"
                          ) as progress, warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", IdentifiabilityWarning)
            twin.calibrate(
                histories, method="surrogate" if surrogate else "ga", windows=window or (),
                ramps=ramps, min_steady_s=60.0 * min_steady_minutes,
                max_steady_s=60.0 * max_steady_minutes, pressure_witness=pressure_witness,
                sensor_bias=sensor_bias, priors=priors, population=population,
                generations=generations, max_evaluations=max_evaluations, random_state=seed,
                workers=workers, scheduler=scheduler, progress=progress, resume=resume,
                checkpoint=None if surrogate else out.with_name(f"{out.stem}.checkpoint"))
        written = []
        if report is not None:
            with console.status("writing the report") as status:
                written = twin.calibration_report(
                    report, sensitivity=sensitivity,
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
    print_calibration(twin, out, files=len(data), written=written)
