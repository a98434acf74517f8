"""The method's real-coded genetic algorithm, assembled from pymoo pieces.

* selection: :class:`~pymoo.operators.selection.tournament.TournamentSelection` of size ``k``
  with :func:`tournament_by_fitness`, a ``k``-way fold of pymoo's ``compare`` (constraint
  violation first, then the objective, random on ties — GA's default rule, for any ``k``);
* crossover: simulated binary crossover ``SBX(prob=p_c, eta=η_c)`` (``p_c`` per mating);
* mutation: polynomial mutation ``PM(prob=1, prob_var=p_m, eta=η_m)`` — ``p_m`` is the
  per-variable probability of Deb's convention (pymoo's ``prob`` is per individual);
* re-mutation of out-of-bounds offspring: :class:`RemutationRepair`;
* elitism: GA's ``FitnessSurvival`` keeps the best of parents and offspring.

Defaults and sources: population 50 and 200 generations as in the method; ``p_c = 0.9``,
``η_c = 15``, ``p_m = 1/n_var``, ``η_m = 20`` are Deb's recommendations for real-coded GAs
(Deb & Agrawal 1995; Deb 2001, *Multi-Objective Optimization using Evolutionary Algorithms*)
and pymoo's own defaults for SBX/PM. pymoo's bounded SBX and PM clamp to the bounds themselves,
so the repair is a safeguard in the method's sense that normally finds nothing to do; its
counters show whether it acted.
"""

from __future__ import annotations

import math

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.population import Population
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.sampling.rnd import FloatRandomSampling
from pymoo.operators.selection.tournament import TournamentSelection, compare

__all__ = ["RemutationRepair", "check_ga_settings", "check_integer", "make_ga",
           "polynomial_perturbation", "tournament_by_fitness"]


def tournament_by_fitness(pop: Population, P: np.ndarray,
                          random_state: np.random.Generator | None = None,
                          **kwargs: object) -> np.ndarray:
    """Winner of each tournament row of ``P`` (k competitors): least CV, then least F."""
    if random_state is None:
        raise ValueError("tournament_by_fitness needs the algorithm's random_state")
    winners = np.empty(P.shape[0], dtype=int)
    for i, row in enumerate(P):
        best = int(row[0])
        for challenger in (int(c) for c in row[1:]):
            a, b = pop[best], pop[challenger]
            if a.CV[0] > 0.0 or b.CV[0] > 0.0:
                best = int(compare(best, a.CV[0], challenger, b.CV[0], "smaller_is_better",
                                   return_random_if_equal=True, random_state=random_state))
            else:
                best = int(compare(best, a.F[0], challenger, b.F[0], "smaller_is_better",
                                   return_random_if_equal=True, random_state=random_state))
        winners[i] = best
    return winners[:, None]


def polynomial_perturbation(x: np.ndarray, span: np.ndarray, eta: float,
                            random_state: np.random.Generator) -> np.ndarray:
    """Deb's (unbounded) polynomial mutation ``x + δ·span``, δ ∈ (−1, 1) with index ``eta``."""
    r = random_state.random(np.shape(x))
    power = 1.0 / (eta + 1.0)
    delta = np.where(r < 0.5, (2.0 * r) ** power - 1.0, 1.0 - (2.0 * (1.0 - r)) ** power)
    return x + delta * span


class RemutationRepair(Repair):
    """Re-mutate out-of-bounds variables until inside the bounds; clip after ``max_tries``.

    Each offending variable is re-mutated from its offending value with polynomial mutation
    (index ``eta``, scale = bound width) until the result lies within the bounds; after
    ``max_tries`` failed draws it is clipped. Counters (cumulative): ``n_out_of_bounds``
    variables found outside, ``n_remutations`` draws, ``n_clipped`` variables clipped.
    """

    def __init__(self, eta: float = 20.0, max_tries: int = 20) -> None:
        super().__init__()
        if not (_is_real(eta) and math.isfinite(eta) and eta > 0):
            raise ValueError(f"eta must be a finite number > 0 (got {eta!r})")
        check_integer("max_tries", max_tries, 1)
        self.eta = float(eta)
        self.max_tries = int(max_tries)
        self.n_out_of_bounds = 0
        self.n_remutations = 0
        self.n_clipped = 0

    def _do(self, problem: Problem, X: np.ndarray, random_state: np.random.Generator | None = None,
            **kwargs: object) -> np.ndarray:
        values = np.array(X, dtype=float)
        xl = np.broadcast_to(np.asarray(problem.xl, dtype=float), values.shape)
        xu = np.broadcast_to(np.asarray(problem.xu, dtype=float), values.shape)
        outside = (values < xl) | (values > xu)
        if not outside.any():
            return values
        if random_state is None:
            raise ValueError("RemutationRepair needs the algorithm's random_state")
        self.n_out_of_bounds += int(outside.sum())
        start = values[outside]
        low, high = xl[outside], xu[outside]
        result = start.copy()
        pending = np.ones(start.size, dtype=bool)
        for _ in range(self.max_tries):
            if not pending.any():
                break
            self.n_remutations += int(pending.sum())
            draw = polynomial_perturbation(start[pending], (high - low)[pending], self.eta,
                                           random_state)
            inside = (draw >= low[pending]) & (draw <= high[pending])
            index = np.flatnonzero(pending)
            result[index[inside]] = draw[inside]
            pending[index[inside]] = False
        self.n_clipped += int(pending.sum())
        result[pending] = np.clip(start[pending], low[pending], high[pending])
        values[outside] = result
        return values


