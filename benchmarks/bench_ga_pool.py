"""Benchmark: where the GA's wall time goes on the local pool (issue 18, "GA ≤ 5 min").

Run: python benchmarks/bench_ga_pool.py [--generations G] [--population P] [--repeats N]
[--pair-cache FILE] — on part 2 of ``bench_joint_calibration.py`` (the two 2-h holds of the
plant's ``day``, instruments seed 0, the same objective settings):

1. **Per generation of a short GA** (P × G on a pool of two, the benchmark's configuration):
   wall time, each worker's busy wall and CPU time (``time.process_time`` in the worker), the
   share of it in the compiled kernel (``kernel.run_kernel`` timed in the worker), the parent's
   CPU time, the chunks sent and the gap between generations;
2. **Concurrency**: CPU time per evaluation (the pair, one candidate) in one process alone, then
   in two processes at once (spawned, started on a common clock), alternately ``--repeats``
   times, then the same with a compute-only co-runner (a dependent floating-point chain that
   touches no memory) and with a memory-streaming co-runner (copies between two 64-MB arrays)
   beside one evaluating process. If the pool's CPU time per evaluation exceeds the lone
   process's, the two workers slow each other down — no evaluator change removes that; if
   the streaming co-runner slows the kernel and the compute-only one does not, the kernel's
   speed depends on the shared caches and memory, which other jobs (and other virtual
   machines on the host) load too.

CPU times next to wall times and the load average with every figure: the machine is shared.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import pickle
import platform
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from numba import njit

from bench_joint_calibration import two_hold_pair
from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration import calibrator as calibrator_module
from steamtwin.calibration.evaluation import ProcessPoolEvaluator
from steamtwin.calibration.identifiability import IdentifiabilityWarning
from steamtwin.calibration.settings import DEFAULT_SENSORS, THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.windowset import WindowSet, find_calibration_windows
from steamtwin.dcs.plant import run_plant
from steamtwin.model import kernel
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import load_spec

CANDIDATE = np.array([0.999, 1.0, 1.0])
_kernel_cpu = [0.0]
_installed: list = []


def _load() -> str:
    return "load " + " / ".join(f"{v:.1f}" for v in os.getloadavg())


def _timed_kernel(run):
    def timed(*args, **kwargs):
        start = time.process_time()
        try:
            return run(*args, **kwargs)
        finally:
            _kernel_cpu[0] += time.process_time() - start
    return timed


def _install(objective) -> None:
    kernel.run_kernel = _timed_kernel(kernel.run_kernel)
    _installed.append(objective)


def _chunk(rows: np.ndarray) -> tuple[list, tuple]:
    wall, cpu, in_kernel = time.perf_counter(), time.process_time(), _kernel_cpu[0]
    results = _installed[0].evaluate_many(rows)
    return results, (os.getpid(), wall, time.perf_counter(), time.process_time() - cpu,
                     _kernel_cpu[0] - in_kernel, len(rows))


class _AccountingPool(ProcessPoolEvaluator):
    """The library's pool, its chunks run through :func:`_chunk`, one log row per batch."""

    def __init__(self, workers: int) -> None:
        super().__init__(workers)
        self.log: list[tuple[float, float, float, list[tuple]]] = []

    def start(self, objective) -> None:
        self._workers = self.workers
        self._pool = ProcessPoolExecutor(self.workers,
                                         mp_context=multiprocessing.get_context("spawn"),
                                         initializer=_install, initargs=(objective,))

    def evaluate(self, candidates: np.ndarray) -> list:
        wall, cpu = time.perf_counter(), time.process_time()
        results, stats = [], []
        parts = np.array_split(np.atleast_2d(candidates), 2 * self._workers)  # as the library
        for chunk, stat in self._pool.map(_chunk, [part for part in parts if len(part)]):
            results.extend(chunk)
            stats.append(stat)
        self.log.append((wall, time.perf_counter(), time.process_time() - cpu, stats))
        return results


def _pair(cache: Path | None) -> tuple[WindowSet, dict[str, float]]:
    if cache is not None and cache.exists():
        with cache.open("rb") as handle:
            return pickle.load(handle)
    spec = load_spec("reference")
    run = run_plant("day", random_state=0)
    measured, true = run.measured, run.true_outputs
    sigma = {s: float(np.nanstd((measured[s] - true[s]).to_numpy())) for s in DEFAULT_SENSORS}
    windows = WindowSet(tuple(find_calibration_windows(measured, spec.design.generator_power,
                                                       sigma=sigma)))
    pair = (two_hold_pair(windows), sigma)
    if cache is not None:
        with cache.open("wb") as handle:
            pickle.dump(pair, handle)
    return pair


def _calibrator(sigma: dict[str, float], search: GeneticSearch | None = None) -> Calibrator:
    model = FullOrderModel(load_spec("reference"))
    _ = model.design_
    return Calibrator(model, objective=ObjectiveSettings(sigma=sigma,
                                                         sensor_bias=THERMOCOUPLE_BIAS),
                      search=search)


