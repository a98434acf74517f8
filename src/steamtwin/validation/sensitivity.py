"""Sobol' indices of the three unmeasurable parameters for the HP temperatures.

Which share of an output's variance does each of ``flow_coefficient``, ``friction_coefficient``
and ``heat_transfer_coefficient`` carry when all three range uniformly over their bounds?

Method
    Variance-based global sensitivity (Sobol' 2001, *Math. Comput. Simul.* 55:271): the
    first-order index S1_i = V[E(Y|x_i)]/V(Y) is the share a parameter carries alone, the total
    index ST_i = E[V(Y|x_~i)]/V(Y) adds every interaction it takes part in. Samples are
    Saltelli's scheme on a scrambled Sobol' sequence, N·(D + 2) parameter sets for D = 3 without
    second-order indices (``SALib.sample.sobol``); S1 by the estimator of Saltelli et al. 2010
    (*Comput. Phys. Commun.* 181:259, Table 2 (b)), ST by Jansen's (ibid., Table 2 (f)), with
    bootstrap confidence intervals (``SALib.analyze.sobol``; Herman & Usher 2017, *JOSS* 2:97).
    N must be a power of 2 to keep the Sobol' sequence's balance.

    Both estimators are differences of Monte-Carlo means: an index near zero can come out
    slightly negative, and ΣS1 slightly above 1, within the confidence interval. Values are
    reported as estimated, not clipped; :meth:`SobolResult.checks` tests ΣS1 ≤ 1 and ST ≥ S1
    within the intervals.

The window must be a transient
    Each parameter set is one run of the simulator over ``inputs`` — a load ramp, not a hold: at
    steady state the metal is in equilibrium and the heat-transfer coefficient changes nothing
    but the tiny lagging-loss share of the metal temperature, so its indices are ≈ 0 there by
    construction. The metal starts in equilibrium with the first sample.

Statistics (a scalar per run, output and statistic; see :data:`STATISTICS`)
    ``mean``
        Time-mean of the output over the window (K). The level of the steam temperatures along
        the operating line: set by the flow capacity (stage pressures) and the friction losses
        (stage efficiencies); heat transfer only moves it through the heat the metal stores.
    ``lag_rms``
        RMS over the window of the output minus its quasi-steady value (K) — the part of the
        output that exists only because the metal stores heat: the metal temperature's lag
        behind the steam and the steam's loss to (or gain from) the metal. The quasi-steady
        output is a second run of the same parameters on the same inputs spaced
        :data:`QUASI_STEADY_STEP_S` apart, where each implicit metal step reaches equilibrium.
        The lag is set by the metal's time constant C/(h·A), hence by the heat-transfer
        coefficient, and by how far and fast the steam temperature at the metal moves during
        the ramp (flow and friction). It doubles the model runs.

    On the reference unit (``benchmarks/bench_sensitivity.py``, N = 256, ramps to 30 % at
    3 %/min) the flow coefficient carries most of the variance of both statistics: it moves
    the stage pressures and, through the nozzle-governing valve points, how far the
    control-stage steam temperature swings during the ramp — the amplitude the metal lags
    behind. Heat transfer's share is ≈ 0 of the time-means and a minority of the lags.

A statistic whose spread over all runs is below :data:`SPREAD_RESOLUTION` of the output's level
(≈ 6 mK for a temperature near 600 K, about what the model's sweeps leave) has no variance to
apportion: its indices are NaN.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from SALib.analyze import sobol as sobol_analyze
from SALib.sample import sobol as sobol_sample

from steamtwin.calibration.evaluation import Evaluator
from steamtwin.calibration.settings import PARAMETER_NAMES, check_bounds, check_random_state
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator
from steamtwin.progress import ProgressCallback

__all__ = [
    "CONF_LEVEL",
    "DEFAULT_OUTPUTS",
    "DEFAULT_STATISTICS",
    "QUASI_STEADY_STEP_S",
    "SPREAD_RESOLUTION",
    "STATISTICS",
    "SobolResult",
    "sobol_indices",
]

logger = logging.getLogger(__name__)

STATISTICS: dict[str, str] = {
    "mean": "time-mean of the output over the window",
    "lag_rms": "RMS over the window of the output minus its quasi-steady value",
}
"""Scalar statistics of an output over the window (same unit as the output: K, Pa, W)."""

DEFAULT_OUTPUTS: tuple[str, ...] = ("hp_exhaust_temperature", "hp_inner_casing_temperature")
DEFAULT_STATISTICS: tuple[str, ...] = ("mean", "lag_rms")

QUASI_STEADY_STEP_S = 1.0e10
"""Sample spacing (s) of the quasi-steady run: ~300 years, ≫ the metal's time constants (hours),
so each implicit-Euler metal step leaves ≤ 1e-5 of the previous imbalance."""

SPREAD_RESOLUTION = 1.0e-5
"""Spread (standard deviation over runs) of a statistic, relative to the output's level, below
which it counts as constant (≈ 6 mK at 600 K; the model's sweeps leave ≤ 0.02 K per sample,
far less in a time-mean)."""

CONF_LEVEL = 0.95
"""Level of the bootstrap confidence intervals."""

BOOTSTRAP_RESAMPLES = 1000

_PROGRESS_BATCHES = 10  # batches the runs go to the evaluator in, for progress reports

_COLUMNS = ("S1", "S1_conf", "ST", "ST_conf")


class _Run(NamedTuple):
    """One parameter set's result: statistics (outputs × statistics) and the outputs' levels
    (time-mean |y|), or the simulator's reason for rejecting it."""

    values: np.ndarray | None
    levels: np.ndarray | None
    error: str = ""


