"""Benchmark: stuck/spike detection and false findings of the quality check on the virtual plant.

Run: python benchmarks/bench_quality_detection.py [--draws 10] [--hours 24] — runs the virtual
plant's ``day`` scenario once (true signals), then records it through the project's instrument
model (:func:`steamtwin.dcs.sensors.measure`, :func:`default_sensor_models`) with ``--draws``
different instrument seeds and, per draw:

* clean data (faults off): false spike and stuck findings (samples) per signal-day;
* stuck episodes of exactly 60 s and 120 s (1 per signal-hour, nothing else injected; those
  cut short by the end of the record are left out): share of episodes whose every sample is
  flagged STUCK;
* one-sample spikes of exactly A·σ (σ = the instrument's white-noise σ; A = 4 … 8; 2 per
  signal-hour): share found (SPIKE on the injected sample), against the white-noise
  expectation Φ(A/1.013 − 4.5) for k = 4.5;
* whether the noise the detector sees is white: the estimated σ and quantum against the
  instrument model's, and the lag-1 autocorrelation of the departures from the 61-sample
  rolling median (about −1/60 for white noise).

Prints Markdown tables; the figures of a run are recorded in docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np
import pandas as pd
from scipy.ndimage import median_filter
from scipy.special import ndtr

from steamtwin.dcs.plant import KKS_TAGS, run_plant
from steamtwin.dcs.quality import (
    Flag,
    check_quality,
    clean,
    estimate_noise_sigma,
    estimate_resolution,
)
from steamtwin.dcs.sensors import FaultConfig, default_sensor_models, measure

AMPLITUDES = (4.0, 5.0, 6.0, 7.0, 8.0)
STUCK_SECONDS = (60.0, 120.0)
N_SIGMAS = 4.5


def spikes_only(amplitude: float) -> FaultConfig:
    """One-sample spikes of exactly ``amplitude``·σ, 2 per signal-hour, nothing else."""
    return FaultConfig(dropout_rate_per_h=0.0, spike_rate_per_h=2.0, spike_min_sigmas=amplitude,
                       spike_min_span_fraction=0.0, spike_max_span_fraction=0.0)


def stuck_only(seconds: float) -> FaultConfig:
    """Stuck episodes of exactly ``seconds`` at 1 s, 1 per signal-hour, nothing else."""
    return FaultConfig(dropout_rate_per_h=0.0, spike_rate_per_h=0.0, stuck_rate_per_h=1.0,
                       stuck_median_s=seconds, stuck_sigma_ln=0.0, stuck_max_s=seconds)


def flagged(true: pd.DataFrame, seed: int, faults: FaultConfig,
            ) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Measured frame, its cleaning flags and the injected faults of one instrument draw."""
    record = measure(true, default_sensor_models(), np.random.default_rng(seed), faults=faults)
    return record.measured, clean(record.measured).flags, record.injected.faults


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=10, help="instrument seeds (default 10)")
    parser.add_argument("--hours", type=float, default=24.0,
                        help="hours of the day scenario used (default 24)")
    arguments = parser.parse_args()
    if arguments.draws < 1 or not 0.0 < arguments.hours <= 24.0:
        parser.error("--draws ≥ 1 and 0 < --hours ≤ 24")

    begin = time.perf_counter()
    run = run_plant("day", random_state=0)
    true = run.true_inputs.join(run.true_outputs)[list(KKS_TAGS)]
    true = true.iloc[: round(arguments.hours * 3600) + 1]
    signals = list(true.columns)
    days = (len(true) - 1) / 86400.0
    models = default_sensor_models()

    false_spikes = {name: 0 for name in signals}
    false_stuck = {name: 0 for name in signals}
    sigma_ratio = {name: [] for name in signals}
    quantum_ratio = {name: [] for name in signals}
    lag1 = {name: [] for name in signals}
    found = {a: [0, 0] for a in AMPLITUDES}
    found_by_signal = {a: {name: [0, 0] for name in signals} for a in AMPLITUDES}
    spike_false = {a: 0 for a in AMPLITUDES}
    stuck_found = {s: [0, 0] for s in STUCK_SECONDS}
    for draw in range(arguments.draws):
        measured, flags, _ = flagged(true, draw, FaultConfig.off())
        report = check_quality(measured)
        for finding in report.findings:
            if finding.kind == "spike":
                false_spikes[str(finding.signal)] += finding.count
            if finding.kind == "stuck":
                false_stuck[str(finding.signal)] += finding.count
        for name in signals:
            x = measured[name].to_numpy()
            model = models[name]
            quantum = estimate_resolution(x)
            sigma_ratio[name].append(estimate_noise_sigma(x, quantum) / model.noise_sigma)
            quantum_ratio[name].append(quantum / model.resolution)
            residual = x - median_filter(x, size=61, mode="nearest")
            lag1[name].append(float(np.corrcoef(residual[:-1], residual[1:])[0, 1]))
        for amplitude in AMPLITUDES:
            _, flags, faults = flagged(true, draw, spikes_only(amplitude))
            injected = np.zeros(flags.shape, dtype=bool)
            for event in faults.itertuples():
                j = signals.index(event.signal)
                injected[event.start_row, j] = True
                hit = bool(flags.iloc[event.start_row, j] & int(Flag.SPIKE))
                found[amplitude][0] += hit
                found[amplitude][1] += 1
                found_by_signal[amplitude][event.signal][0] += hit
                found_by_signal[amplitude][event.signal][1] += 1
            spike = (flags.to_numpy() & int(Flag.SPIKE)).astype(bool)
            spike_false[amplitude] += int((spike & ~injected).sum())
        for seconds in STUCK_SECONDS:
            _, flags, faults = flagged(true, draw, stuck_only(seconds))
            for event in faults.itertuples():
                if event.n_samples < seconds:  # cut short by the end of the record
                    continue
                rows = flags[event.signal].to_numpy()[event.start_row:event.end_row + 1]
                stuck_found[seconds][0] += bool((rows & int(Flag.STUCK)).all())
                stuck_found[seconds][1] += 1
    wall = time.perf_counter() - begin

    signal_days = days * arguments.draws
    print(f"# Quality detection on the virtual plant: {arguments.draws} draws × {days:g} day(s) "
          f"of 1-s data, {platform.machine()}, {wall:.0f} s wall\n")
    print("## Clean data (faults off): false findings per signal-day, and the noise seen\n")
    print("| signal | false spikes / day | false stuck samples / day | σ est. / σ model | "
          "quantum est. / model | lag-1 autocorr. of departures |")
    print("|---|---|---|---|---|---|")
    for name in signals:
        print(f"| {name} | {false_spikes[name] / signal_days:.2f} | "
              f"{false_stuck[name] / signal_days:.2f} | {np.mean(sigma_ratio[name]):.3f} | "
              f"{np.mean(quantum_ratio[name]):.3f} | {np.mean(lag1[name]):+.3f} |")
    total = sum(false_spikes.values()) / (signal_days * len(signals))
    print(f"\nAll signals: {total:.2f} false spikes and "
          f"{sum(false_stuck.values()) / (signal_days * len(signals)):.2f} false stuck samples "
          "per signal-day.\n")
    print("## One-sample spikes of A·σ: share found (k = 4.5)\n")
    print("| A | found | share | worst signal | white-noise expectation Φ(A/1.013 − 4.5) | "
          "false spikes / signal-day in these runs |")
    print("|---|---|---|---|---|---|")
    for amplitude in AMPLITUDES:
        hits, count = found[amplitude]
        worst = min(signals, key=lambda n: found_by_signal[amplitude][n][0]
                    / max(found_by_signal[amplitude][n][1], 1))
        w_hits, w_count = found_by_signal[amplitude][worst]
        expect = float(ndtr(amplitude / 1.013 - N_SIGMAS))
        print(f"| {amplitude:g} | {hits} / {count} | {hits / max(count, 1):.3f} | {worst} "
              f"{w_hits / max(w_count, 1):.3f} | {expect:.3f} | "
              f"{spike_false[amplitude] / (signal_days * len(signals)):.2f} |")
    reach = 1.013 * (N_SIGMAS + 1.6449)  # Φ⁻¹(0.95) = 1.6449
    print(f"\nWhite noise reaches 95 % at A ≈ {reach:.2f} (k = 4.5).\n")
    print("## Stuck episodes: share with every sample flagged STUCK\n")
    print("| duration | found | share |")
    print("|---|---|---|")
    for seconds in STUCK_SECONDS:
        hits, count = stuck_found[seconds]
        print(f"| {seconds:g} s | {hits} / {count} | {hits / max(count, 1):.3f} |")


if __name__ == "__main__":
    main()
