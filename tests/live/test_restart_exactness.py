"""A restart gives the uninterrupted run, exactly, wherever the stream was cut (issue 21: "the
service SIGKILLed and restarted → identical database to an uninterrupted run").

The gate's detectors judge a sample from statistics over a window (noise, spread of the
departures from the rolling median, run persistence), so a verdict is only reproducible if the
window is a function of the stream, not of how its blocks arrived or where a restart resumed
(:mod:`steamtwin.live.gate`). Short records with many dropouts and spikes, random block sizes,
crash points and context lengths; bit-for-bit comparison.
"""

from __future__ import annotations

import asyncio
import functools
import tempfile
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from steamtwin.dcs.plant import PlantRun, plant_tag_map, run_plant, write_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.live.gate import GateOutput, StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters

QUERY = "SELECT unit, time, source, signal, value, flag FROM series ORDER BY ALL"
SEEDS = (3, 5)
DROPOUTS_PER_H = (0.0, 30.0)


ROWS = slice(1000, 1450)  # 7.5 min of the record: short, with its faults


@functools.cache
def _plant(seed: int, dropouts_per_h: float) -> tuple[PlantRun, pd.DataFrame, Path]:
    """A short faulty record (dropouts, spikes, stuck runs): the run, its measured samples in
    :data:`ROWS` and a historian CSV of just those rows."""
    truth = PlantTruth(faults=FaultConfig(dropout_rate_per_h=dropouts_per_h,
                                          spike_rate_per_h=60, stuck_rate_per_h=10,
                                          stuck_median_s=60))
    run = run_plant("deep-peak-50", hours=0.01, random_state=seed, truth=truth)
    folder = Path(tempfile.mkdtemp(prefix="restart-exact-"))
    historian = write_plant(run, folder, file_format="csv")["historian"]
    header, *lines = historian.read_text().splitlines(keepends=True)
    short = folder / "short.csv"
    short.write_text(header + "".join(lines[ROWS]))
    return run, run.measured.iloc[ROWS], short


def _gate(run: PlantRun, context: int) -> StreamGate:
    return StreamGate(gate_options(plant_tag_map(), run.injected.sensors),
                      context_samples=context)


def _joined(outputs: list[GateOutput]) -> tuple[pd.DataFrame, pd.DataFrame]:
    outputs = [o for o in outputs if len(o.data)]
    return pd.concat([o.data for o in outputs]), pd.concat([o.flags for o in outputs])


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.sampled_from(SEEDS), dropouts=st.sampled_from(DROPOUTS_PER_H),
       first=st.integers(20, 150), crashed=st.integers(20, 150), resumed=st.integers(20, 150),
       crash_after=st.integers(2, 12), context=st.sampled_from((61, 150, 1800)))
@example(seed=3, dropouts=30.0, first=40, crashed=40, resumed=40, crash_after=5, context=1800)
def test_gate_verdicts_do_not_depend_on_the_cut_or_a_restart(seed, dropouts, first, crashed,
                                                             resumed, crash_after, context):
    run, stream, _ = _plant(seed, dropouts)
    reference = _gate(run, context)
    whole = [reference.push(stream.iloc[i:i + first]) for i in range(0, len(stream), first)]
    expected = _joined([*whole, reference.flush()])

    gate = _gate(run, context)
    kept: list[GateOutput] = []
    state = gate.get_state()
    for i in range(0, min(crash_after * crashed, len(stream)), crashed):
        out = gate.push(stream.iloc[i:i + crashed])
        if len(out.data):  # the service saves the state with each block it stores
            kept.append(out)
            state = gate.get_state()
    # the process dies; a new gate continues from the saved state with the samples after it
    restarted = _gate(run, context).set_state(state)
    after = stream[stream.index > kept[-1].data.index[-1]] if kept else stream
    kept += [restarted.push(after.iloc[i:i + resumed]) for i in range(0, len(after), resumed)]
    got = _joined([*kept, restarted.flush()])
    pd.testing.assert_frame_equal(got[0], expected[0], check_freq=False)
    pd.testing.assert_frame_equal(got[1], expected[1], check_freq=False)


@pytest.fixture(scope="module")
def model(reference_spec) -> FullOrderModel:
    fom = FullOrderModel(reference_spec)
    _ = fom.design_
    return fom


def _twin(db: Path, model: FullOrderModel, run: PlantRun, snapshot_s: float) -> LiveTwin:
    return LiveTwin("unit1", model, ModelParameters(), _gate(run, 150), LiveHistorian(db),
                    snapshot_every_s=snapshot_s)


@settings(max_examples=2, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.sampled_from(SEEDS), dropouts=st.sampled_from(DROPOUTS_PER_H),
       first=st.integers(20, 120), resumed=st.integers(20, 120), crash_after=st.integers(3, 8),
       snapshot_s=st.sampled_from((0.0, 90.0)))
@example(seed=3, dropouts=30.0, first=40, resumed=40, crash_after=5, snapshot_s=600.0)
def test_a_restart_stores_the_uninterrupted_database(model, seed, dropouts, first, resumed,
                                                     crash_after, snapshot_s):
    run, _, historian = _plant(seed, dropouts)
    tags, folder = plant_tag_map(), Path(tempfile.mkdtemp(prefix="restart-db-"))
    reference = _twin(folder / "r.duckdb", model, run, snapshot_s).start()
    asyncio.run(reference.run(ReplaySource(historian, tags, block_samples=first)))
    expected = reference.historian.connection.execute(QUERY).df()
    reference.close()

    crashed = _twin(folder / "c.duckdb", model, run, snapshot_s).start()

    async def until_crash() -> None:
        count = 0
        async for block in ReplaySource(historian, tags, block_samples=first).blocks():
            crashed.process(block)
            count += 1
            if count == crash_after:  # SIGKILL: no finish, the pending samples are lost
                return

    asyncio.run(until_crash())
    crashed.close()
    restarted = _twin(folder / "c.duckdb", model, run, snapshot_s).start()
    asyncio.run(restarted.run(ReplaySource(historian, tags, block_samples=resumed,
                                           start_after=restarted.resume_after())))
    got = restarted.historian.connection.execute(QUERY).df()
    restarted.close()
    pd.testing.assert_frame_equal(got, expected)
