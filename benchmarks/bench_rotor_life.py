"""Fatigue and creep life of a 24-h groove-stress record at 1-s samples (issue 23, item 4).

The record is synthetic and only shapes the workload (the rotor FEM/ROM is built elsewhere):
control-stage steam temperature linear in load (530 °C at 100 %, 490 °C at 30 %, illustrative),
four 5 %/min ramps 100 → 30 → 100 % a day; the groove surface follows the steam with a 2-min lag,
the rotor mean with a 25-min lag; the thermal stress is E·α/(1 − ν)·(T_mean − T_surface) with a
stress concentration 2 (Timoshenko & Goodier §152 for the surface of a long cylinder), on a
150 MPa standing (centrifugal) stress, plus 1 MPa white noise for the small cycles a measured
record has. Prints rainflow cycles, fatigue damage (best fit and ASME design factors), creep
damage, and wall/CPU times of each step.

Run: python benchmarks/bench_rotor_life.py [--seed 0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from steamtwin.rotor.creep import creep_damage
from steamtwin.rotor.fatigue import ASME_DESIGN_FACTORS, fatigue_damage
from steamtwin.rotor.steel import steel

SECONDS = 86_400
RAMP_STARTS_H = (3.0, 9.0, 15.0, 21.0)
RAMP_S = 70.0 / 5.0 * 60.0  # 70 % load at 5 %/min


def load_profile(time_s: np.ndarray) -> np.ndarray:
    """Load fraction: down at 3 h and 15 h, up at 9 h and 21 h."""
    knots_t, knots_load = [0.0], [1.0]
    for i, start in enumerate(RAMP_STARTS_H):
        level = 0.3 if i % 2 == 0 else 1.0
        knots_t += [start * 3600.0, start * 3600.0 + RAMP_S]
        knots_load += [knots_load[-1], level]
    knots_t.append(float(SECONDS))
    knots_load.append(knots_load[-1])
    return np.interp(time_s, knots_t, knots_load)


def lagged(signal: np.ndarray, tau_s: float) -> np.ndarray:
    """First-order lag, 1-s samples (implicit Euler)."""
    out = np.empty_like(signal)
    out[0] = signal[0]
    for i in range(1, signal.size):
        out[i] = (tau_s * out[i - 1] + signal[i]) / (tau_s + 1.0)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    material = steel("30CrMoNiV5-11")
    time_s = np.arange(SECONDS, dtype=float)
    steam = 490.0 + 273.15 + 40.0 * (load_profile(time_s) - 0.3) / 0.7
    surface, mean = lagged(steam, 120.0), lagged(steam, 1500.0)
    e, nu = material.youngs_modulus(surface), 0.30
    alpha = material.mean_expansion(surface)
    noise = np.random.default_rng(args.seed).normal(0.0, 1e6, SECONDS)
    stress = 150e6 + 2.0 * e * alpha / (1.0 - nu) * (mean - surface) + noise
    print(f"stress {stress.min() / 1e6:.0f} … {stress.max() / 1e6:.0f} MPa, surface "
          f"{surface.min() - 273.15:.0f} … {surface.max() - 273.15:.0f} °C")
    for label, call in (
        ("fatigue, mean curve", lambda: fatigue_damage(stress, surface, material)),
        ("fatigue, ASME factors", lambda: fatigue_damage(stress, surface, material,
                                                         design=ASME_DESIGN_FACTORS)),
        ("creep", lambda: creep_damage(np.clip(stress, 0.0, None), surface, time_s, material)),
    ):
        wall, cpu = time.perf_counter(), time.process_time()
        result = call()
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        cycles = f", {len(result.cycles)} rainflow rows" if hasattr(result, "cycles") else ""
        print(f"{label:24s} damage {result.total_damage:.3e}{cycles}; wall {wall:.3f} s, "
              f"CPU {cpu:.3f} s")


if __name__ == "__main__":
    main()
