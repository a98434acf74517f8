"""The live service end to end on a replayed day (issue 21, "What must hold": ≥ 1 000× real
time for gate + FOM + ROM + residuals + DuckDB on one core, memory flat from hour 1 to 24).

The virtual plant's 24-h ``day`` (seed 0, 1-s samples) is written as a Parquet historian and
replayed at ``--speed max`` (``live.ReplaySource``, ``--block`` samples a block, default 60)
through one
``live.LiveTwin`` with everything on: the streaming gate, the streamed FOM read through the
typical thermocouple lags, the blade ROM's probe temperatures (hp1, built here on a coarse mesh
at the design coefficients), residuals with the monitor fitted on a healthy day (``day`` seed
100, same instruments; ``live.monitor_file.fit_monitor``) and J per load band, the online
recalibration filter (10-min tracker steps; swaps on schedule or alarm), and the DuckDB
historian. Run it pinned to one core (``taskset -c 0``) for the one-core figure.

Prints CPU seconds (process time, every thread) and wall seconds for the day and their
multiples of real time, the resident memory (``/proc/self/statm``) at every block — per data
hour its median and maximum, and their growth from hour 1 to the last whole hour — DuckDB's own
memory at the end, and what the database holds.

Run: taskset -c 0 python benchmarks/bench_live_service.py [--cache DIR] [--hours 24] [--block 60]
     [--historian-memory-mb 64]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from collections.abc import AsyncIterator
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.calibration.tracking import ParameterTracker, tracking_sigma
from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.live.config import SERVICE_MEMORY_LIMIT_MB
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.monitor_file import fit_monitor
from steamtwin.live.recalibration import LiveRecalibration
from steamtwin.live.sensitivity import SensitivityCache
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource, SourceBlock
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.rom.build import build_rom
from steamtwin.spec import load_spec

PAGE = os.sysconf("SC_PAGE_SIZE")


def _rss_mb() -> float:
    with open("/proc/self/statm", encoding="ascii") as statm:
        return int(statm.read().split()[1]) * PAGE / 1e6


class _Metered:
    """The replay source, recording the resident memory at every block, by data hour (the
    hour the block ends in; one reading is one instant of an allocator that keeps freed
    memory for a while, so each hour's median and maximum are reported)."""

    def __init__(self, source: ReplaySource) -> None:
        self.source = source
        self.rss: dict[int, list[float]] = {}
        self.start: pd.Timestamp | None = None

    async def blocks(self) -> AsyncIterator[SourceBlock]:
        async for block in self.source.blocks():
            if len(block.frame):
                self.start = self.start if self.start is not None else block.frame.index[0]
                hour = int((block.frame.index[-1] - self.start) / pd.Timedelta(hours=1))
                self.rss.setdefault(hour, []).append(_rss_mb())
            yield block


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "live-service-cache")
    parser.add_argument("--hours", type=float, default=None, help="default: the whole day")
    parser.add_argument("--block", type=int, default=60,
                        help="samples per source block (the service's block_samples)")
    parser.add_argument("--historian-memory-mb", type=float, default=SERVICE_MEMORY_LIMIT_MB,
                        help="DuckDB's memory limit (the service's historian_memory_mb)")
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    spec = load_spec("reference")
    model = FullOrderModel(spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    params = ModelParameters()
    paths = {"historian": args.cache / "historian.parquet", "tag_map": args.cache / "tags.toml"}
    if not paths["historian"].exists():
        run = run_plant("day", random_state=0, hours=args.hours)
        write_plant(run, args.cache, file_format="parquet")
        healthy = run_plant("day", random_state=100, instruments=run.injected.sensors)
        healthy.measured.to_parquet(args.cache / "healthy.parquet")
        run.injected.sensors.to_parquet(args.cache / "instruments.parquet")
    instruments = pd.read_parquet(args.cache / "instruments.parquet")
    tag_map = plant_tag_map()
    clock = time.perf_counter()
    gate = StreamGate(gate_options(tag_map, instruments))
    healthy = pd.read_parquet(args.cache / "healthy.parquet")
    parts = [gate.push(healthy.iloc[i:i + 3600]).data for i in range(0, len(healthy), 3600)]
    cleaned = pd.concat([p for p in [*parts, gate.flush().data] if len(p)])
    monitor = fit_monitor(model, params, cleaned, tag_map, source="healthy day")
    mesh = blade_volume_mesh(spec, "hp1", element_size=0.01)
    rom, _ = build_rom(spec, mesh, params, n_snapshots=16, max_workers=1)
    print(f"setup (monitor fit, ROM build): {time.perf_counter() - clock:.0f} s; ROM probes "
          f"{list(rom.probes)}")

    with tempfile.TemporaryDirectory() as folder:
        tracker = ParameterTracker(model, sigma=tracking_sigma(tag_map), step_s=600.0)
        twin = LiveTwin("unit1", model, params, StreamGate(gate_options(tag_map, instruments)),
                        LiveHistorian(Path(folder) / "live.duckdb",
                                      memory_limit_mb=args.historian_memory_mb),
                        rom=rom, monitor=monitor,
                        monitored=monitor.sensors,
                        sensitivity=SensitivityCache(model, monitor.sensors),
                        recalibration=LiveRecalibration(tracker))
        source = _Metered(ReplaySource(paths["historian"], tag_map, speed=None,
                                       block_samples=args.block))
        cpu, wall = time.process_time(), time.perf_counter()
        summary = asyncio.run(twin.run(source))
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        size = (Path(folder) / "live.duckdb").stat().st_size / 1e6
        duckdb_mb = twin.historian.connection.execute(
            "SELECT sum(memory_usage_bytes) FROM duckdb_memory()").fetchone()[0] / 1e6
        alarms = twin.historian.alarms("unit1")
        twin.close()
    seconds = summary.samples  # 1-s samples
    print(f"{summary.samples} samples ({seconds / 3600:.1f} h of data), {summary.rows} rows, "
          f"{summary.alarms} alarm(s), {summary.swaps} swap(s), {summary.findings} finding(s), "
          f"database {size:.0f} MB")
    print(f"CPU {cpu:.1f} s → {seconds / cpu:.0f}× real time; wall {wall:.1f} s → "
          f"{seconds / wall:.0f}× real time")
    hours = [h for h in sorted(source.rss) if len(source.rss[h]) > 1]  # whole hours
    median = {h: float(np.median(source.rss[h])) for h in hours}
    peak = {h: max(source.rss[h]) for h in hours}
    print("RSS by data hour, median/max of its blocks (MB): "
          + ", ".join(f"{h}: {median[h]:.0f}/{peak[h]:.0f}" for h in hours))
    if len(hours) > 1 and 1 in median:
        last = hours[-1]
        print(f"growth from hour 1 to hour {last}: median {median[last] - median[1]:+.0f} MB, "
              f"max {peak[last] - peak[1]:+.0f} MB; DuckDB's own memory at the end "
              f"{duckdb_mb:.0f} MB")
    if len(alarms):
        print(alarms[["kind", "signal", "start", "end"]].to_string())
    print(f"block {args.block} samples; DuckDB memory limit {args.historian_memory_mb:.0f} MB; "
          f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
