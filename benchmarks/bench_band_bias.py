"""Benchmark: where the twin's steady bias against the virtual plant sits, load by load.

Run: python benchmarks/bench_band_bias.py [--step 0.025 | --loads L ...] [--features]

Noise-free steady states of the virtual plant (:func:`~steamtwin.dcs.plant_model.
plant_steady_states`, loads 30 … 100 %) against the twin fed the plant's measured inputs at the
plant's twin-equivalent parameters: per output signal, twin − plant in units of that signal's
instrument error (RMS of a class-1 instrument's error: the rectangular bias ±tol, tol/√3, and
its noise σ in quadrature — what a perfect model scores against the DCS; ``dcs.sensors``).
``--features`` repeats the table with each of the plant's structural features (issue 18 item 8)
switched off in turn, so the feature behind a load band's bias shows as the one whose removal
takes it away. The twin is the reference spec's, as :attr:`PlantTruth.twin_equivalent` fits it.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import time
from dataclasses import replace

import numpy as np
import pandas as pd

from steamtwin.dcs.plant_model import (
    START,
    PlantTruth,
    plant_steady_states,
    twin_equivalent_parameters,
)
from steamtwin.dcs.sensors import default_sensor_models
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import load_spec

SIGNALS = ("control_stage_pressure", "control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature")
SHORT = {"control_stage_pressure": "p1", "control_stage_temperature": "T1",
         "hp_exhaust_temperature": "Texh", "hp_inner_casing_temperature": "Tcas"}


def instrument_error(name: str, value: float) -> float:
    """RMS error (SI) of the DCS instrument of ``name`` at ``value``: bias uniform in ±tol
    (IEC 60584-1 / transmitter class, ``dcs.sensors``) and noise σ in quadrature."""
    model = default_sensor_models()[name]
    tol = float(model.tolerance(np.array([value]))[0])
    return float(np.hypot(tol / np.sqrt(3.0), model.noise_sigma))


def deviations(truth: PlantTruth, loads: tuple[float, ...]
               ) -> tuple[pd.DataFrame, ModelParameters]:
    """Twin − plant per load and signal, in instrument errors; and the parameters used."""
    states = plant_steady_states(loads, truth)
    params = twin_equivalent_parameters(replace(truth, drift=None))
    twin = FullOrderModel(load_spec("reference"))
    rows = {}
    for load in states.index:
        frame = states.loc[[load], list(INPUT_SIGNALS)].set_axis(pd.to_datetime([START]))
        out = twin.simulate(frame, params).iloc[0]
        rows[load] = {SHORT[s]: (out[s] - states.loc[load, s])
                      / instrument_error(s, float(states.loc[load, s])) for s in SIGNALS}
    return pd.DataFrame(rows).T.rename_axis("load"), params


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--step", type=float, default=0.025)
    parser.add_argument("--features", action="store_true")
    parser.add_argument("--loads", type=float, nargs="+",
                        help="load fractions instead of 0.30 … 1.00 by --step")
    arguments = parser.parse_args()
    loads = tuple(arguments.loads or np.round(np.arange(0.30, 1.0 + 1e-9, arguments.step), 4))
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; load average {os.getloadavg()[0]:.1f}")
    cases = {"plant": PlantTruth()}
    if arguments.features:
        cases |= {
            "no overlap": replace(PlantTruth(), valve_overlap=0.0),
            "no tip leakage": replace(PlantTruth(), tip_clearances=(0.0,)),
            "no boiler schedule": replace(PlantTruth(), main_steam_schedule=None,
                                          reheat_schedule=None),
            "simple": PlantTruth.simple(),
        }
    for label, truth in cases.items():
        wall, cpu = time.perf_counter(), time.process_time()
        table, params = deviations(truth, loads)
        print(f"\n{label}: twin − plant / instrument error at twin-equivalent φ "
              f"{params.flow_coefficient:.4f}, friction {params.friction_coefficient:.3f} "
              f"({time.perf_counter() - wall:.0f} s wall, {time.process_time() - cpu:.0f} s CPU)")
        print(table.to_string(float_format=lambda v: f"{v:+.2f}"))
        band = table[(table.index >= 0.8) & (table.index < 0.9)]
        print("80–90 % band mean: " + ", ".join(f"{c} {band[c].mean():+.2f}" for c in table))
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print(f"\nCPU {usage.ru_utime + usage.ru_stime:.0f} s; load average "
          f"{os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
