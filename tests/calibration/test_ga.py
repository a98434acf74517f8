"""The GA pieces: re-mutation repair, k-way tournament, operator settings."""

from __future__ import annotations

import numpy as np
import pytest
from pymoo.core.population import Population
from pymoo.core.problem import Problem

from steamtwin.calibration.ga import RemutationRepair, make_ga, tournament_by_fitness


def test_repair_puts_every_variable_in_bounds_and_counts():
    problem = Problem(n_var=3, n_obj=1, xl=np.array([0.9, 0.5, 0.5]), xu=np.array([1.1, 2.0, 2.0]))
    X = np.array([[1.0, 1.0, 1.0],       # inside: untouched
                  [1.12, 0.49, 1.0],     # slightly outside: re-mutated
                  [5.0, -3.0, 2.5]])     # far outside: clipped after max_tries
    repair = RemutationRepair(eta=20.0, max_tries=10)
    repaired = repair._do(problem, X, random_state=np.random.default_rng(3))
    assert ((repaired >= problem.xl) & (repaired <= problem.xu)).all()
    np.testing.assert_array_equal(repaired[0], X[0])
    assert repair.n_out_of_bounds == 5
    assert repair.n_remutations >= 5
    assert repair.n_clipped >= 2  # 5.0 and -3.0 lie further out than any draw reaches
    assert repair.n_remutations <= 5 * 10


def test_tournament_picks_the_best_of_k():
    pop = Population.new(X=np.zeros((4, 1)))
    pop.set("F", np.array([[3.0], [1.0], [2.0], [0.5]]), "CV", np.zeros((4, 1)))
    P = np.array([[0, 1, 2], [2, 3, 0]])
    winners = tournament_by_fitness(pop, P, random_state=np.random.default_rng(0))
    np.testing.assert_array_equal(winners[:, 0], [1, 3])


def test_operator_settings():
    ga = make_ga(3, population=10, crossover_probability=0.8, tournament_size=3)
    assert ga.pop_size == 10
    assert ga.mating.selection.pressure == 3
    assert ga.mating.crossover.prob.value == 0.8
    assert ga.mating.mutation.prob_var.value == 1.0 / 3
    assert isinstance(ga.repair, RemutationRepair)


@pytest.mark.parametrize(("arguments", "message"), [
    ({"n_var": 0}, r"^n_var must be an integer ≥ 1 \(got 0\)$"),
    ({"population": 0}, r"^population must be an integer ≥ 2 \(got 0\)$"),
    ({"population": 3, "tournament_size": 4},
     r"^tournament_size must be an integer within \[2, 3\] \(got 4\)$"),
    ({"tournament_size": 1.0}, r"^tournament_size must be an integer within \[2, 50\]"),
    ({"crossover_probability": "0.9"},
     r"^crossover_probability must be a number within \[0, 1\] \(got '0\.9'\)$"),
    ({"mutation_probability": 2}, r"^mutation_probability must be a number within \[0, 1\]"),
    ({"crossover_eta": -15.0}, r"^crossover_eta must be a finite number > 0 \(got -15\.0\)$"),
    ({"mutation_eta": float("nan")}, r"^mutation_eta must be a finite number > 0 \(got nan\)$"),
])
def test_make_ga_names_the_argument_out_of_range(arguments, message):
    with pytest.raises(ValueError, match=message):
        make_ga(**{"n_var": 3, **arguments})


def test_repair_arguments_are_named():
    with pytest.raises(ValueError, match=r"^eta must be a finite number > 0 \(got 0\)$"):
        RemutationRepair(eta=0)
    with pytest.raises(ValueError, match=r"^max_tries must be an integer ≥ 1 \(got 0\)$"):
        RemutationRepair(max_tries=0)
