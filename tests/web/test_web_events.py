"""The live feed's server-sent events (issue 22, item 1): the wire format of the WHATWG HTML
standard (§9.2), one poll fanned out to every subscriber of the unit, nothing replayed from
before the first look, and a subscriber that falls behind dropped with a last event."""

from __future__ import annotations

import asyncio

import pandas as pd

from steamtwin.web.events import LiveFeed, format_event

T0 = pd.Timestamp("2026-03-01T00:00:00Z")


class _Historian:
    """What the feed reads, held in memory: last times per unit and the samples."""

    def __init__(self) -> None:
        self.times: dict[str, pd.Timestamp] = {"u1": T0, "u2": T0}
        self.samples: list[tuple[str, pd.Timestamp]] = []

    def live_times(self) -> dict[str, pd.Timestamp]:
        return dict(self.times)

    def alarm_marks(self) -> tuple[int, int]:
        return 0, 0

    def samples_after(self, unit, after, limit):
        return [{"time": t.isoformat(), "values": {"twin/x": 1.0}}
                for u, t in self.samples if u == unit and (after is None or t > after)][-limit:]

    def store(self, unit: str, seconds: int) -> None:
        time = T0 + pd.Timedelta(seconds=seconds)
        self.samples.append((unit, time))
        self.times[unit] = time


def test_the_wire_format():
    assert format_event("sample", {"a": [1, None]}, "2026-03-01T00:00:01+00:00") == (
        'event: sample\nid: 2026-03-01T00:00:01+00:00\ndata: {"a":[1,null]}\n\n')
    assert format_event("alarms", {}) == "event: alarms\ndata: {}\n\n"


async def _run() -> tuple[list[str], list[str], list[str]]:
    historian = _Historian()
    historian.store("u1", 0)  # before the first look: never sent
    feed = LiveFeed(historian, queue_size=3)
    await feed.poll()
    one, both, slow = feed.stream("u1"), feed.stream(None), feed.stream("u2")
    first = [await anext(one), await anext(both), await anext(slow)]
    assert first == ["retry: 2000\n\n"] * 3 and feed.subscribers == 3
    historian.store("u1", 1)
    historian.store("u2", 1)
    await feed.poll()
    got_one = [await anext(one)]
    got_both = [await anext(both), await anext(both)]
    for k in range(2, 6):  # u2 moves on; its subscriber reads nothing: 4 events > 3 queued
        historian.store("u2", k)
        await feed.poll()
    got_slow = [await anext(slow) for _ in range(4)]
    return got_one, got_both, got_slow


def test_one_poll_reaches_every_subscriber_and_a_slow_one_is_dropped():
    got_one, got_both, got_slow = asyncio.run(_run())
    assert got_one == [format_event("sample", {"unit": "u1", "time": "2026-03-01T00:00:01"
                                               "+00:00", "values": {"twin/x": 1.0}},
                                    "2026-03-01T00:00:01+00:00")]
    assert ['"unit":"u1"' in text for text in got_both] == [True, False]
    assert [text.split("\n")[0] for text in got_slow] == [
        "event: sample", "event: sample", "event: sample", "event: dropped"]


def test_a_reconnecting_client_gets_what_it_missed_once():
    """Last-Event-ID: the samples after it from the historian, the active alarms, then live;
    a sample both stored before the historian was read and queued live is sent once."""

    async def run() -> list[str]:
        historian = _Historian()
        historian.alarms = lambda unit, active: [{"id": 1, "unit": unit}]
        feed = LiveFeed(historian)
        await feed.poll()
        for k in (1, 2, 3):
            historian.store("u1", k)
        stream = feed.stream("u1", T0 + pd.Timedelta(seconds=1))
        assert await anext(stream) == "retry: 2000\n\n"  # subscribed from here on
        historian.store("u1", 4)
        await feed.poll()  # queues 2, 3, 4 live while the historian also holds them
        got = [await anext(stream) for _ in range(4)]
        historian.store("u1", 5)
        await feed.poll()
        got.append(await anext(stream))
        return got

    got = asyncio.run(run())
    ids = [line.removeprefix("id: ") for text in got for line in text.split("\n")
           if line.startswith("id: ")]
    assert ids == [(T0 + pd.Timedelta(seconds=k)).isoformat() for k in (2, 3, 4, 5)]
    assert [text.split("\n")[0] for text in got] == [
        "event: sample", "event: sample", "event: sample", "event: alarms", "event: sample"]
    assert '"active":[{"id":1,"unit":"u1"}]' in got[3]
