"""Checkpoints hold only data: exact resume, planted pickles refused unrun, every field checked."""

from __future__ import annotations

import copy
import dataclasses
import json
import pathlib
import pickle
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from steamtwin.calibration import Calibrator, CheckpointError, GeneticSearch
from steamtwin.calibration.checkpoint import CHECKPOINT_FORMAT, load_checkpoint
from steamtwin.calibration.search import HISTORY_COLUMNS

SEARCH = GeneticSearch(population=8, generations=6)


def _calibrator(simulator, checkpoint=None, progress=None, random_state=3) -> Calibrator:
    return Calibrator(simulator, search=dataclasses.replace(SEARCH, checkpoint=checkpoint),
                      random_state=random_state, workers=1, progress=progress)


class _Interrupted(Exception):
    pass


def _stop_after(generation: int):
    def progress(fraction: float, message: str) -> None:
        if fraction >= generation / SEARCH.generations - 1e-12:
            raise _Interrupted
    return progress


def _same_result(a: Calibrator, b: Calibrator) -> None:
    pd.testing.assert_frame_equal(a.history_, b.history_, check_exact=True)
    assert a.params_ == b.params_
    assert a.rmse_ == b.rmse_
    assert (a.n_evaluations_, a.n_penalised_) == (b.n_evaluations_, b.n_penalised_)
    assert a.repair_counts_ == b.repair_counts_
    np.testing.assert_array_equal(a.population_, b.population_)


@pytest.fixture(scope="module")
def whole(linear_simulator, linear_window) -> Calibrator:
    return _calibrator(linear_simulator).fit([linear_window])


@pytest.fixture(scope="module")
def written(linear_simulator, linear_window, tmp_path_factory) -> Path:
    """A checkpoint left by a run stopped after generation 3 (of 6)."""
    path = tmp_path_factory.mktemp("checkpoint") / "run.checkpoint"
    with pytest.raises(_Interrupted):
        _calibrator(linear_simulator, path, progress=_stop_after(3)).fit([linear_window])
    return path


@pytest.mark.parametrize("stop", [1, 2, 5, 6])
def test_resume_from_any_generation_equals_the_uninterrupted_run(linear_simulator,
                                                                 linear_window, whole, tmp_path,
                                                                 stop):
    path = tmp_path / "run.checkpoint"
    with pytest.raises(_Interrupted):
        _calibrator(linear_simulator, path, progress=_stop_after(stop)).fit([linear_window])
    resumed = _calibrator(linear_simulator, path).fit([linear_window], resume=True)
    _same_result(whole, resumed)
    assert whole.n_penalised_ > 0  # the run exercised the penalty and its counters
    # and again from the finished run's own checkpoint: its result, no further work
    again = _calibrator(linear_simulator, path).fit([linear_window], resume=True)
    _same_result(whole, again)


def test_checkpoint_is_a_json_document_of_data(written):
    document = json.loads(written.read_text(encoding="utf-8"))
    assert document["format"] == CHECKPOINT_FORMAT
    assert document["generation"] == 3 and len(document["history"]) == 3
    assert len(document["population"]["X"]) == SEARCH.population
    assert document["random_state"]["bit_generator"] == "PCG64"
    assert not list(written.parent.glob(".*.tmp"))  # the temporary file was renamed


