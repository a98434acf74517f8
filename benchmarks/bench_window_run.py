"""Benchmark: one window-run of the full-order model, what the GA repeats 10 000 times.

Run: python benchmarks/bench_window_run.py [--repeats N] — on the virtual plant's ``day`` (seed
0) the 30 % and the evening 100 % holds, their last 2 h at 1 s (7 200 samples; the windows of
``bench_joint_calibration.py`` part 2), the reference FullOrderModel, ``check_inputs`` once,
then ``simulate_checked`` for three parameter sets: CPU time of the calling thread, min of N
repeats, ms per window-run (CPU time, not wall: the machine is shared; the load average is
printed with each figure). Then where the time goes:

* Python around the kernel (``simulate_checked`` − ``kernel.run_kernel`` alone);
* the sensor lags (:func:`~steamtwin.model.measurement.lag` with
  :data:`~steamtwin.model.measurement.TYPICAL_TIME_CONSTANTS_S` on the three temperatures);
* the compiled loop per sample and its sweeps per sample;
* one steam-property look-up (ln p, cell location and bicubic (p, h) → T at the window's stage
  states, in a compiled loop), as the unit the compiled loop's cost per sample is given in.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
from numba import njit

from steamtwin.calibration.windowset import CalibrationWindow, find_calibration_windows
from steamtwin.dcs.plant import run_plant
from steamtwin.model import kernel
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S, lag
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import load_spec
from steamtwin.steam import if97
from steamtwin.steam.tables import PH_T, ph_property, steam_tables

SAMPLES = 7200
PARAMETER_SETS = {
    "design (1, 1, 1)": ModelParameters(),
    "(0.97, 1.2, 0.7)": ModelParameters(flow_coefficient=0.97, friction_coefficient=1.2,
                                        heat_transfer_coefficient=0.7),
    "(1.03, 0.8, 1.5)": ModelParameters(flow_coefficient=1.03, friction_coefficient=0.8,
                                        heat_transfer_coefficient=1.5),
}
TEMPERATURES = ("control_stage_temperature", "hp_exhaust_temperature",
                "hp_inner_casing_temperature")


def cpu_ms(call, repeats: int) -> float:
    """Min over ``repeats`` of the calling thread's CPU time of ``call()`` (ms)."""
    best = np.inf
    for _ in range(repeats):
        start = time.thread_time()
        call()
        best = min(best, time.thread_time() - start)
    return best * 1e3


def load() -> str:
    return "load {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


@njit(cache=True)
def _lookups(tables, pressures, enthalpies, rounds):
    total = 0.0
    for _ in range(rounds):
        for k in range(pressures.size):
            total += ph_property(tables, PH_T, pressures[k], enthalpies[k])
    return total


def kernel_call(model: FullOrderModel, checked, params: ModelParameters):
    """``run_kernel`` on ``checked`` with the arrays ``FullOrderModel._solve`` builds."""
    constants = model.design_.kernel
    p0, t0, flow, p_exhaust = (checked.columns[name] for name in model.input_signals)
    n, stages = p0.size, constants.stage_capacity.size
    tables = steam_tables()
    parameter_array = np.array([[params.flow_coefficient, params.friction_coefficient,
                                 params.heat_transfer_coefficient]])
    tolerance = np.array([model.pressure_tolerance, model.enthalpy_tolerance])

    def call() -> None:
        carry = model._carry(constants, checked, None)  # the fresh start _solve makes
        kernel.run_kernel(
            constants, tables, checked.time_step, p0, t0, flow, p_exhaust,
            checked.inlet_states(constants), parameter_array,
            tolerance, carry["pressures"], carry["enthalpies"], carry["metal"],
            np.full((n, kernel.N_RESULTS), np.nan), np.zeros(n, dtype=np.int64),
            np.zeros((0, stages + 1)), np.zeros((0, stages + 1)), carry["throttled"],
            carry["cs_out"], carry["leak_flow"], carry["inlet_pv"], carry["previous"], False)

    return call


def window_report(model: FullOrderModel, window: CalibrationWindow, repeats: int) -> None:
    """Print the timings and the breakdown of one window (module docstring)."""
    frame = window.data.iloc[-SAMPLES:]
    checked = model.check_inputs(frame)
    print(f"\nhold at {100 * window.load_fraction:.0f} % load, {len(frame)} samples from "
          f"{frame.index[0]}")
    for name, params in PARAMETER_SETS.items():
        model.simulate_checked(checked, params, TEMPERATURES)  # warm-up (compilation)
        ms = cpu_ms(lambda p=params: model.simulate_checked(checked, p, TEMPERATURES),
                    repeats)
        print(f"  simulate_checked {name}: {ms:.1f} ms per window-run "
              f"({ms / len(frame) * 1e3:.2f} µs per sample; {load()})")
    params = ModelParameters()
    total = cpu_ms(lambda: model.simulate_checked(checked, params, TEMPERATURES), repeats)
    call = kernel_call(model, checked, params)
    call()
    compiled = cpu_ms(call, repeats)
    computed = model.simulate_checked(checked, params, TEMPERATURES)
    lags = cpu_ms(lambda: [lag(computed[:, j], checked.time_step, TYPICAL_TIME_CONSTANTS_S[name])
                           for j, name in enumerate(TEMPERATURES)], repeats)
    detail = model.simulate_detailed(frame, params, stages=True)
    sweeps = detail.diagnostics["iterations"].to_numpy()
    print(f"  breakdown (design parameters; {load()}):")
    print(f"    compiled loop (run_kernel)   {compiled:6.1f} ms  "
          f"({compiled / len(frame) * 1e3:.2f} µs per sample, {sweeps.mean():.3f} sweeps "
          "per sample)")
    print(f"    Python around it              {total - compiled:6.1f} ms")
    print(f"    sensor lags (3 thermocouples) {lags:6.1f} ms  (not in the GA benchmark's model)")
    pressures = detail.stage_pressures.to_numpy().ravel()
    enthalpies = np.asarray(if97.enthalpy_pt(pressures,
                                             detail.stage_temperatures.to_numpy().ravel()))
    tables = steam_tables()
    rounds = 10
    _lookups(tables, pressures[:10], enthalpies[:10], 1)
    lookup = cpu_ms(lambda: _lookups(tables, pressures, enthalpies, rounds),
                    repeats) / (rounds * pressures.size) * 1e6
    print(f"    one (p, h) → T look-up {lookup:.1f} ns at the window's stage states; the compiled "
          f"loop costs {compiled / len(frame) * 1e6 / lookup:.0f} look-ups' worth per sample")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=9)
    arguments = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}; {load()}")
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    _ = model.design_
    start = time.perf_counter()
    run = run_plant("day", random_state=0)
    print(f"plant day: {time.perf_counter() - start:.0f} s")
    windows = [w for w in find_calibration_windows(run.measured, spec.design.generator_power)
               if w.kind == "steady"]
    pair = [min(windows, key=lambda w: abs(w.load_fraction - 0.3)),
            max(windows, key=lambda w: (round(w.load_fraction, 2), w.data.index[0]))]
    for window in pair:
        window_report(model, window, arguments.repeats)


if __name__ == "__main__":
    main()
