"""The HTTP service inside the live service's event loop (issue 22): uvicorn serving the
historian the service writes, on a real loopback socket — a sample committed by the writer
reaches an open server-sent event stream, a new alarm too, /metrics parses as Prometheus text;
and ``steamtwin serve`` refuses a non-loopback bind without a token file before it starts."""

from __future__ import annotations

import asyncio
import json

import httpx
import pandas as pd
import pytest
from prometheus_client.parser import text_string_to_metric_families
from typer.testing import CliRunner
from web_fixtures import START, unit_block

from steamtwin.cli.main import app as cli
from steamtwin.live.historian import Alarm, BlockEvents, LiveHistorian
from steamtwin.web.app import WebSettings
from steamtwin.web.server import HttpServiceError, HttpSettings, bind_socket, http_companion


async def _events(lines, wanted: str, timeout_s: float) -> dict:
    """The data of the next event named ``wanted`` on an SSE line stream."""
    event = None
    async with asyncio.timeout(timeout_s):
        async for line in lines:
            if line.startswith("event: "):
                event = line.removeprefix("event: ")
            elif line.startswith("data: ") and event == wanted:
                return json.loads(line.removeprefix("data: "))
    raise AssertionError(f"no {wanted} event")


async def _scenario(db, committed: dict) -> tuple[dict, dict, str, dict]:
    bound: dict[str, int] = {}
    companion = http_companion(HttpSettings(port=0, web=WebSettings(poll_s=0.05)),
                               on_bound=lambda _host, port: bound.update(port=port))
    historian = LiveHistorian(db)
    historian.open()
    done = asyncio.Event()
    server = asyncio.create_task(companion(historian, done))
    try:
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{bound['port']}",
                                     timeout=5.0) as client:
            async with asyncio.timeout(5.0):
                while True:  # until uvicorn has started
                    try:
                        health = (await client.get("/health")).json()
                        break
                    except httpx.TransportError:
                        await asyncio.sleep(0.05)
            async with client.stream("GET", "/api/events?unit=unit1") as stream:
                assert stream.headers["content-type"].startswith("text/event-stream")
                lines = stream.aiter_lines()
                assert await anext(lines) == "retry: 2000"
                start_s = 7200
                sample = None
                for _ in range(20):  # the feed notes where things stand on its first poll
                    frames, flags = unit_block(start_s, 2)
                    historian.commit_block("unit1", frames, flags)  # as the service does
                    committed.update(frames["twin"]["blade_leading_edge"].items())
                    start_s += 2
                    try:
                        sample = await _events(lines, "sample", 0.5)
                        break
                    except TimeoutError:
                        continue
                assert sample is not None
                frames, flags = unit_block(start_s, 3)
                alarm_time = frames["measured"].index[1]
                historian.commit_block("unit1", frames, flags, events=BlockEvents(alarms=(
                    Alarm("unit1", "sensor_fault", alarm_time, "hp_exhaust_temperature",
                          evidence={"statistic": 7.0}),)))
                alarm = await _events(lines, "alarm", 5.0)
                metrics = (await client.get("/metrics")).text
    finally:
        done.set()
        await server
        historian.close()
    return health, sample, metrics, alarm


def test_a_committed_sample_and_alarm_reach_the_event_stream(filled_db):
    committed: dict[pd.Timestamp, float] = {}
    health, sample, metrics, alarm = asyncio.run(_scenario(filled_db, committed))
    assert health["units"]["unit1"]["last_sample"] == "2026-03-01T01:59:59+00:00"
    assert sample["unit"] == "unit1"
    time = pd.Timestamp(sample["time"])
    assert time >= START + pd.Timedelta(hours=2)  # new, not from the history
    assert sample["values"]["twin/blade_leading_edge"] == committed[time]
    assert alarm["kind"] == "sensor_fault" and alarm["evidence"] == {"statistic": 7.0}
    families = {f.name: f for f in text_string_to_metric_families(metrics)}
    assert {s.labels["unit"]: s.value for s in
            families["steamtwin_alarms_active"].samples} == {"unit1": 2.0, "unit2": 0.0}
    assert families["steamtwin_events_subscribers"].samples[0].value == 1.0
    requests = families["steamtwin_http_requests"]  # the parser drops _total
    assert any(s.labels == {"route": "/health", "method": "GET", "status": "200"}
               for s in requests.samples)
    buckets = [s for s in families["steamtwin_http_request_duration_seconds"].samples
               if s.name.endswith("_bucket") and s.labels["route"] == "/health"]
    assert buckets[-1].labels["le"] == "+Inf"
    assert [s.value for s in buckets] == sorted(s.value for s in buckets)  # cumulative


