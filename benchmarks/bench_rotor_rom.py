"""Benchmark of the rotor conduction ROM (steamtwin.rotor.transient_rom) against its full order.

Run: python benchmarks/bench_rotor_rom.py [--nr 20 --nz 16] [--skip-day-fom] — prints

1. the fit on the test section of tests/rotor/rotor_section.py (axisymmetric rectangle, three
   steam groups on the rim, CrMoV-like k(T), c(T) at 700/760/820 K) trained on 100 → 30 % → 100 %
   ramps at 2 and 8 %/min at Δt = 1 s: modes, training error, wall and CPU time;
2. the error at the four critical nodes (K) and of the rim thermal stress (% of its range) on
   loads it was not trained on: a 5 %/min ramp and a 24-h peak-shaving day at 1 s, against the
   full-order implicit-Euler run (whose 24-h time is reported too);
3. the batch run of the 24-h record (86 400 steps) and the streaming step (mean of 20 000 calls),
   wall and CPU time, and the batch time per step at r = 10, 20, 40 modes.
Timing figures depend on the machine's load: the script prints `uptime`'s load average.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "rotor"))
from rotor_section import (
    BORE,
    RIM,
    Section,
    peak_shaving_day,
    ramp,
    steam_history,
    surface_stress_operator,
)

from steamtwin.rotor.transient_rom import ConductionRom, full_order_run

REFERENCES = (700.0, 760.0, 820.0)


def timed(function, *args, **kwargs):
    wall, cpu = time.perf_counter(), time.process_time()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - wall, time.process_time() - cpu


def errors(rom, operators, history, critical, stress, fom=None):
    if fom is None:
        fom, wall, cpu = timed(full_order_run, operators, history,
                               reference_temperatures=REFERENCES)
    else:
        wall = cpu = float("nan")
    run = rom.simulate(history)
    reference = fom[1:] @ stress.T
    temperature = np.abs(run.temperature - fom[1:, critical]).max()
    stress_error = (np.abs(run.output - reference).max(axis=0) / np.ptp(reference, axis=0)).max()
    return temperature, 100 * stress_error, wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nr", type=int, default=20)
    parser.add_argument("--nz", type=int, default=16)
    parser.add_argument("--skip-day-fom", action="store_true",
                        help="skip the 24-h full-order run (the longest part)")
    args = parser.parse_args()
    print(f"{platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, load {os.getloadavg()}")
    section = Section(args.nr, args.nz)
    operators = [section.operators(t) for t in REFERENCES]
    critical = [section.node(RIM, 0.05), section.node(RIM, 0.15), section.node(BORE, 0.15),
                section.node(0.2, 0.05)]
    stress = surface_stress_operator(section, critical[:2])
    training = [steam_history(ramp(rate, 1.0), 1.0) for rate in (2.0, 8.0)]
    rom, wall, cpu = timed(ConductionRom().fit, operators, training,
                           reference_temperatures=REFERENCES, temperature_nodes=critical,
                           output_operator=stress)
    print(f"fit: {section.basis.N} nodes, {sum(h.steps for h in training)} training steps → "
          f"{rom.n_modes_} modes, training error {rom.training_error_:.2e} K; "
          f"{wall:.1f} s wall, {cpu:.1f} s CPU")

    ramp5 = steam_history(ramp(5.0, 1.0), 1.0)
    t_err, s_err, wall, cpu = errors(rom, operators, ramp5, critical, stress)
    print(f"5 %/min ramp ({ramp5.steps} s): max error {t_err:.2e} K, stress {s_err:.3f} % of "
          f"range; full order {wall:.1f} s wall, {cpu:.1f} s CPU")
    day = steam_history(peak_shaving_day(1.0, random_state=7), 1.0)
    if not args.skip_day_fom:
        t_err, s_err, wall, cpu = errors(rom, operators, day, critical, stress)
        print(f"24-h day at 1 s: max error {t_err:.2e} K, stress {s_err:.3f} % of range; "
              f"full order {wall:.1f} s wall, {cpu:.1f} s CPU")

    rom.simulate(day)  # compiled kernels loaded
    _, wall, cpu = timed(rom.simulate, day)
    print(f"batch 24 h ({day.steps} steps, r = {rom.n_modes_}): {wall:.3f} s wall, "
          f"{cpu:.3f} s CPU")
    state = rom.initial_state(day.htc[0], day.steam_temperature[0])
    state = rom.step(state, day.htc[0], day.steam_temperature[0], 1.0)
    calls = 20_000
    wall, cpu = time.perf_counter(), time.process_time()
    for k in range(calls):
        state = rom.step(state, day.htc[k], day.steam_temperature[k], 1.0)
    print(f"streaming step: {(time.perf_counter() - wall) / calls * 1e6:.1f} µs wall, "
          f"{(time.process_time() - cpu) / calls * 1e6:.1f} µs CPU")
    for modes in (10, 20, 40):
        sized = ConductionRom(energy=1.0, max_modes=modes).fit(
            operators, training[1:], reference_temperatures=REFERENCES)
        sized.simulate(day)
        _, wall, cpu = timed(sized.simulate, day)
        print(f"r = {sized.n_modes_}: batch {wall / day.steps * 1e6:.2f} µs/step wall, "
              f"{cpu / day.steps * 1e6:.2f} µs/step CPU")
    print(f"load {os.getloadavg()}")


if __name__ == "__main__":
    main()