@dataclass(frozen=True)
class _StatisticRuns:
    """What an evaluator ships to its workers once: simulator, window, outputs, statistics.

    Duck-types the calibration :class:`~steamtwin.calibration.objective.Objective`
    (``evaluate_many``), so the serial, process-pool and Dask evaluators run it unchanged.
    """

    simulator: Simulator
    inputs: pd.DataFrame
    outputs: tuple[str, ...]
    statistics: tuple[str, ...]

    def evaluate_many(self, rows: np.ndarray) -> list[_Run]:
        """Results for the rows (n, 3) of parameter sets, in order."""
        return [self.evaluate(row) for row in np.atleast_2d(rows)]

    def evaluate(self, x: Sequence[float]) -> _Run:
        """Statistics of one parameter set (order: PARAMETER_NAMES)."""
        try:
            params = ModelParameters(**{n: float(v) for n, v in
                                        zip(PARAMETER_NAMES, x, strict=True)})
            y = self._outputs(self.inputs, params)
            quasi = (self._outputs(self.inputs.set_axis(
                np.arange(len(self.inputs)) * QUASI_STEADY_STEP_S), params)
                if "lag_rms" in self.statistics else None)
        except ValueError as error:
            return _Run(None, None, str(error) or type(error).__name__)
        values = np.empty((len(self.outputs), len(self.statistics)))
        for j, name in enumerate(self.statistics):
            if name == "mean":
                values[:, j] = y.mean(axis=0)
            else:  # lag_rms
                values[:, j] = np.sqrt(np.mean((y - quasi) ** 2, axis=0))
        return _Run(values, np.abs(y).mean(axis=0))

    def _outputs(self, inputs: pd.DataFrame, params: ModelParameters) -> np.ndarray:
        simulated = self.simulator.simulate(inputs, params)
        y = simulated[list(self.outputs)].to_numpy(dtype=float)
        if y.shape != (len(inputs), len(self.outputs)) or not np.isfinite(y).all():
            raise ValueError("the simulator returned non-finite or missing outputs")
        return y


