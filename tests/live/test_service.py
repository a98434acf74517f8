"""One unit's live twin end to end (issue 21): a historian file replayed through gate, streamed
FOM, ROM-free residuals and the DuckDB historian; a restart after a crash gives the
uninterrupted run's database."""

from __future__ import annotations

import asyncio

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop

QUERY = "SELECT unit, time, source, signal, value, flag FROM series ORDER BY ALL"
PARAMETERS = "SELECT * FROM parameters ORDER BY ALL"


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    truth = PlantTruth(faults=FaultConfig(dropout_rate_per_h=3, spike_rate_per_h=6))
    run = run_plant("deep-peak-50", hours=0.25, random_state=8, truth=truth)
    paths = write_plant(run, tmp_path_factory.mktemp("plant"), file_format="csv")
    return run, paths


@pytest.fixture(scope="module")
def model(reference_spec) -> FullOrderModel:
    fom = FullOrderModel(reference_spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    _ = fom.design_
    return fom


def _twin(db, model, run) -> LiveTwin:
    gate = StreamGate(gate_options(plant_tag_map(), run.injected.sensors))
    return LiveTwin("unit1", model, ModelParameters(), gate, LiveHistorian(db))


def test_a_replay_is_stored_with_twin_and_residuals(tmp_path, plant, model):
    run, paths = plant
    twin = _twin(tmp_path / "a.duckdb", model, run).start()
    summary = asyncio.run(twin.run(ReplaySource(paths["historian"], plant_tag_map(),
                                                block_samples=120)))
    wide = twin.historian.series("unit1")
    twin.close()
    assert summary.samples == len(run.measured) == len(wide)
    assert summary.without_twin > 0  # input dropouts: no twin value, counted
    exhaust = wide["residual/hp_exhaust_temperature"].dropna()
    assert exhaust.abs().median() < 5.0  # the uncalibrated twin within a few K
    # the twin's stored outputs are the streamed model's: one batch run over the same samples
    fed = wide[[f"measured/{n}" for n in model.input_signals]].dropna()
    batch = model.simulate(fed.set_axis(list(model.input_signals), axis=1))
    stored = wide.loc[fed.index, "twin/hp_exhaust_temperature"]
    assert np.abs(stored.to_numpy() - batch["hp_exhaust_temperature"].to_numpy()).max() <= 1e-9
    flagged = wide.filter(like="flag/").notna().to_numpy().sum()
    assert flagged > 0  # the injected spikes and dropouts reached the database as flags


def test_a_restart_after_a_crash_gives_the_uninterrupted_database(tmp_path, plant, model):
    run, paths = plant
    tag_map = plant_tag_map()
    reference = _twin(tmp_path / "reference.duckdb", model, run).start()
    asyncio.run(reference.run(ReplaySource(paths["historian"], tag_map, block_samples=100)))
    expected = reference.historian.connection.execute(QUERY).df()
    expected_parameters = reference.historian.connection.execute(PARAMETERS).df()
    reference.close()
    # the starting set, recorded once with the first block at its first sample
    assert set(expected_parameters["reason"]) == {"start"}
    assert (pd.to_datetime(expected_parameters["time"], utc=True) == expected["time"].min()).all()
    assert dict(zip(expected_parameters["name"], expected_parameters["value"], strict=True)) == {
        name: float(value) for name, value in vars(ModelParameters()).items()}

    crashed = _twin(tmp_path / "crashed.duckdb", model, run).start()

    async def until_crash():
        blocks = ReplaySource(paths["historian"], tag_map, block_samples=100).blocks()
        count = 0
        async for block in blocks:
            crashed.process(block)
            count += 1
            if count == 4:  # the process dies here: no finish, pending samples lost
                return

    asyncio.run(until_crash())
    stored_before = crashed.historian.connection.execute(
        "SELECT count(DISTINCT time) FROM series").fetchone()[0]
    crashed.close()
    assert 0 < stored_before < len(run.measured)

    restarted = _twin(tmp_path / "crashed.duckdb", model, run).start()
    source = ReplaySource(paths["historian"], tag_map, block_samples=100,
                          start_after=restarted.resume_after())
    asyncio.run(restarted.run(source))
    got = restarted.historian.connection.execute(QUERY).df()
    got_parameters = restarted.historian.connection.execute(PARAMETERS).df()
    restarted.close()
    pd.testing.assert_frame_equal(got, expected)
    pd.testing.assert_frame_equal(got_parameters, expected_parameters)  # not twice
