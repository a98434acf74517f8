"""Throughput of the live twin's pieces on a replayed day (issue 21, "What must hold": ≥ 1 000×
real time for gate + FOM + ROM + residuals + DuckDB on one core; measured here piece by piece
until the service that chains them lands).

The virtual plant's 24-h ``day`` (seed 0, 1-s samples) is replayed in blocks of ``--block``
samples through: the streaming data-quality gate (``live.StreamGate``, the tag map's ranges and
the instruments' noise and resolution), the streamed full-order model
(``FullOrderModel.simulate_stream`` read through the typical thermocouple lags), the residual
block means and the multi-hypothesis CUSUM (``live.ResidualMonitor``, fitted on the first two
hours), and the DuckDB historian (``live.LiveHistorian.commit_block``: measured, twin and
residual series, one transaction per block, a model-state snapshot every block). Prints each
piece's CPU seconds for the day and its multiple of real time; the streamed model's largest
difference from one batch run over the day; the resident memory at hour 1 and hour 24.

Run: python benchmarks/bench_live_pieces.py [--hours 24] [--block 600] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.residuals import ResidualMonitor, block_means
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import load_spec

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature", "control_stage_pressure")


def _rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, default=24.0)
    parser.add_argument("--block", type=int, default=600)
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "steamtwin-bench")
    args = parser.parse_args()
    run = run_plant("day", random_state=0)
    measured = run.measured.iloc[:int(args.hours * 3600)]
    seconds = len(measured)
    options = gate_options(plant_tag_map(), run.injected.sensors)
    model = FullOrderModel(load_spec("reference"), sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    _ = model.design_
    model.simulate(measured.iloc[:10][list(INPUT_SIGNALS)].ffill().bfill())  # compile
    params = ModelParameters()
    gate = StreamGate(options)
    args.out.mkdir(parents=True, exist_ok=True)
    db = args.out / "live_pieces.duckdb"
    db.unlink(missing_ok=True)
    clocks = {"gate": 0.0, "model": 0.0, "residuals": 0.0, "historian": 0.0}
    state = None
    twin_parts, residual_parts, fed = [], [], []
    rss_hour1 = None
    monitor = ResidualMonitor(SENSORS, {"control_stage_temperature": 0.05,
                                        "hp_exhaust_temperature": 0.05,
                                        "hp_inner_casing_temperature": 0.05,
                                        "control_stage_pressure": 2.0e3})
    fitted = False
    alarms = 0
    with LiveHistorian(db) as historian:
        for start in range(0, seconds, args.block):
            clock = time.process_time()
            out = gate.push(measured.iloc[start:start + args.block])
            clocks["gate"] += time.process_time() - clock
            if out.data.empty:
                continue
            clock = time.process_time()
            inputs = out.data[list(INPUT_SIGNALS)]
            complete = inputs.notna().all(axis=1).to_numpy()
            twin = pd.DataFrame(np.nan, index=out.data.index, columns=list(model.output_signals))
            if complete.any():
                fed.append(inputs[complete])
                outputs, state = model.simulate_stream(inputs[complete], params, state)
                twin.loc[outputs.index] = outputs.to_numpy()
            clocks["model"] += time.process_time() - clock
            clock = time.process_time()
            residual = out.data[list(SENSORS)] - twin[list(SENSORS)]
            means = block_means(residual, 60.0)
            if not fitted and len(residual_parts) * args.block >= 7200:
                monitor.fit(block_means(pd.concat(residual_parts), 60.0)[list(SENSORS)])
                fitted = True
            if fitted:
                for stamp, row in means[list(SENSORS)].iterrows():
                    alarms += sum(not e.ended for e in monitor.update(stamp, row, None))
            clocks["residuals"] += time.process_time() - clock
            clock = time.process_time()
            flags = out.flags.where(out.flags != 0).astype(object)
            historian.commit_block("u1", {"measured": out.data, "twin": twin,
                                          "residual": residual}, flags,
                                   state=state.to_dict() if state is not None else None)
            clocks["historian"] += time.process_time() - clock
            twin_parts.append(twin)
            residual_parts.append(residual)
            if rss_hour1 is None and start >= 3600:
                rss_hour1 = _rss_mb()
    fed_inputs = pd.concat(fed)
    streamed = pd.concat(twin_parts).loc[fed_inputs.index]
    batch = model.simulate(fed_inputs, params)
    difference = np.abs(streamed.to_numpy() - batch.to_numpy())
    print(f"{len(measured)} samples ({seconds / 3600:g} h), blocks of {args.block}; "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"  streamed vs one batch run over the same {len(fed_inputs)} samples: max "
          f"{difference.max():.2e} (K, Pa, W)")
    total = sum(clocks.values())
    for name, used in clocks.items():
        print(f"  {name:10s} {used:7.2f} s CPU  ({seconds / max(used, 1e-9):8.0f}× real time)")
    print(f"  {'all':10s} {total:7.2f} s CPU  ({seconds / total:8.0f}× real time)")
    print(f"  resident memory: {rss_hour1} MB at hour 1, {_rss_mb():.0f} MB at the end "
          "(peak RSS)")
    print(f"  alarms on the clean day (monitor fitted on the first 2 h): {alarms}")


if __name__ == "__main__":
    main()
