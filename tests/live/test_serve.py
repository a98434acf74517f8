"""``steamtwin serve`` (issue 21, item 8): the configuration, a replayed unit end to end and
restarted without storing a sample twice, and a unit read live from the virtual plant's OPC UA
server on 127.0.0.1."""

from __future__ import annotations

import asyncio
import socket

import pytest
from typer.testing import CliRunner

from steamtwin.cli.main import app
from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import ConfigError, load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.plant_server import PlantServer, PlantServerSettings, plant_node_ids
from steamtwin.live.runner import run_service

pytestmark = pytest.mark.slow  # 11 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    run = run_plant("deep-peak-50", hours=0.05, random_state=6)
    folder = tmp_path_factory.mktemp("plant")
    return run, write_plant(run, folder, file_format="parquet"), folder


def _samples(db) -> int:
    with LiveHistorian(db) as historian:
        return historian.connection.execute(
            "SELECT count(*) FROM (SELECT DISTINCT unit, time FROM series)").fetchone()[0]


def test_configuration_mistakes_name_file_and_key(tmp_path, plant):
    _, paths, _ = plant
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "twin.duckdb"\n[[units]]\nname = "u1"\ntags = '
                      f'"{paths["tag_map"]}"\n[units.source]\nkind = "opcua"\n'
                      'endpoint = "opc.tcp://127.0.0.1:1/"\n')
    with pytest.raises(ConfigError, match=r"units\[0\].source: no certificate/private_key"):
        load_config(config)
    config.write_text('database = "twin.duckdb"\n[[units]]\nname = "u1"\ntags = "nope.toml"\n')
    with pytest.raises(ConfigError, match=r"units\[0\].tags = 'nope.toml': no such file"):
        load_config(config)
    config.write_text('database = "twin.duckdb"\ncolour = "red"\n')
    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['colour'\]"):
        load_config(config)
    config.write_text(f'database = "twin.duckdb"\nhistorian_memory_mb = 4\n[[units]]\n'
                      f'name = "u1"\ntags = "{paths["tag_map"]}"\n')
    with pytest.raises(ConfigError, match=r"historian_memory_mb = 4: expected a number of MB"):
        load_config(config)


def test_serve_a_replayed_unit_and_restart_without_duplicates(tmp_path, plant):
    run, paths, _ = plant
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "twin.duckdb"\n[[units]]\nname = "unit1"\n'
                      f'tags = "{paths["tag_map"]}"\nblock_samples = 50\n[units.source]\n'
                      f'kind = "replay"\npath = "{paths["historian"]}"\nspeed = "max"\n')
    runner = CliRunner()
    first = runner.invoke(app, ["serve", "--config", str(config), "--log-level", "warning"])
    assert first.exit_code == 0, first.output
    assert f"unit1: {len(run.measured)} samples stored" in first.output
    again = runner.invoke(app, ["serve", "--config", str(config), "--log-level", "warning"])
    assert again.exit_code == 0, again.output
    assert "unit1: 0 samples stored" in again.output  # everything was there already
    assert _samples(tmp_path / "twin.duckdb") == len(run.measured)
    assert load_config(config).historian_memory_mb == 32.0  # the default bound


def test_serve_reads_the_plant_over_opc_ua(tmp_path, plant):
    run, _, _ = plant
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    settings = PlantServerSettings(port=port, speed=None)
    tags = tmp_path / "live-tags.toml"
    write_tag_map(plant_node_ids(plant_tag_map()), tags)
    config = tmp_path / "unit.toml"
    config.write_text(f'database = "live.duckdb"\n[[units]]\nname = "unit1"\ntags = "{tags}"\n'
                      f'block_samples = 20\n[units.source]\nkind = "opcua"\n'
                      f'endpoint = "{settings.endpoint}"\nallow_insecure = true\n')
    measured = run.measured.iloc[:150]

    async def scenario():
        stop = asyncio.Event()
        async with PlantServer(measured, plant_tag_map(), settings) as server:
            service = asyncio.create_task(run_service(load_config(config), stop))
            await asyncio.sleep(1.5)  # connected and subscribed
            await server.publish()
            await asyncio.sleep(4.0)  # the last samples settle and pass the gate's look-ahead
            stop.set()
            return await service

    summaries = asyncio.run(scenario())
    stored = _samples(tmp_path / "live.duckdb")
    # all but the gate's look-ahead (samples waiting for their successors when stopped)
    assert 150 - 61 - 59 <= stored <= 150  # pending: the look-ahead and an open 60-s bin
    assert summaries["unit1"].samples == stored
