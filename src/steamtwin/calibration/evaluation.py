"""Evaluating candidate parameter sets: serially, on a local process pool or on a Dask cluster.

An :class:`Objective` (the simulator, the prepared windows, sensors and weights) is sent to the
workers **once** when an evaluator starts — as the pool's initializer argument, or scattered
(broadcast) to every Dask worker — so each evaluation ships only its three numbers and returns
one RMSE. Results come back in the order of the candidates, so the GA sees the same values
whatever evaluates them: a run is reproducible from its seed on any evaluator.

Worker processes are started with ``spawn`` (never ``fork``: the parent may hold threads, and
forking a process with threads is undefined behaviour in POSIX). Each worker loads the compiled
model from the on-disk cache (:mod:`steamtwin.cache`), which takes a few seconds once.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Protocol

import numpy as np

from steamtwin.calibration.objective import Evaluation, Objective

__all__ = [
    "DaskEvaluator",
    "Evaluator",
    "ProcessPoolEvaluator",
    "SerialEvaluator",
    "dask_client",
    "make_evaluator",
]


class Evaluator(Protocol):
    """Scores batches of candidates for one :class:`Objective` between ``start`` and ``close``."""

    def start(self, objective: Objective) -> None:
        """Ship ``objective`` to wherever candidates are evaluated."""

    def evaluate(self, candidates: np.ndarray) -> list[Evaluation]:
        """Results for the rows of ``candidates`` (n, 3), in order."""

    def close(self) -> None:
        """Release workers (idempotent)."""


class SerialEvaluator:
    """Evaluates in the calling process, one candidate after the other."""

    def start(self, objective: Objective) -> None:
        """Keep ``objective``."""
        self._objective = objective

    def evaluate(self, candidates: np.ndarray) -> list[Evaluation]:
        """Results for the rows of ``candidates``, in order."""
        return self._objective.evaluate_many(candidates)

    def close(self) -> None:
        """Nothing to release."""


# -- local process pool ----------------------------------------------------------------------

_installed: Objective | None = None


def _install(objective: Objective) -> None:
    global _installed
    _installed = objective


def _evaluate_installed(rows: np.ndarray) -> list[Evaluation]:
    if _installed is None:  # pragma: no cover - the initializer always runs first
        raise RuntimeError("no objective installed in this worker")
    return _installed.evaluate_many(rows)


def _chunks(candidates: np.ndarray, parts: int) -> list[np.ndarray]:
    rows = np.atleast_2d(np.asarray(candidates, dtype=float))
    return [chunk for chunk in np.array_split(rows, min(parts, len(rows))) if len(chunk)]


class ProcessPoolEvaluator:
    """Evaluates on ``workers`` local processes (default: every core).

    The objective is pickled once per worker (pool initializer); each batch is split into about
    ``2·workers`` chunks so that a slow candidate does not leave a core idle.
    """

    def __init__(self, workers: int | None = None) -> None:
        self.workers = workers

    def start(self, objective: Objective) -> None:
        """Start the pool with ``objective`` installed in every worker."""
        workers = (os.cpu_count() or 1) if self.workers is None else self.workers
        if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers must be an integer ≥ 1 (got {self.workers!r})")
        self._workers = workers
        self._pool = ProcessPoolExecutor(max_workers=workers,
                                         mp_context=multiprocessing.get_context("spawn"),
                                         initializer=_install, initargs=(objective,))

    def evaluate(self, candidates: np.ndarray) -> list[Evaluation]:
        """Results for the rows of ``candidates``, in order."""
        chunks = _chunks(candidates, 2 * self._workers)
        return [result for chunk in self._pool.map(_evaluate_installed, chunks)
                for result in chunk]

    def close(self) -> None:
        """Shut the pool down."""
        pool = getattr(self, "_pool", None)
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


# -- Dask ------------------------------------------------------------------------------------


def _evaluate_on_worker(rows: np.ndarray, objective: Objective) -> list[Evaluation]:
    return objective.evaluate_many(rows)


class DaskEvaluator:
    """Evaluates on a Dask cluster: ``scheduler`` is an address (``tcp://host:8786``) or a
    ``distributed.Client`` (left open on :meth:`close`; a client made here is closed).

    The objective is scattered to every worker once (``broadcast=True``); each batch becomes
    about ``2·workers`` tasks that refer to it. ``connect_timeout_s``: how long (s) to try
    reaching a scheduler given by address before giving up.
    """

    def __init__(self, scheduler: Any, connect_timeout_s: float = 30.0) -> None:
        self.scheduler = scheduler
        self.connect_timeout_s = connect_timeout_s

    def start(self, objective: Objective) -> None:
        """Connect and broadcast ``objective`` to the workers."""
        self._client, self._own_client = dask_client(self.scheduler, self.connect_timeout_s)
        self._workers = max(1, len(self._client.scheduler_info()["workers"]))
        [self._objective] = self._client.scatter([objective], broadcast=True, hash=False)

    def evaluate(self, candidates: np.ndarray) -> list[Evaluation]:
        """Results for the rows of ``candidates``, in order."""
        chunks = _chunks(candidates, 2 * self._workers)
        futures = self._client.map(_evaluate_on_worker, chunks, objective=self._objective,
                                   pure=False)
        return [result for chunk in self._client.gather(futures) for result in chunk]

    def close(self) -> None:
        """Release the scattered objective; close the client if this evaluator made it."""
        client = getattr(self, "_client", None)
        if client is None:
            return
        self._objective = None
        if self._own_client:
            client.close()
        self._client = None


def dask_client(scheduler: Any, connect_timeout_s: float = 30.0) -> tuple[Any, bool]:
    """``(client, own)`` for ``scheduler``: a ``distributed.Client`` as given (``own`` False:
    the caller's to close), or a new one connected to an address (``tcp://host:8786``; ``own``
    True). ValueError naming the address when it cannot be reached within
    ``connect_timeout_s`` (s), or when ``scheduler`` is neither."""
    from distributed import Client

    if isinstance(scheduler, Client):
        return scheduler, False
    if isinstance(scheduler, str) and scheduler:
        try:
            return Client(scheduler, timeout=connect_timeout_s), True
        except OSError as error:
            raise ValueError(f"cannot reach the Dask scheduler at {scheduler!r}: "
                             f"{error}") from None
    raise ValueError(f"scheduler must be an address or a distributed.Client (got {scheduler!r})")


def make_evaluator(workers: int | None = None, scheduler: Any = None) -> Evaluator:
    """The evaluator for ``workers``/``scheduler``: Dask if a scheduler is given, else serial
    for ``workers == 1``, else a local process pool (``workers`` None = every core)."""
    if scheduler is not None:
        return DaskEvaluator(scheduler)
    if workers == 1:
        return SerialEvaluator()
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise ValueError(f"workers must be an integer ≥ 1 (got {workers!r})")
    return ProcessPoolEvaluator(workers)

