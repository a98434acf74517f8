"""Per-generation checkpoints of a GA calibration, and resuming from them.

A checkpoint is one UTF-8 JSON document that holds only data — nothing in it is unpickled,
imported or executed, so a planted or damaged file can at worst be refused:

* ``format`` (:data:`CHECKPOINT_FORMAT`) and ``fingerprint``, the SHA-256 of the run's
  settings and prepared data (:func:`run_fingerprint`): a checkpoint resumes only the run that
  wrote it;
* ``generation`` (completed generations, 1 = the initial population) and ``terminated``
  (pymoo ended the run early because mating found no new offspring);
* ``population``: the GA's current population, ``X`` (rows of variables, within the bounds)
  and ``F`` (RMSE, K). The calibration problem has no constraints, so every constraint
  violation is 0 and is not stored; the elite (pymoo's ``opt``) is the population's least
  RMSE and is recomputed from it;
* ``random_state``: the numpy ``Generator``'s ``bit_generator.state`` (PCG64, plain integers);
* ``repair``: the re-mutation repair's counters; ``evaluations``, ``penalised`` and
  ``last_error``: the problem's evaluation counters and last rejection reason;
* ``history``: the per-generation rows so far.

:func:`load_checkpoint` validates every field against the run (variables, bounds, population
size, generations, history columns) before anything is used; each problem is a
:class:`CheckpointError` naming the file and the field. :func:`restore_algorithm` puts the state
into a GA freshly built by :func:`~steamtwin.calibration.ga.make_ga` and set up with the run's
seed and termination: the resumed run then takes exactly the course of an uninterrupted one.
The file is written to a temporary name and renamed (``os.replace``, atomic on POSIX), so a
kill leaves either the previous or the new generation's checkpoint, never a torn one.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pymoo.core.algorithm import Algorithm
from pymoo.core.population import Population
from pymoo.core.problem import Problem
from pymoo.util.optimum import filter_optimum

from steamtwin.calibration.ga import RemutationRepair
from steamtwin.calibration.objective import Objective
from steamtwin.errors import CalibrationAreaError

__all__ = ["CHECKPOINT_FORMAT", "CheckpointError", "CheckpointState", "load_checkpoint",
           "restore_algorithm", "run_fingerprint", "save_checkpoint"]

CHECKPOINT_FORMAT = "steamtwin-calibration-checkpoint/2"
"""Format tag; version 1 was a pickle and is refused like any other non-JSON file."""

_FIELDS = ("format", "fingerprint", "generation", "terminated", "population", "random_state",
           "repair", "evaluations", "penalised", "last_error", "history")
_REPAIR_COUNTERS = ("out_of_bounds", "remutations", "clipped")
_PCG64_STATE_LIMIT = 2**128  # PCG64's state and increment are 128-bit integers
_UINT32_LIMIT = 2**32


class CheckpointError(CalibrationAreaError):
    """A checkpoint file that cannot resume this run; the message names file and field."""


@dataclass(frozen=True)
class CheckpointState:
    """A validated checkpoint: what :func:`restore_algorithm` and the calibrator restore.

    ``X`` (rows, n_var) and ``F`` (rows,) RMSE in K; ``random_state`` a PCG64 state dict;
    ``repair`` the :class:`RemutationRepair` counters by name.
    """

    generation: int
    terminated: bool
    X: np.ndarray
    F: np.ndarray
    random_state: dict[str, object]
    repair: dict[str, int]
    evaluations: int
    penalised: int
    last_error: str | None
    history: list[dict[str, object]]


def run_fingerprint(settings: dict[str, object], objective: Objective) -> str:
    """SHA-256 of the run's settings and prepared data (inputs, measurements, sensors)."""
    digest = hashlib.sha256()
    digest.update(json.dumps(settings, sort_keys=True, default=repr).encode())
    digest.update(json.dumps([list(objective.sensors), objective.weights.tolist(),
                              type(objective.simulator).__qualname__]).encode())
    for window in objective.windows:
        digest.update(np.ascontiguousarray(window.inputs.to_numpy(dtype=float)).tobytes())
        digest.update(np.ascontiguousarray(window.measured).tobytes())
        digest.update(str(window.inputs.index[0]).encode())
        digest.update(repr((window.weight, None if window.sigma is None
                            else window.sigma.tolist(), window.group,
                            None if window.bias_spread is None
                            else window.bias_spread.tolist())).encode())
    return digest.hexdigest()


