"""Benchmark of the ramp-rate advisor (steamtwin.rotor.advisor) on the reference unit's rotor.

Run: python benchmarks/bench_rotor_advisor.py [--mesh-size 0.03] [--skip-fem]
— prints

1. the rotor model's fit (default mesh and training ramps) and the advisor's fit (the steady
   steam table of the operating line): wall and CPU time;
2. the time of one advice (median of 5 calls, wall and CPU) for a few ramps and allowables, with
   the advised rate, what limited it, the number of ROM runs, and a start-up curve 30 → 100 %;
3. the full-FEM check of one binding advice: the FEM's peak excess over the allowable at the
   advised rate and 5 % faster (≤ 0 and > 0 expected), and the FEM run's time.
Timing figures depend on the machine's load: the script prints `uptime`'s load average.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

from steamtwin.rotor.advisor import RampAdvisor
from steamtwin.rotor.model import RotorModel
from steamtwin.spec import load_spec

CASES = (  # (from load, to load, allowable Pa or None, design cycles or None, hold s)
    (0.5, 0.3, None, 1e4, 3600.0),
    (1.0, 0.3, 150e6, None, 3600.0),
    (1.0, 0.8, 80e6, None, 3600.0),
    (0.3, 1.0, 250e6, None, 3600.0),
)
FEM_CASE = (1.0, 0.8, 80e6, 1800.0)


def timed(function, *args, **kwargs):
    wall, cpu = time.perf_counter(), time.process_time()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - wall, time.process_time() - cpu


def fem_excess(model, advisor, advice, rate, hold):
    steam = advisor.steam_frame(advice.from_load, advice.to_load, rate, hold)
    fem = model.simulate_steam(steam, full_order=True).frame
    return max(float(advice.limits[loc].excess(fem[f"{loc}_equivalent"].to_numpy()).max())
               for loc in advice.limits), len(steam)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh-size", type=float, default=None, help="m (default 0.03)")
    parser.add_argument("--skip-fem", action="store_true")
    args = parser.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f} {os.getloadavg()[1]:.1f}")
    spec = load_spec("reference")
    model, wall, cpu = timed(RotorModel(spec, mesh_size=args.mesh_size).fit)
    print(f"rotor model fit: {wall:.1f} s wall, {cpu:.1f} s CPU, "
          f"{model.mesh_.p.shape[1]} nodes, {model.rom_.n_modes_} modes")
    for from_load, to_load, allowable, cycles, hold in CASES:
        advisor, wall, cpu = timed(RampAdvisor(model, allowable, cycles=cycles).fit)
        walls, cpus = [], []
        for _ in range(5):
            advice, wall1, cpu1 = timed(advisor.advise, None, from_load, to_load,
                                        hold_after_s=hold)
            walls.append(wall1)
            cpus.append(cpu1)
        limit = (f"{allowable / 1e6:.0f} MPa" if allowable is not None
                 else f"{cycles:g} cycles")
        peak = ", ".join(f"{loc} {p / 1e6:.1f} MPa" for loc, p in advice.peak_pa.items())
        print(f"{from_load:.0%} → {to_load:.0%}, {limit}: {100 * advice.rate_per_min:.3f} %/min "
              f"({advice.limited_by}; {len(advice.evaluations)} ROM runs; peak {peak}; "
              f"groove fatigue {advice.fatigue_damage['groove']:.2e}) — advise "
              f"{statistics.median(walls):.3f} s wall, {statistics.median(cpus):.3f} s CPU "
              f"(median of 5); advisor fit {wall:.2f} s wall, {cpu:.2f} s CPU")
    advisor = RampAdvisor(model, 250e6).fit()
    curve, wall, cpu = timed(advisor.curve, None, 0.3, 1.0, hold_after_s=3600.0)
    print(f"start-up curve 30 → 100 % at 250 MPa: {wall:.2f} s wall, {cpu:.2f} s CPU")
    print(curve.table[["from_load", "to_load", "soak_s", "rate_per_min", "limited_by",
                       "groove_peak_pa"]].to_string(index=False))
    if args.skip_fem:
        return
    from_load, to_load, allowable, hold = FEM_CASE
    advisor = RampAdvisor(model, allowable).fit()
    advice = advisor.advise(None, from_load, to_load, hold_after_s=hold)
    for factor in (1.0, 1.05):
        (excess, steps), wall, cpu = timed(fem_excess, model, advisor, advice,
                                           factor * advice.rate_per_min, hold)
        print(f"full FEM, {from_load:.0%} → {to_load:.0%} at {factor:.2f} × the advised "
              f"{100 * advice.rate_per_min:.3f} %/min: peak excess {excess / 1e6:+.2f} MPa over "
              f"the {allowable / 1e6:.0f} MPa allowable; {steps} steps, {wall:.1f} s wall, "
              f"{cpu:.1f} s CPU")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
