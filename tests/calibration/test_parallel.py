"""Parallel and distributed evaluation, checkpoints and resuming: same seed, same result."""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import textwrap
import time

import pandas as pd
import pytest

from steamtwin.calibration import Calibrator, GeneticSearch
from steamtwin.calibration.evaluation import (
    DaskEvaluator,
    ProcessPoolEvaluator,
    SerialEvaluator,
    make_evaluator,
)

pytestmark = pytest.mark.slow  # 67 s of the full suite (2026-11-27): not in the quick loop

SMALL = {"search": GeneticSearch(population=6, generations=3), "random_state": 4}


ONE_GENERATION = GeneticSearch(population=4, generations=1)


def test_pool_and_dask_cluster_give_the_serial_result(reference_model, low_load_window):
    from distributed import Client, LocalCluster

    serial = Calibrator(reference_model, workers=1, **SMALL).fit([low_load_window])
    pool = Calibrator(reference_model, workers=2, **SMALL).fit([low_load_window])
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        dask = Calibrator(reference_model, scheduler=client, **SMALL).fit([low_load_window])
        by_address = Calibrator(reference_model, scheduler=cluster.scheduler_address,
                                search=ONE_GENERATION, random_state=4).fit([low_load_window])
    pd.testing.assert_frame_equal(serial.history_, pool.history_)
    pd.testing.assert_frame_equal(serial.history_, dask.history_)
    assert serial.params_ == pool.params_ == dask.params_
    assert serial.n_evaluations_ == dask.n_evaluations_ == 6 * 3
    assert by_address.history_["best_rmse"].iloc[0] == pytest.approx(
        Calibrator(reference_model, workers=1, search=ONE_GENERATION, random_state=4)
        .fit([low_load_window]).score_)


def test_evaluator_choice_and_bad_arguments():
    assert isinstance(make_evaluator(1), SerialEvaluator)
    assert isinstance(make_evaluator(2), ProcessPoolEvaluator)
    assert isinstance(make_evaluator(None, "tcp://127.0.0.1:1"), DaskEvaluator)
    with pytest.raises(ValueError, match="workers"):
        make_evaluator(0)
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler"):
        DaskEvaluator("tcp://127.0.0.1:9", connect_timeout_s=1.0).start(None)


class _Interrupted(Exception):
    pass


def test_resume_after_interruption_equals_uninterrupted_run(reference_model, low_load_window,
                                                            tmp_path):
    search = GeneticSearch(population=6, generations=5)
    whole = Calibrator(reference_model, search=search, random_state=4,
                       workers=1).fit([low_load_window])
    checkpoint = tmp_path / "run.ckpt"

    def resumable(path, progress=None, random_state=4) -> Calibrator:
        return Calibrator(reference_model, search=dataclasses.replace(search, checkpoint=path),
                          random_state=random_state, workers=1, progress=progress)

    def stop_at_generation_2(fraction: float, message: str) -> None:
        if fraction >= 2 / 5:
            raise _Interrupted

    with pytest.raises(_Interrupted):
        resumable(checkpoint, stop_at_generation_2).fit([low_load_window])
    resumed = resumable(checkpoint).fit([low_load_window], resume=True)
    pd.testing.assert_frame_equal(whole.history_, resumed.history_)
    assert whole.params_ == resumed.params_
    assert resumed.n_evaluations_ == whole.n_evaluations_
    with pytest.raises(ValueError, match="other settings or data"):
        resumable(checkpoint, random_state=5).fit([low_load_window], resume=True)
    with pytest.raises(ValueError, match="no checkpoint"):
        resumable(tmp_path / "none.ckpt").fit([low_load_window], resume=True)
    (tmp_path / "junk.ckpt").write_bytes(b"not a pickle")
    with pytest.raises(ValueError, match="not a readable calibration checkpoint"):
        resumable(tmp_path / "junk.ckpt").fit([low_load_window], resume=True)


KILLED_RUN = textwrap.dedent("""
    import sys, time
    import pandas as pd
    from pathlib import Path
    from steamtwin.calibration import Calibrator, GeneticSearch
    from steamtwin.model.fom import FullOrderModel
    from steamtwin.spec import load_spec

    window = pd.read_parquet(sys.argv[1])
    marker = Path(sys.argv[3])

    def progress(fraction, message):
        marker.write_text(str(round(fraction * 6)))
        time.sleep(0.3)  # leave the killer time to strike mid-run

    search = GeneticSearch(population=6, generations=6, checkpoint=sys.argv[2])
    Calibrator(FullOrderModel(load_spec("reference")), search=search, random_state=4,
               workers=1, progress=progress).fit([window])
""")


def test_resume_after_a_real_kill(reference_model, low_load_window, tmp_path):
    data, checkpoint, marker = tmp_path / "w.parquet", tmp_path / "k.ckpt", tmp_path / "gen"
    low_load_window.to_parquet(data)
    process = subprocess.Popen([sys.executable, "-c", KILLED_RUN, str(data), str(checkpoint),
                                str(marker)])
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline and process.poll() is None:
        if marker.exists() and marker.read_text() not in ("", "0", "1"):
            break
        time.sleep(0.05)
    assert process.poll() is None, "the run ended before it could be killed"
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    assert checkpoint.exists()
    search = GeneticSearch(population=6, generations=6)
    resumed = Calibrator(reference_model, search=dataclasses.replace(search, checkpoint=checkpoint),
                         random_state=4, workers=1).fit([low_load_window], resume=True)
    whole = Calibrator(reference_model, search=search, random_state=4,
                       workers=1).fit([low_load_window])
    pd.testing.assert_frame_equal(whole.history_, resumed.history_)
    assert whole.params_ == resumed.params_
