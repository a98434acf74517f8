"""``steamtwin monitor fit``: the residual monitor the live service raises its alarms with."""

from __future__ import annotations

from pathlib import Path

import typer

from steamtwin.cli.paths import prepare_output_file
from steamtwin.live.monitor_file import fit_monitor_files

monitor_app = typer.Typer(help="Residual alarms of the live twin.", no_args_is_help=True)


@monitor_app.command("fit")
def fit(
    data: list[Path] = typer.Option(..., "--data", help="Healthy historian export(s) (CSV or "
                                    "Parquet); ramps included, so the baseline knows them."),
    tags: Path = typer.Option(..., help="Tag map (TOML) of the export and the live source."),
    out: Path = typer.Option(Path("monitor.json"), help="Monitor file to write (JSON)."),
    turbine: str = typer.Option("reference", help="'reference' or a turbine spec (TOML)."),
    params: Path | None = typer.Option(None, help="Calibrated params.json (coefficients and "
                                       "sensor offsets) the live twin runs with."),
) -> None:
    """Fit the alarm thresholds on a healthy stretch of history: the twin replayed over it at
    the live parameters, σ and the load-dependent baseline of every sensor's residual learned
    from its 60-s block means. The file goes in the service configuration as "monitor".

    Example: steamtwin monitor fit --data healthy-week.parquet --tags tags.toml --params params.json --out monitor.json
    """  # noqa: E501
    prepare_output_file(out, "--out")
    monitor, path = fit_monitor_files(turbine, tags, data, out, params)
    for sensor in monitor.sensors:
        typer.echo(f"{sensor}: σ {monitor.sigma_[sensor]:.4g} (SI), floor "
                   f"{monitor.instrument_sigma[sensor]:.3g}")
    typer.echo(f"wrote {path}")
