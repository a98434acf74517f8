"""The rotor in the live twin (issue 23, item 6): every accepted sample steps the rotor model on
the streamed FOM's stage states; the stored rotor signals equal one-sample-at-a-time stepping
of the model, and a restart after a crash gives the uninterrupted run's database, rotor
included."""

from __future__ import annotations

import asyncio

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.live.config import ConfigError, load_config
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.rotor_stream import ROTOR_SIGNALS, LiveRotor
from steamtwin.live.runner import build_unit
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.parameters import ModelParameters
from steamtwin.rotor.model import RotorModel

QUERY = "SELECT unit, time, source, signal, value, flag FROM series ORDER BY ALL"


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    # test_service.py's record: its restart is exact (other seeds and block sizes show gate
    # flags that differ after a restart — a gate matter, reported, not the rotor's)
    truth = PlantTruth(faults=FaultConfig(dropout_rate_per_h=3, spike_rate_per_h=6))
    run = run_plant("deep-peak-50", hours=0.25, random_state=8, truth=truth)
    paths = write_plant(run, tmp_path_factory.mktemp("plant"), file_format="csv")
    return run, paths


@pytest.fixture(scope="module")
def rotor_model(reference_spec) -> RotorModel:
    """A very coarse rotor model (one training ramp, 60-s steps): ~1 s to fit."""
    return RotorModel(reference_spec, mesh_size=0.08, groove_mesh_size=0.006,
                      training_step_s=60.0, training_hold_s=900.0,
                      fit_ramps=[(1.0, 0.5, 0.05)]).fit()


def _twin(db, model, run, rotor_model) -> LiveTwin:
    gate = StreamGate(gate_options(plant_tag_map(), run.injected.sensors))
    return LiveTwin("unit1", model, ModelParameters(), gate, LiveHistorian(db),
                    rotor=LiveRotor(rotor_model))


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory, plant, reference_model, rotor_model):
    """The whole record through the twin with its rotor: (wide series, database rows)."""
    run, paths = plant
    twin = _twin(tmp_path_factory.mktemp("db") / "a.duckdb", reference_model, run,
                 rotor_model).start()
    asyncio.run(twin.run(ReplaySource(paths["historian"], plant_tag_map(), block_samples=100)))
    wide = twin.historian.series("unit1")
    rows = twin.historian.connection.execute(QUERY).df()
    twin.close()
    return wide, rows


@pytest.mark.slow  # 5–10 s with the record's replay (as test_service.py's)
def test_stored_rotor_signals_are_the_model_stepped_once_per_accepted_sample(
        uninterrupted, reference_model, rotor_model):
    wide, _ = uninterrupted
    stored = wide[[f"twin/{name}" for name in ROTOR_SIGNALS]].dropna()
    fed = wide[[f"measured/{n}" for n in reference_model.input_signals]].dropna()
    assert stored.index.equals(fed.index)  # a rotor value exactly where the twin has one
    gaps = np.diff(fed.index.asi8)
    assert len(set(gaps)) > 1  # dropouts: the rotor stepped over uneven gaps
    # reference: the model's own steam side and one step per sample, from equilibrium
    steam = rotor_model.steam_side(fed.set_axis(list(reference_model.input_signals), axis=1))
    state = rotor_model.initial_state(steam.iloc[0])
    rows = [rotor_model.observe(state)]
    for k in range(1, len(steam)):
        step = (steam.index[k] - steam.index[k - 1]).total_seconds()
        state, row = rotor_model.step(state, dict(zip(steam.columns, steam.iloc[k].to_numpy(),
                                                      strict=True)), step)
        rows.append(row)
    expected = pd.DataFrame(rows)[list(ROTOR_SIGNALS.values())].to_numpy()
    np.testing.assert_allclose(stored.to_numpy(), expected, rtol=1e-9, atol=1e-3)
    # the load falls over the record: the groove surface cools ahead of the bulk (tension)
    groove = stored["twin/rotor_groove_temperature"]
    mean = stored["twin/rotor_mean_temperature"]
    assert (groove.iloc[-1] - mean.iloc[-1]) < (groove.iloc[0] - mean.iloc[0])


@pytest.mark.slow  # as test_service.py's restart test, with the rotor
def test_a_restart_continues_the_rotor_exactly(tmp_path, plant, reference_model, rotor_model,
                                               uninterrupted):
    run, paths = plant
    tag_map = plant_tag_map()
    _, expected = uninterrupted
    assert set(ROTOR_SIGNALS) <= set(expected.loc[expected["source"] == "twin", "signal"])

    crashed = _twin(tmp_path / "crashed.duckdb", reference_model, run, rotor_model).start()

    async def until_crash():
        count = 0
        async for block in ReplaySource(paths["historian"], tag_map, block_samples=100).blocks():
            crashed.process(block)
            count += 1
            if count == 4:  # the process dies here: pending samples lost
                return

    asyncio.run(until_crash())
    crashed.close()
    restarted = _twin(tmp_path / "crashed.duckdb", reference_model, run, rotor_model).start()
    resume = restarted.resume_after()
    assert resume is not None
    asyncio.run(restarted.run(ReplaySource(paths["historian"], tag_map, block_samples=100,
                                           start_after=resume)))
    got = restarted.historian.connection.execute(QUERY).df()
    restarted.close()
    pd.testing.assert_frame_equal(got, expected, check_exact=False, rtol=1e-12, atol=1e-9)


def test_the_service_configuration_names_the_rotor(tmp_path):
    (tmp_path / "tags.toml").write_text("")
    (tmp_path / "rotor.npz").write_bytes(b"")
    base = ('database = "t.duckdb"\n[[units]]\nname = "u"\ntags = "tags.toml"\n'
            '[units.source]\nkind = "replay"\npath = "tags.toml"\n')
    head, source = base.split("[units.source]")
    path = tmp_path / "unit.toml"
    path.write_text(head + 'rotor = "rotor.npz"\nrotor_allowable_mpa = 450\n[units.source]'
                    + source)
    unit = load_config(path).units[0]
    assert unit.rotor == tmp_path / "rotor.npz" and unit.rotor_allowable == 450e6
    path.write_text(head + 'rotor = "fit"\n[units.source]' + source)
    assert load_config(path).units[0].rotor == "fit"
    path.write_text(head + "rotor_allowable_mpa = 450\n[units.source]" + source)
    with pytest.raises(ConfigError, match="rotor_allowable_mpa needs a rotor model"):
        load_config(path)
    path.write_text(head + 'rotor = "missing.npz"\n[units.source]' + source)
    with pytest.raises(ConfigError, match=r"units\[0\]\.rotor = 'missing.npz': no such file"):
        load_config(path)


@pytest.mark.slow  # with the plant record's fixture
def test_the_service_builds_a_unit_with_its_rotor_file(tmp_path, plant, rotor_model):
    _, paths = plant
    rotor_model.save(tmp_path / "rotor.npz")
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "twin.duckdb"\n[[units]]\nname = "u"\n'
                      f'tags = "{paths["tag_map"]}"\nrotor = "rotor.npz"\n[units.source]\n'
                      f'kind = "replay"\npath = "{paths["historian"]}"\n')
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:
        twin, _ = build_unit(load_config(config).units[0], historian)
    assert isinstance(twin.rotor, LiveRotor)
    assert twin.rotor.model.groups_ == rotor_model.groups_
    assert twin.rotor.model.critical_points == rotor_model.critical_points
