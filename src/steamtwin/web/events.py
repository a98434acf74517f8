"""Live updates by server-sent events (issue 22, item 1): new samples and alarms.

One poller (:class:`LiveFeed`) watches the historian for every client — the ``progress``
table's last committed time per unit and the alarm table's fingerprint, every ``poll_s`` —
and fans what is new out to each subscriber's bounded queue, so 200 open pages cost one query
per poll, not 200. A subscriber that falls ``queue_size`` events behind is dropped (it gets a
``dropped`` event and the browser's EventSource reconnects) rather than growing memory.

Wire format: the ``text/event-stream`` of the WHATWG HTML Living Standard, §9.2 "Server-sent
events": ``event:`` (``sample``, ``alarm``, ``alarms``, ``dropped``), ``id:`` (the sample's
time), one ``data:`` line of JSON, a blank line; ``retry:`` sets the reconnection delay and a
comment line (``: keep-alive``) every ``heartbeat_s`` keeps proxies from closing an idle
stream.

Reconnection: the stream of a client that sends ``Last-Event-ID`` (the standard's header; the
``id`` of a sample event is its time) starts with the samples stored after that time — read
from the historian, provisional ones included, at most ``backfill`` of the newest per unit —
and the active alarm list, then goes on live. The client is subscribed before the historian is
read, and a live sample no newer than the last one sent is skipped, so no sample of the gap is
lost or sent twice.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import AsyncIterator
from dataclasses import dataclass, field

import pandas as pd

from steamtwin.web.queries import HistorianReader

__all__ = ["LiveFeed", "format_event"]

LOG = logging.getLogger("steamtwin.web")


def format_event(event: str, data: object, event_id: str | None = None) -> str:
    """One server-sent event (module docstring): JSON ``data`` on one line."""
    head = f"event: {event}\n" + (f"id: {event_id}\n" if event_id else "")
    return f"{head}data: {json.dumps(data, separators=(',', ':'))}\n\n"


def _sample_event(unit: str, sample: dict) -> str:
    """A ``sample`` event of ``unit``, its id the sample's time."""
    return format_event("sample", {"unit": unit, **sample}, sample["time"])


@dataclass
class _Subscriber:
    """One stream's queue of (unit, sample time or None, event text); None ends it."""

    unit: str | None
    queue: asyncio.Queue = field(default_factory=lambda: asyncio.Queue(maxsize=64))
    dropped: bool = False


