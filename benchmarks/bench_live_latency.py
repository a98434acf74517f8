"""Latency of the live service: OPC UA value write → stored twin sample (issue 21, "What must
hold": ≤ 200 ms at p99 with 10 units at 1 Hz).

Ten virtual-plant OPC UA servers (``live.PlantServer``, one per unit, 127.0.0.1, no security)
run in a child process and publish the same plant run (``deep-peak-50``, seed 0) at 1 Hz with
timestamps on the wall clock; the child records the wall time (``time.time``) at which every
tag of a sample has been written. The service runs in this process exactly as
``steamtwin serve`` does (``live.runner.run_service`` over a 10-unit config, OPC UA sources,
provisional values on) with a historian that records the wall time each sample's rows were
committed: first stored (the provisional row, or the final one when it comes first) and final
(after the gate's 60-s look-ahead). Latency = stored − written, per unit and sample, after a
``--warmup`` of the first samples (connection, first blocks).

Prints p50/p95/p99/max of both latencies, the units per provisional transaction (group commit,
``live.runner.ProvisionalGroup``), the service's CPU seconds (process time) per second of data,
and the load average.

``--profile`` also times every unit's final work (``LiveTwin.settle``: wall and thread CPU per
call that stored samples) and its provisional work (``LiveTwin.receive_rows``), the two halves
whose serial cost on one event loop makes the tail.

Run: python benchmarks/bench_live_latency.py [--units 10] [--seconds 180] [--warmup 10]
[--profile]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import multiprocessing
import os
import socket
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.tagmap import write_tag_map
from steamtwin.live.config import load_config
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.plant_server import PlantServer, PlantServerSettings, plant_node_ids
from steamtwin.live.runner import run_service
from steamtwin.live.service import LiveSummary, LiveTwin


class _Recording(LiveHistorian):
    """The historian, noting when each (unit, sample) was first stored and stored final."""

    def __init__(self, path: Path) -> None:
        super().__init__(path)
        self.first: dict[tuple[str, pd.Timestamp], float] = {}
        self.final: dict[tuple[str, pd.Timestamp], float] = {}
        self.group_sizes: list[int] = []  # units per provisional transaction

    def _note(self, unit: str, frames: Mapping[str, pd.DataFrame], final: bool) -> None:
        now = time.time()
        for stamp in frames["measured"].index:
            self.first.setdefault((unit, stamp), now)
            if final:
                self.final.setdefault((unit, stamp), now)

    def store_provisional_many(self, batch):
        rows = super().store_provisional_many(batch)
        self.group_sizes.append(len(batch))
        for entry in batch:
            self._note(entry.unit, entry.frames, final=False)
        return rows

    def commit_block(self, unit, frames, flags=None, state=None, events=None):
        rows = super().commit_block(unit, frames, flags, state, events)
        self._note(unit, frames, final=True)
        return rows


def _free_ports(count: int) -> list[int]:
    sockets = [socket.socket() for _ in range(count)]
    for probe in sockets:
        probe.bind(("127.0.0.1", 0))
    ports = [probe.getsockname()[1] for probe in sockets]
    for probe in sockets:
        probe.close()
    return ports


def _serve(signals: pd.DataFrame, ports: list[int], seconds: int, out: str, done, release) -> None:
    """The child: one PlantServer per port, publishing from the next whole second on. Sets
    ``done`` when every sample is out and waits for ``release`` (the service stopped) before
    it stops the servers, so no client sees its server vanish."""
    tag_map = plant_node_ids(plant_tag_map())

    async def main() -> None:
        written: dict[str, list] = {str(port): [] for port in ports}
        servers = [PlantServer(signals.iloc[:seconds], tag_map,
                               PlantServerSettings(port=port, speed=1.0)) for port in ports]
        for server in servers:
            await server.start()
        await asyncio.gather(*(s.wait_for_subscribers(signals.shape[1], timeout_s=120.0)
                               for s in servers))
        start = pd.Timestamp(np.ceil(time.time()) + 2.0, unit="s", tz="UTC")
        for server in servers:  # timestamps on the wall clock, from `start` on
            server.signals = server.signals.set_axis(
                start + (server.signals.index - server.signals.index[0]))
        await asyncio.sleep(max(0.0, start.timestamp() - time.time()))

        def recorder(port: int, server: PlantServer):
            def record(_fraction: float, _message: str) -> None:
                written[str(port)].append((server.signals.index[server.published - 1]
                                           .isoformat(), time.time()))
            return record

        for port, server in zip(ports, servers, strict=True):
            server.progress = recorder(port, server)
        await asyncio.gather(*(s.publish() for s in servers))
        await asyncio.sleep(3.0)
        Path(out).write_text(json.dumps(written), encoding="utf-8")
        done.set()
        while not release.is_set():
            await asyncio.sleep(0.2)
        for server in servers:
            await server.stop()

    asyncio.run(main())


def _timed(method, record: list[tuple[float, float, int]],
           spans: list[tuple[float, float]] | None = None):
    """``method`` (LiveTwin.settle or receive_rows) noting (wall s, thread CPU s, samples
    stored) per call, and in ``spans`` the wall-clock (start, end) of the calls that stored
    samples."""
    def timed(self, *args):
        summary = next((a for a in args if isinstance(a, LiveSummary)), None)
        stored = summary.samples if summary is not None else 0
        began, wall, cpu = time.time(), time.perf_counter(), time.thread_time()
        result = method(self, *args)
        record.append((time.perf_counter() - wall, time.thread_time() - cpu,
                       (summary.samples if summary is not None else 0) - stored))
        if spans is not None and record[-1][2] > 0:
            spans.append((began, time.time()))
        return result
    return timed


def _noting_arrival(method, arrived: dict[tuple[str, pd.Timestamp], float]):
    """``LiveTwin.receive_rows`` noting when each (unit, sample) reached the service (the
    source's block handed to the twin): write → arrival is the OPC UA delivery, arrival →
    stored the service's own work and waits."""
    def noting(self, block, *args):
        now = time.time()
        for stamp in block.frame.index:
            arrived.setdefault((self.name, stamp), now)
        return method(self, block, *args)
    return noting


def _profile_line(name: str, record: list[tuple[float, float, int]], storing: bool) -> str:
    calls = np.array([(w, c) for w, c, n in record if (n > 0) == storing] or [(0.0, 0.0)])
    wall, cpu = calls[:, 0] * 1e3, calls[:, 1] * 1e3
    return (f"{name}: {len(calls)} calls, wall p50 {np.median(wall):.1f} / p99 "
            f"{np.percentile(wall, 99):.1f} / max {wall.max():.1f} ms, thread CPU p50 "
            f"{np.median(cpu):.1f} / max {cpu.max():.1f} ms")


def _quantiles(values: np.ndarray) -> str:
    p50, p95, p99 = np.percentile(values, [50, 95, 99]) * 1e3
    return (f"p50 {p50:.0f} ms, p95 {p95:.0f} ms, p99 {p99:.0f} ms, "
            f"max {values.max() * 1e3:.0f} ms (n = {values.size})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--units", type=int, default=10)
    parser.add_argument("--seconds", type=int, default=180, help="samples each server sends")
    parser.add_argument("--warmup", type=int, default=10, help="first samples not counted")
    parser.add_argument("--profile", action="store_true",
                        help="time the units' final and provisional work")
    args = parser.parse_args()
    settles: list[tuple[float, float, int]] = []
    receives: list[tuple[float, float, int]] = []
    spans: list[tuple[float, float]] = []  # wall clock of the final blocks
    arrived: dict[tuple[str, pd.Timestamp], float] = {}
    if args.profile:
        LiveTwin.settle = _timed(LiveTwin.settle, settles, spans)
        LiveTwin.receive_rows = _noting_arrival(_timed(LiveTwin.receive_rows, receives),
                                                arrived)
    signals = run_plant("deep-peak-50", hours=0.05, random_state=0).measured
    ports = _free_ports(args.units)
    with tempfile.TemporaryDirectory() as folder:
        base = Path(folder)
        write_tag_map(plant_node_ids(plant_tag_map()), base / "tags.toml")
        units = "".join(
            f'[[units]]\nname = "unit{k}"\ntags = "tags.toml"\n[units.source]\nkind = "opcua"\n'
            f'endpoint = "opc.tcp://127.0.0.1:{port}/steamtwin/plant/"\n'
            'allow_insecure = true\n' for k, port in enumerate(ports))
        (base / "service.toml").write_text(f'database = "live.duckdb"\n{units}',
                                           encoding="utf-8")
        config = load_config(base / "service.toml")
        written_file = base / "written.json"
        context = multiprocessing.get_context("spawn")
        done, release = context.Event(), context.Event()
        child = context.Process(
            target=_serve, args=(signals, ports, args.seconds, str(written_file), done, release))
        child.start()
        historian = _Recording(base / "live.duckdb")

        async def service() -> float:
            stop = asyncio.Event()
            cpu = time.process_time()
            task = asyncio.create_task(run_service(config, stop, historian=historian))
            while child.is_alive() and not done.is_set():
                await asyncio.sleep(0.5)
            await asyncio.sleep(2.0)
            stop.set()
            await task
            release.set()
            return time.process_time() - cpu

        cpu = asyncio.run(service())
        child.join()
        written = json.loads(written_file.read_text(encoding="utf-8"))
    first, final, during, delivery, work = [], [], [], [], []
    for k, port in enumerate(ports):
        for stamp, at in written[str(port)][args.warmup:]:
            key = (f"unit{k}", pd.Timestamp(stamp))
            if key in historian.first:
                first.append(historian.first[key] - at)
                during.append(any(start < historian.first[key] and end > at
                                  for start, end in spans))
                if key in arrived:
                    delivery.append(arrived[key] - at)
                    work.append(historian.first[key] - arrived[key])
            if key in historian.final:
                final.append(historian.final[key] - at)
    sent = sum(len(v) - args.warmup for v in written.values())
    print(f"{args.units} units × {args.seconds} samples at 1 Hz; {sent} samples counted, "
          f"{len(first)} stored, {len(final)} stored final")
    print(f"write → first stored (provisional): {_quantiles(np.array(first))}")
    if final:
        print(f"write → final row (after the gate's look-ahead): {_quantiles(np.array(final))}")
    if historian.group_sizes:
        print(f"provisional transactions: {len(historian.group_sizes)}, "
              f"{np.mean(historian.group_sizes):.1f} units each on average")
    print(f"service CPU {cpu:.1f} s for {args.seconds} s of data "
          f"({cpu / args.seconds * 100:.0f} % of a core); load average "
          f"{os.getloadavg()[0]:.1f}")
    if args.profile:
        print(_profile_line("final work (settle) storing samples", settles, True))
        print(_profile_line("provisional work (receive_rows)", receives, False))
        if delivery:
            print(f"write → arrival at the service (OPC UA delivery): "
                  f"{_quantiles(np.array(delivery))}")
            print(f"arrival → first stored (the service): {_quantiles(np.array(work))}")
        overlapped = np.array(during, dtype=bool)
        for name, chosen in (("overlapping a final block", overlapped),
                             ("overlapping none", ~overlapped)):
            if chosen.any():
                print(f"write → first stored, samples {name}: "
                      f"{_quantiles(np.array(first)[chosen])}")


if __name__ == "__main__":
    main()
