"""Replay a day of plant data through the live twin and plot measured against twin.

What it shows: the live twin (``steamtwin.live``) without an OPC UA server — a historian file
played as a stream, sample by sample, as ``steamtwin serve`` does with a ``replay`` source.

1. The virtual plant runs its ``day`` scenario (load following 30–100 %: night at 50 %,
   morning peak, a deep-peak valley at 30 % at noon, evening peak) and writes the historian
   export and its tag map.
2. A twin: ``Twin.from_spec("reference")`` with the empirical parameters, or the folder
   ``calibrate_from_historian.py`` saved (``--twin DIR``: its calibrated parameters and
   sensor offsets).
3. :class:`~steamtwin.live.sources.ReplaySource` plays the export in blocks;
   :class:`~steamtwin.live.service.LiveTwin` passes each block through the streaming quality
   gate, advances the full-order model over it (read through the plant's sensors: the
   thermocouples' lags, the casing thermocouple's depth) and stores measured, twin and
   residual series in a DuckDB file.
4. The stored series come back out (``LiveHistorian.series``): a figure of measured vs twin
   control-stage and HP-exhaust temperatures with their residuals over the day, and a table
   of each monitored signal's residual RMS (``residuals.csv``; K, or Pa for the pressure).

How long (CPU time, measured on a 2-core x86_64): ``--quick`` (the day's holds shortened to a
tenth and every ramp at 5 %/min: 2.7 h of 1-s samples) about 11 s; the default (the full
24 h, 86 400 samples) a few minutes.

    python examples/replay_day.py --quick --out replay-output [--twin calibrate-output/twin]
"""

from __future__ import annotations

import argparse
import asyncio
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

import steamtwin
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.dcs.tagmap import load_tag_map
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.service import MONITORED, LiveTwin
from steamtwin.live.sources import ReplaySource
from steamtwin.twin import monitoring_model

UNIT = "unit-1"
PLOTTED = {"control_stage_temperature": "control-stage temperature",
           "hp_exhaust_temperature": "HP-exhaust temperature"}
WARM_UP_S = 600.0
"""Left out of the residual statistics (s): the twin starts its metal and sensors in the first
sample's steady state and needs a few minutes to settle (the figure shows it)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("replay-output"),
                        help="folder for the day's data, the live database and the figure")
    parser.add_argument("--twin", type=Path, default=None,
                        help="a saved twin folder (default: the reference unit, parameters 1)")
    parser.add_argument("--quick", action="store_true",
                        help="a shortened day, ramps at 5 %%/min (seconds, for tests)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the plant's instruments")
    args = parser.parse_args()

    hours, ramp_rate = (0.25, 5.0) if args.quick else (None, None)
    run = run_plant("day", hours=hours, ramp_rate=ramp_rate, random_state=args.seed)
    files = write_plant(run, args.out / "day")
    print(f"virtual plant: {len(run.measured)} samples of the 'day' scenario → "
          f"{files['historian']}")

    twin = (steamtwin.Twin.load(args.twin) if args.twin is not None
            else steamtwin.Twin.from_spec("reference"))
    print(f"twin: {twin}")
    tag_map = load_tag_map(files["tag_map"])
    model = monitoring_model(twin.spec, monitor="fom", sensor_lag=True, tag_map=tag_map,
                             offsets=twin.offsets)  # the FOM read through the plant's sensors
    database = args.out / "live.duckdb"
    database.unlink(missing_ok=True)  # a rerun starts over (the twin would resume after it)
    with LiveHistorian(database) as historian:
        live = LiveTwin(UNIT, model, twin.parameters, StreamGate(gate_options(tag_map)),
                        historian)
        source = ReplaySource(files["historian"], tag_map, speed=None, block_samples=600)
        summary = asyncio.run(live.run(source))
        series = historian.series(UNIT)
    print(f"live twin: {summary.samples} samples stored in {database} "
          f"({summary.without_twin} without a twin value, {summary.findings} gate findings)")

    steady = series.index >= series.index[0] + pd.Timedelta(seconds=WARM_UP_S)
    rows = []
    for signal in MONITORED:
        column = f"residual/{signal}"
        if column not in series.columns:
            continue
        residual = series.loc[steady, column].dropna().to_numpy(dtype=float)
        rows.append({"signal": signal, "unit": "Pa" if signal.endswith("pressure") else "K",
                     "samples": len(residual), "mean": float(residual.mean()),
                     "rms": float(np.sqrt(np.mean(residual**2))),
                     "max_abs": float(np.abs(residual).max())})
    table = pd.DataFrame(rows)
    table.to_csv(args.out / "residuals.csv", index=False)
    print("residual (measured − twin) after the first 10 min:")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))

    figure = plot(series, twin.spec.design.generator_power)
    path = args.out / "measured_vs_twin.png"
    figure.savefig(path, dpi=120)
    plt.close(figure)
    print(f"figure: {path}")


def plot(series: pd.DataFrame, rated_power_w: float) -> plt.Figure:
    """Load, and per plotted temperature measured vs twin (°C) with the residual (K)."""
    time_h = (series.index - series.index[0]).total_seconds() / 3600.0
    figure, axes = plt.subplots(1 + 2 * len(PLOTTED), 1, sharex=True,
                                figsize=(10, 2.2 * (1 + 2 * len(PLOTTED))))
    axes[0].plot(time_h, series["measured/load"] / rated_power_w * 100.0, color="0.3")
    axes[0].set_ylabel("load (%)")
    for k, (signal, label) in enumerate(PLOTTED.items()):
        values, residual = axes[1 + 2 * k], axes[2 + 2 * k]
        values.plot(time_h, series[f"measured/{signal}"] - 273.15, label="measured", lw=0.8)
        values.plot(time_h, series[f"twin/{signal}"] - 273.15, label="twin", lw=0.8)
        values.set_ylabel(f"{label}\n(°C)")
        values.legend(loc="upper right")
        residual.plot(time_h, series[f"residual/{signal}"], color="C3", lw=0.6)
        residual.axhline(0.0, color="0.5", lw=0.5)
        residual.set_ylabel("residual (K)")
    axes[-1].set_xlabel("time (h)")
    figure.suptitle("The day replayed through the live twin: measured vs twin")
    figure.tight_layout()
    return figure


if __name__ == "__main__":
    main()
