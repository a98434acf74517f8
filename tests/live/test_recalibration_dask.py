"""Online recalibration on a Dask cluster (issue 21, item 6: "local pool or the Dask scheduler
given with --scheduler"): the service's tracker steps run as tasks on the cluster, and the
parameters it swaps in are the ones the same service swaps in when it runs them itself."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration.tracking import ParameterTracker
from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.readers import canonical_to_historian
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.runner import run_service
from steamtwin.model.fom import FullOrderModel

SIGMA = {"control_stage_temperature": 0.3, "hp_exhaust_temperature": 0.3,
         "hp_inner_casing_temperature": 0.3, "control_stage_pressure": 9.0e3}


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as local:
        yield local


def _swaps(database) -> pd.DataFrame:
    with LiveHistorian(database) as historian:
        return historian.connection.execute(
            "SELECT * FROM parameters ORDER BY time, name").df()


def test_the_service_recalibrates_on_the_cluster_as_it_does_locally(tmp_path, cluster):
    from distributed import Client, get_task_stream

    measured = run_plant("deep-peak-50", hours=0.01, random_state=7).measured.iloc[:130]
    tags, historian = tmp_path / "tags.toml", tmp_path / "historian.parquet"
    write_tag_map(plant_tag_map(), tags)
    canonical_to_historian(measured, plant_tag_map()).to_parquet(historian, index=False)
    # 1-min tracker steps, a scheduled swap due after 1 min of data: two steps, two swaps
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "twin.duckdb"\n[[units]]\nname = "unit1"\n'
                      f'tags = "{tags}"\nblock_samples = 60\n'
                      '[units.recalibration]\nevery_h = 0.015\nstep_min = 1\n'
                      f'[units.source]\nkind = "replay"\npath = "{historian}"\n')
    local = load_config(config)
    asyncio.run(run_service(local))
    remote = load_config(config)
    remote = type(remote)(database=tmp_path / "remote.duckdb", units=remote.units,
                          source=remote.source)
    with Client(cluster) as client, get_task_stream(client) as tasks:
        asyncio.run(run_service(remote, scheduler=client))
    fits = [task for task in tasks.data if str(task["key"]).startswith("_fit_step")]
    expected = _swaps(local.database)
    swapped = expected[expected["reason"] != "start"]  # after the starting set
    assert (swapped["reason"] == "schedule").all() and swapped["time"].nunique() >= 1
    # every tracker step (one a minute of data) ran on the cluster ...
    assert len(fits) == len(measured) // 60
    # ... and the swapped-in parameters, and so the twin's series, are the local run's
    pd.testing.assert_frame_equal(_swaps(remote.database), expected)
    with LiveHistorian(local.database) as a, LiveHistorian(remote.database) as b:
        query = "SELECT * FROM series ORDER BY ALL"
        pd.testing.assert_frame_equal(a.connection.execute(query).df(),
                                      b.connection.execute(query).df())


def test_a_tracker_given_an_address_connects_and_closes_its_own_client(
        reference_spec, model_plant, cluster):
    model = FullOrderModel(reference_spec)
    data = model_plant(reference_spec, np.full(250, 0.5), np.full(250, 0.985), SIGMA, seed=8)
    local = ParameterTracker(model, sigma=SIGMA, step_s=120.0).run(data)
    clients = len(cluster.scheduler.clients)
    remote = ParameterTracker(model, sigma=SIGMA, step_s=120.0,
                              scheduler=cluster.scheduler_address).run(data)
    assert len(cluster.scheduler.clients) == clients + 1  # its own, still open
    remote.close()
    for _ in range(100):  # the scheduler hears of the close asynchronously
        if len(cluster.scheduler.clients) == clients:
            break
        time.sleep(0.02)
    assert len(cluster.scheduler.clients) == clients
    pd.testing.assert_frame_equal(remote.trajectory_, local.trajectory_)
    assert (remote.trajectory_["error"] == "").all() and len(remote.trajectory_) == 2
