"""Benchmark: how far the twin sits from the virtual plant, before and after the plant grew its
own physics (issue 18, item 8: tip leakage, valve overlap, boiler schedule, thermocouple depth,
rotor with a bore).

Run: python benchmarks/bench_plant_realism.py [--quick] — for the simple plant
(``PlantTruth.simple()``: gland leakage only) and today's plant (``PlantTruth()``):

1. steady states at 30/50/75/100 % without instruments: the twin (reference spec) fed the
   plant's measured inputs, its control-stage pressure (%), control-stage and HP-exhaust
   temperatures (K) minus the plant's, with the empirical constants (1, 1, 1), with the
   twin-equivalent parameters (noise-free joint fit over the four loads) and with a noise-free
   fit of flow and friction coefficients at that load alone (what the twin's structure leaves);
2. a quick GA calibration (P 20 × G 20; ``--quick``: P 10 × G 10) on each 2-h deep-peak hold
   (30 %, 50 %) as the DCS recorded it: RMSE before/after, flow coefficient against the
   twin-equivalent truth, and the calibrated twin's steady deviations at the four loads.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
import warnings
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.dcs.plant import run_plant
from steamtwin.dcs.plant_model import TWIN_EQUIVALENT_LOADS, PlantTruth, plant_steady_states
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import load_spec

LOADS = TWIN_EQUIVALENT_LOADS


def _deviations(twin: FullOrderModel, states: pd.DataFrame, params: ModelParameters
                ) -> pd.DataFrame:
    """Twin minus plant at each steady state: p1 in %, T1 and T_exhaust in K."""
    rows = {}
    for load in states.index:
        frame = states.loc[[load], list(INPUT_SIGNALS)].set_axis(pd.to_datetime(["2026-03-01"]))
        twin_row = twin.simulate(frame, params).iloc[0]
        plant = states.loc[load]
        rows[load] = {
            "p1 %": 100.0 * (twin_row["control_stage_pressure"]
                             / plant["control_stage_pressure"] - 1.0),
            "T1 K": twin_row["control_stage_temperature"] - plant["control_stage_temperature"],
            "Texh K": twin_row["hp_exhaust_temperature"] - plant["hp_exhaust_temperature"],
        }
    return pd.DataFrame(rows).T


def _fit_at(twin: FullOrderModel, states: pd.DataFrame, load: float, start: ModelParameters
            ) -> ModelParameters:
    """Noise-free fit of flow and friction coefficients at one steady state."""
    def residuals(x: np.ndarray) -> np.ndarray:
        params = replace(start, flow_coefficient=float(x[0]), friction_coefficient=float(x[1]))
        d = _deviations(twin, states.loc[[load]], params).iloc[0]
        return np.array([d["p1 %"] / 0.1, d["T1 K"] / 0.5, d["Texh K"] / 0.5])

    fit = least_squares(residuals, [start.flow_coefficient, start.friction_coefficient],
                        bounds=([0.9, 0.5], [1.1, 2.0]), diff_step=1e-4)
    return replace(start, flow_coefficient=float(fit.x[0]), friction_coefficient=float(fit.x[1]))


def _table(title: str, frames: dict[str, pd.DataFrame]) -> None:
    print(f"\n{title}")
    print("| load | " + " | ".join(f"{name}: p1 % / T1 K / Texh K" for name in frames) + " |")
    print("|---|" + "---|" * len(frames))
    for load in LOADS:
        cells = [" / ".join(f"{frame.loc[load, c]:+.2f}" for c in ("p1 %", "T1 K", "Texh K"))
                 for frame in frames.values()]
        print(f"| {load:.0%} | " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    arguments = parser.parse_args()
    population, generations = (10, 10) if arguments.quick else (20, 20)
    warnings.simplefilter("ignore", IdentifiabilityWarning)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; GA P = {population}, G = {generations}")
    twin = FullOrderModel(load_spec("reference"))
    plants = {"simple plant": PlantTruth.simple(), "plant": PlantTruth()}
    for name, truth in plants.items():
        start = time.perf_counter()
        states = plant_steady_states(LOADS, truth)
        equivalent = truth.twin_equivalent
        print(f"\n## {name}: twin-equivalent flow {equivalent.flow_coefficient:.4f}, friction "
              f"{equivalent.friction_coefficient:.3f} ({time.perf_counter() - start:.0f} s)")
        per_load = pd.concat([_deviations(twin, states.loc[[load]],
                                          _fit_at(twin, states, load, equivalent))
                              for load in LOADS])
        _table("steady states, twin − plant", {
            "empirical (1, 1, 1)": _deviations(twin, states, ModelParameters()),
            "twin-equivalent": _deviations(twin, states, equivalent),
            "fitted per load": per_load})
        calibrated = {}
        for scenario in ("deep-peak-30", "deep-peak-50"):
            hold = run_plant(scenario, random_state=0, truth=truth).measured.iloc[-7200:]
            start = time.perf_counter()
            ga = Calibrator(twin, search=GeneticSearch(population=population,
                                                       generations=generations)).fit([hold])
            p = calibrated[scenario] = ga.params_
            print(f"\n{scenario} hold: RMSE {ga.rmse([hold]):.3f} → {ga.rmse_:.3f} K, flow "
                  f"{p.flow_coefficient:.4f} (twin-equivalent {equivalent.flow_coefficient:.4f}),"
                  f" friction {p.friction_coefficient:.3f}, heat transfer "
                  f"{p.heat_transfer_coefficient:.3f} ({time.perf_counter() - start:.0f} s)")
        _table("steady states, twin calibrated on each hold − plant",
               {f"on {scenario}": _deviations(twin, states, params)
                for scenario, params in calibrated.items()})


if __name__ == "__main__":
    main()
