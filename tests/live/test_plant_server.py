"""The virtual plant's OPC UA server (issue 21, item 3), tested with a real asyncua client on
127.0.0.1 — never a mock of the server."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pandas as pd
import pytest
from asyncua import Client, ua
from ports import free_port

from steamtwin.dcs.plant import plant_tag_map
from steamtwin.live.nodes import resolve_node_id
from steamtwin.live.plant_server import (
    NAMESPACE_URI,
    PlantServer,
    PlantServerSettings,
    plant_node_ids,
)
from steamtwin.units import convert

pytestmark = pytest.mark.slow  # 6 s of the full suite (2026-11-27): not in the quick loop


def _signals(n: int = 120) -> pd.DataFrame:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC")
    rng = np.random.default_rng(1)
    frame = pd.DataFrame({
        "main_steam_pressure": 16.0e6 + rng.normal(0, 2e4, n),
        "main_steam_temperature": 811.15 + rng.normal(0, 0.3, n),
        "hp_exhaust_temperature": 600.0 + np.arange(n) * 0.01,
    }, index=index)
    frame.iloc[10:13, 2] = np.nan  # a dropout
    return frame


def test_settings_are_checked():
    with pytest.raises(ValueError, match="speed must be a positive"):
        PlantServerSettings(speed=0.0)
    with pytest.raises(ValueError, match="clock 'now' needs speed 1"):
        PlantServerSettings(speed=10.0, clock="now")
    with pytest.raises(ValueError, match="port"):
        PlantServerSettings(port=70000)


def test_a_client_reads_values_status_timestamps_and_history():
    frame = _signals()
    tag_map = plant_tag_map()
    settings = PlantServerSettings(port=free_port(), speed=None, history_samples=100)

    async def scenario():
        async with PlantServer(frame, tag_map, settings) as server:
            sent = await server.publish(60)
            async with Client(url=server.endpoint, timeout=10) as client:
                index = await client.get_namespace_index(NAMESPACE_URI)
                exhaust = client.get_node(ua.NodeId(
                    tag_map.signals["hp_exhaust_temperature"].column, index))
                latest = await exhaust.read_data_value()
                pressure = client.get_node(await resolve_node_id(
                    client, plant_node_ids(tag_map).signals["main_steam_pressure"].node_id))
                with pytest.raises(ValueError, match="does not serve namespace"):
                    await resolve_node_id(client, "nsu=urn:elsewhere;s=X")
                latest_p = await pressure.read_value()
                history = await exhaust.read_raw_history(
                    frame.index[0].to_pydatetime(), frame.index[59].to_pydatetime())
                unit = await (await exhaust.get_child(f"{index}:EngineeringUnit")).read_value()
                sent += await server.publish()  # the rest
                history_all = await exhaust.read_raw_history(
                    frame.index[0].to_pydatetime(), frame.index[-1].to_pydatetime())
            return sent, latest, latest_p, history, history_all, unit

    sent, latest, latest_p, history, history_all, unit = asyncio.run(scenario())
    assert sent == len(frame)
    assert unit == "degC"
    # the last published sample, in the tag's wire unit, with its own timestamp
    assert latest.Value.Value == pytest.approx(frame["hp_exhaust_temperature"].iloc[59] - 273.15)
    assert pd.Timestamp(latest.SourceTimestamp) == frame.index[59]
    assert latest_p == pytest.approx(frame["main_steam_pressure"].iloc[59] / 1e6)
    # HistoryRead: every published value, the dropout as Bad (never filled)
    assert len(history) == 60
    values = np.array([dv.Value.Value for dv in history])
    expected = convert(frame["hp_exhaust_temperature"].to_numpy()[:60], "K", "degC")
    assert np.allclose(values[np.isfinite(expected)], expected[np.isfinite(expected)])
    bad = [not dv.StatusCode.is_good() for dv in history]
    assert bad == [not math.isfinite(x) for x in expected]
    # only the last history_samples are kept
    assert len(history_all) == 100
    assert pd.Timestamp(history_all[-1].SourceTimestamp) == frame.index[-1]


def test_speed_paces_the_samples():
    frame = _signals(6)
    settings = PlantServerSettings(port=free_port(), speed=10.0)

    async def scenario():
        async with PlantServer(frame, plant_tag_map(), settings) as server:
            loop = asyncio.get_running_loop()
            start = loop.time()
            await server.publish()
            return loop.time() - start

    elapsed = asyncio.run(scenario())
    assert 0.45 <= elapsed < 10.0  # five 1-s steps at 10× real time: 0.5 s, never less
