"""What ``steamtwin calibrate`` and ``calibrate-online`` print: data quality, progress, result."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from steamtwin.dcs.history import History
from steamtwin.progress import ProgressCallback
from steamtwin.twin import Twin

__all__ = ["print_calibration", "print_quality", "progress_bar"]


def print_quality(histories: Sequence[History], console: Console) -> None:
    """Per file, the samples the quality gate excluded and the error-level findings accepted."""
    for history in histories:
        excluded = {name: n for name, n in history.excluded.items() if n}
        if excluded:
            console.print(f"{history.historian.source}: data quality: excluded "
                          f"{sum(excluded.values())} sample(s) "
                          f"({', '.join(f'{name} {n}' for name, n in excluded.items())}); "
                          "'steamtwin dcs check' lists why")
        for finding in history.report.errors:
            console.print(f"accepted data-quality error: {finding.message}")


@contextmanager
def progress_bar(console: Console, description: str) -> Iterator[ProgressCallback]:
    """A transient progress bar on ``console``; yields its ``progress(fraction, message)``."""
    columns = (TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(description, total=1.0)

        def progress(fraction: float, message: str) -> None:
            bar.update(task, completed=fraction, description=message)

        yield progress


def print_calibration(twin: Twin, out: Path, *, files: int, written: Sequence[Path]) -> None:
    """Save the calibrated parameters to ``out`` (history CSV beside it) and print the windows,
    the parameters with their intervals, the RMSE before and after, and what was written."""
    calibrator, windows = twin.calibrator_, twin.windows_
    params_path, history_path = calibrator.save(out)
    p = calibrator.params_
    bands = windows.bands()
    typer.echo(f"windows: {len(windows)} ({sum(len(w.data) for w in windows)} samples) from "
               f"{files} file(s) in {len(set(bands))} load band(s) "
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
    typer.echo(f"RMSE before (empirical 1, 1, 1): {twin.initial_rmse_:.3f} K; after: "
               f"{calibrator.rmse_:.3f} K (load-band weighted)")
    typer.echo(f"wrote {params_path} and {history_path}")
    if written:
        typer.echo(f"wrote {', '.join(str(path) for path in written)}")
