"""An OPC UA server that publishes a plant's historian tags live (asyncua).

The live twin reads its unit through OPC UA (IEC 62541), the interface plant DCSs offer; a
twin needs a real endpoint to be developed and tested against. :class:`PlantServer` publishes
a canonical SI frame (e.g. the virtual plant's ``PlantRun.measured``) through its tag map: one
OPC UA variable per mapped signal, node id ``ns=<ns>;s=<tag>`` in the namespace
:data:`NAMESPACE_URI`, the value in the tag's wire unit (``Double``), with

* the sample's **source timestamp** — the data's own (``clock="data"``, a replay of a past
  day) or shifted so that the first sample is the server's start (``clock="now"``, speed 1
  only: later samples would otherwise carry times from the future);
* its **status code**: ``Good``, or ``BadNoCommunication`` where the sample is missing (a
  dropout; OPC UA Part 4, §7.39 status codes) — a missing value is published as missing,
  never filled;
* **HistoryRead** of the recent past (OPC UA Part 11, ReadRawModifiedDetails): the last
  ``history_samples`` published values of each node, kept by asyncua's in-memory history
  storage and saved on every publication (not sampled by a subscription, which could skip
  values at high speed).

Samples go out at ``speed`` × real time from the data's own sample times (``speed=None``:
as fast as the event loop allows). The server runs without security (``NoSecurity``,
anonymous): it is a test plant on loopback by default; the twin's OPC UA *client* is where
the plant's certificates and user tokens are used.
"""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np
import pandas as pd
from asyncua import Server, ua

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap
from steamtwin.progress import ProgressCallback
from steamtwin.units import convert

__all__ = ["NAMESPACE_URI", "PlantServer", "PlantServerSettings", "plant_node_ids"]

NAMESPACE_URI = "urn:steamtwin:virtual-plant"
"""Namespace of the published tags; node ids in a tag map use ``nsu=`` with it."""

CLOCKS = ("data", "now")


@dataclass(frozen=True)
class PlantServerSettings:
    """``host``/``port`` of the endpoint (loopback by default); ``speed``: samples go out at
    this multiple of real time (None: as fast as possible); ``clock``: "data" keeps the
    samples' own timestamps, "now" shifts them to start at the server's start (speed 1);
    ``history_samples``: values per node that HistoryRead can return (the recent past)."""

    host: str = "127.0.0.1"
    port: int = 4840
    speed: float | None = 1.0
    clock: str = "data"
    history_samples: int = 3600

    def __post_init__(self) -> None:
        if not 0 <= self.port <= 65535:
            raise ValueError(f"port must be in 0…65535 (got {self.port!r})")
        if self.speed is not None and not (math.isfinite(self.speed) and self.speed > 0.0):
            raise ValueError(f"speed must be a positive factor of real time or None for as "
                             f"fast as possible (got {self.speed!r})")
        if self.clock not in CLOCKS:
            raise ValueError(f"clock must be one of {CLOCKS} (got {self.clock!r})")
        if self.clock == "now" and self.speed != 1.0:
            raise ValueError("clock 'now' needs speed 1: at any other speed the timestamps "
                             "would leave real time")
        if self.history_samples < 1:
            raise ValueError(f"history_samples must be ≥ 1 (got {self.history_samples!r})")

    @property
    def endpoint(self) -> str:
        """``opc.tcp://host:port/steamtwin/plant/``."""
        return f"opc.tcp://{self.host}:{self.port}/steamtwin/plant/"


def plant_node_ids(tag_map: TagMap) -> TagMap:
    """``tag_map`` with each signal's ``node_id`` set to its node on a :class:`PlantServer`
    (``nsu=<NAMESPACE_URI>;s=<tag>``: independent of the namespace index)."""
    import dataclasses

    signals = {name: dataclasses.replace(spec, node_id=f"nsu={NAMESPACE_URI};s={spec.column}")
               for name, spec in tag_map.signals.items()}
    return dataclasses.replace(tag_map, signals=signals)


