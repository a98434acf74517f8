"""``steamtwin demo``: the whole chain on a turbine spec and blade row, ending in the report."""

from __future__ import annotations

import logging
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from steamtwin.cli.paths import prepare_output_folder
from steamtwin.pipeline import DemoSettings, run_demo


def demo(
    out: Path = typer.Option(Path("demo-output"), help="Folder for the demo's files."),
    full: bool = typer.Option(False, "--full/--quick", help="The method's settings: GA P 50 × "
                              "G 200, 32 snapshots, ~200k-node mesh, 150k-point scan, Table 7 "
                              "at G 200 (hours on two cores). --quick (the default): minutes."),
    turbine: str = typer.Option("reference", help="Built-in turbine name or spec TOML path; "
                                "the virtual-plant stages need the reference unit's spec."),
    row: str = typer.Option("hp1", help="Blade row scanned, reconstructed and modelled by the "
                            "ROM (hp1…, ip1…)."),
    hold_hours: float = typer.Option(2.0, min=0.05, max=12.0,
                                     help="Length of the 30 % and 50 % holds (h)."),
    workers: int | None = typer.Option(None, min=1, help="Local processes (default: every "
                                       "core)."),
    seed: int = typer.Option(0, help="Seed of the plant's instruments, the scan and the GA."),
) -> None:
    """Run the twin end to end (default: the built-in 600 MW reference unit) and write the
    report.

    Scan and reconstruct the blade row (default: the first HP rotor blade) → mesh →
    virtual-plant data (30 % and 50 % holds with their ramps, and a day of load following) →
    calibration → blade ROM on the calibrated model → HP rotor stress and life over the day →
    monitoring replay of the 2-h windows →
    OUT/report.html with Tables 5–8, Figures 7–10, geometry fidelity, scan uncertainty, Sobol
    indices and noise propagation; OUT also holds the twin (Twin.load(OUT)).

    Example: steamtwin demo --out demo-output
    """
    prepare_output_folder(out, "--out")
    settings = (DemoSettings.full if full else DemoSettings.quick)(
        spec=turbine, row=row, hold_hours=hold_hours, workers=workers, random_state=seed)
    console = Console()
    with Progress(TextColumn("{task.description:<40}"), BarColumn(), TextColumn(
            "{task.percentage:>3.0f} %"), TimeElapsedColumn(), console=console) as progress:
        stages = settings.stages
        tasks: dict[str, TaskID] = {name: progress.add_task(name, total=1.0, start=False)
                                    for name in stages}

        def report(fraction: float, message: str) -> None:
            # run_demo: each stage an equal share of the run, the message led by its name
            stage = next(name for name in stages if message.startswith(name))
            done = min(max(fraction * len(stages) - stages.index(stage), 0.0), 1.0)
            task = tasks[stage]
            progress.start_task(task)
            progress.update(task, completed=done)
            if done >= 1.0:
                progress.stop_task(task)

        with _log_to(out / "demo.log"):
            result = run_demo(out, settings, progress=report)
    for message in result.warnings:
        console.print(f"warning: {message}")
    _summary(console, result)


@contextmanager
def _log_to(path: Path):
    """The libraries' log records (the live stage's OPC UA client and server: reconnections,
    their tracebacks) go to ``path`` instead of between the progress bars."""
    handler = logging.FileHandler(path, encoding="utf-8")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    root = logging.getLogger()
    root.addHandler(handler)
    try:
        yield
    finally:
        root.removeHandler(handler)
        handler.close()


def _summary(console: Console, result) -> None:  # result: steamtwin.pipeline.DemoResult
    p = result.params
    table6 = result.tables["table6_rmse"].set_index("condition")
    console.print(
        f"calibrated: flow {p.flow_coefficient:.4f}, friction {p.friction_coefficient:.3f}, "
        f"heat transfer {p.heat_transfer_coefficient:.3f}; RMSE " + "; ".join(
            f"{name}: {row.rmse_empirical_K:.2f} → {row.rmse_calibrated_K:.2f} K "
            f"(−{row.reduction_pct:.0f} %)" + (
                f", {row.rmse_delivered_K:.2f} K with the sensor offsets"
                if "rmse_delivered_K" in table6.columns else "")
            for name, row in table6.iterrows()))
    table8 = result.tables["table8_deviation"]
    for row in table8[table8["signal"] == "hp_exhaust_temperature"].itertuples(index=False):
        console.print(f"monitoring, {row.window} (day run, unseen): HP-exhaust temperature mean "
                      f"abs deviation {row.mean_abs_deviation:.2f} K, max "
                      f"{row.max_abs_deviation:.2f} K")
    rotor = result.tables.get("rotor_life_day")
    if rotor is not None:
        record = rotor.set_index("item").loc["whole record"]
        console.print(f"HP rotor over the day run: life consumed {record.total_damage:.3g} "
                      f"(fatigue {record.fatigue_damage:.3g}, creep {record.creep_damage:.3g}); "
                      f"peak groove stress {record.peak_groove_von_mises_MPa:.0f} MPa of "
                      f"{record.allowable_MPa:.0f} MPa allowed")
    total = sum(result.timings.values())
    console.print(f"report: {result.out / 'report.html'} ({total / 60:.1f} min)")
