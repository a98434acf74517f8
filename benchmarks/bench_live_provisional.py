"""CPU of the live twin's provisional path per unit and sample (issue 21, latency: the service's
own part of "OPC UA value change → stored twin sample ≤ 200 ms at p99 with 10 units at 1 Hz").

One :class:`~steamtwin.live.service.LiveTwin` (provisional values on, as the service runs a
live unit) is fed the virtual plant's ``deep-peak-50`` one sample at a time, as an OPC UA
source delivers it; after each sample its provisional rows are stored
(:meth:`LiveHistorian.store_provisional_many`, the group commit's call, here with one unit), and
every ``--settle`` samples the final block is judged and committed (:meth:`LiveTwin.settle`).
Prints the thread CPU time per sample of ``receive_rows`` (gate, one-sample FOM, residuals,
rows) and of the store, as median and 99th percentile over the samples after ``--warmup``, and
the settle calls' (most judge nothing: the final block comes every ``--settle`` samples). No
event loop, no OPC UA: the clean figure of the per-sample work.

Run: python benchmarks/bench_live_provisional.py [--seconds 600] [--settle 60] [--warmup 60]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.service import LiveSummary, LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import load_spec


async def _blocks(path: Path) -> list:
    source = ReplaySource(path, plant_tag_map(), block_samples=1)
    return [block async for block in source.blocks()]


def _ms(values: list[float]) -> str:
    array = np.array(values) * 1e3
    return f"median {np.median(array):.2f} ms, p99 {np.percentile(array, 99):.2f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=int, default=600, help="samples fed")
    parser.add_argument("--settle", type=int, default=60, help="samples per final block")
    parser.add_argument("--warmup", type=int, default=60, help="first samples not counted")
    args = parser.parse_args()
    run = run_plant("deep-peak-50", hours=args.seconds / 3600.0 + 0.01, random_state=0)
    model = FullOrderModel(load_spec("reference"), sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    _ = model.design_
    with tempfile.TemporaryDirectory() as folder:
        paths = write_plant(run, Path(folder), file_format="parquet")
        blocks = asyncio.run(_blocks(paths["historian"]))[:args.seconds]
        historian = LiveHistorian(Path(folder) / "live.duckdb")
        twin = LiveTwin("unit1", model, ModelParameters(),
                        StreamGate(gate_options(plant_tag_map(), run.injected.sensors)),
                        historian, provisional=True).start()
        summary = LiveSummary()
        receive, store, settle = [], [], []
        for k, block in enumerate(blocks):
            begin = time.thread_time()
            rows = twin.receive_rows(block, summary)
            middle = time.thread_time()
            if rows is not None:
                historian.store_provisional_many([rows])
            end = time.thread_time()
            twin.settle(summary, args.settle)
            if k >= args.warmup:
                receive.append(middle - begin)
                store.append(end - middle)
                settle.append(time.thread_time() - end)
        twin.finish(summary)
        twin.close()
    calls = [s for s in settle if s > 1e-4]
    print(f"{len(receive)} samples counted ({args.warmup} warm-up), final block every "
          f"{args.settle}; load average {os.getloadavg()[0]:.1f}")
    print(f"receive_rows CPU per sample: {_ms(receive)}")
    print(f"store_provisional_many CPU per sample: {_ms(store)}")
    path = [a + b for a, b in zip(receive, store, strict=True)]
    print(f"provisional path CPU per sample: {_ms(path)}")
    print(f"settle CPU per sample (mostly nothing to judge): {_ms(settle)}")
    print(f"settle: {len(calls)} calls over 0.1 ms, mean {np.mean(calls) * 1e3:.1f} ms CPU; "
          f"{summary.samples} samples stored")


if __name__ == "__main__":
    main()
