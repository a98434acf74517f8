"""Surrogate-assisted calibration: the GA searches a cheap RBF surrogate, the model checks it.

Method (the usual surrogate-based optimisation loop: Jones, Schonlau & Welch 1998, *J. Global
Optim.* 13:455; Forrester, Sóbester & Keane 2008, *Engineering Design via Surrogate Modelling*,
ch. 3 and 7; Regis & Shoemaker 2005 for RBF surrogates):

1. **Initial design**: a Latin hypercube of ``initial_samples`` points in the bounds (default
   10 per variable, Loeppky, Sacks & Welch 2009), evaluated with the model.
2. **Surrogate**: an RBF interpolant (``scipy.interpolate.RBFInterpolator``, thin-plate spline
   plus a linear polynomial) of ``log(RMSE)`` over the bounds scaled to the unit cube. The log
   makes the steep walls around the valley as smooth as its floor; rejected candidates (penalty
   RMSE) enter at twice the worst feasible RMSE, so the surrogate steers away from them without
   a 1000-K cliff.
3. **GA on the surrogate**: the method's GA (:func:`~steamtwin.calibration.ga.make_ga`), which
   costs milliseconds here.
4. **Infill**: the surrogate optimum (and distinct runners-up of the GA's final population),
   local probes around the best model-evaluated point, and one space-filling point (the
   farthest of a random set from every evaluated point) are evaluated with the model, as one
   parallel batch, and added to the data.
5. Repeat 2–4 until the best model-evaluated RMSE has improved by less than
   ``improvement_tolerance`` for ``patience`` rounds, or ``max_evaluations`` is spent.
6. **Polish** (at most ``polish_evaluations`` model runs, within ``max_evaluations``): a
   bounded trust-region least-squares descent on the model itself from the best point
   (``scipy.optimize.least_squares``, trust-region reflective: Branch, Coleman & Li 1999,
   *SIAM J. Sci. Comput.* 21:1; Gauss–Newton steps on the residual vector whose sum of squares
   is the score's square, forward-difference Jacobian with step :data:`_POLISH_STEP` of each
   range). The surrogate finds the basin; on a flat tempered posterior its infill stops a few
   thousandths of the score above the minimum, which can be 0.1 K of RMSE away in parameters
   (measured on ``bench_joint_calibration.py``'s two windows), and a few Gauss–Newton steps
   close that gap for tens of runs (Forrester, Sóbester & Keane 2008, §7.4: finish a
   surrogate search with a local search on the true function).

The result is always a model-evaluated point (the best of every run, polish included), never
a surrogate prediction; the calibrator's
``n_evaluations_`` is what the model was asked for. What is minimised is the calibration
objective's score — the negative log posterior's monotone transform with the default priors
(the MAP), the RMSE with ``priors=None`` (:mod:`~steamtwin.calibration.objective`) — and the
Laplace posterior at the result (for a ``WindowSet`` also the cluster-robust one over its load
bands, the wider per parameter) gives the intervals, as for the GA.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem
from pymoo.optimize import minimize
from scipy.interpolate import RBFInterpolator
from scipy.optimize import least_squares
from scipy.stats import qmc

from steamtwin.calibration.ga import check_ga_settings, check_integer, make_ga
from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem, fitness
from steamtwin.calibration.search import SearchResult
from steamtwin.calibration.settings import PARAMETER_NAMES
from steamtwin.errors import SteamtwinError
from steamtwin.progress import ProgressCallback

__all__ = ["SurrogateSearch"]

_MIN_SEPARATION = 1e-4  # unit-cube distance below which a candidate repeats an evaluated point
_CANDIDATE_SEPARATION = 0.02  # between infill points of one batch (unit cube)
_LOCAL_SPREAD = 0.03  # σ of the local probes around the best point (unit cube)
# Forward-difference step of the polish's Jacobian in the unit cube (2e-4 of the flow
# coefficient, 1.5e-3 of the friction and heat-transfer coefficients): an approximate Jacobian
# only shapes the Gauss–Newton steps and a step is kept only if the model's score falls, so a
# rough one costs runs rather than a worse answer; measured: 16 runs on the benchmark's pair.
_POLISH_STEP = 1e-3
_POLISH_TOLERANCE = 1e-6  # relative change of the cost (and of x) that ends the polish


class _SurrogateProblem(Problem):
    """The surrogate as a vectorised pymoo problem (unit-cube variables)."""

    def __init__(self, surrogate: RBFInterpolator, n_var: int) -> None:
        super().__init__(n_var=n_var, n_obj=1, xl=np.zeros(n_var), xu=np.ones(n_var))
        self.surrogate = surrogate

    def _evaluate(self, x: np.ndarray, out: dict, *args: object, **kwargs: object) -> None:
        out["F"] = self.surrogate(np.atleast_2d(x))[:, None]


@dataclass(frozen=True)
class SurrogateSearch:
    """Far fewer model runs: the GA on an RBF surrogate with model-run infill (module
    docstring). ``initial_samples``: the Latin-hypercube design (None: 10 per variable);
    ``infill_per_round``: model runs per round; ``max_evaluations``: the model-run budget;
    ``patience`` rounds without an improvement of more than ``improvement_tolerance`` (in the
    objective's score, K without priors) end the search; ``population`` × ``generations``: the
    GA on the surrogate; ``polish_evaluations``: model runs of the final local descent (step 6;
    0: none). Arguments outside their range raise ``ValueError`` naming the
    argument, here. The result's ``history`` has one row per round (model runs so far, best
    score and fitness, the surrogate's own prediction at its optimum, best parameters) and
    a last one after the polish (its prediction NaN), ``samples`` every model-evaluated point
    and its score.
    """

    initial_samples: int | None = None
    infill_per_round: int = 4
    max_evaluations: int = 400
    patience: int = 8
    improvement_tolerance: float = 0.002
    population: int = 50
    generations: int = 100
    polish_evaluations: int = 40

    mode = "surrogate"
    """The name of the strategy in the parameters file (``calibration.mode``)."""

    def __post_init__(self) -> None:
        initial = self.design_size()
        for name, value, low in (("initial_samples", initial, len(PARAMETER_NAMES) + 2),
                                 ("infill_per_round", self.infill_per_round, 1),
                                 ("patience", self.patience, 1),
                                 ("generations", self.generations, 1),
                                 ("polish_evaluations", self.polish_evaluations, 0)):
            check_integer(name, value, low)
        least = int(initial) + int(self.infill_per_round)
        if isinstance(self.max_evaluations, bool) or not isinstance(
                self.max_evaluations, int | np.integer) or self.max_evaluations < least:
            raise ValueError(f"max_evaluations must be an integer ≥ initial_samples + "
                             f"infill_per_round = {least} (got {self.max_evaluations!r})")
        tolerance = self.improvement_tolerance
        if isinstance(tolerance, bool) or not isinstance(
                tolerance, int | float | np.integer | np.floating) or not (
                0.0 <= tolerance < float("inf")):
            raise ValueError(f"improvement_tolerance must be a finite number ≥ 0 K "
                             f"(got {tolerance!r})")
        check_ga_settings(len(PARAMETER_NAMES), population=self.population)

    def design_size(self) -> int | None:
        """Points of the initial design: ``initial_samples``, default 10 per variable
        (Loeppky, Sacks & Welch 2009)."""
        return 10 * len(PARAMETER_NAMES) if self.initial_samples is None \
            else self.initial_samples

    def record(self) -> dict[str, object]:
        """What the parameters file records of the search."""
        return {"initial_samples": self.initial_samples,
                "infill_per_round": self.infill_per_round,
                "max_evaluations": self.max_evaluations,
                "polish_evaluations": self.polish_evaluations}

    def run(self, problem: CalibrationProblem, *, random_state: int,
            progress: ProgressCallback | None = None, resume: bool = False,
            settings: Mapping[str, object] | None = None) -> SearchResult:
        """Run the surrogate loop on ``problem`` (its evaluator started); it has no
        checkpoint (``resume`` is refused) and no use for the calibrator's ``settings``."""
        if resume:
            raise ValueError("resume continues a GA run; the surrogate mode has no checkpoint")
        n_var = problem.n_var
        low, high = np.asarray(problem.xl, float), np.asarray(problem.xu, float)
        random = np.random.default_rng(random_state)
        unit = qmc.LatinHypercube(d=n_var, seed=random).random(int(self.design_size()))
        points, values = _evaluate(problem, unit, low, high, np.empty((0, n_var)), np.empty(0))
        rows: list[dict[str, object]] = []
        stale, best, round_number = 0, float(values.min()), 0
        while points.shape[0] < self.max_evaluations and stale < self.patience:
            round_number += 1
            surrogate = _fit_surrogate(points, values)
            result = minimize(
                _SurrogateProblem(surrogate, n_var), make_ga(n_var, population=self.population),
                termination=("n_gen", self.generations),
                seed=int(random.integers(2**31 - 1)), verbose=False)
            budget = min(self.infill_per_round, self.max_evaluations - points.shape[0])
            infill = _infill(result.pop.get("X"), result.pop.get("F")[:, 0], points, values,
                             budget, random)
            if infill.shape[0] == 0:
                break  # the surrogate has nothing new to ask the model
            points, values = _evaluate(problem, infill, low, high, points, values)
            improved = best - float(values.min()) > self.improvement_tolerance
            best = min(best, float(values.min()))
            stale = 0 if improved else stale + 1
            rows.append(_history_row(round_number, points, values, low, high,
                                     float(np.exp(result.F[0]))))
            if progress is not None:
                progress(min(1.0, points.shape[0] / self.max_evaluations),
                         f"surrogate round {round_number}: {points.shape[0]} model runs, "
                         f"best RMSE {best:.3f} K")
        budget = min(self.polish_evaluations, self.max_evaluations - points.shape[0])
        if budget > 0 and values.min() < PENALTY_RMSE:
            points, values = _polish(problem, points, values, low, high, budget)
            rows.append(_history_row(round_number + 1, points, values, low, high, math.nan))
            if progress is not None:
                progress(min(1.0, points.shape[0] / self.max_evaluations),
                         f"surrogate polish: {points.shape[0]} model runs, best score "
                         f"{float(values.min()):.3f}")
        samples = pd.DataFrame(low + points * (high - low), columns=list(PARAMETER_NAMES))
        samples["score"] = values
        return SearchResult(
            x=low + points[int(np.argmin(values))] * (high - low),
            history=pd.DataFrame(rows).set_index("round") if rows else pd.DataFrame(),
            samples=samples)


def _evaluate(problem: CalibrationProblem, unit: np.ndarray, low: np.ndarray,
              high: np.ndarray, points: np.ndarray, values: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """The model's score at each unit-cube row of ``unit``, appended to the data so far."""
    rmse = problem.evaluate_candidates(low + unit * (high - low))
    return np.vstack([points, unit]), np.concatenate([values, rmse])


class _PolishEnded(SteamtwinError):
    """The polish spent its budget or the model rejected a step (stops scipy's solver from
    inside; never leaves :func:`_polish`)."""


def _polish(problem: CalibrationProblem, points: np.ndarray, values: np.ndarray,
            low: np.ndarray, high: np.ndarray, budget: int) -> tuple[np.ndarray, np.ndarray]:
    """Step 6 of the module docstring from the best of ``points`` (unit cube) with at most
    ``budget`` model runs; every run is appended to the data."""
    tried: list[np.ndarray] = []
    scores: list[float] = []

    def residuals(u: np.ndarray) -> np.ndarray:
        if len(tried) == budget:
            raise _PolishEnded
        result, vector = problem.evaluate_with_residuals(low + u * (high - low))
        tried.append(np.array(u, dtype=float))
        scores.append(result.value)
        if vector is None:
            raise _PolishEnded
        return vector

    start = points[int(np.argmin(values))]
    with contextlib.suppress(_PolishEnded):
        least_squares(residuals, start, bounds=(0.0, 1.0), method="trf", jac="2-point",
                      diff_step=_POLISH_STEP, ftol=_POLISH_TOLERANCE, xtol=_POLISH_TOLERANCE,
                      gtol=None)
    if not tried:
        return points, values
    return np.vstack([points, *tried]), np.concatenate([values, scores])


def _history_row(round_number: int, points: np.ndarray, values: np.ndarray,
                 low: np.ndarray, high: np.ndarray, predicted: float) -> dict[str, object]:
    best = int(np.argmin(values))
    x = low + points[best] * (high - low)
    return {"round": round_number, "evaluations": int(points.shape[0]),
            "best_rmse": float(values[best]), "best_fitness": fitness(float(values[best])),
            "surrogate_optimum_rmse": predicted,
            **dict(zip(PARAMETER_NAMES, (float(v) for v in x), strict=True))}


def _fit_surrogate(points: np.ndarray, values: np.ndarray) -> RBFInterpolator:
    """Thin-plate RBF of log RMSE; rejected points enter at twice the worst feasible RMSE."""
    feasible = values < PENALTY_RMSE
    ceiling = 2.0 * values[feasible].max() if feasible.any() else PENALTY_RMSE
    target = np.log(np.minimum(values, ceiling))
    return RBFInterpolator(points, target, kernel="thin_plate_spline", degree=1)


def _infill(population: np.ndarray, predicted: np.ndarray, evaluated: np.ndarray,
            values: np.ndarray, budget: int, random: np.random.Generator) -> np.ndarray:
    """Up to ``budget`` new points (unit cube): the surrogate's best distinct members, local
    probes around the best model-evaluated point, then one space filler.

    The local probes (Gaussian, σ = :data:`_LOCAL_SPREAD` of each range) keep refining the basin
    the model has confirmed when the surrogate's own optimum repeats a known point; the space
    filler keeps the surrogate honest far from the data (Regis & Shoemaker 2007, *INFORMS J.
    Comput.* 19:497, mix local and global candidates the same way).
    """
    chosen: list[np.ndarray] = []

    def new(x: np.ndarray) -> bool:
        known = np.vstack([evaluated, *chosen]) if chosen else evaluated
        return bool(np.min(np.linalg.norm(known - x, axis=1)) >= _MIN_SEPARATION) and not (
            chosen and np.min(np.linalg.norm(np.array(chosen) - x, axis=1))
            < _CANDIDATE_SEPARATION)

    exploit = max(1, (budget - 1) // 2) if budget > 1 else 1
    for index in np.argsort(predicted):
        x = np.clip(population[index], 0.0, 1.0)
        if new(x):
            chosen.append(x)
        if len(chosen) == exploit:
            break
    best = evaluated[int(np.argmin(values))]
    for _ in range(50):
        if len(chosen) >= budget - 1:
            break
        x = np.clip(best + random.normal(0.0, _LOCAL_SPREAD, best.size), 0.0, 1.0)
        if new(x):
            chosen.append(x)
    if len(chosen) < budget:
        pool = random.random((2000, evaluated.shape[1]))
        known = np.vstack([evaluated, *chosen]) if chosen else evaluated
        distance = np.min(np.linalg.norm(pool[:, None, :] - known[None, :, :], axis=2), axis=1)
        chosen.append(pool[int(np.argmax(distance))])
    return np.array(chosen[:budget])