def save_checkpoint(path: Path, algorithm: Algorithm, problem: Problem,
                    history: list[dict[str, object]], fingerprint: str) -> None:
    """Write the GA's state after a generation as JSON, atomically (temporary file, rename).

    ``algorithm`` is the running GA of :func:`~steamtwin.calibration.ga.make_ga` (its repair a
    :class:`RemutationRepair`), ``problem`` the calibration problem with its counters.
    """
    repair = algorithm.repair
    document = {
        "format": CHECKPOINT_FORMAT,
        "fingerprint": fingerprint,
        "generation": int(algorithm.n_iter) - 1,  # pymoo counts ahead
        "terminated": bool(algorithm.termination.force_termination),
        "population": {"X": algorithm.pop.get("X").tolist(),
                       "F": algorithm.pop.get("F")[:, 0].tolist()},
        "random_state": algorithm.random_state.bit_generator.state,
        "repair": {"out_of_bounds": repair.n_out_of_bounds,
                   "remutations": repair.n_remutations, "clipped": repair.n_clipped},
        "evaluations": int(problem.n_evaluations),
        "penalised": int(problem.n_penalised),
        "last_error": problem.last_error,
        "history": history,
    }
    text = json.dumps(document, allow_nan=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp")
    with open(temporary, "w", encoding="utf-8") as handle:
        handle.write(text)
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(temporary, path)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not a finite number")


def load_checkpoint(path: Path, problem: Problem, fingerprint: str, *, population: int,
                    generations: int, history_columns: Sequence[str]) -> CheckpointState:
    """Read and validate the checkpoint at ``path`` for this run.

    ``problem`` gives the variables' count and bounds, ``population`` the GA's population size,
    ``generations`` the run's length and ``history_columns`` the keys of a history row. Raises
    :class:`CheckpointError` naming the file and the field for anything that does not fit.
    """
    if not path.is_file():
        raise CheckpointError(f"{path}: no checkpoint to resume from")
    try:
        document = json.loads(path.read_bytes().decode("utf-8"),
                              parse_constant=_reject_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise CheckpointError(
            f"{path}: not a readable calibration checkpoint (expected a {CHECKPOINT_FORMAT} "
            f"JSON document: {error}); run again without resume") from None
    check = _Checker(path)
    if not isinstance(document, dict):
        raise check.error("(document)", "expected a JSON object")
    missing = [name for name in _FIELDS if name not in document]
    if missing:
        raise check.error(missing[0], "missing")
    unknown = sorted(set(document) - set(_FIELDS))
    if unknown:
        raise check.error(unknown[0], "unknown field")
    if document["format"] != CHECKPOINT_FORMAT:
        raise check.error("format", f"expected {CHECKPOINT_FORMAT!r}, found "
                          f"{str(document['format'])[:80]!r}")
    if document["fingerprint"] != fingerprint:
        raise check.error("fingerprint", "the checkpoint was written for other settings or "
                          "data; run again without resume (or with the original settings and "
                          "data)")
    generation = check.integer("generation", document["generation"], 1, generations)
    terminated = document["terminated"]
    if not isinstance(terminated, bool):
        raise check.error("terminated", "expected true or false")
    X, F = check.population(document["population"], problem, population)
    evaluations = check.integer("evaluations", document["evaluations"], len(X))
    penalised = check.integer("penalised", document["penalised"], 0, evaluations)
    last_error = document["last_error"]
    if not (last_error is None or isinstance(last_error, str)):
        raise check.error("last_error", "expected a string or null")
    repair = document["repair"]
    if not isinstance(repair, dict) or set(repair) != set(_REPAIR_COUNTERS):
        raise check.error("repair", f"expected an object with {list(_REPAIR_COUNTERS)}")
    counters = {name: check.integer(f"repair.{name}", repair[name], 0)
                for name in _REPAIR_COUNTERS}
    return CheckpointState(
        generation=generation, terminated=terminated, X=X, F=F,
        random_state=check.random_state(document["random_state"]), repair=counters,
        evaluations=evaluations, penalised=penalised, last_error=last_error,
        history=check.history(document["history"], generation, history_columns))


class _Checker:
    """Field checks of one checkpoint file; every failure names the file and the field."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, field: str, problem: str) -> CheckpointError:
        return CheckpointError(f"{self.path}: field {field!r}: {problem}")

    def integer(self, field: str, value: object, low: int, high: int | None = None) -> int:
        allowed = f"[{low}, {high}]" if high is not None else f"≥ {low}"
        if (isinstance(value, bool) or not isinstance(value, int) or value < low
                or (high is not None and value > high)):
            raise self.error(field, f"expected an integer {allowed}, found {value!r:.80}")
        return value

    def numbers(self, field: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
        """A nested JSON list of finite numbers of ``shape`` as a float array."""
        if not _is_number_tree(value, shape):
            raise self.error(field, f"expected a list of finite numbers of shape {shape}")
        return np.array(value, dtype=float)

    def population(self, value: object, problem: Problem, population: int
                   ) -> tuple[np.ndarray, np.ndarray]:
        if not isinstance(value, dict) or set(value) != {"X", "F"}:
            raise self.error("population", "expected an object with 'X' and 'F'")
        rows = value["X"]
        if not isinstance(rows, list) or not 1 <= len(rows) <= population:
            raise self.error("population.X", f"expected 1 to {population} rows (the "
                             "population size)")
        variables = self.numbers("population.X", rows, (len(rows), int(problem.n_var)))
        low, high = np.asarray(problem.xl, float), np.asarray(problem.xu, float)
        outside = np.argwhere((variables < low) | (variables > high))
        if outside.size:
            row, column = (int(i) for i in outside[0])
            raise self.error("population.X", f"row {row + 1}, variable {column + 1}: "
                             f"{variables[row, column]!r} lies outside the bounds "
                             f"[{low[column]:g}, {high[column]:g}]")
        rmse = self.numbers("population.F", value["F"], (len(rows),))
        if (rmse < 0).any():
            raise self.error("population.F", "an RMSE (K) is negative")
        return variables, rmse

    def random_state(self, value: object) -> dict[str, object]:
        field = "random_state"
        if not isinstance(value, dict) or set(value) != {"bit_generator", "state",
                                                         "has_uint32", "uinteger"}:
            raise self.error(field, "expected a PCG64 state: bit_generator, state, has_uint32, "
                             "uinteger")
        if value["bit_generator"] != "PCG64":
            raise self.error(f"{field}.bit_generator", "expected 'PCG64'")
        inner = value["state"]
        if not isinstance(inner, dict) or set(inner) != {"state", "inc"}:
            raise self.error(f"{field}.state", "expected an object with 'state' and 'inc'")
        for name in ("state", "inc"):
            self.integer(f"{field}.state.{name}", inner[name], 0, _PCG64_STATE_LIMIT - 1)
        self.integer(f"{field}.has_uint32", value["has_uint32"], 0, 1)
        self.integer(f"{field}.uinteger", value["uinteger"], 0, _UINT32_LIMIT - 1)
        try:
            np.random.PCG64().state = value
        except (TypeError, ValueError) as error:
            raise self.error(field, f"numpy refuses it ({error})") from None
        return value

    def history(self, value: object, generation: int, columns: Sequence[str]
                ) -> list[dict[str, object]]:
        if not isinstance(value, list) or len(value) != generation:
            raise self.error("history", f"expected a list of {generation} rows (one per "
                             "completed generation)")
        for number, row in enumerate(value, start=1):
            field = f"history[{number}]"
            if not isinstance(row, dict) or list(row) != list(columns):
                raise self.error(field, f"expected the columns {list(columns)}")
            for name, item in row.items():
                if not _is_finite_number(item):
                    raise self.error(f"{field}.{name}", f"expected a finite number, found "
                                     f"{item!r:.80}")
            if row.get("generation") != number:
                raise self.error(f"{field}.generation", f"expected {number}")
        return value


def _is_finite_number(value: object) -> bool:
    """True for a JSON number (not a boolean) that is a finite float once converted."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return math.isfinite(value) if isinstance(value, float) else abs(value) <= sys.float_info.max


def _is_number_tree(value: object, shape: tuple[int, ...]) -> bool:
    """True when ``value`` is a nested list of ``shape`` whose leaves are JSON numbers."""
    if not shape:
        return _is_finite_number(value)
    return isinstance(value, list) and len(value) == shape[0] and all(
        _is_number_tree(item, shape[1:]) for item in value)


def restore_algorithm(algorithm: Algorithm, state: CheckpointState) -> None:
    """Put a checkpoint's state into a GA set up for the same run (same settings and seed).

    ``algorithm`` comes from :func:`~steamtwin.calibration.ga.make_ga` and
    ``algorithm.setup(problem, termination=("n_gen", generations), seed=...)``; after this its
    next :meth:`~pymoo.core.algorithm.Algorithm.next` runs generation ``state.generation + 1``.
    """
    repair = algorithm.repair
    if not isinstance(repair, RemutationRepair):
        raise TypeError("restore_algorithm needs the GA of make_ga (a RemutationRepair)")
    rows = len(state.X)
    pop = Population.new(X=state.X.copy())
    pop.set("F", state.F[:, None].copy(), "G", np.empty((rows, 0)), "H", np.empty((rows, 0)))
    evaluated = tuple(algorithm.evaluator.evaluate_values_of)
    pop.apply(lambda individual: individual.evaluated.update(evaluated))
    algorithm.pop = pop
    algorithm.opt = filter_optimum(pop, least_infeasible=True)
    algorithm.is_initialized = True
    algorithm.start_time = time.time()  # as pymoo's _initialize; pymoo's result() needs it
    algorithm.random_state.bit_generator.state = state.random_state
    # as pymoo's _post_advance does: update the termination at the completed generation,
    # then count ahead to the next one
    algorithm.termination.force_termination = state.terminated
    algorithm.n_iter = state.generation
    algorithm.termination.update(algorithm)
    algorithm.n_iter = state.generation + 1
    repair.n_out_of_bounds = state.repair["out_of_bounds"]
    repair.n_remutations = state.repair["remutations"]
    repair.n_clipped = state.repair["clipped"]