def generations(pair: WindowSet, sigma: dict[str, float], population: int, count: int) -> None:
    """Part 1: the short GA, generation by generation."""
    pool = _AccountingPool(2)
    calibrator_module.make_evaluator = lambda workers, scheduler: pool
    start, cpu = time.perf_counter(), time.process_time()
    fitted = _calibrator(sigma, GeneticSearch(population=population, generations=count))
    fitted.fit(pair)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    log = pool.log
    print(f"GA P {population} × G {count}, pool of two: fit {wall:.1f} s wall, parent CPU "
          f"{cpu:.1f} s, {fitted.n_evaluations_} evaluations, score {fitted.score_:.10f}; "
          f"{_load()}")
    print("generation | wall s | chunks | worker busy s | worker CPU s | kernel share | "
          "parent CPU s | gap before s")
    for g, (begin, end, parent, stats) in enumerate(log):
        busy, spent, in_kernel = {}, {}, {}
        for pid, first, last, used, kernel_used, _ in stats:
            busy[pid] = busy.get(pid, 0.0) + last - first
            spent[pid] = spent.get(pid, 0.0) + used
            in_kernel[pid] = in_kernel.get(pid, 0.0) + kernel_used
        gap = begin - log[g - 1][1] if g else 0.0
        print(f"{g + 1} | {end - begin:.2f} | {[s[5] for s in stats]} | "
              f"{' / '.join(f'{v:.2f}' for v in busy.values())} | "
              f"{' / '.join(f'{v:.2f}' for v in spent.values())} | "
              f"{sum(in_kernel.values()) / sum(spent.values()):.3f} | {parent:.3f} | {gap:.3f}")
    steady = log[1:]
    rows = sum(s[5] for entry in steady for s in entry[3])
    worker_cpu = sum(s[3] for entry in steady for s in entry[3])
    wall_steady = sum(entry[1] - entry[0] for entry in steady)
    print(f"generations 2–{len(log)}: {1e3 * worker_cpu / rows:.1f} ms worker CPU per "
          f"evaluation, {1e3 * 2 * wall_steady / rows:.1f} ms of pool wall × 2 workers per "
          f"evaluation")


@njit(cache=False)
def _dependent_chain(n: int) -> float:
    """Two multiply–adds per iteration, each waiting for the last: 4 dependent floating-point
    operations of 3 cycles each on AMD Zen 3/4 (Agner Fog, *Instruction tables*), 12 cycles."""
    x = 1.0
    for _ in range(n):
        x = x * 1.0000001 + 1e-9
        x = x - 1e-9 * x
    return x


def clock_reference(iterations: int = 100_000_000) -> float:
    """The core's effective clock (GHz) from :func:`_dependent_chain`'s CPU time: what the
    processor delivers to code that touches no memory, against which a slower kernel shows
    whether the clock or something shared (caches, memory, a sibling thread) changed."""
    _dependent_chain(10)
    start = time.process_time()
    _dependent_chain(iterations)
    return 12.0 * iterations / (time.process_time() - start) / 1e9


def _evaluate_alone(arguments: tuple[dict[str, float], WindowSet, int, float]) -> float:
    sigma, pair, repeats, begin = arguments
    objective = _calibrator(sigma).problem(pair).objective
    objective.evaluate(CANDIDATE)
    time.sleep(max(0.0, begin - time.time()))
    cpu = time.process_time()
    for _ in range(repeats):
        objective.evaluate(CANDIDATE)
    return (time.process_time() - cpu) / repeats


def _spin(arguments: tuple[dict[str, float], WindowSet, int, float]) -> float:
    """A dependent multiply–add chain (no memory traffic) for about as long as the others."""
    begin = arguments[3]
    time.sleep(max(0.0, begin - time.time()))
    x, stop = 1.0, time.perf_counter() + 3.0
    while time.perf_counter() < stop:
        for _ in range(10_000):
            x = x * 1.0000001 + 1e-9
    return float("nan")


def _stream(arguments: tuple[dict[str, float], WindowSet, int, float]) -> float:
    """Copies between two 64-MB arrays (twice the last-level cache) for about as long."""
    begin = arguments[3]
    source, target = np.ones(8 * 2**20), np.empty(8 * 2**20)
    time.sleep(max(0.0, begin - time.time()))
    stop = time.perf_counter() + 3.0
    while time.perf_counter() < stop:
        np.copyto(target, source)
    return float("nan")


def concurrency(pair: WindowSet, sigma: dict[str, float], repeats: int, rounds: int) -> None:
    """Part 2: CPU per evaluation alone, two at once, and beside a compute-only co-runner."""
    context = multiprocessing.get_context("spawn")
    cases = {"alone": [_evaluate_alone], "two evaluating": [_evaluate_alone] * 2,
             "beside a compute-only loop": [_evaluate_alone, _spin],
             "beside a memory-streaming loop": [_evaluate_alone, _stream]}
    print(f"\nclock reference (dependent chain, CPU time): {clock_reference():.2f} GHz; {_load()}")
    print(f"CPU ms per evaluation of the pair (candidate {CANDIDATE.tolist()}, {repeats} "
          "in a row per process)")
    for round_ in range(rounds):
        for name, tasks in cases.items():
            with context.Pool(len(tasks)) as pool:
                begin = time.time() + 15.0
                handles = [pool.apply_async(task, ((sigma, pair, repeats, begin),))
                           for task in tasks]
                figures = [h.get() for h in handles]
            shown = " / ".join(f"{1e3 * v:.1f}" for v in figures if v == v)
            print(f"round {round_ + 1}, {name}: {shown}; {_load()}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--population", type=int, default=50)
    parser.add_argument("--generations", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=25)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--pair-cache", type=Path, default=None,
                        help="pickle of the pair and σ (written on first use)")
    parser.add_argument("--skip-ga", action="store_true", help="only the concurrency part")
    arguments = parser.parse_args()
    warnings.simplefilter("ignore", IdentifiabilityWarning)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; {_load()}")
    pair, sigma = _pair(arguments.pair_cache)
    if not arguments.skip_ga:
        generations(pair, sigma, arguments.population, arguments.generations)
    concurrency(pair, sigma, arguments.repeats, arguments.rounds)


if __name__ == "__main__":
    main()