def check_integer(name: str, value: object, low: int, high: int | None = None) -> None:
    """ValueError naming ``name`` unless ``value`` is an integer ≥ ``low`` (and ≤ ``high``)."""
    allowed = f"within [{low}, {high}]" if high is not None else f"≥ {low}"
    if (isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low
            or (high is not None and value > high)):
        raise ValueError(f"{name} must be an integer {allowed} (got {value!r})")


def _is_real(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float | np.integer
                                                      | np.floating)


def check_ga_settings(n_var: int, *, population: int = 50, crossover_probability: float = 0.9,
                      crossover_eta: float = 15.0, mutation_probability: float | None = None,
                      mutation_eta: float = 20.0, tournament_size: int = 2) -> None:
    """Raise ``ValueError`` naming the first argument of :func:`make_ga` outside its range.

    ``n_var`` ≥ 1, ``population`` ≥ 2, ``tournament_size`` within [2, population], the
    probabilities within [0, 1] (``mutation_probability`` may be None: 1/n_var), the
    distribution indices ``crossover_eta`` and ``mutation_eta`` finite and > 0.
    """
    check_integer("n_var", n_var, 1)
    check_integer("population", population, 2)
    check_integer("tournament_size", tournament_size, 2, int(population))
    probabilities = [("crossover_probability", crossover_probability)]
    if mutation_probability is not None:
        probabilities.append(("mutation_probability", mutation_probability))
    for name, value in probabilities:
        if not (_is_real(value) and 0.0 <= value <= 1.0):
            raise ValueError(f"{name} must be a number within [0, 1] (got {value!r})")
    for name, value in (("crossover_eta", crossover_eta), ("mutation_eta", mutation_eta)):
        if not (_is_real(value) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0 (got {value!r})")


def make_ga(n_var: int, *, population: int = 50, crossover_probability: float = 0.9,
            crossover_eta: float = 15.0, mutation_probability: float | None = None,
            mutation_eta: float = 20.0, tournament_size: int = 2,
            repair: Repair | None = None, initial_population: np.ndarray | None = None) -> GA:
    """The method's GA for ``n_var`` variables (see the module docstring for the defaults).

    ``mutation_probability`` per variable, default ``1/n_var``; ``repair`` defaults to a
    :class:`RemutationRepair` with ``eta = mutation_eta``; ``initial_population`` (rows of
    variables) warm-starts the GA instead of uniform random sampling. Arguments outside
    their range raise ``ValueError`` naming the argument (:func:`check_ga_settings`).
    """
    check_ga_settings(n_var, population=population,
                      crossover_probability=crossover_probability, crossover_eta=crossover_eta,
                      mutation_probability=mutation_probability, mutation_eta=mutation_eta,
                      tournament_size=tournament_size)
    p_m = 1.0 / n_var if mutation_probability is None else float(mutation_probability)
    sampling = FloatRandomSampling() if initial_population is None else np.atleast_2d(
        np.asarray(initial_population, dtype=float))
    return GA(
        pop_size=population,
        sampling=sampling,
        selection=TournamentSelection(func_comp=tournament_by_fitness, pressure=tournament_size),
        crossover=SBX(prob=crossover_probability, eta=crossover_eta),
        mutation=PM(prob=1.0, prob_var=p_m, eta=mutation_eta),
        repair=repair if repair is not None else RemutationRepair(eta=mutation_eta),
        eliminate_duplicates=True,
    )