class _Payload:
    """Unpickling this writes ``marker`` (what a planted checkpoint could do to the user)."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (pathlib.Path.write_text, (self.marker, "code ran"))


def test_a_planted_pickle_is_refused_and_never_run(linear_simulator, linear_window, tmp_path):
    control = tmp_path / "control-marker"
    pickle.loads(pickle.dumps(_Payload(control)))  # the payload is live when unpickled …
    assert control.read_text() == "code ran"
    marker = tmp_path / "marker"
    planted = tmp_path / "run.checkpoint"
    planted.write_bytes(pickle.dumps({"format": "steamtwin-calibration-checkpoint/1",
                                      "algorithm": _Payload(marker)}))
    with pytest.raises(CheckpointError, match="not a readable calibration checkpoint") as error:
        _calibrator(linear_simulator, planted).fit([linear_window], resume=True)
    assert str(planted) in str(error.value)
    assert not marker.exists()  # … and resuming never unpickled it


@pytest.fixture(scope="module")
def run(linear_simulator, linear_window):
    """The calibration problem and fingerprint of the run ``written`` belongs to."""
    calibrator = _calibrator(linear_simulator)
    problem = calibrator.problem([linear_window])
    return problem, SEARCH.fingerprint(problem, calibrator.run_settings())


def _load(path: Path, run):
    problem, fingerprint = run
    return load_checkpoint(path, problem, fingerprint, population=SEARCH.population,
                           generations=SEARCH.generations, history_columns=HISTORY_COLUMNS)


def _edit(document: dict, path: str, value: object) -> dict:
    """``document`` with the item at ``path`` ("a.b.0", "-" deletes) set to ``value``."""
    edited = copy.deepcopy(document)
    *parents, last = path.split(".")
    target = edited
    for key in parents:
        target = target[int(key)] if isinstance(target, list) else target[key]
    key = int(last) if isinstance(target, list) else last
    if value == "-":
        del target[key]
    else:
        target[key] = value
    return edited


WRONG = [
    # (path in the document, new value, field named in the message)
    ("format", "steamtwin-calibration-checkpoint/1", "'format'"),
    ("fingerprint", "0" * 64, "'fingerprint'"),
    ("generation", 0, "'generation'"),
    ("generation", 7, "'generation'"),
    ("generation", 2.0, "'generation'"),
    ("generation", True, "'generation'"),
    ("terminated", "no", "'terminated'"),
    ("population.X", [[1.0, 1.0]] * 8, "'population.X'"),                 # a variable short
    ("population.X", [[1.0, 1.0, 1.0]] * 9, "'population.X'"),            # above population
    ("population.X", [], "'population.X'"),
    ("population.X.0", [1.0, "1", 1.0], "'population.X'"),
    ("population.X.0", [1.5, 1.0, 1.0], "'population.X'"),                 # out of bounds
    ("population.F", [1.0] * 7, "'population.F'"),
    ("population.F.0", -1.0, "'population.F'"),
    ("population.F.0", float("inf"), "'population.F'"),
    ("population.X.0.1", float("inf"), "'population.X'"),
    ("population.X.0.1", 10**400, "'population.X'"),                      # beyond a float
    ("history.0.mean_rmse", 10**400, "'history[1].mean_rmse'"),
    ("population", [], "'population'"),
    ("evaluations", -1, "'evaluations'"),
    ("evaluations", 3, "'evaluations'"),                                   # fewer than rows
    ("penalised", 10**6, "'penalised'"),
    ("last_error", 5, "'last_error'"),
    ("random_state.bit_generator", "MT19937", "'random_state.bit_generator'"),
    ("random_state.state.state", -1, "'random_state.state.state'"),
    ("random_state.state.inc", 2**128, "'random_state.state.inc'"),
    ("random_state.state.inc", "1", "'random_state.state.inc'"),
    ("random_state.has_uint32", 2, "'random_state.has_uint32'"),
    ("random_state.uinteger", 2**32, "'random_state.uinteger'"),
    ("random_state.state", "-", "'random_state'"),
    ("repair.clipped", -1, "'repair.clipped'"),
    ("repair.clipped", "-", "'repair'"),
    ("history", [], "'history'"),
    ("history.1.best_rmse", "low", "'history[2].best_rmse'"),
    ("history.1.best_rmse", None, "'history[2].best_rmse'"),
    ("history.2.generation", 4, "'history[3].generation'"),
    ("history.0.remutations", "-", "'history[1]'"),
    ("history.0.extra", 1.0, "'history[1]'"),
    ("history", "-", "'history'"),
    ("surprise", 1, "'surprise': unknown field"),
]


@pytest.mark.parametrize(("where", "value", "field"), WRONG)
def test_a_wrong_field_is_refused_naming_file_and_field(written, run, tmp_path,
                                                        where, value, field):
    document = json.loads(written.read_text(encoding="utf-8"))
    path = tmp_path / "edited.checkpoint"
    # 1e400 is valid JSON that parses to inf (json.dumps would write the invalid "Infinity")
    text = json.dumps(_edit(document, where, value)).replace("Infinity", "1e400")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(CheckpointError) as error:
        _load(path, run)
    message = str(error.value)
    assert message.startswith(f"{path}: field {field}"), message


def test_other_settings_are_refused(linear_simulator, linear_window, written):
    with pytest.raises(CheckpointError, match=r"'fingerprint'.*other settings or data"):
        _calibrator(linear_simulator, written, random_state=4).fit([linear_window], resume=True)
    with pytest.raises(CheckpointError, match="'fingerprint'"):
        _calibrator(linear_simulator, written).fit([linear_window.iloc[1:]], resume=True)


@pytest.mark.parametrize("damage", ["truncated", "binary", "nan", "deep", "list", "empty"])
def test_damaged_files_are_refused(written, run, tmp_path, damage):
    text = written.read_text(encoding="utf-8")
    content = {
        "truncated": text[: len(text) // 2].encode(),
        "binary": b"\x80\x04\x95" + bytes(range(256)),
        "nan": text.replace('"penalised": ', '"penalised": NaN, "x": ', 1).encode(),
        "deep": b"[" * 200_000 + b"]" * 200_000,
        "list": b"[1, 2, 3]",
        "empty": b"",
    }[damage]
    path = tmp_path / "damaged.checkpoint"
    path.write_bytes(content)
    with pytest.raises(CheckpointError, match=f"^{path}: ") as error:
        _load(path, run)
    assert "not a readable calibration checkpoint" in str(error.value) or (
        "(document)" in str(error.value))


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**400), 10**400)
    | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=5),
    lambda children: st.lists(children, max_size=4)
    | st.dictionaries(st.text(max_size=5), children, max_size=4),
    max_leaves=12)


def _paths(value: object, prefix: str = "") -> list[str]:
    """Every item path of a JSON document, in :func:`_edit`'s notation."""
    items = value.items() if isinstance(value, dict) else (
        enumerate(value) if isinstance(value, list) else ())
    paths = []
    for key, item in items:
        path = f"{prefix}{key}"
        paths.append(path)
        paths.extend(_paths(item, f"{path}."))
    return paths


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_any_edit_is_refused_as_a_checkpoint_error_or_gives_valid_state(written, run, tmp_path,
                                                                        data):
    document = json.loads(written.read_text(encoding="utf-8"))
    where = data.draw(st.sampled_from(_paths(document)))
    value = data.draw(JSON_VALUES)
    path = tmp_path / "fuzzed.checkpoint"
    path.write_text(json.dumps(_edit(document, where, value)), encoding="utf-8")
    try:
        state = _load(path, run)
    except CheckpointError as error:
        assert str(error).startswith(f"{path}: ")
        return
    # accepted: then every part is what a resume can use
    assert state.X.shape == (len(state.F), 3) and np.isfinite(state.X).all()
    assert 1 <= state.generation <= SEARCH.generations == 6
    assert len(state.history) == state.generation
    assert 0 <= state.penalised <= state.evaluations
