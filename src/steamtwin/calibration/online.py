"""Online calibration: keep the parameters current as DCS data arrive.

Every ``every_s`` seconds of data time the GA recalibrates on the last ``window_s`` seconds,
warm-started from the previous update's final population (so a handful of generations follow a
slow change instead of a full run from scratch), and the new parameter set replaces the live one
in a :class:`ParameterStore` in one step. A file replayed in chunks and a live feed are the same
to it: :meth:`OnlineCalibrator.update` takes whatever arrived since the last call.

Nothing is skipped silently: an update that cannot run (too few samples, a long input dropout,
every candidate rejected) leaves the parameters as they were and is logged in the trajectory with
its reason.
"""

from __future__ import annotations

import json
import os
import threading
from collections.abc import Iterable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.calibration.calibrator import apply_tempering
from steamtwin.calibration.evaluation import make_evaluator
from steamtwin.calibration.ga import check_integer, make_ga
from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem
from steamtwin.calibration.settings import PARAMETER_NAMES, ObjectiveSettings, check_random_state
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator
from steamtwin.progress import ProgressCallback

__all__ = ["OnlineCalibrator", "ParameterStore", "append_chunk", "replay_chunks"]


class ParameterStore:
    """The twin's live parameters, swapped atomically.

    Readers call :meth:`get` and receive one immutable :class:`ModelParameters`; :meth:`swap`
    replaces it under a lock and, given ``path``, rewrites the parameters JSON through a
    temporary file and ``os.replace`` — a reader of the file, too, sees the old set or the new
    one, never a mix.
    """

    def __init__(self, params: ModelParameters | None = None, path: str | Path | None = None
                 ) -> None:
        self._params = params or ModelParameters()
        self._lock = threading.Lock()
        self.path = None if path is None else Path(path)

    def get(self) -> ModelParameters:
        """The current parameter set."""
        with self._lock:
            return self._params

    def swap(self, params: ModelParameters) -> None:
        """Make ``params`` the current set (and the file's, if the store has a path)."""
        if not isinstance(params, ModelParameters):
            raise TypeError(f"expected ModelParameters, got {type(params).__name__}")
        with self._lock:
            if self.path is not None:
                temporary = self.path.with_name(f".{self.path.name}.tmp")
                temporary.write_text(json.dumps({"parameters": asdict(params)}, indent=2) + "\n",
                                     encoding="utf-8")
                os.replace(temporary, self.path)
            self._params = params


def append_chunk(buffer: pd.DataFrame, chunk: pd.DataFrame) -> pd.DataFrame:
    """``buffer`` with a newly arrived ``chunk`` (DatetimeIndex, strictly after the buffer's
    last sample) appended; ValueError otherwise. An empty chunk leaves the buffer as it is."""
    if not isinstance(chunk, pd.DataFrame) or not isinstance(chunk.index, pd.DatetimeIndex):
        raise ValueError("each chunk must be a DataFrame with a DatetimeIndex")
    if chunk.empty:
        return buffer
    if not buffer.empty and chunk.index[0] <= buffer.index[-1]:
        raise ValueError(f"chunk starting {chunk.index[0]} does not follow the data so far "
                         f"(last {buffer.index[-1]}); chunks must arrive in order")
    return pd.concat([buffer, chunk]) if not buffer.empty else chunk


