"""Benchmark: one full-order simulation of a 2-hour, 1-second window (7 200 samples).

Run: python benchmarks/bench_fom.py — prints the median wall time of the model call (kernel plus
input checks) for a steady hold, a deep peak-shaving ramp, that ramp with DCS-like noise on
every input, and the virtual plant's recorded 2-h hold at 30 % load (what calibration
evaluates), on one core, after a warm-up call (compilation and table building excluded; they
are reported separately).
"""

from __future__ import annotations

import os
import platform
import statistics
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np

from steamtwin.dcs.plant import run_plant
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.spec import load_spec

SAMPLES = 7200
REPEATS = 7


def main() -> None:
    start = time.perf_counter()
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    _ = model.design_
    setup = time.perf_counter() - start
    cases = {
        "hold at 50 % load": np.full(SAMPLES, 0.5),
        "ramp 100 → 30 % at 5 %/min + hold": ramp_profile(1.0, 0.3, 0.05, 600.0,
                                                         SAMPLES - 600.0 - 840.0 - 1.0),
    }
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    print(f"setup (spec, steam tables, kernel compile/cache load, design step): {setup:.1f} s")
    noisy = load_profile_inputs(spec, cases["ramp 100 → 30 % at 5 %/min + hold"][:SAMPLES])
    random = np.random.default_rng(7)
    noise = {"main_steam_pressure": 0.001 * 16.7e6, "main_steam_temperature": 1.0,
             "main_steam_flow": 0.005 * 500.0, "hp_exhaust_pressure": 0.001 * 3.9e6}
    for column, sigma in noise.items():  # DCS-like sensor noise on every input
        noisy[column] += random.normal(0.0, sigma, len(noisy))
    frames = {name: load_profile_inputs(spec, load[:SAMPLES]) for name, load in cases.items()}
    frames["same ramp with sensor noise on every input"] = noisy
    # what the GA evaluates: the virtual plant's 2-h hold at 30 % load as its DCS recorded it
    frames["deep-peak-30 hold as recorded (virtual plant, seed 0)"] = run_plant(
        "deep-peak-30", random_state=0).measured.iloc[-SAMPLES:]
    for name, frame in frames.items():
        diagnostics = model.simulate_detailed(frame, stages=False).diagnostics
        times = []
        for _ in range(REPEATS):
            tick = time.perf_counter()
            model.simulate(frame)
            times.append(time.perf_counter() - tick)
        print(f"{name}: {len(frame)} samples, median {statistics.median(times) * 1e3:.1f} ms, "
              f"min {min(times) * 1e3:.1f} ms, sweeps/sample "
              f"{diagnostics['iterations'].mean():.2f}")


if __name__ == "__main__":
    main()