class PlantServer:
    """Publish ``signals`` (canonical names, SI, on a time index) through ``tag_map`` over OPC
    UA; use as ``async with PlantServer(...) as server: await server.publish()``.

    Signals the tag map does not cover are refused (ValueError naming them). ``published``
    counts the samples sent so far; ``progress(fraction, message)``
    (:data:`steamtwin.progress.ProgressCallback`) is called after each sample.
    """

    def __init__(self, signals: pd.DataFrame, tag_map: TagMap,
                 settings: PlantServerSettings = PlantServerSettings(),
                 progress: ProgressCallback | None = None) -> None:
        self.signals = signals
        self.tag_map = tag_map
        self.settings = settings
        self.progress = progress
        self.published = 0
        self._server: Server | None = None
        self._nodes: dict[str, ua.NodeId] = {}

    @property
    def endpoint(self) -> str:
        """The server's endpoint URL."""
        return self.settings.endpoint

    @property
    def node_ids(self) -> dict[str, ua.NodeId]:
        """Signal → node id of its variable (after start)."""
        return dict(self._nodes)

    async def __aenter__(self) -> PlantServer:
        await self.start()
        return self

    async def __aexit__(self, *_exc: object) -> None:
        await self.stop()

    async def start(self) -> None:
        """Build the address space and open the endpoint."""
        frame = self.signals
        if not isinstance(frame.index, pd.DatetimeIndex) or frame.index.tz is None:
            raise ValueError("the signals need a time-zone-aware DatetimeIndex (UTC)")
        unmapped = [name for name in frame.columns if name not in self.tag_map.signals]
        if unmapped:
            raise ValueError(f"signals {unmapped} are not mapped in {self.tag_map.source}")
        server = Server()
        await server.init()
        server.set_endpoint(self.settings.endpoint)
        server.set_server_name("steamtwin virtual plant")
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        index = await server.register_namespace(NAMESPACE_URI)
        unit = await server.nodes.objects.add_object(index, "Unit")
        storage = server.iserver.history_manager.storage
        for name in frame.columns:
            spec = self.tag_map.signals[name]
            node_id = ua.NodeId(spec.column, index)
            variable = await unit.add_variable(node_id, spec.column,
                                               ua.Variant(math.nan, ua.VariantType.Double))
            await variable.add_property(index, "EngineeringUnit", spec.unit)
            await variable.add_property(index, "Signal", name)
            await variable.write_attribute(ua.AttributeIds.Historizing,
                                         ua.DataValue(ua.Variant(True, ua.VariantType.Boolean)))
            for attribute in (ua.AttributeIds.AccessLevel, ua.AttributeIds.UserAccessLevel):
                await variable.set_attr_bit(attribute, ua.AccessLevel.HistoryRead)
            await server.write_attribute_value(node_id, ua.DataValue(
                Value=ua.Variant(math.nan, ua.VariantType.Double),
                StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData)))
            await storage.new_historized_node(node_id, None, self.settings.history_samples)
            self._nodes[name] = node_id
        await server.start()
        self._server = server

    async def stop(self) -> None:
        """Close the endpoint (idempotent)."""
        if self._server is not None:
            server, self._server = self._server, None
            await server.stop()

    async def wait_for_subscribers(self, monitored_items: int, timeout_s: float = 60.0) -> None:
        """Return once a client has subscribed to at least ``monitored_items`` of the tags
        (TimeoutError after ``timeout_s`` of wall time): what is published before a client
        subscribes reaches it only through HistoryRead."""
        if self._server is None:
            raise RuntimeError("start the server first (async with PlantServer(...))")
        service = self._server.iserver.subscription_service
        deadline = asyncio.get_running_loop().time() + timeout_s
        while sum(len(s.monitored_item_srv._monitored_items)  # asyncua exposes no count
                  for s in list(service.subscriptions.values())) < monitored_items:
            if asyncio.get_running_loop().time() > deadline:
                raise TimeoutError(f"no client subscribed to {monitored_items} tags within "
                                   f"{timeout_s:g} s")
            await asyncio.sleep(0.05)

    async def publish(self, samples: int | None = None) -> int:
        """Send the next ``samples`` samples (None: all that are left) at the set speed; return
        how many were sent. Values in the tags' wire units; see the module docstring."""
        if self._server is None:
            raise RuntimeError("start the server first (async with PlantServer(...))")
        frame = self.signals
        total = len(frame)
        stop = total if samples is None else min(total, self.published + samples)
        wire = {name: convert(frame[name].to_numpy(dtype=float), SIGNALS[name].si_unit,
                              self.tag_map.signals[name].unit) for name in frame.columns}
        times = frame.index
        offset = pd.Timedelta(0)
        if self.settings.clock == "now":
            offset = pd.Timestamp.now(tz="UTC") - times[0]
        seconds = (times - times[0]).total_seconds().to_numpy(dtype=float)
        wall_start = time.monotonic() - (seconds[self.published] / self.settings.speed
                                         if self.settings.speed else 0.0)
        storage = self._server.iserver.history_manager.storage
        sent = 0
        for k in range(self.published, stop):
            if self.settings.speed is not None:
                delay = wall_start + seconds[k] / self.settings.speed - time.monotonic()
                if delay > 0.0:
                    await asyncio.sleep(delay)
            elif k % 64 == 0:
                await asyncio.sleep(0)  # let clients in
            stamp = (times[k] + offset).to_pydatetime()
            now = datetime.now(UTC)
            for name, node_id in self._nodes.items():
                value = float(wire[name][k])
                good = bool(np.isfinite(value))
                data_value = ua.DataValue(
                    Value=ua.Variant(value, ua.VariantType.Double),
                    StatusCode=ua.StatusCode(ua.StatusCodes.Good if good
                                              else ua.StatusCodes.BadNoCommunication),
                    SourceTimestamp=stamp, ServerTimestamp=now)
                await self._server.write_attribute_value(node_id, data_value)
                await storage.save_node_value(node_id, data_value)
            self.published = k + 1
            sent += 1
            if self.progress is not None:
                self.progress(self.published / total,
                              f"sample {self.published}/{total}")
        return sent