async def _reconnect(db) -> tuple[dict, list[tuple[str, dict]], list[tuple[str, dict]]]:
    """Samples stored while a client was away; it reconnects with the last id it saw."""
    bound: dict[str, int] = {}
    companion = http_companion(HttpSettings(port=0, web=WebSettings(poll_s=0.05)),
                               on_bound=lambda _host, port: bound.update(port=port))
    historian = LiveHistorian(db)
    historian.open()
    frames, flags = unit_block(7200, 5)
    historian.commit_block("unit1", frames, flags)  # stored while the client was away
    missed = dict(frames["twin"]["blade_leading_edge"].items())
    done = asyncio.Event()
    server = asyncio.create_task(companion(historian, done))
    try:
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{bound['port']}",
                                     timeout=5.0) as client:
            async with asyncio.timeout(5.0):
                while True:  # until uvicorn has started
                    try:
                        await client.get("/health")
                        break
                    except httpx.TransportError:
                        await asyncio.sleep(0.05)
            bad = (await client.get("/api/events", headers={"last-event-id": "yesterday"})
                   ).json()
            seen = (START + pd.Timedelta(seconds=7201)).isoformat()
            async with client.stream("GET", "/api/events?unit=unit1",
                                     headers={"last-event-id": seen}) as stream:
                lines = stream.aiter_lines()
                backfill = [await _named_event(lines, 1.0) for _ in range(4)]
                frames, flags = unit_block(7205, 1)
                historian.commit_block("unit1", frames, flags)
                live = [await _named_event(lines, 5.0)]
    finally:
        done.set()
        await server
        historian.close()
    assert all(pd.Timestamp(data["time"]) in missed for name, data in backfill
               if name == "sample")
    return bad, backfill, live


async def _named_event(lines, timeout_s: float) -> tuple[str, dict]:
    """The next event's name and data on an SSE line stream."""
    event = None
    async with asyncio.timeout(timeout_s):
        async for line in lines:
            if line.startswith("event: "):
                event = line.removeprefix("event: ")
            elif line.startswith("data: ") and event is not None:
                return event, json.loads(line.removeprefix("data: "))
    raise AssertionError("the stream ended")


def test_a_client_reconnecting_with_last_event_id_gets_the_samples_it_missed(filled_db):
    bad, backfill, live = asyncio.run(_reconnect(filled_db))
    assert "Last-Event-ID='yesterday': not an ISO 8601 time" in bad["error"]
    second = pd.Timedelta(seconds=1)
    assert [(name, data.get("time")) for name, data in backfill] == [
        ("sample", (START + k * second).isoformat()) for k in (7202, 7203, 7204)] + [
        ("alarms", None)]
    assert [alarm["kind"] for alarm in backfill[3][1]["active"]] == ["degradation"]
    assert [(name, data["time"]) for name, data in live] == [
        ("sample", (START + 7205 * second).isoformat())]


def test_a_port_in_use_is_a_clear_error():
    taken = bind_socket("127.0.0.1", 0)
    try:
        with pytest.raises(HttpServiceError, match=r"cannot listen on 127.0.0.1:\d+"):
            bind_socket("127.0.0.1", taken.getsockname()[1])
    finally:
        taken.close()


def test_serve_refuses_a_non_loopback_bind_without_tokens(serve_config):
    runner = CliRunner()
    refused = runner.invoke(cli, ["serve", "--config", str(serve_config.source),
                                  "--http-port", "0", "--bind", "0.0.0.0"])
    assert refused.exit_code == 2
    assert "needs --token-file" in refused.output
    orphan = runner.invoke(cli, ["serve", "--config", str(serve_config.source),
                                 "--token-file", str(serve_config.source)])
    assert orphan.exit_code == 2 and "add --http-port" in orphan.output
