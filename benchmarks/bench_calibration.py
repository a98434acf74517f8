"""Benchmark: the method's GA (P = 50, G = 200) and the surrogate mode on the virtual plant.

Run: python benchmarks/bench_calibration.py [--quick] [--scenario NAME ...] — for each of the
deep-peak-30 and deep-peak-50 scenarios (or those named), on the 2-h, 1-s hold as the DCS
recorded it:

* wall time of the full GA on the local process pool (every core), model evaluations;
* RMSE with the empirical constants (1, 1, 1) and calibrated, the reduction in %;
* the instruments' own error on that window (RMS of measured − true temperature, pooled over
  the three sensors: bias, noise, lag, quantisation) — a perfect model cannot beat it — and the
  calibrated RMSE as a multiple of it;
* the calibrated parameters against the plant's twin-equivalent truth, and the identifiability
  check's verdict per parameter;
* the surrogate mode's RMSE and model evaluations against the full GA's;
* on data the calibration has not seen: each calibrated set on the same hold recorded with
  other instruments' draws (seed 1: other biases, noise) and on the other scenario's hold.

``--quick`` runs P = 20, G = 20 to check the script. ``--draws SEED ...`` instead calibrates
(P = 30, G = 40) on each hold as recorded by instruments drawn with each seed — other
thermocouple biases — and prints the biases, the RMSE before and after, the instrument error
and the flow coefficient per draw.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
import warnings

import numpy as np
import pandas as pd

from steamtwin.calibration import Calibrator, GeneticSearch, SurrogateSearch
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.settings import DEFAULT_SENSORS
from steamtwin.dcs.plant import run_plant
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import load_spec


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--scenario", nargs="+", default=["deep-peak-30", "deep-peak-50"])
    parser.add_argument("--draws", nargs="+", type=int, metavar="SEED",
                        help="only the per-draw table, for these instrument seeds")
    arguments = parser.parse_args()
    if arguments.draws:
        instrument_draws(arguments.scenario, arguments.draws)
        return
    population, generations = (20, 20) if arguments.quick else (50, 200)
    warnings.simplefilter("ignore", IdentifiabilityWarning)
    model = FullOrderModel(load_spec("reference"))
    _ = model.design_
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; GA P = {population}, G = {generations}")
    calibrated: dict[str, ModelParameters] = {}
    unseen: dict[str, pd.DataFrame] = {}
    unseen_floor: dict[str, float] = {}
    for scenario in arguments.scenario:
        run = run_plant(scenario, random_state=0)
        hold = run.measured.iloc[-7200:]
        other = run_plant(scenario, random_state=1)
        unseen[scenario] = other.measured.iloc[-7200:]
        unseen_floor[scenario] = _instrument_error(unseen[scenario], other.true_outputs)
        instrument = _instrument_error(hold, run.true_outputs)
        start = time.perf_counter()
        ga = Calibrator(model, search=GeneticSearch(population=population,
                                                    generations=generations)).fit([hold])
        ga_time = time.perf_counter() - start
        before = ga.rmse([hold])
        start = time.perf_counter()
        surrogate = Calibrator(model, search=SurrogateSearch(max_evaluations=min(
            1000, ga.n_evaluations_ // 10))).fit([hold])
        surrogate_time = time.perf_counter() - start
        truth = run.truth.twin_equivalent
        p = calibrated[scenario] = ga.params_
        print(f"\n{scenario}, 2-h hold ({len(hold)} samples)")
        print(f"  full GA: {ga_time:.0f} s wall, {ga.n_evaluations_} evaluations "
              f"({ga_time / ga.n_evaluations_ * 1e3:.0f} ms each on the pool)")
        print(f"  RMSE empirical {before:.3f} K → calibrated {ga.rmse_:.3f} K "
              f"(−{100 * (1 - ga.rmse_ / before):.1f} %)")
        print(f"  instrument error on the window {instrument:.3f} K; calibrated RMSE = "
              f"{ga.rmse_ / instrument:.2f} × it")
        print(f"  parameters: flow {p.flow_coefficient:.4f} (twin-equivalent truth "
              f"{truth.flow_coefficient:.4f}), friction {p.friction_coefficient:.3f} "
              f"({truth.friction_coefficient}), heat transfer {p.heat_transfer_coefficient:.3f} "
              f"({truth.heat_transfer_coefficient})")
        verdict = ga.identifiability_["identifiable"]
        print("  identifiable: " + ", ".join(f"{name} {'yes' if ok else 'no'}"
                                             for name, ok in verdict.items()))
        print(f"  surrogate: RMSE {surrogate.rmse_:.3f} K with {surrogate.n_evaluations_} model "
              f"runs ({100 * surrogate.n_evaluations_ / ga.n_evaluations_:.1f} % of the GA's), "
              f"{surrogate_time:.0f} s; difference {surrogate.rmse_ - ga.rmse_:+.3f} K")
    print("\nOn data the calibration has not seen (2-h holds, instruments seed 1):")
    for source, params in calibrated.items():
        for target, window in unseen.items():
            before, after = (Calibrator(model).rmse([window], candidate)
                             for candidate in (None, params))
            print(f"  calibrated on {source} (seed 0) → {target}: RMSE empirical {before:.3f} K "
                  f"→ calibrated {after:.3f} K (−{100 * (1 - after / before):.1f} %; instrument "
                  f"error {unseen_floor[target]:.3f} K)")


def instrument_draws(scenarios: list[str], seeds: list[int]) -> None:
    """Calibrate (P = 30, G = 40) on each hold as recorded with each instrument seed."""
    warnings.simplefilter("ignore", IdentifiabilityWarning)
    model = FullOrderModel(load_spec("reference"))
    print("| hold, instruments seed | thermocouple biases (K) | empirical → calibrated "
          "| instrument error | calibrated / instrument | flow coefficient |")
    print("|---|---|---|---|---|---|")
    for scenario in scenarios:
        for seed in seeds:
            run = run_plant(scenario, random_state=seed)
            hold = run.measured.iloc[-7200:]
            true = run.true_outputs.loc[hold.index]
            biases = " / ".join(f"{float(np.nanmean(hold[s] - true[s])):+.2f}"
                                for s in DEFAULT_SENSORS)
            ga = Calibrator(model, search=GeneticSearch(population=30, generations=40)).fit(
                [hold])
            before, floor = ga.rmse([hold]), _instrument_error(hold, run.true_outputs)
            print(f"| {scenario}, {seed} | {biases} | {before:.3f} → {ga.rmse_:.3f} K "
                  f"(−{100 * (1 - ga.rmse_ / before):.0f} %) | {floor:.2f} K "
                  f"| {ga.rmse_ / floor:.2f} | {ga.params_.flow_coefficient:.4f} "
                  f"(truth {run.truth.twin_equivalent.flow_coefficient:.4f}) |", flush=True)


def _instrument_error(window: pd.DataFrame, true_outputs: pd.DataFrame) -> float:
    """RMS (K) of measured − true temperature over the default sensors on ``window``."""
    true = true_outputs.loc[window.index]
    return float(np.sqrt(np.nanmean(np.concatenate(
        [(window[s] - true[s]).to_numpy() ** 2 for s in DEFAULT_SENSORS]))))


if __name__ == "__main__":
    main()
