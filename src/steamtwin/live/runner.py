"""The live service: every configured unit's :class:`~steamtwin.live.service.LiveTwin` run side
by side on one event loop, sharing one DuckDB historian, until its sources end or it is told
to stop (``steamtwin serve``). Progress and findings go to the ``steamtwin.live`` logger.

Latency (issue 21): each unit's provisional rows go to a :class:`ProvisionalGroup` that stores
those of every unit whose sample came in at the same moment in one transaction, before any of
these units does its final (look-ahead) work; the final work of the units falls in different
seconds (``settle`` phases in :func:`run_service`) and runs on one final-work thread, not on the
event loop: a unit's 60-sample final block (gate over its look-ahead context, FOM, ROM,
residuals, recalibration filter, DuckDB commit: 20–33 ms of CPU, 40–110 ms of wall time under
load, measured in ``bench_live_latency.py --profile``) would otherwise hold the loop and every
other unit's provisional values that arrive meanwhile. (Measured, the staggered phases and the
group commit already put it between arrivals — 0–6 of 900 samples waited on one —
docs/benchmarks.md, "Latency, third pass"; the thread keeps it so with more units or longer
blocks.) The thread gets the CPU while the loop waits on its sockets, and the FOM's numba kernels
(``nogil``) and DuckDB release the GIL for much of it. Per unit nothing changes order: a unit
hands its block to the thread and awaits it before it takes its next samples, so its
provisional and final rows are stored in the order they are without the thread; one thread for
all units keeps the final blocks one at a time, as on the loop. A replay at full speed has no
provisional values and nobody waiting, so its final work stays on the loop (the order of every
unit's commits as before)."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
from collections.abc import Awaitable, Callable, Sequence
from concurrent.futures import Executor, ThreadPoolExecutor
from typing import Any

from steamtwin.calibration.evaluation import dask_client
from steamtwin.calibration.tracking import ParameterTracker, tracking_sigma
from steamtwin.live.config import ServiceConfig, UnitConfig
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian, ProvisionalRows
from steamtwin.live.monitor_file import load_monitor
from steamtwin.live.recalibration import LiveRecalibration, centred_priors
from steamtwin.live.rotor_stream import LiveRotor
from steamtwin.live.sensitivity import SensitivityCache
from steamtwin.live.service import MONITORED, LiveSummary, LiveTwin
from steamtwin.live.sources import OpcUaSecurity, OpcUaSource, ReplaySource, Source
from steamtwin.live.unit_model import unit_model
from steamtwin.rom.romfile import load_rom
from steamtwin.rotor.model import RotorModel

__all__ = ["Companion", "ProvisionalGroup", "build_unit", "run_service", "stop_on_signals"]

LOG = logging.getLogger("steamtwin.live")


def build_unit(unit: UnitConfig, historian: LiveHistorian, scheduler: Any = None
               ) -> tuple[LiveTwin, Source]:
    """The unit's live twin (its FOM read through the tag map's sensors and the params'
    offsets) and its source, resuming after the historian's last committed sample.
    ``scheduler``: the Dask scheduler address or ``distributed.Client`` its recalibration's
    tracker steps run on (None: in this process; :class:`ParameterTracker`)."""
    setup, params = unit_model(unit.turbine, unit.tags, unit.params)
    tag_map, model = setup.tag_map, setup.model
    monitor = None if unit.monitor is None else load_monitor(unit.monitor)
    recalibration = None
    if unit.recalibration is not None:
        tracker = ParameterTracker(model, sigma=tracking_sigma(tag_map),
                                   priors=centred_priors(params),
                                   step_s=unit.recalibration.step_s,
                                   trajectory_rows=round(86_400.0 / unit.recalibration.step_s),
                                   scheduler=scheduler)
        recalibration = LiveRecalibration(tracker, every_s=unit.recalibration.every_s,
                                          settle_steps=unit.recalibration.settle_steps)
    rotor = None
    if unit.rotor == "fit":  # the FEM training runs: 24–38 s of CPU at the default mesh
        LOG.info("%s: fitting the rotor model from the spec (rotor = \"fit\")", unit.name)
        rotor = LiveRotor(RotorModel(setup.spec).fit(params))
    elif unit.rotor is not None:
        rotor = LiveRotor(RotorModel.load(unit.rotor, setup.spec))
    source_config = unit.source
    # a live or paced source gets provisional values (latency); a replay at full speed not
    provisional = source_config.kind != "replay" or source_config.speed is not None
    twin = LiveTwin(unit.name, model, params, StreamGate(gate_options(tag_map)), historian,
                    rom=None if unit.rom is None else load_rom(unit.rom), monitor=monitor,
                    monitored=MONITORED if monitor is None else monitor.sensors,
                    sensitivity=None if monitor is None else SensitivityCache(model,
                                                                              monitor.sensors),
                    recalibration=recalibration, provisional=provisional, rotor=rotor)
    twin.start()
    resume = twin.resume_after()
    if source_config.kind == "replay":
        source: Source = ReplaySource(source_config.path, tag_map, speed=source_config.speed,
                                      block_samples=unit.block_samples, start_after=resume)
    else:
        password = None
        if source_config.password_file is not None:
            password = source_config.password_file.read_text(encoding="utf-8").strip()
        security = OpcUaSecurity(certificate=source_config.certificate,
                                 private_key=source_config.private_key,
                                 user=source_config.user, password=password,
                                 allow_insecure=source_config.allow_insecure)
        source = OpcUaSource(source_config.endpoint, tag_map, security, start_after=resume)
    return twin, source


#: Event-loop rounds the group commit waits before it writes (:class:`ProvisionalGroup`): a
#: data change read from a socket passes through a few tasks (the client's publish loop, the
#: subscription handler, the source's queue) before its unit has rows; a round with nothing to
#: do costs microseconds.
GATHER_ROUNDS = 8


class ProvisionalGroup:
    """Group commit of the units' provisional rows: the rows of every unit whose sample came
    in while the first one's were being computed are stored in one transaction
    (:meth:`LiveHistorian.store_provisional_many`; DeWitt et al., SIGMOD 1984). A unit awaits
    its group's write before it settles, so its final rows never precede its provisional
    ones."""

    def __init__(self, historian: LiveHistorian) -> None:
        self.historian = historian
        self._rows: list[ProvisionalRows] = []
        self._write: asyncio.Task | None = None

    async def store(self, rows: ProvisionalRows | None) -> None:
        """Store ``rows`` with the group's; returns once they are committed."""
        if rows is None:
            await asyncio.sleep(0)  # the other units' turn (a replay source need not yield)
            return
        self._rows.append(rows)
        if self._write is None:
            self._write = asyncio.create_task(self._gather_and_write())
        await asyncio.shield(self._write)

    async def _gather_and_write(self) -> None:
        for _ in range(GATHER_ROUNDS):
            await asyncio.sleep(0)
        batch, self._rows, self._write = self._rows, [], None
        self.historian.store_provisional_many(batch)


