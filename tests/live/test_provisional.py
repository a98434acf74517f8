"""Provisional twin values (issue 21, latency): stored as soon as a sample arrives, replaced by
the final row once the gate's look-ahead has judged it; a restart still gives the uninterrupted
run's database."""

from __future__ import annotations

import asyncio

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.quality import Flag
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS

QUERY = "SELECT unit, time, source, signal, value, flag FROM series ORDER BY ALL"


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    truth = PlantTruth(faults=FaultConfig(dropout_rate_per_h=6, spike_rate_per_h=6))
    run = run_plant("deep-peak-50", hours=0.05, random_state=8, truth=truth)
    paths = write_plant(run, tmp_path_factory.mktemp("plant"), file_format="parquet")
    pd.read_parquet(paths["historian"]).iloc[:400].to_parquet(paths["historian"])  # 400 s
    return run, paths


@pytest.fixture(scope="module")
def model(reference_spec) -> FullOrderModel:
    fom = FullOrderModel(reference_spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    _ = fom.design_
    return fom


def _twin(db, model, run, provisional: bool) -> LiveTwin:
    gate = StreamGate(gate_options(plant_tag_map(), run.injected.sensors))
    return LiveTwin("unit1", model, ModelParameters(), gate, LiveHistorian(db),
                    provisional=provisional).start()


async def _blocks(path, start_after=None):
    source = ReplaySource(path, plant_tag_map(), block_samples=20, start_after=start_after)
    return [block async for block in source.blocks()]


def test_provisional_rows_lead_the_final_ones_and_leave_no_trace(tmp_path, plant, model):
    run, paths = plant
    reference = _twin(tmp_path / "reference.duckdb", model, run, provisional=False)
    for block in asyncio.run(_blocks(paths["historian"])):
        reference.process(block)
    reference.finish()
    expected = reference.historian.connection.execute(QUERY).df()
    reference.close()

    twin = _twin(tmp_path / "live.duckdb", model, run, provisional=True)
    connection = twin.historian.connection
    seen: list[pd.DataFrame] = []
    blocks = asyncio.run(_blocks(paths["historian"]))
    for block in blocks[:8]:
        twin.receive(block)
        last = connection.execute("SELECT max(time) FROM latest_series").fetchone()[0]
        assert pd.Timestamp(last) == block.frame.index[-1]  # stored before any look-ahead
        twin.settle()
        committed = twin.historian.resume_time("unit1")
        rows = connection.execute("SELECT * FROM provisional").df()
        times = pd.to_datetime(rows["time"], utc=True)
        assert committed is None or (times > committed).all()  # superseded rows are gone
        assert times.max() == block.frame.index[-1]
        seen.append(rows[rows["source"] == "twin"])
    twin.close()  # a crash: no finish, provisional rows left behind

    restarted = _twin(tmp_path / "live.duckdb", model, run, provisional=True)
    for block in asyncio.run(_blocks(paths["historian"], restarted.resume_after())):
        restarted.process(block)
    restarted.finish()
    got = restarted.historian.connection.execute(QUERY).df()
    left = restarted.historian.connection.execute("SELECT count(*) FROM provisional").fetchone()
    restarted.close()
    pd.testing.assert_frame_equal(got, expected)  # the uninterrupted run's series
    assert left[0] == 0

    # the provisional twin values are the final ones (to round-off) except just after an input
    # value the final gate rejected (a spike: the provisional chain fed it to the model)
    provisional = (pd.concat(seen).drop_duplicates(["time", "signal"], keep="last")
                   .set_index(["time", "signal"])["value"])
    final = expected[expected["source"] == "twin"].set_index(["time", "signal"])["value"]
    both = pd.concat({"p": provisional, "f": final}, axis=1, join="inner").dropna()
    assert len(both) > 0.5 * len(provisional)
    relative = ((both["p"] - both["f"]).abs() / both["f"].abs()).to_numpy()
    assert (relative <= 1e-12).mean() >= 0.9
    flags = expected[(expected["source"] == "measured") & expected["signal"].isin(INPUT_SIGNALS)
                     & expected["flag"].notna()]
    rejected = pd.to_datetime(
        flags[(flags["flag"].astype(float).astype(int) & int(Flag.REMOVED)) != 0]["time"],
        utc=True)
    assert len(rejected) > 0
    differ = pd.to_datetime(both.index.get_level_values("time")[relative > 1e-12], utc=True)
    after = (differ.to_numpy()[:, None] - rejected.to_numpy()[None, :]).astype("timedelta64[s]")
    reach = np.timedelta64(2 * 60, "s")  # the look-ahead and a block
    assert ((after > np.timedelta64(0, "s")) & (after <= reach)).any(axis=1).all()
