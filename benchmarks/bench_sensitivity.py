"""Benchmark: Sobol' indices of the three parameters and main-steam temperature noise propagation.

Run: python benchmarks/bench_sensitivity.py [--quick] [--workers N] [--figures DIR] — on the
reference unit, 1-s samples, a ramp down at 3 %/min followed by a 30-min hold:

* ``ramp-100-30``: 100 → 30 %; the flow coefficient's range starts at 0.94 because below ~0.935
  the wide-open valves cannot pass rated flow (the model rejects those runs);
* ``ramp-90-30``: 90 → 30 % over the full physical bounds.

For each: N = 256 (N·5 = 1280 parameter sets, two model runs each for the quasi-steady lag),
wall time on the local process pool, the cost of one run, and S1/ST with 95 % intervals of the
time-mean and the lag RMS of the HP-exhaust and casing-metal temperatures. Then noise of
σ = 0.5 and 1 K on the main-steam temperature along the 100 → 30 % ramp (8 repeats): deviation
and gain per output. Prints one JSON document. ``--quick`` runs N = 16 to check the script.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from steamtwin.calibration.evaluation import make_evaluator
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.spec import load_spec
from steamtwin.validation.noise import noise_figure, noise_propagation
from steamtwin.validation.sensitivity import sobol_indices

CASES = {
    "ramp-100-30": (1.0, {"flow_coefficient": (0.94, 1.10)}),
    "ramp-90-30": (0.9, None),
}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--workers", type=int, default=None, help="default: every core")
    parser.add_argument("--figures", type=Path, default=None, help="folder for the PNGs")
    arguments = parser.parse_args()
    n_base = 16 if arguments.quick else 256
    spec = load_spec("reference")
    model = FullOrderModel(spec)
    _ = model.design_
    if arguments.figures is not None:
        arguments.figures.mkdir(parents=True, exist_ok=True)
    report: dict[str, object] = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
                   f"{platform.python_version()}",
        "workers": arguments.workers or os.cpu_count(), "n_base": n_base, "cases": {},
    }
    for name, (start_load, bounds) in CASES.items():
        inputs = load_profile_inputs(spec, ramp_profile(start_load, 0.3, 0.03, 60.0, 1800.0))
        single = []
        for _ in range(3):
            began = time.perf_counter()
            model.simulate(inputs)
            single.append(time.perf_counter() - began)
        began = time.perf_counter()
        result = sobol_indices(model, inputs, bounds=bounds, n_base=n_base, random_state=0,
                               evaluator=make_evaluator(arguments.workers))
        wall = time.perf_counter() - began
        table = result.table()
        indices: dict[str, dict] = {}
        for (output, statistic, parameter), row in table.iterrows():
            entry = indices.setdefault(output, {}).setdefault(
                statistic, {"std": float(f"{row['std']:.4g}")})
            entry[parameter] = {key: round(float(row[key]), 4)
                                for key in ("S1", "S1_conf", "ST", "ST_conf")}
        checks = result.checks()
        report["cases"][name] = {
            "samples": len(inputs), "bounds": {k: list(v) for k, v in result.bounds.items()},
            "model_runs": result.model_runs, "wall_s": round(wall, 1),
            "wall_ms_per_run": round(1e3 * wall / result.model_runs, 2),
            "single_run_ms": round(1e3 * float(np.median(single)), 1),
            "indices": indices,
            "consistent": bool(checks[["sum_S1_ok", "st_ge_s1"]].all().all()),
        }
        if arguments.figures is not None:
            result.figure(arguments.figures / f"sobol-{name}.png")
    inputs = load_profile_inputs(spec, ramp_profile(1.0, 0.3, 0.03, 60.0, 1800.0))
    began = time.perf_counter()
    noise = noise_propagation(model, inputs, sigmas_K=(0.5, 1.0), repeats=8, random_state=0)
    noise_wall = time.perf_counter() - began
    rms = noise["rms_deviation"].unstack("sigma_K")
    report["noise"] = {
        "window": "ramp 100 → 30 % at 3 %/min + 30-min hold, 1-s samples", "repeats": 8,
        "wall_s": round(noise_wall, 1),
        "table": {f"{sigma:g} K": {output: {key: float(f"{value:.4g}") for key, value in
                                            row.items()}
                                   for (_, output), row in noise.loc[[sigma]].iterrows()}
                  for sigma in (0.5, 1.0)},
        "rms_ratio_1K_to_0.5K": {output: round(float(value), 4)
                                 for output, value in (rms[1.0] / rms[0.5]).items()},
    }
    if arguments.figures is not None:
        noise_figure(model, inputs, arguments.figures / "noise.png", minutes=5.0)
    print(json.dumps(report, indent=2, ensure_ascii=False))


if __name__ == "__main__":
    main()
