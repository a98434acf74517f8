"""Where the live twin's samples come from, behind one small protocol (issue 21, item 2).

A source yields :class:`SourceBlock` s: consecutive samples as a canonical SI frame on a UTC
time index (NaN where a value is missing or its status is not good), a per-sample ``bad``
mask (the status said so) and the :class:`SourceFinding` s met on the way — an unknown node
id, a value that is not a number, a timestamp going backwards or from the future, a unit
that differs from the tag map's. A finding names the tag and time; the source goes on.

* :class:`ReplaySource` plays a historian file (any layout the readers accept) at ``speed`` ×
  real time, or as fast as possible (``speed=None``).
* :class:`OpcUaSource` subscribes to the tag map's ``node_id`` s on an OPC UA server (asyncua):
  data changes with their source timestamps, grouped into samples on a grid of
  ``resolution_s`` (a sample is passed on once every tag is in, or ``settle_s`` seconds of
  wall time after its first value arrived); on (re)connection it reads the missed span
  back with HistoryRead where the server keeps it and reports the rest as a gap — never
  invented. Security:
  Basic256Sha256 / SignAndEncrypt with the client's certificate and key, and user/password;
  no security and anonymous only when ``allow_insecure`` says so.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np
import pandas as pd
from asyncua import Client, ua

from steamtwin.dcs.readers import read_historian
from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap
from steamtwin.live.nodes import resolve_node_id
from steamtwin.units import convert

__all__ = ["OpcUaSecurity", "OpcUaSource", "ReplaySource", "Source", "SourceBlock",
           "SourceFinding"]

#: Timestamps further ahead of the receiving clock than this are "from the future" (s):
#: a generous allowance for unsynchronised DCS clocks (IEC 61850-5 class T1 is 1 ms; a plant
#: without time sync drifts by seconds per day).
FUTURE_TOLERANCE_S = 5.0
#: InfoType "DataValue" (bit 10) with the Overflow bit (bit 7) of an OPC UA StatusCode: the
#: server's queue for the monitored item overflowed and values were lost (OPC UA Part 4,
#: §7.39, Table 180).
OVERFLOW_BITS = 0x480
#: Values the server may queue per monitored item between two publishes: a burst of a few
#: hours of 1-s samples (a server flushing a buffer after a network outage) fits; what does not
#: is reported through OVERFLOW_BITS by a server that sets them.
QUEUE_SIZE = 100_000
#: The subscription's requested publishing interval (ms): how long the server gathers data
#: changes before it sends them (OPC UA Part 4, §5.13.2), the floor of the source's latency
#: (on average half of it). 20 ms keeps a 1-Hz sample's delivery well inside issue 21's 200-ms
#: budget; a server that cannot publish that fast revises it to its fastest (Part 4, §5.13.2:
#: asyncua's server grants what is asked), at the cost of 50 mostly empty publish cycles a
#: second on the server (measured, docs/benchmarks.md).
PUBLISHING_INTERVAL_MS = 20.0
#: Longest silence (s) before the server sends a keep-alive message on the subscription (the
#: source checks the connection itself after 0.5 s without data; this only bounds the server's
#: idle traffic).
KEEP_ALIVE_S = 5.0
#: Interval (s) of asyncua's liveness probe of the server, which is also the probe's timeout
#: (asyncua takes the smaller of it and half the session timeout): a dead but open connection
#: is found within twice this; a server or client loop busy for less than this (the client
#: decoding a burst of 10 000 values while a probe waits) is not taken for a lost server.
#: asyncua's default of 1 s dropped the connection mid-burst on a loaded CI machine; against a
#: server without history the values written while reconnecting are then a gap.
WATCHDOG_S = 5.0
_ARRIVED = "__arrived__"  # key of a pending sample's first arrival (monotonic s)


@dataclass(frozen=True)
class SourceFinding:
    """Something a source met and did not pass on as data: ``kind`` (e.g. "unknown_node",
    "not_a_number", "backwards", "future", "unit_mismatch", "gap", "disconnected",
    "crowded" (several values on one sample time: a burst), "overflow"), the
    signal and its tag, the time it concerns and a sentence saying what happened."""

    kind: str
    signal: str | None
    tag: str | None
    time: pd.Timestamp | None
    message: str


@dataclass
class SourceBlock:
    """Consecutive samples: ``frame`` (UTC index, canonical SI columns, NaN where missing or
    bad), ``bad`` (True where the source's status excluded the value) and ``findings``."""

    frame: pd.DataFrame
    bad: pd.DataFrame
    findings: list[SourceFinding] = field(default_factory=list)


class Source(Protocol):
    """A stream of :class:`SourceBlock` s, oldest first."""

    def blocks(self) -> AsyncIterator[SourceBlock]:
        """Yield the next blocks until the source ends (a replay) or is closed."""
        ...


class ReplaySource:
    """Play ``path`` (CSV/Parquet, read through ``tag_map``) ``block_samples`` samples at a
    time at ``speed`` × real time (None: as fast as possible), from after ``start_after``
    (UTC; a restart resumes there)."""

    def __init__(self, path: str | Path, tag_map: TagMap, speed: float | None = None,
                 block_samples: int = 60, start_after: pd.Timestamp | None = None) -> None:
        if speed is not None and not (math.isfinite(speed) and speed > 0.0):
            raise ValueError(f"speed must be a positive factor of real time or None (got "
                             f"{speed!r})")
        if block_samples < 1:
            raise ValueError(f"block_samples must be ≥ 1 (got {block_samples!r})")
        self.path, self.tag_map = Path(path), tag_map
        self.speed, self.block_samples, self.start_after = speed, block_samples, start_after

    async def blocks(self) -> AsyncIterator[SourceBlock]:
        """The file's samples in blocks, paced by ``speed``."""
        data = read_historian(self.path, self.tag_map)
        frame = data.signals.sort_index(kind="stable")
        bad = pd.DataFrame({name: data.bad_quality.get(name, np.zeros(len(data.signals),
                                                                       bool))
                            for name in data.signals.columns}, index=data.signals.index)
        bad = bad.loc[frame.index]
        if self.start_after is not None:
            keep = frame.index > self.start_after
            frame, bad = frame[keep], bad[keep]
        if frame.empty:
            return
        seconds = (frame.index - frame.index[0]).total_seconds().to_numpy(dtype=float)
        wall_start = time.monotonic()
        for start in range(0, len(frame), self.block_samples):
            stop = min(start + self.block_samples, len(frame))
            delay = 0.0  # behind the pace or at full speed: still yield to the loop's others
            if self.speed is not None:
                delay = max(0.0, wall_start + seconds[stop - 1] / self.speed - time.monotonic())
            await asyncio.sleep(delay)
            chunk, chunk_bad = frame.iloc[start:stop], bad.iloc[start:stop]
            yield SourceBlock(chunk.where(~chunk_bad.to_numpy()), chunk_bad)


@dataclass(frozen=True)
class OpcUaSecurity:
    """How the client authenticates: ``certificate``/``private_key`` (PEM or DER files) for
    Basic256Sha256 / SignAndEncrypt (``server_certificate`` optional, to pin the server's),
    ``user``/``password`` for a user token; ``allow_insecure`` must be True to connect
    without security, anonymously (a test plant on loopback)."""

    certificate: Path | None = None
    private_key: Path | None = None
    server_certificate: Path | None = None
    user: str | None = None
    password: str | None = None
    allow_insecure: bool = False

    def __post_init__(self) -> None:
        if (self.certificate is None) != (self.private_key is None):
            raise ValueError("certificate and private_key go together")
        if self.certificate is None and not self.allow_insecure:
            raise ValueError("no client certificate: give certificate and private_key for "
                             "Basic256Sha256/SignAndEncrypt, or allow_insecure=True to connect "
                             "without security (only to a test plant)")
        if (self.user is None) != (self.password is None):
            raise ValueError("user and password go together")

    async def apply(self, client: Client) -> None:
        """Configure ``client`` (before connecting)."""
        if self.certificate is not None:
            parts = ["Basic256Sha256", "SignAndEncrypt", str(self.certificate),
                     str(self.private_key)]
            if self.server_certificate is not None:
                parts.append(str(self.server_certificate))
            await client.set_security_string(",".join(parts))
        if self.user is not None:
            client.set_user(self.user)
            client.set_password(self.password or "")


class _Collector:
    """asyncua subscription handler: data changes into a queue, in arrival order."""

    def __init__(self, queue: asyncio.Queue, signals: dict[object, str]) -> None:
        self.queue, self.signals = queue, signals

    def datachange_notification(self, node, value, data) -> None:  # asyncua's callback name
        self.queue.put_nowait((self.signals.get(node.nodeid), data.monitored_item.Value))

    def status_change_notification(self, status) -> None:  # asyncua's callback name
        self.queue.put_nowait((None, status))


class OpcUaSource:
    """Samples from an OPC UA server (see the module docstring). ``endpoint``: the server's
    URL; ``tag_map``: each signal's ``node_id`` and wire unit; ``resolution_s``: the sample
    grid the source timestamps are rounded to; ``settle_s``: how long (s of wall time) a
    sample stays open for late tags; ``start_after``: resume after this time (HistoryRead back to
    it on connection); ``reconnect_s``: wait between connection attempts;
    ``publishing_interval_ms``: the subscription's requested publishing interval (ms, see
    :data:`PUBLISHING_INTERVAL_MS`)."""

    def __init__(self, endpoint: str, tag_map: TagMap, security: OpcUaSecurity,
                 resolution_s: float = 1.0, settle_s: float = 2.0,
                 start_after: pd.Timestamp | None = None, reconnect_s: float = 1.0,
                 history_limit: int = 10_000, timeout_s: float = 10.0,
                 publishing_interval_ms: float = PUBLISHING_INTERVAL_MS) -> None:
        missing = [name for name, spec in tag_map.signals.items() if spec.node_id is None]
        if missing:
            raise ValueError(f"{tag_map.source}: signals {missing} have no node_id; the OPC UA "
                             "source needs one per signal")
        if not resolution_s > 0.0:
            raise ValueError(f"resolution_s must be positive (got {resolution_s!r})")
        if not publishing_interval_ms > 0.0:
            raise ValueError("publishing_interval_ms must be positive (ms; got "
                             f"{publishing_interval_ms!r})")
        self.endpoint, self.tag_map, self.security = endpoint, tag_map, security
        self.resolution_s, self.settle_s = resolution_s, settle_s
        self.start_after, self.reconnect_s = start_after, reconnect_s
        self.history_limit, self.timeout_s = history_limit, timeout_s
        self.publishing_interval_ms = publishing_interval_ms
        self._closed = asyncio.Event()
        self.connections = 0

    def close(self) -> None:
        """Stop after the current block."""
        self._closed.set()

    async def blocks(self) -> AsyncIterator[SourceBlock]:
        """Blocks of complete samples as they settle, across reconnections, until closed."""
        last_emitted = self.start_after
        pending: dict[pd.Timestamp, dict[str, tuple[float, bool]]] = {}
        latest_per_signal: dict[str, pd.Timestamp] = {}
        while not self._closed.is_set():
            findings: list[SourceFinding] = []
            client = Client(url=self.endpoint, timeout=self.timeout_s,
                            watchdog_intervall=WATCHDOG_S)
            await self.security.apply(client)
            try:
                await client.connect()
            except (TimeoutError, OSError, ua.UaError) as error:
                yield SourceBlock(*_empty(self.tag_map), [SourceFinding(
                    "disconnected", None, None, None,
                    f"cannot connect to {self.endpoint}: {error}; retrying in "
                    f"{self.reconnect_s:g} s")])
                await self._wait(self.reconnect_s)
                continue
            self.connections += 1
            try:
                nodes, unit_findings = await self._nodes(client)
                findings += unit_findings
                queue: asyncio.Queue = asyncio.Queue()
                signal_of = {node.nodeid: name for name, node in nodes.items()}
                subscription = await client.create_subscription(
                    self._subscription_parameters(), _Collector(queue, signal_of))
                # every new source timestamp is a sample, even when value and status repeat
                # (a quantised reading): trigger StatusValueTimestamp (OPC UA Part 4, §7.22.2);
                # asyncua's subscribe_data_change takes no filter, its _subscribe does
                await subscription._subscribe(
                    list(nodes.values()), ua.AttributeIds.Value,
                    mfilter=ua.DataChangeFilter(
                        Trigger=ua.DataChangeTrigger.StatusValueTimestamp),
                    queuesize=QUEUE_SIZE, sampling_interval=0)
                if last_emitted is not None:  # back-fill what was missed
                    for name, node in nodes.items():
                        history = await node.read_raw_history(
                            last_emitted.to_pydatetime() + pd.Timedelta(microseconds=1),
                            None, self.history_limit)
                        for value in history:
                            self._accept(name, value, pending, latest_per_signal, last_emitted,
                                         findings, backfill=True)
                while not self._closed.is_set() or not queue.empty():
                    try:
                        name, value = await asyncio.wait_for(queue.get(), timeout=0.5)
                    except TimeoutError:
                        await client.check_connection()
                        name = value = None
                    # take everything already delivered before judging what has settled:
                    # the consumer may have kept the loop busy while notifications queued up
                    arrived = [(name, value)]
                    while not queue.empty():
                        arrived.append(queue.get_nowait())
                    crowded: dict[str, list] = {}
                    for name, value in arrived:
                        if isinstance(value, ua.DataValue) and name is not None:
                            self._accept(name, value, pending, latest_per_signal,
                                         last_emitted, findings, crowded=crowded)
                        elif value is not None and not isinstance(value, ua.DataValue):
                            raise ConnectionError(f"subscription status {value}")
                    findings += self._crowded_findings(crowded)
                    block = self._settled(pending, latest_per_signal, findings)
                    if block is not None:
                        if len(block.frame):
                            self._note_gap(last_emitted, block)
                            last_emitted = block.frame.index[-1]
                        findings = []
                        yield block
            except (TimeoutError, OSError, ConnectionError, ua.UaError) as error:
                findings.append(SourceFinding(
                    "disconnected", None, None, last_emitted,
                    f"lost {self.endpoint} after {last_emitted}: {error}; reconnecting and "
                    "reading the gap back by HistoryRead"))
                yield SourceBlock(*_empty(self.tag_map), findings)
                await self._wait(self.reconnect_s)
            finally:
                with contextlib.suppress(Exception):
                    await client.disconnect()
        block = self._settled(pending, latest_per_signal, [], flush=True)
        if block is not None:
            yield block

    def _subscription_parameters(self) -> ua.CreateSubscriptionParameters:
        """The subscription asked for: ``publishing_interval_ms``, a keep-alive message after
        :data:`KEEP_ALIVE_S` without data and a lifetime of asyncua's default 10 000 intervals
        (≥ 3 keep-alives, OPC UA Part 4, §5.13.2) — asked for in counts of intervals that the
        server need not revise (asyncua's own choice at 20 ms exceeds its server's cap)."""
        interval = self.publishing_interval_ms
        keep_alive = max(1, math.ceil(KEEP_ALIVE_S * 1e3 / interval))
        return ua.CreateSubscriptionParameters(
            RequestedPublishingInterval=interval, RequestedLifetimeCount=max(10_000,
                                                                             3 * keep_alive),
            RequestedMaxKeepAliveCount=keep_alive, MaxNotificationsPerPublish=10_000,
            PublishingEnabled=True, Priority=0)

    def _note_gap(self, last: pd.Timestamp | None, block: SourceBlock) -> None:
        """A finding for samples that never arrived between ``last`` and the block."""
        if last is None:
            return
        missing = (block.frame.index[0] - last).total_seconds() / self.resolution_s - 1.0
        if missing >= 0.5:
            block.findings.append(SourceFinding(
                "gap", None, None, last,
                f"no sample from {last} to {block.frame.index[0]} ({round(missing)} missing): "
                "neither the subscription nor the server's history had them; left as a gap"))

    async def _wait(self, seconds: float) -> None:
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(self._closed.wait(), timeout=seconds)

    async def _nodes(self, client: Client) -> tuple[dict[str, object], list[SourceFinding]]:
        nodes, findings = {}, []
        for name, spec in self.tag_map.signals.items():
            try:
                node = client.get_node(await resolve_node_id(client, spec.node_id))
                await node.read_browse_name()
            except (ValueError, ua.UaError) as error:
                findings.append(SourceFinding(
                    "unknown_node", name, spec.column, None,
                    f"{name} ({spec.column}): node {spec.node_id!r} not found on "
                    f"{self.endpoint} ({error}); the signal stays empty"))
                continue
            nodes[name] = node
            try:
                unit_node = await node.get_child(f"{node.nodeid.NamespaceIndex}:EngineeringUnit")
                served = str(await unit_node.read_value())
            except ua.UaError:
                served = None
            if served is not None and served != spec.unit:
                findings.append(SourceFinding(
                    "unit_mismatch", name, spec.column, None,
                    f"{name} ({spec.column}): the server says its unit is {served!r}, the tag "
                    f"map {spec.unit!r}; values are read in the tag map's unit"))
        return nodes, findings

    def _crowded_findings(self, crowded: dict[str, list]) -> list[SourceFinding]:
        """One finding per signal whose values fell on sample times already taken."""
        found = []
        for name, (count, first, last) in crowded.items():
            spec = self.tag_map.signals[name]
            found.append(SourceFinding(
                "crowded", name, spec.column, first,
                f"{name} ({spec.column}): {count} value(s) from {first} to {last} fell on "
                f"sample times already taken (grid {self.resolution_s:g} s): a burst faster "
                "than the grid; the last value of each sample time was kept"))
        return found

    def _accept(self, name: str, value: ua.DataValue, pending: dict, latest: dict,
                last_emitted: pd.Timestamp | None, findings: list[SourceFinding],
                backfill: bool = False, crowded: dict[str, list] | None = None) -> None:
        spec = self.tag_map.signals[name]
        if value.StatusCode is not None and value.StatusCode.value == \
                ua.StatusCodes.BadWaitingForInitialData:
            return  # no value yet (OPC UA Part 4, §7.39): not a sample
        stamp_raw = value.SourceTimestamp or value.ServerTimestamp
        if stamp_raw is None:
            findings.append(SourceFinding("no_timestamp", name, spec.column, None,
                                          f"{name} ({spec.column}): a value without a "
                                          "timestamp was left out"))
            return
        stamp = pd.Timestamp(stamp_raw)
        stamp = stamp.tz_localize("UTC") if stamp.tzinfo is None else stamp.tz_convert("UTC")
        stamp = stamp.round(pd.Timedelta(seconds=self.resolution_s))
        if stamp > pd.Timestamp.now(tz="UTC") + pd.Timedelta(seconds=FUTURE_TOLERANCE_S):
            findings.append(SourceFinding("future", name, spec.column, stamp,
                                          f"{name} ({spec.column}): timestamp {stamp} lies in "
                                          "the future; the value was left out"))
            return
        if (last_emitted is not None and stamp <= last_emitted) or (
                name in latest and stamp < latest[name]):
            if not backfill:
                findings.append(SourceFinding("backwards", name, spec.column, stamp,
                                              f"{name} ({spec.column}): timestamp {stamp} goes "
                                              "back before samples already taken; left out"))
            return
        raw = value.Value.Value if value.Value is not None else None
        if isinstance(raw, bool) or not isinstance(raw, int | float | np.number):
            findings.append(SourceFinding("not_a_number", name, spec.column, stamp,
                                          f"{name} ({spec.column}): value {raw!r} at {stamp} "
                                          "is not a number; left empty"))
            number, good = math.nan, False
        else:
            number = float(convert(np.array([float(raw)]), spec.unit,
                                   SIGNALS[name].si_unit)[0])
            good = value.StatusCode is None or value.StatusCode.is_good()
            if not math.isfinite(number):
                good = False
        if value.StatusCode is not None and (
                value.StatusCode.value & OVERFLOW_BITS) == OVERFLOW_BITS:
            findings.append(SourceFinding("overflow", name, spec.column, stamp,
                                          f"{name} ({spec.column}): the server's queue "
                                          f"overflowed before {stamp}; values were lost there"))
        latest[name] = stamp
        row = pending.setdefault(stamp, {_ARRIVED: time.monotonic()})
        if name in row and crowded is not None:
            count, first, _ = crowded.get(name, (0, stamp, stamp))
            crowded[name] = [count + 1, first, stamp]
        row[name] = (number, good)

    def _settled(self, pending: dict, latest: dict, findings: list[SourceFinding],
                 flush: bool = False) -> SourceBlock | None:
        """The oldest samples that are complete (every tag in) or have waited ``settle_s``
        since their first value arrived, in time order up to the first that is neither (an
        OPC UA publish response may carry one tag's queue before another's)."""
        names = list(self.tag_map.signals)
        now = time.monotonic()
        ready = []
        for stamp in sorted(pending):
            row = pending[stamp]
            if flush or len(row) - 1 == len(names) or now - row[_ARRIVED] >= self.settle_s:
                ready.append(stamp)
            else:
                break
        if not ready:
            return None if not findings else SourceBlock(*_empty(self.tag_map), findings)
        values = np.full((len(ready), len(names)), np.nan)
        bad = np.zeros((len(ready), len(names)), dtype=bool)
        for i, stamp in enumerate(ready):
            row = pending.pop(stamp)
            for j, name in enumerate(names):
                if name in row:
                    number, good = row[name]
                    values[i, j] = number if good else np.nan
                    bad[i, j] = not good
        index = pd.DatetimeIndex(ready, name="time")
        return SourceBlock(pd.DataFrame(values, index=index, columns=names),
                           pd.DataFrame(bad, index=index, columns=names), findings)


def _empty(tag_map: TagMap) -> tuple[pd.DataFrame, pd.DataFrame]:
    index = pd.DatetimeIndex([], tz="UTC", name="time")
    names: Sequence[str] = list(tag_map.signals)
    return (pd.DataFrame(columns=names, index=index, dtype=float),
            pd.DataFrame(columns=names, index=index, dtype=bool))
