"""The calibrator's search strategies: what looks for the objective's minimum.

A strategy is a small frozen dataclass of its own settings with one method,
``run(problem, random_state=, progress=, resume=, fingerprint=) -> SearchResult``, which
minimises a :class:`~steamtwin.calibration.objective.CalibrationProblem` whose evaluator the
calibrator has already started, and returns the best model-evaluated decision vector with its
record. Everything around it — the objective's settings, tempering, evaluators, the posterior,
identifiability, the parameters file — is the
:class:`~steamtwin.calibration.calibrator.Calibrator`'s, the same for every strategy (pymoo's
split of problem, algorithm and ``minimize``).

* :class:`GeneticSearch`: the method's real-coded GA (:mod:`~steamtwin.calibration.ga`) on the
  model itself, with a checkpoint per generation;
* :class:`~steamtwin.calibration.surrogate.SurrogateSearch`: the GA on an RBF surrogate, the
  model run only for the initial design and the infill points.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from pymoo.core.algorithm import Algorithm

from steamtwin.calibration.checkpoint import (
    load_checkpoint,
    restore_algorithm,
    run_fingerprint,
    save_checkpoint,
)
from steamtwin.calibration.ga import RemutationRepair, check_ga_settings, check_integer, make_ga
from steamtwin.calibration.objective import CalibrationProblem, fitness
from steamtwin.calibration.settings import PARAMETER_NAMES
from steamtwin.progress import ProgressCallback

__all__ = ["HISTORY_COLUMNS", "GeneticSearch", "SearchResult"]

HISTORY_COLUMNS: tuple[str, ...] = (
    "generation", "best_rmse", "mean_rmse", "best_fitness", "mean_fitness", *PARAMETER_NAMES,
    "evaluations", "penalised", "remutations")
"""Columns of a GA history row (``generation`` becomes the index of ``history_``).
``best_rmse``/``mean_rmse`` are the minimised objective: the RMSE (K) without priors and σ,
otherwise the posterior score (:mod:`~steamtwin.calibration.objective`)."""


@dataclass(frozen=True)
class SearchResult:
    """What a search found: ``x`` the best model-evaluated decision vector (PARAMETER_NAMES
    order, dimensionless) and ``history`` (per generation or round); ``population`` (the GA's
    final population), ``repair_counts`` (the re-mutation repair's counters) and ``samples``
    (every model-evaluated point and its score) where the strategy has them, else None."""

    x: np.ndarray
    history: pd.DataFrame
    population: np.ndarray | None = None
    repair_counts: dict[str, int] | None = None
    samples: pd.DataFrame | None = None


@dataclass(frozen=True)
class GeneticSearch:
    """The method's GA on the model (:func:`~steamtwin.calibration.ga.make_ga`; defaults and
    their sources there): ``population`` × ``generations``, SBX ``crossover_probability``
    and ``crossover_eta``, polynomial ``mutation_probability`` (per variable; None = 1/3) and
    ``mutation_eta``, ``tournament_size``. ``checkpoint``: a file rewritten after every
    generation (:mod:`~steamtwin.calibration.checkpoint`); a run resumed from it ends with
    the result of an uninterrupted one. Arguments outside their range raise ``ValueError``
    naming the argument, here.
    """

    population: int = 50
    generations: int = 200
    crossover_probability: float = 0.9
    crossover_eta: float = 15.0
    mutation_probability: float | None = None
    mutation_eta: float = 20.0
    tournament_size: int = 2
    checkpoint: str | Path | None = None

    mode = "ga"
    """The name of the strategy in the parameters file (``calibration.mode``)."""

    def __post_init__(self) -> None:
        check_ga_settings(len(PARAMETER_NAMES), population=self.population,
                          crossover_probability=self.crossover_probability,
                          crossover_eta=self.crossover_eta,
                          mutation_probability=self.mutation_probability,
                          mutation_eta=self.mutation_eta, tournament_size=self.tournament_size)
        check_integer("generations", self.generations, 1)

    def course(self) -> dict[str, object]:
        """Every setting that shapes the run's course (not the checkpoint's path)."""
        return {k: v for k, v in asdict(self).items() if k != "checkpoint"}

    def record(self) -> dict[str, object]:
        """What the parameters file records of the search."""
        return {"population": self.population, "generations": self.generations}

    def fingerprint(self, problem: CalibrationProblem, settings: Mapping[str, object]) -> str:
        """The run's identity in a checkpoint: the calibrator's ``settings``, this search's
        course and the prepared data (:func:`~steamtwin.calibration.checkpoint.run_fingerprint`)."""
        return run_fingerprint({**settings, **self.course()}, problem.objective)

    def run(self, problem: CalibrationProblem, *, random_state: int,
            progress: ProgressCallback | None = None, resume: bool = False,
            settings: Mapping[str, object] | None = None) -> SearchResult:
        """Run the GA on ``problem`` (its evaluator started); ``settings``: the calibrator's
        settings that, with the prepared data, identify the run in a checkpoint."""
        if resume and self.checkpoint is None:
            raise ValueError("resume needs a checkpoint file")
        checkpoint = None if self.checkpoint is None else Path(self.checkpoint)
        digest = self.fingerprint(problem, settings or {})
        repair = RemutationRepair(eta=self.mutation_eta)
        algorithm = make_ga(
            problem.n_var, population=self.population,
            crossover_probability=self.crossover_probability, crossover_eta=self.crossover_eta,
            mutation_probability=self.mutation_probability, mutation_eta=self.mutation_eta,
            tournament_size=self.tournament_size, repair=repair)
        algorithm.setup(problem, termination=("n_gen", self.generations), seed=random_state,
                        verbose=False, save_history=False)
        rows: list[dict[str, object]] = []
        if resume:
            state = load_checkpoint(checkpoint, problem, digest, population=self.population,
                                    generations=self.generations,
                                    history_columns=HISTORY_COLUMNS)
            restore_algorithm(algorithm, state)
            rows = state.history
            problem.n_evaluations, problem.n_penalised = state.evaluations, state.penalised
            problem.last_error = state.last_error
        while algorithm.has_next():
            algorithm.next()
            rows.append(_history_row(algorithm, problem, repair))
            if checkpoint is not None:
                save_checkpoint(checkpoint, algorithm, problem, rows, digest)
            if progress is not None:
                done = int(rows[-1]["generation"])
                progress(done / self.generations, f"generation {done}/{self.generations}: "
                         f"best objective {rows[-1]['best_rmse']:.3f}")
        return SearchResult(
            x=algorithm.opt[0].X, history=pd.DataFrame(rows).set_index("generation"),
            population=algorithm.pop.get("X").copy(),
            repair_counts={"out_of_bounds": repair.n_out_of_bounds,
                           "remutations": repair.n_remutations, "clipped": repair.n_clipped})


def _history_row(algorithm: Algorithm, problem: CalibrationProblem,
                 repair: RemutationRepair) -> dict[str, object]:
    rmse = algorithm.pop.get("F")[:, 0]
    best = algorithm.opt[0]
    best_rmse = float(best.F[0])
    return {
        "generation": int(algorithm.n_gen) - 1,  # pymoo counts ahead; 1 = initial population
        "best_rmse": best_rmse,
        "mean_rmse": float(np.mean(rmse)),
        "best_fitness": fitness(best_rmse),
        "mean_fitness": float(np.mean(fitness(rmse))),
        **dict(zip(PARAMETER_NAMES, (float(v) for v in best.X), strict=True)),
        "evaluations": problem.n_evaluations,
        "penalised": problem.n_penalised,
        "remutations": repair.n_remutations,
    }