@dataclass(frozen=True)
class SobolResult:
    """Sobol' indices of the parameters for each output and statistic.

    ``indices``: rows (output, statistic, parameter), columns S1, S1_conf, ST, ST_conf
    (dimensionless; ``*_conf`` the half-width of the :data:`CONF_LEVEL` bootstrap interval) and
    ``std`` (spread of the statistic over the runs, unit of the output: K). ``runs``: one row
    per parameter set, the parameters and each ``<output>:<statistic>``. ``model_runs``: calls
    of ``simulate``.
    """

    indices: pd.DataFrame
    runs: pd.DataFrame
    n_base: int
    model_runs: int
    bounds: Mapping[str, tuple[float, float]]

    def table(self) -> pd.DataFrame:
        """The indices (a copy): rows output × statistic × parameter, columns S1, S1_conf, ST,
        ST_conf, std."""
        return self.indices.copy()

    def checks(self) -> pd.DataFrame:
        """Consistency per (output, statistic): ``sum_S1`` ≤ 1 + ``sum_S1_conf`` (the S1
        intervals summed; ``sum_S1_ok``) and ST ≥ S1 − (S1_conf + ST_conf) for every parameter
        (``st_ge_s1``). The estimates share their samples, so their errors are correlated and
        the intervals are added, not combined in quadrature. NaN indices pass."""
        rows = []
        for (output, statistic), group in self.indices.groupby(level=[0, 1], sort=False):
            finite = group["S1"].notna().all()
            sum_s1 = float(group["S1"].sum()) if finite else math.nan
            margin = float(group["S1_conf"].sum()) if finite else math.nan
            gap = group["ST"] - group["S1"] + group["S1_conf"] + group["ST_conf"]
            rows.append({"output": output, "statistic": statistic, "sum_S1": sum_s1,
                         "sum_S1_conf": margin,
                         "sum_S1_ok": bool(not finite or sum_s1 <= 1.0 + margin),
                         "st_ge_s1": bool(not finite or (gap >= 0.0).all())})
        return pd.DataFrame(rows).set_index(["output", "statistic"])

    def figure(self, path: str | Path) -> Path:
        """Bar chart of S1 and ST per parameter with their confidence intervals, one panel per
        output and statistic, written as PNG to ``path``."""
        path = Path(path)
        panels = list(self.indices.groupby(level=[0, 1], sort=False))
        columns = min(2, len(panels))
        rows = math.ceil(len(panels) / columns)
        figure = Figure(figsize=(5.0 * columns, 3.6 * rows))
        axes = figure.subplots(rows, columns, squeeze=False).ravel()
        position = np.arange(len(PARAMETER_NAMES))
        width = 0.38
        labels = [name.replace("_coefficient", "") for name in PARAMETER_NAMES]
        for axis, ((output, statistic), group) in zip(axes, panels, strict=False):
            group = group.droplevel([0, 1]).loc[list(PARAMETER_NAMES)]
            axis.set_title(f"{output.replace('_', ' ')}: {statistic}\n"
                           f"spread over the runs {group['std'].iloc[0]:.3g}", fontsize=9)
            if group["S1"].isna().all():
                axis.text(0.5, 0.5, "no spread over the runs", ha="center",
                          transform=axis.transAxes)
            for shift, kind, color in ((-width / 2, "S1", "tab:blue"),
                                       (width / 2, "ST", "tab:orange")):
                axis.bar(position + shift, group[kind], width, yerr=group[f"{kind}_conf"],
                         capsize=3, color=color, label=kind)
            axis.axhline(0.0, color="black", lw=0.6)
            axis.set_xticks(position, labels)
            value = group[["S1", "ST"]].to_numpy()
            conf = group[["S1_conf", "ST_conf"]].to_numpy()
            axis.set_ylim(min(-0.1, float(np.nanmin(value - conf, initial=0.0))),
                          max(1.1, float(np.nanmax(value + conf, initial=0.0))))
            axis.set_ylabel("Sobol' index")
            axis.legend(fontsize=8)
            axis.grid(axis="y", alpha=0.3)
        for axis in axes[len(panels):]:
            axis.set_visible(False)
        figure.suptitle(f"Sobol' indices, N = {self.n_base} ({self.model_runs} model runs), "
                        f"{CONF_LEVEL:.0%} intervals")
        figure.tight_layout()
        figure.savefig(path, dpi=120)
        return path


def _check_choice(values: Sequence[str], known: Sequence[str], what: str) -> tuple[str, ...]:
    chosen = (values,) if isinstance(values, str) else tuple(values)
    unknown = [v for v in chosen if v not in known]
    if not chosen or unknown or len(set(chosen)) != len(chosen):
        raise ValueError(f"{what} must be distinct names out of {list(known)} "
                         f"(got {list(chosen)})")
    return chosen


