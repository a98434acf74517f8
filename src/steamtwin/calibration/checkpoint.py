"""Per-generation checkpoints of a GA calibration, and resuming from them.

A checkpoint holds the pymoo algorithm — population, elite, generation counter and its random
generator's state — plus the history so far and the evaluation counters. It is a pickle (the
algorithm object is pymoo's own; pymoo documents checkpoints the same way), so only resume
from checkpoints you wrote yourself. The problem (model and data) is *not* stored: it is
referred to by a persistent id and re-attached on loading, after a fingerprint of the settings
and the prepared data has shown that it is the same run. The file is written to a temporary
name and renamed (``os.replace``, atomic on POSIX), so a kill leaves either the previous or the
new generation's checkpoint, never a torn one.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import pickle
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pymoo.core.algorithm import Algorithm
from pymoo.core.problem import Problem

from steamtwin.calibration.objective import Objective

__all__ = ["CHECKPOINT_FORMAT", "CheckpointState", "load_checkpoint", "run_fingerprint",
           "save_checkpoint"]

CHECKPOINT_FORMAT = "steamtwin-calibration-checkpoint/1"
_PROBLEM_ID = "calibration-problem"


@dataclass(frozen=True)
class CheckpointState:
    """What a checkpoint restores: the algorithm, history rows and evaluation counters."""

    algorithm: Algorithm
    history: list[dict[str, object]]
    evaluations: int
    penalised: int


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
    return digest.hexdigest()


class _Pickler(pickle.Pickler):
    def __init__(self, file: io.BytesIO, problem: Problem) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._problem = problem

    def persistent_id(self, obj: object) -> str | None:
        return _PROBLEM_ID if obj is self._problem else None


class _Unpickler(pickle.Unpickler):
    def __init__(self, file: io.BytesIO, problem: Problem) -> None:
        super().__init__(file)
        self._problem = problem

    def persistent_load(self, pid: object) -> Problem:
        if pid != _PROBLEM_ID:
            raise pickle.UnpicklingError(f"unknown persistent id {pid!r}")
        return self._problem


def save_checkpoint(path: Path, algorithm: Algorithm, problem: Problem,
                    history: list[dict[str, object]], fingerprint: str) -> None:
    """Write the checkpoint atomically (temporary file, then rename)."""
    buffer = io.BytesIO()
    _Pickler(buffer, problem).dump({
        "format": CHECKPOINT_FORMAT,
        "fingerprint": fingerprint,
        "algorithm": algorithm,
        "history": history,
        "evaluations": problem.n_evaluations,
        "penalised": problem.n_penalised,
    })
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp")
    with open(temporary, "wb") as handle:
        handle.write(buffer.getvalue())
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(temporary, path)


def load_checkpoint(path: Path, problem: Problem, fingerprint: str) -> CheckpointState:
    """Read a checkpoint for ``problem``; errors name the file and what does not match."""
    if not path.is_file():
        raise ValueError(f"{path}: no checkpoint to resume from")
    try:
        document = _Unpickler(io.BytesIO(path.read_bytes()), problem).load()
    except (pickle.UnpicklingError, EOFError, AttributeError, ImportError, TypeError) as error:
        raise ValueError(f"{path}: not a readable calibration checkpoint ({error})") from None
    if not isinstance(document, dict) or document.get("format") != CHECKPOINT_FORMAT:
        raise ValueError(f"{path}: not a calibration checkpoint of format {CHECKPOINT_FORMAT}")
    if document["fingerprint"] != fingerprint:
        raise ValueError(f"{path}: the checkpoint was written for other settings or data; "
                         "run again without resume (or with the original settings and data)")
    return CheckpointState(algorithm=document["algorithm"], history=list(document["history"]),
                           evaluations=int(document["evaluations"]),
                           penalised=int(document["penalised"]))
