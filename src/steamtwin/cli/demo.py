"""``steamtwin demo``: the pipeline on the built-in reference unit, as far as it exists.

Today: the full-order model (design point against the heat balance, the off-design line at
30/50/75/100 % load, a deep peak-shaving ramp with three heat-transfer settings); virtual-plant
DCS data of the 30 % and 50 % holds; calibration on both holds (surrogate-assisted by default,
the method's GA with ``--full``) with Table 6, Figure 8 and the identifiability check; the blade
ROM built on the calibrated model and replayed over the 50 % hold. Stages not built yet are
named as skipped.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd
import typer
from rich.console import Console
from rich.progress import Progress

from steamtwin.calibration import Calibrator
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.report import rmse_table, temperature_comparison_figure
from steamtwin.calibration.surrogate import SurrogateCalibrator
from steamtwin.dcs.canonical_csv import write_canonical_csv
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.dcs.signals import SIGNALS
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.build import build_rom
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.reconstruction import predict_series
from steamtwin.rom.romfile import save_rom
from steamtwin.spec import load_spec

NOT_YET_BUILT = (
    "blade scan and reconstruction (geometry)",
    "validation report (tables 5-8, figures 9-10, Sobol, noise propagation)",
)


def demo(
    out: Path = typer.Option(Path("demo-output"), help="Folder for the demo's files."),
    full: bool = typer.Option(False, "--full", help="The method's settings: GA P 50 × G 200 "
                              "instead of the surrogate, 32 ROM snapshots."),
    hold_hours: float = typer.Option(2.0, min=0.1, help="Length of the 30 % and 50 % holds (h)."),
    evaluations: int = typer.Option(150, min=40, help="Model runs of the surrogate calibration."),
    snapshots: int = typer.Option(16, min=8, help="ROM snapshots (default run; --full: 32)."),
) -> None:
    """Run the twin end to end on the built-in 600 MW reference unit.

    Example: steamtwin demo --out demo-output
    """
    console = Console()
    out.mkdir(parents=True, exist_ok=True)
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    with Progress(console=console, transient=False) as progress:
        task = progress.add_task("design point (compiles the model on first run)", total=3)
        design = model.simulate_detailed(model.design_inputs(), stages=False).diagnostics.iloc[0]
        progress.update(task, advance=1, description="off-design line 30/50/75/100 %")
        loads = [0.30, 0.50, 0.75, 1.00]
        line = pd.concat(  # each load its own run: a steady state, metal in equilibrium
            [model.simulate_detailed(load_profile_inputs(spec, [load]), stages=False).diagnostics
             for load in loads], ignore_index=True)
        line.insert(0, "load_fraction", loads)
        progress.update(task, advance=1, description="ramp 100 → 30 % at 3 %/min, 2-h hold")
        ramp_inputs = load_profile_inputs(spec, ramp_profile(1.0, 0.3, 0.03, 600.0, 7200.0))
        ramps = {
            h: model.simulate(ramp_inputs, ModelParameters(heat_transfer_coefficient=h))
            for h in (0.5, 1.0, 2.0)
        }
        progress.update(task, advance=1, description="done")
    _off_design_table(line).to_csv(out / "off_design_line.csv", index=False, float_format="%.6g")
    write_canonical_csv(ramp_inputs.join(ramps[1.0]), out / "ramp_simulation.csv")
    _plot_ramp(ramp_inputs, ramps, out / "ramp_simulation.png")
    heat_balance = spec.design
    console.print(
        "design point vs heat balance: control-stage pressure "
        f"{design.control_stage_pressure / 1e6:.3f} MPa "
        f"(spec {heat_balance.control_stage_pressure / 1e6:.3f}), HP-exhaust temperature "
        f"{design.hp_exhaust_temperature - 273.15:.2f} °C "
        f"(spec {heat_balance.hp_exhaust_temperature - 273.15:.2f}), HP power "
        f"{design.hp_power / 1e6:.2f} MW (spec {heat_balance.hp_power / 1e6:.2f})"
    )
    console.print(f"wrote {out / 'off_design_line.csv'}, {out / 'ramp_simulation.csv'}, "
                  f"{out / 'ramp_simulation.png'}")
    _plant_calibration_rom(out, spec, model, console, full=full, hold_hours=hold_hours,
                           evaluations=evaluations, snapshots=32 if full else snapshots)
    console.print("skipped (not built yet): " + "; ".join(NOT_YET_BUILT))


def _plant_calibration_rom(out: Path, spec, model: FullOrderModel, console: Console, *,
                           full: bool, hold_hours: float, evaluations: int,
                           snapshots: int) -> None:
    """Virtual-plant holds → calibration (Table 6, Figure 8) → blade ROM → replay of 50 %."""
    with Progress(console=console, transient=False) as progress:
        task = progress.add_task("virtual plant: 30 % and 50 % holds", total=4)
        holds = {}
        for load in (30, 50):
            run = run_plant(f"deep-peak-{load}", hours=hold_hours, seed=load)
            write_plant(run, out / f"plant-{load}")
            holds[f"{load} % load"] = run.measured.iloc[-round(hold_hours * 3600):]
        windows = list(holds.values())
        progress.update(task, advance=1, description="calibration" + (
            " (GA P 50 × G 200)" if full else f" (surrogate, ≤ {evaluations} model runs)"))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", IdentifiabilityWarning)
            calibrator = (Calibrator(model, population=50, generations=200) if full
                          else SurrogateCalibrator(model, max_evaluations=evaluations))
            calibrator.fit(windows)
        calibrator.save(out / "params.json")
        table6 = rmse_table(model, {name: [w] for name, w in holds.items()}, calibrator.params_)
        table6.to_csv(out / "table6_rmse.csv")
        temperature_comparison_figure(model, holds["50 % load"], calibrator.params_,
                                      out / "figure8_temperatures.png",
                                      title="Predicted vs measured, 50 % load (Figure 8)")
        calibrator.identifiability_.to_csv(out / "identifiability.csv")
        progress.update(task, advance=1,
                        description=f"blade ROM: {snapshots} snapshots on the calibrated model")
        bundle, _ = build_rom(spec, blade_volume_mesh(spec, "hp1"), calibrator.params_,
                              n_snapshots=snapshots)
        save_rom(bundle, out / "rom.npz")
        progress.update(task, advance=1, description="ROM replay of the 50 % hold")
        hold = holds["50 % load"]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)
            monitored = predict_series(bundle, hold.ffill()).sensors
        write_canonical_csv(monitored[[c for c in monitored.columns
                                       if c in SIGNALS]], out / "monitored_50.csv")
        progress.update(task, advance=1, description="done")
    p = calibrator.params_
    for warning in caught:
        console.print(f"warning: {warning.message}")
    console.print(
        f"calibrated: flow {p.flow_coefficient:.4f}, friction {p.friction_coefficient:.3f}, "
        f"heat transfer {p.heat_transfer_coefficient:.3f} ({calibrator.n_evaluations_} model "
        "runs); RMSE " + "; ".join(
            f"{name}: {row.rmse_empirical_K:.2f} → {row.rmse_calibrated_K:.2f} K"
            for name, row in table6.iterrows()))
    exhaust = (monitored["hp_exhaust_temperature"] - hold["hp_exhaust_temperature"]).abs()
    console.print(f"ROM: {bundle.rom.n_modes_} modes; HP-exhaust temperature on the 50 % hold: "
                  f"mean abs deviation {exhaust.mean():.2f} K, max {exhaust.max():.2f} K")
    console.print(f"wrote {out / 'params.json'}, {out / 'table6_rmse.csv'}, "
                  f"{out / 'figure8_temperatures.png'}, {out / 'rom.npz'}, "
                  f"{out / 'monitored_50.csv'}, plant data in {out / 'plant-30'} and "
                  f"{out / 'plant-50'}")


def _off_design_table(line: pd.DataFrame) -> pd.DataFrame:
    """The off-design line in the units engineers read (MPa, °C, MW)."""
    return pd.DataFrame({
        "load_fraction": line["load_fraction"],
        "control_stage_pressure_MPa": line["control_stage_pressure"] / 1e6,
        "control_stage_temperature_degC": line["control_stage_temperature"] - 273.15,
        "hp_exhaust_temperature_degC": line["hp_exhaust_temperature"] - 273.15,
        "hp_inner_casing_temperature_degC": line["hp_inner_casing_temperature"] - 273.15,
        "hp_power_MW": line["hp_power"] / 1e6,
        "control_stage_efficiency": line["control_stage_efficiency"],
        "active_admission_arc": line["active_admission_arc"],
    })


def _plot_ramp(inputs: pd.DataFrame, runs: dict[float, pd.DataFrame], path: Path) -> None:
    minutes = (inputs.index - inputs.index[0]).total_seconds() / 60.0
    figure, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    axes[0].plot(minutes, inputs["main_steam_flow"] * 3.6, color="black")
    axes[0].set_ylabel("main-steam flow (t/h)")
    for multiplier, outputs in runs.items():
        label = f"heat-transfer coefficient × {multiplier:g}"
        axes[1].plot(minutes, outputs["hp_exhaust_temperature"] - 273.15, label=label)
        axes[2].plot(minutes, outputs["hp_inner_casing_temperature"] - 273.15, label=label)
    axes[1].set_ylabel("HP-exhaust steam (°C)")
    axes[2].set_ylabel("inner-casing metal (°C)")
    axes[2].set_xlabel("time (min)")
    axes[2].legend()
    figure.suptitle("Reference unit: ramp 100 % → 30 % load at 3 %/min (full-order model)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