def replay_chunks(data: pd.DataFrame | Iterable[pd.DataFrame], chunk_s: float
                  ) -> tuple[Iterable[pd.DataFrame], float]:
    """``data`` as a stream: a long frame cut into ``chunk_s``-second chunks (with its span in
    s), or an iterable of chunks as it is (span NaN)."""
    if not (isinstance(chunk_s, int | float) and np.isfinite(chunk_s) and chunk_s > 0):
        raise ValueError(f"chunk_s must be a positive number of seconds (got {chunk_s!r})")
    if not isinstance(data, pd.DataFrame):
        return data, float("nan")
    if not isinstance(data.index, pd.DatetimeIndex) or data.empty:
        raise ValueError("data must be a non-empty DataFrame with a DatetimeIndex")
    keys = ((data.index - data.index[0]).total_seconds() // chunk_s).astype(int)
    return ((part for _, part in data.groupby(keys, sort=True)),
            float((data.index[-1] - data.index[0]).total_seconds()))


class OnlineCalibrator:
    """Recalibrate on a sliding window as data arrive; log the parameter trajectory.

    ``window_s`` (s): the data each update fits; ``every_s`` (s of data time): how often;
    ``first_generations`` for the first update (random start), ``generations`` for the later,
    warm-started ones. After :meth:`update`/:meth:`run`: ``trajectory_`` (one row per update,
    indexed by the window's end: the three parameters, ``rmse`` (K) of the new set and
    ``rmse_previous`` (K) of the set it replaced on the same window, ``evaluations``,
    ``error``), ``params_`` (current), ``n_evaluations_``. ``objective``: the objective's
    :class:`~steamtwin.calibration.settings.ObjectiveSettings`, as for
    :class:`~steamtwin.calibration.calibrator.Calibrator` (default: without priors, each update
    fits the plain RMSE; with priors every update is a MAP fit, its likelihood tempered as the
    settings say, and a parameter the last window cannot see stays near its prior instead of
    wandering; ``rmse`` and ``rmse_previous`` of the trajectory are then the posterior scores
    the update compared). Update ``k`` (from 0) seeds its GA with ``random_state + k``.
    """

    def __init__(self, simulator: Simulator, *, objective: ObjectiveSettings | None = None,
                 window_s: float = 3600.0, every_s: float = 1800.0, population: int = 20,
                 generations: int = 8, first_generations: int = 25, random_state: int = 0,
                 workers: int | None = 1, scheduler: Any = None,
                 store: ParameterStore | None = None,
                 progress: ProgressCallback | None = None) -> None:
        self.simulator = simulator
        self.objective = objective
        self.window_s = window_s
        self.every_s = every_s
        self.population = population
        self.generations = generations
        self.first_generations = first_generations
        self.random_state = random_state
        self.workers = workers
        self.scheduler = scheduler
        self.store = store
        self.progress = progress

    # -- state ------------------------------------------------------------------------------

    def _start(self) -> None:
        for name in ("window_s", "every_s"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number of seconds (got {value!r})")
        for name, low in (("population", 2), ("generations", 1), ("first_generations", 1)):
            check_integer(name, getattr(self, name), low)
        self._random_state = check_random_state(self.random_state)
        objective = self.objective
        if not isinstance(objective, ObjectiveSettings | None):
            raise TypeError(f"OnlineCalibrator: objective must be ObjectiveSettings or None "
                            f"(got {type(objective).__name__})")
        self._settings = ObjectiveSettings(priors=None) if objective is None else objective
        self.store_ = self.store if self.store is not None else ParameterStore()
        self.store_.swap(self.store_.get())  # the live file exists from the start
        self._buffer = pd.DataFrame()
        self._next_due: pd.Timestamp | None = None
        self._population: np.ndarray | None = None
        self._rows: list[dict[str, object]] = []
        self.n_evaluations_ = 0
        self.trajectory_ = pd.DataFrame()
        self.params_ = self.store_.get()

    # -- public API -------------------------------------------------------------------------

    def update(self, chunk: pd.DataFrame) -> pd.DataFrame:
        """Take newly arrived data (canonical SI signals, later than the last chunk); run every
        update that has come due. Returns the trajectory rows added by this call."""
        if not hasattr(self, "_buffer"):
            self._start()
        self._buffer = append_chunk(self._buffer, chunk)
        if self._buffer.empty:
            return pd.DataFrame()
        window = pd.Timedelta(seconds=self.window_s)
        if self._next_due is None:
            self._next_due = self._buffer.index[0] + window
        added = []
        while self._buffer.index[-1] >= self._next_due:
            end = self._next_due
            data = self._buffer.loc[end - window:end]
            added.append(self._recalibrate(data, end))
            self._next_due = end + pd.Timedelta(seconds=self.every_s)
        self._buffer = self._buffer.loc[self._next_due - window:]
        if added:
            self._rows.extend(added)
            self.trajectory_ = pd.DataFrame(self._rows).set_index("time")
        return pd.DataFrame(added).set_index("time") if added else pd.DataFrame()

    def run(self, data: pd.DataFrame | Iterable[pd.DataFrame], chunk_s: float = 60.0
            ) -> OnlineCalibrator:
        """Replay ``data`` — a long frame, cut into ``chunk_s``-second chunks, or an iterable of
        chunks (a stream) — through :meth:`update`; returns self."""
        chunks, total = replay_chunks(data, chunk_s)
        self._start()
        for chunk in chunks:
            self.update(chunk)
            if self.progress is not None and np.isfinite(total) and total > 0:
                done = (chunk.index[-1] - data.index[0]).total_seconds() / total
                p = self.params_
                self.progress(done, f"{chunk.index[-1]}: flow {p.flow_coefficient:.3f}, "
                              f"friction {p.friction_coefficient:.3f}, heat transfer "
                              f"{p.heat_transfer_coefficient:.3f}")
        return self

    # -- one update -------------------------------------------------------------------------

    def _recalibrate(self, data: pd.DataFrame, end: pd.Timestamp) -> dict[str, object]:
        row: dict[str, object] = {"time": end, "error": ""}
        current = self.store_.get()
        try:
            problem = CalibrationProblem(self.simulator, [data], self._settings)
            apply_tempering(problem)
        except ValueError as error:
            return {**row, **asdict(current), "rmse": np.nan, "rmse_previous": np.nan,
                    "evaluations": 0, "error": str(error)}
        first = self._population is None
        start = None if first else np.clip(self._population, problem.xl, problem.xu)
        algorithm = make_ga(problem.n_var, population=self.population,
                            initial_population=start)
        generations = self.first_generations if first else self.generations
        algorithm.setup(problem, termination=("n_gen", generations),
                        seed=self._random_state + len(self._rows), verbose=False)
        evaluator = make_evaluator(self.workers, self.scheduler)
        evaluator.start(problem.objective)
        problem.evaluator = evaluator
        try:
            previous = problem.score(current)
            while algorithm.has_next():
                algorithm.next()
        finally:
            problem.evaluator = None
            evaluator.close()
        best = algorithm.opt[0]
        rmse = float(best.F[0])
        self.n_evaluations_ += problem.n_evaluations
        row.update(rmse_previous=previous, evaluations=problem.n_evaluations)
        if rmse >= PENALTY_RMSE:
            return {**row, **asdict(current), "rmse": rmse,
                    "error": f"every candidate was rejected ({problem.last_error})"}
        self._population = algorithm.pop.get("X").copy()
        chosen = problem.parameters(best.X) if rmse <= previous else current
        if chosen is not current:
            self.store_.swap(chosen)
        self.params_ = self.store_.get()
        return {**row, **dict(zip(PARAMETER_NAMES, (getattr(chosen, n) for n in PARAMETER_NAMES),
                                  strict=True)), "rmse": min(rmse, previous)}