class LiveFeed:
    """The poller and its subscribers (see the module docstring). ``poll_s``: seconds between
    polls; ``heartbeat_s``: seconds between keep-alive comments; ``queue_size``: events a
    subscriber may fall behind before it is dropped; ``backfill``: most samples per unit sent
    to a reconnecting client (600: the Unit page's 10-min window at 1 Hz)."""

    def __init__(self, reader: HistorianReader, poll_s: float = 0.25,
                 heartbeat_s: float = 15.0, queue_size: int = 64, backfill: int = 600) -> None:
        self.reader = reader
        self.poll_s = poll_s
        self.heartbeat_s = heartbeat_s
        self.queue_size = queue_size
        self.backfill = backfill
        self._subscribers: list[_Subscriber] = []
        self._last: dict[str, pd.Timestamp] | None = None
        self._alarm_marks: tuple[int, int] | None = None
        self._closed = asyncio.Event()

    @property
    def subscribers(self) -> int:
        """Open event streams."""
        return len(self._subscribers)

    def close(self) -> None:
        """End every stream and the poller."""
        self._closed.set()
        for subscriber in self._subscribers:
            subscriber.dropped = True
            if subscriber.queue.full():
                subscriber.queue.get_nowait()
            subscriber.queue.put_nowait(None)

    async def run(self) -> None:
        """Poll until :meth:`close` (run as a task beside the server)."""
        while not self._closed.is_set():
            try:
                await self.poll()
            except Exception:  # a failed poll (e.g. the database closing) must not end the feed
                LOG.exception("live feed: poll failed")
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._closed.wait(), self.poll_s)

    async def poll(self) -> None:
        """One look at the historian: publish the samples and alarms that are new since the
        last look (the first look only takes note of where things stand)."""
        times = await asyncio.to_thread(self.reader.live_times)
        marks = await asyncio.to_thread(self.reader.alarm_marks)
        first = self._last is None
        last = self._last if self._last is not None else {}
        self._last = dict(times)
        previous_marks, self._alarm_marks = self._alarm_marks, marks
        if first or not self._subscribers:
            return
        for unit, time in times.items():
            if last.get(unit) == time:
                continue
            samples = await asyncio.to_thread(self.reader.samples_after, unit, last.get(unit),
                                              self.queue_size)
            for sample in samples:
                self._publish(unit, _sample_event(unit, sample), pd.Timestamp(sample["time"]))
        if previous_marks is not None and marks != previous_marks:
            for alarm_id in range(previous_marks[0] + 1, marks[0] + 1):
                alarm = await asyncio.to_thread(self.reader.alarm, alarm_id)
                if alarm is not None:
                    self._publish(alarm["unit"], format_event("alarm", alarm))
            active = await asyncio.to_thread(self.reader.alarms, None, True)
            self._publish(None, format_event("alarms", {"active": active}))

    def _publish(self, unit: str | None, text: str, stamp: pd.Timestamp | None = None) -> None:
        for subscriber in list(self._subscribers):
            if subscriber.unit is not None and unit is not None and subscriber.unit != unit:
                continue
            try:
                subscriber.queue.put_nowait((unit, stamp, text))
            except asyncio.QueueFull:
                self._subscribers.remove(subscriber)
                subscriber.dropped = True

    async def _missed(self, unit: str | None, after: pd.Timestamp
                      ) -> AsyncIterator[tuple[str, pd.Timestamp, str]]:
        """The samples stored after ``after`` (of ``unit``; every unit when None), oldest
        first per unit, as (unit, time, event text)."""
        units = [unit] if unit is not None else sorted(
            await asyncio.to_thread(self.reader.live_times))
        for name in units:
            samples = await asyncio.to_thread(self.reader.samples_after, name, after,
                                              self.backfill)
            for sample in samples:
                yield name, pd.Timestamp(sample["time"]), _sample_event(name, sample)

    async def stream(self, unit: str | None = None, last_event_id: pd.Timestamp | None = None
                     ) -> AsyncIterator[str]:
        """One client's event stream (of ``unit``; every unit when None); with
        ``last_event_id`` (the last sample time the client saw, UTC) it starts with what the
        client missed (module docstring)."""
        subscriber = _Subscriber(unit, asyncio.Queue(maxsize=self.queue_size))
        self._subscribers.append(subscriber)
        sent: dict[str, pd.Timestamp] = {}  # newest sample time sent, per unit
        try:
            yield "retry: 2000\n\n"
            if last_event_id is not None:
                async for name, stamp, text in self._missed(unit, last_event_id):
                    sent[name] = stamp
                    yield text
                active = await asyncio.to_thread(self.reader.alarms, unit, True)
                yield format_event("alarms", {"active": active})
            while not self._closed.is_set():
                if subscriber.dropped and subscriber.queue.empty():
                    yield format_event("dropped", {"reason": "the client fell behind; "
                                                   "reconnect"})
                    return
                try:
                    item = await asyncio.wait_for(subscriber.queue.get(), self.heartbeat_s)
                except TimeoutError:
                    yield ": keep-alive\n\n"
                    continue
                if item is None:
                    return
                name, stamp, text = item
                if stamp is not None and name in sent and stamp <= sent[name]:
                    continue  # already sent from the historian
                yield text
        finally:
            if subscriber in self._subscribers:
                self._subscribers.remove(subscriber)
