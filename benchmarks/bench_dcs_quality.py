"""Benchmark: data-quality check and cleaning of 24 h × 1 s × 50 columns (4.3 M values).

Run: python benchmarks/bench_dcs_quality.py — builds synthetic, plausible historian data of a
600 MW unit in peak-shaving operation (9 canonical signals + 41 auxiliary measurements, sensor
noise, a few injected faults: spikes, a stuck run, NaN, out-of-range values, duplicate and
unsorted rows, a gap) and prints the median wall time of check_quality and clean.
"""

from __future__ import annotations

import os
import platform
import statistics
import time

import numpy as np
import pandas as pd

from steamtwin.dcs.quality import QualityOptions, check_quality, clean

SECONDS = 86_400
COLUMNS = 50
REPEATS = 3


def synthetic_day(seed: int = 1) -> tuple[pd.DataFrame, dict[str, tuple[float, float]]]:
    """One day at 1 s in SI, with injected faults; returns the frame and physical ranges."""
    rng = np.random.default_rng(seed)
    t = np.arange(SECONDS, dtype=float)
    # 100 % → 30 % → 100 % twice a day at ~1.5 %/min
    share = np.interp(t, [0, 20e3, 22.8e3, 40e3, 42.8e3, 60e3, 62.8e3, 75e3, 77.8e3, SECONDS],
                      [1.0, 1.0, 0.3, 0.3, 1.0, 1.0, 0.3, 0.3, 1.0, 1.0])
    base = {
        "main_steam_pressure": (16.7e6 * (0.45 + 0.55 * share), 2e4),
        "main_steam_temperature": (811.0 - 10.0 * (1 - share), 0.4),
        "main_steam_flow": (500.0 * share, 1.0),
        "control_stage_pressure": (13.0e6 * share, 2e4),
        "control_stage_temperature": (765.0 - 40.0 * (1 - share), 0.4),
        "hp_exhaust_pressure": (3.9e6 * share, 5e3),
        "hp_exhaust_temperature": (600.0 + 20.0 * (1 - share), 0.4),
        "hp_inner_casing_temperature": (760.0 - 30.0 * (1 - share), 0.1),
        "load": (600e6 * share, 3e5),
    }
    data = {name: level + rng.normal(0.0, sigma, SECONDS) for name, (level, sigma) in base.items()}
    for k in range(COLUMNS - len(base)):
        data[f"aux_{k:02d}"] = 100.0 + 50.0 * share + rng.normal(0.0, 0.5, SECONDS)
    frame = pd.DataFrame(data, index=pd.date_range("2024-03-01", periods=SECONDS, freq="1s",
                                                   tz="Asia/Shanghai"))
    values = frame.to_numpy(copy=True)
    values[rng.integers(0, SECONDS, 200), rng.integers(0, COLUMNS, 200)] *= 1.2  # spikes
    frame = pd.DataFrame(values, index=frame.index, columns=frame.columns)
    frame.iloc[30_000:31_500, 3] = frame.iloc[30_000, 3]  # 25 min stuck
    frame.iloc[50_000:50_300, 5] = np.nan
    frame.iloc[60_000:60_010, 0] = -1.0e6  # sensor fault value, out of range
    frame = frame.drop(frame.index[70_000:70_100])  # 100 s gap
    frame = pd.concat([frame.iloc[:1000], frame.iloc[990:1000], frame.iloc[1000:]])  # duplicates
    swapped = frame.index.to_numpy().copy()
    swapped[[5000, 5001]] = swapped[[5001, 5000]]  # unsorted pair
    frame.index = pd.DatetimeIndex(swapped)
    ranges = {"main_steam_pressure": (0.0, 25e6), "load": (-5e6, 700e6)}
    return frame, ranges


def main() -> None:
    frame, ranges = synthetic_day()
    options = QualityOptions(ranges=ranges, source="bench")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    print(f"frame: {frame.shape[0]} rows × {frame.shape[1]} columns = {frame.size / 1e6:.2f} M "
          "values")
    for name, call in (
        ("check_quality", lambda: check_quality(frame, options)),
        ("clean", lambda: clean(frame, options)),
    ):
        times = []
        for _ in range(REPEATS):
            tick = time.perf_counter()
            result = call()
            times.append(time.perf_counter() - tick)
        report = result if name == "check_quality" else result.report
        print(f"{name}: median {statistics.median(times):.2f} s, min {min(times):.2f} s "
              f"({len(report.findings)} findings, {len(report.errors)} errors)")
    print(check_quality(frame, options).to_text())


if __name__ == "__main__":
    main()