def sobol_indices(simulator: Simulator, inputs: pd.DataFrame, *,
                  outputs: Sequence[str] = DEFAULT_OUTPUTS,
                  statistics: Sequence[str] = DEFAULT_STATISTICS,
                  bounds: Mapping[str, tuple[float, float]] | None = None,
                  n_base: int = 256, random_state: int = 0, evaluator: Evaluator | None = None,
                  progress: ProgressCallback | None = None) -> SobolResult:
    """Sobol' indices (S1, ST with intervals) of the three parameters for ``outputs``.

    ``inputs``: a load-ramp window of canonical boundary conditions (SI: Pa, K, kg/s) — at a
    hold the heat-transfer coefficient has nothing to act on (module docstring).
    ``statistics``: names out of :data:`STATISTICS`. ``bounds``: per parameter (partial
    allowed), within the physical bounds; default the physical bounds. ``n_base``: N, a power
    of 2; N·5 parameter sets, each one simulator run (two with ``lag_rms``). Every run must
    succeed: a rejected parameter set is a ``ValueError`` naming it — narrow ``bounds`` or
    choose a window the whole box can run (the flow coefficient's low end cannot pass rated
    flow at full load). ``evaluator``: an unstarted evaluator from
    :mod:`steamtwin.calibration.evaluation` (process pool, Dask), started with this job and
    closed here; default in this process. The same ``random_state`` gives the same result on
    any evaluator.
    """
    outputs = _check_choice(outputs, simulator.output_signals, "outputs")
    statistics = _check_choice(statistics, tuple(STATISTICS), "statistics")
    if (isinstance(n_base, bool) or not isinstance(n_base, int | np.integer) or n_base < 2
            or n_base & (n_base - 1)):
        raise ValueError(f"n_base must be a power of 2 ≥ 2 (the Sobol' sequence's balance "
                         f"needs it; got {n_base!r})")
    limits = check_bounds(bounds)
    if not isinstance(inputs, pd.DataFrame) or inputs.empty:
        raise ValueError("inputs must be a non-empty DataFrame of canonical SI signals")
    missing = [name for name in simulator.input_signals if name not in inputs.columns]
    if missing:
        raise ValueError(f"inputs lack column(s) {missing}")
    problem = {"num_vars": len(PARAMETER_NAMES), "names": list(PARAMETER_NAMES),
               "bounds": [list(limits[name]) for name in PARAMETER_NAMES]}
    rng = np.random.default_rng(check_random_state(random_state))
    samples = sobol_sample.sample(problem, int(n_base), calc_second_order=False, seed=rng)
    # SALib's analyze treats seed 0 as "no seed": draw the bootstrap's seed from 1 up
    bootstrap_seed = int(rng.integers(1, 2**31))
    job = _StatisticRuns(simulator, inputs[list(simulator.input_signals)], outputs, statistics)
    runs = _evaluate(job, samples, evaluator, progress)
    failed = [(row, run.error) for row, run in zip(samples, runs, strict=True) if run.error]
    if failed:
        row, error = failed[0]
        values = ", ".join(f"{n} {v:.4f}" for n, v in zip(PARAMETER_NAMES, row, strict=True))
        raise ValueError(f"{len(failed)} of {len(samples)} parameter sets rejected by the "
                         f"simulator, e.g. ({values}): {error}; Sobol' indices need every run: "
                         "narrow the bounds or choose a window every parameter set can run")
    values = np.stack([run.values for run in runs])  # (samples, outputs, statistics)
    levels = np.stack([run.levels for run in runs]).mean(axis=0)
    table_rows = []
    for i, output in enumerate(outputs):
        for j, statistic in enumerate(statistics):
            y = values[:, i, j]
            spread = float(y.std())
            if spread <= SPREAD_RESOLUTION * levels[i]:
                indices = dict.fromkeys(_COLUMNS, np.full(len(PARAMETER_NAMES), np.nan))
            else:
                indices = sobol_analyze.analyze(problem, y, calc_second_order=False,
                                                num_resamples=BOOTSTRAP_RESAMPLES,
                                                conf_level=CONF_LEVEL, seed=bootstrap_seed)
            for k, name in enumerate(PARAMETER_NAMES):
                table_rows.append({"output": output, "statistic": statistic, "parameter": name,
                                   **{c: float(indices[c][k]) for c in _COLUMNS},
                                   "std": spread})
    table = pd.DataFrame(table_rows).set_index(["output", "statistic", "parameter"])
    run_table = pd.DataFrame(samples, columns=list(PARAMETER_NAMES))
    for i, output in enumerate(outputs):
        for j, statistic in enumerate(statistics):
            run_table[f"{output}:{statistic}"] = values[:, i, j]
    result = SobolResult(indices=table, runs=run_table, n_base=int(n_base),
                         model_runs=len(samples) * (2 if "lag_rms" in statistics else 1),
                         bounds=limits)
    for (output, statistic), check in result.checks().iterrows():
        if not (check["sum_S1_ok"] and check["st_ge_s1"]):
            logger.warning("Sobol' indices of %s (%s) are inconsistent beyond their intervals "
                           "(ΣS1 %.3f, ST ≥ S1 %s): take a larger n_base", output, statistic,
                           check["sum_S1"], check["st_ge_s1"])
    return result


def _evaluate(job: _StatisticRuns, samples: np.ndarray, evaluator: Evaluator | None,
              progress: ProgressCallback | None) -> list[_Run]:
    """Runs of every row of ``samples``, in order, in batches that report progress."""
    batches = [b for b in np.array_split(samples, min(_PROGRESS_BATCHES, len(samples)))
               if len(b)]
    if evaluator is not None:
        evaluator.start(job)
    try:
        runs: list[_Run] = []
        for batch in batches:
            runs.extend(job.evaluate_many(batch) if evaluator is None
                        else evaluator.evaluate(batch))
            if progress is not None:
                progress(len(runs) / len(samples),
                         f"Sobol' runs: {len(runs)}/{len(samples)} parameter sets")
        return runs
    finally:
        if evaluator is not None:
            evaluator.close()