async def _run_unit(twin: LiveTwin, source: Source, stop: asyncio.Event,
                    summary: LiveSummary, group: ProvisionalGroup,
                    settle: tuple[int, int] = (1, 1),
                    final_work: Executor | None = None) -> LiveSummary:
    """``group``: where the unit's provisional rows are stored, with other units' of the same
    moment. ``settle``: (first, then) — the final samples judged at once, the first time and
    then (a live unit: its ``block_samples``, the first time at a phase of its own so that the
    units' final work falls in different seconds instead of delaying every unit's provisional
    values in the same one). ``final_work``: where :meth:`LiveTwin.settle` runs (None: on the
    loop); the unit awaits it before its next block."""
    blocks = source.blocks()
    first, then = settle
    loop = asyncio.get_running_loop()
    try:
        async for block in blocks:
            # every unit's provisional values of the moment before anyone's final work
            await group.store(twin.receive_rows(block, summary))
            stored = summary.samples
            if final_work is None:
                twin.settle(summary, first)
            else:
                await loop.run_in_executor(final_work, twin.settle, summary, first)
            if summary.samples > stored:
                first = then
            for finding in block.findings:
                LOG.warning("%s: %s", twin.name, finding.message)
            if stop.is_set():
                break
    finally:
        await blocks.aclose()
    if not stop.is_set():
        twin.finish(summary)  # a finished replay: no more look-ahead to wait for
    LOG.info("%s: %d samples stored (%d without a twin value), %d alarm(s), %d finding(s), "
             "%d parameter swap(s), %d sample(s) with extrapolated ROM probes", twin.name,
             summary.samples, summary.without_twin, summary.alarms, summary.findings,
             summary.swaps, summary.rom_extrapolated)
    return summary


