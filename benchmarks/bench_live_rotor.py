"""Cost of the rotor in the live twin (issue 23, item 6): a virtual-plant record replayed
through one unit's :class:`~steamtwin.live.service.LiveTwin` at full speed, without and with a
rotor model (:class:`~steamtwin.live.rotor_stream.LiveRotor`), alternately (the machine is
shared: old and new in the same minutes), 60-sample blocks as the service commits them.

Prints, per run, the CPU seconds (``time.process_time``) and wall seconds per stored sample of
the whole chain (gate, FOM, residuals, historian) and the rotor's share (with − without), and
separately the rotor's own work per sample (steam side from the FOM's stage states plus the
ROM steps, :meth:`LiveRotor.advance` timed alone), and the FOM's stream with and without the
stage states (:meth:`FullOrderModel.simulate_stream_detailed` vs ``simulate_stream``).

``--rotor PATH``: a saved rotor model (RotorModel.save); without it one is fitted from the
reference spec at the default mesh first and its fit time printed (what ``rotor = "fit"``
costs a service at start).

Run: python benchmarks/bench_live_rotor.py [--hours 0.5] [--repeats 2] [--rotor rotor.npz]
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from pathlib import Path

import pandas as pd

from steamtwin.dcs.plant import plant_tag_map, run_plant, write_plant
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.rotor_stream import LiveRotor
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.rotor.model import RotorModel
from steamtwin.spec import load_spec


def replay(folder: Path, name: str, model, run, paths, rotor: RotorModel | None
           ) -> tuple[float, float, int]:
    """(CPU s, wall s, samples) of one replay through a fresh twin and database."""
    twin = LiveTwin("unit1", model, ModelParameters(),
                    StreamGate(gate_options(plant_tag_map(), run.injected.sensors)),
                    LiveHistorian(folder / f"{name}.duckdb"),
                    rotor=None if rotor is None else LiveRotor(rotor)).start()
    cpu, wall = time.process_time(), time.perf_counter()
    summary = asyncio.run(twin.run(ReplaySource(paths["historian"], plant_tag_map(),
                                                block_samples=60)))
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    twin.close()
    return cpu, wall, summary.samples


def pieces(model: FullOrderModel, rotor: RotorModel, inputs: pd.DataFrame
           ) -> dict[str, float]:
    """CPU µs per sample of the FOM stream plain / detailed and of LiveRotor.advance."""
    out = {"fom": 0.0, "fom_detailed": 0.0, "rotor": 0.0}
    live = LiveRotor(rotor)
    state = detailed_state = None
    for start in range(0, len(inputs), 60):
        block = inputs.iloc[start:start + 60]
        t = time.process_time()
        _, state = model.simulate_stream(block, None, state)
        out["fom"] += time.process_time() - t
        t = time.process_time()
        run, detailed_state = model.simulate_stream_detailed(block, None, detailed_state)
        out["fom_detailed"] += time.process_time() - t
        t = time.process_time()
        live.advance(model, block, run, ModelParameters())
        out["rotor"] += time.process_time() - t
    return {key: value / len(inputs) * 1e6 for key, value in out.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hours", type=float, default=0.5)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--rotor", type=Path, default=None)
    options = parser.parse_args()
    spec = load_spec("reference")
    if options.rotor is None:
        cpu, wall = time.process_time(), time.perf_counter()
        rotor = RotorModel(spec).fit()
        print(f"rotor fit (default mesh, {rotor.mesh_.p.shape[1]} nodes): "
              f"{time.process_time() - cpu:.1f} s CPU, {time.perf_counter() - wall:.1f} s wall")
    else:
        rotor = RotorModel.load(options.rotor, spec)
    model = FullOrderModel(spec, sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    run = run_plant("deep-peak-50", hours=options.hours, random_state=0)
    with tempfile.TemporaryDirectory() as folder:
        paths = write_plant(run, Path(folder), file_format="csv")
        replay(Path(folder), "warm", model, run, paths, rotor)  # compile, caches
        for k in range(options.repeats):
            rows = {}
            for label, with_rotor in (("without", None), ("with", rotor)):
                rows[label] = replay(Path(folder), f"{label}{k}", model, run, paths,
                                     with_rotor)
            (c0, w0, n), (c1, w1, _) = rows["without"], rows["with"]
            print(f"run {k + 1}: {n} samples; per sample without rotor {c0 / n * 1e6:.0f} µs "
                  f"CPU ({w0 / n * 1e6:.0f} µs wall), with {c1 / n * 1e6:.0f} µs CPU "
                  f"({w1 / n * 1e6:.0f} µs wall): rotor +{(c1 - c0) / n * 1e6:.0f} µs CPU")
    inputs = run.measured[list(INPUT_SIGNALS)].dropna()
    inputs = inputs.iloc[:3600]
    timing = pieces(model, rotor, inputs)
    print(f"pieces (CPU µs per sample, {len(inputs)} samples): FOM stream "
          f"{timing['fom']:.0f}, with stage states {timing['fom_detailed']:.0f}; "
          f"LiveRotor.advance {timing['rotor']:.0f}")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