def stop_on_signals() -> asyncio.Event:
    """An event that SIGINT (Ctrl-C) or SIGTERM sets: the clean stop of a service run from the
    command line. Call it inside the running event loop; where the loop takes no signal
    handlers (Windows, a thread other than the main one) only its owner sets the event."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(signum, stop.set)
    return stop


Companion = Callable[[LiveHistorian, asyncio.Event], Awaitable[None]]
"""A task run beside the units on the open historian (e.g. the HTTP service); it must return
soon after the event (set when every unit has stopped) is set."""


async def run_service(config: ServiceConfig, stop: asyncio.Event | None = None,
                      companions: Sequence[Companion] = (),
                      historian: LiveHistorian | None = None, scheduler: Any = None
                      ) -> dict[str, LiveSummary]:
    """Run every unit of ``config`` until its source ends or ``stop`` is set; returns each
    unit's summary. What was committed stays; a restart continues from it. ``companions``
    run on the same loop and historian from before the first unit starts until the last one
    stops (a companion that fails stops the service). ``historian``: the database to use
    instead of ``config.database``'s (e.g. one that records when rows are stored, for the
    latency benchmark). ``scheduler``: a Dask scheduler address (``tcp://host:8786``) or
    ``distributed.Client``: every unit's recalibration steps run on that cluster, through one
    client for the service (None: in this process); an unreachable address is a ValueError
    before any unit starts."""
    stop = stop if stop is not None else asyncio.Event()
    historian = historian if historian is not None else LiveHistorian(
        config.database, memory_limit_mb=config.historian_memory_mb)
    historian.open()
    done = asyncio.Event()
    beside: list[asyncio.Task] = []
    final_work = ThreadPoolExecutor(max_workers=1, thread_name_prefix="steamtwin-final")
    client, own_client = None, False
    try:
        if scheduler is not None:
            client, own_client = dask_client(scheduler)
        beside = [asyncio.create_task(companion(historian, done)) for companion in companions]

        def stop_if_failed(task: asyncio.Task) -> None:
            if not task.cancelled() and task.exception() is not None:
                stop.set()

        for task in beside:
            task.add_done_callback(stop_if_failed)
        built = [build_unit(unit, historian, client) for unit in config.units]
        group = ProvisionalGroup(historian)
        for twin, _ in built:
            resume = twin.resume_after()
            LOG.info("%s: starting%s", twin.name,
                     f" after {resume.isoformat()}" if resume is not None else "")

        async def until_stopped(k: int, twin: LiveTwin, source: Source) -> LiveSummary:
            summary = LiveSummary()  # kept up to date even when the run is cancelled
            size = config.units[k].block_samples
            settle = ((max(1, round(size * (k + 1) / len(built))), size) if twin.provisional
                      else (1, 1))
            task = asyncio.create_task(_run_unit(
                twin, source, stop, summary, group, settle,
                final_work if twin.provisional else None))
            waiter = asyncio.create_task(stop.wait())
            await asyncio.wait({task, waiter}, return_when=asyncio.FIRST_COMPLETED)
            if not task.done():
                if hasattr(source, "close"):
                    source.close()
                task.cancel()
            waiter.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
            return summary

        results = await asyncio.gather(*(until_stopped(k, t, s)
                                         for k, (t, s) in enumerate(built)))
        return {twin.name: result for (twin, _), result in zip(built, results, strict=True)}
    finally:
        final_work.shutdown(wait=True)  # a block cancelled mid-way still commits (or fails)
        done.set()
        outcomes = await asyncio.gather(*beside, return_exceptions=True)
        historian.close()
        if own_client:
            client.close()
        failed = [o for o in outcomes if isinstance(o, Exception)]
        if failed:
            raise failed[0]
