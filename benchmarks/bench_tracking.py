"""Benchmark: online tracking of the flow coefficient on the virtual plant's day (issue 18,
item 6).

Run: python benchmarks/bench_tracking.py [--hours H] — the plant's ``day`` scenario (deep
peak-shaving: 100 % → 30 % → 100 % with holds and ramps), recorded by its instruments, written
as a historian file and read back through the quality gate (``load_history``), then tracked by
``calibrate-online --method track``'s filter (:class:`ParameterTracker`, 10-minute steps, the
reference twin read through the tag map's or typical sensors, σ from
:func:`tracking_sigma`):

1. a constant plant: the tracked flow coefficient's median per 10 % load band, and their
   spread between 30 % and 100 % load (target ≤ 0.005);
2. the same day with the plant's flow coefficient stepping −2 % at noon: the tracked value
   against the twin-equivalent truth before and after (target: within 0.005 from 30 min after
   the step on).

Prints the figures, the machine and the date; docs/benchmarks.md records them.
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.calibration.tracking import ParameterTracker, tracking_sigma
from steamtwin.dcs.history import load_history
from steamtwin.dcs.plant import run_plant, write_plant
from steamtwin.dcs.plant_model import ParameterDrift, PlantTruth
from steamtwin.model.sensor_setup import sensor_setup
from steamtwin.spec import load_spec


def track_day(truth: PlantTruth, hours: float | None, folder: Path) -> tuple[pd.DataFrame,
                                                                            pd.DataFrame]:
    """The tracker's trajectory over the plant's day and the measured load (fraction)."""
    run = run_plant("day", hours=hours, random_state=0, truth=truth)
    paths = write_plant(run, folder)
    history = load_history(paths["historian"], paths["tag_map"], accept_errors=True)
    spec = load_spec("reference")
    tag_map = history.historian.tag_map
    model = sensor_setup(spec, tag_map).model(spec)
    tracker = ParameterTracker(model, sigma=tracking_sigma(tag_map)).run(history.data)
    load = history.data["load"] / spec.design.generator_power
    return tracker.trajectory_, load


def band_medians(track: pd.DataFrame, load: pd.Series) -> pd.Series:
    """Median tracked flow coefficient per 10 % load band of the step's mean load."""
    step_load = [float(load.loc[(load.index > end - pd.Timedelta(minutes=10))
                                & (load.index <= end)].mean()) for end in track.index]
    bands = (np.round(np.asarray(step_load) * 10.0) / 10.0)
    return track["flow_coefficient"].groupby(bands).median()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=None, help="the scenario's long hold")
    args = parser.parse_args()
    started = time.perf_counter()
    base = PlantTruth()
    equivalent = base.twin_equivalent.flow_coefficient
    print(f"{time.strftime('%Y-%m-%d')}, {platform.machine()}, {platform.processor() or '?'}")
    print(f"twin-equivalent flow coefficient of the plant: {equivalent:.4f}")
    with tempfile.TemporaryDirectory() as folder:
        track, load = track_day(base, args.hours, Path(folder) / "constant")
        medians = band_medians(track, load)
        print("constant plant: median tracked flow coefficient per load band")
        print(medians.round(4).to_string())
        span = medians[(medians.index >= 0.3) & (medians.index <= 1.0)]
        offset = float(track["flow_coefficient"].median()) - equivalent
        print(f"spread 30-100 %: {span.max() - span.min():.4f} (target <= 0.005); "
              f"median error vs twin-equivalent {offset:+.4f}")
        stepped = replace(base.parameters,
                          flow_coefficient=0.98 * base.parameters.flow_coefficient)
        truth = replace(base, drift=ParameterDrift(at_hours=12.0, over_hours=0.0,
                                                   target=stepped))
        after = replace(base, parameters=stepped).twin_equivalent.flow_coefficient
        track, _ = track_day(truth, args.hours, Path(folder) / "step")
        noon = track.index[0] - pd.Timedelta(minutes=10) + pd.Timedelta(hours=12)
        late = track[track.index >= noon + pd.Timedelta(minutes=30)]["flow_coefficient"]
        early = track[track.index <= noon]["flow_coefficient"]
        print(f"step: twin-equivalent {equivalent:.4f} -> {after:.4f}")
        print(f"before noon: max abs error {np.abs(early - equivalent).max():.4f}")
        print(f"from 30 min after the step: max abs error {np.abs(late - after).max():.4f}, "
              f"median {np.median(np.abs(late - after)):.4f} (target <= 0.005)")
        settled = track[track.index >= noon + pd.Timedelta(minutes=30)]
        inside = ((settled["flow_coefficient_low"] <= after)
                  & (after <= settled["flow_coefficient_high"])).mean()
        print(f"95 % intervals (flow meter's uncertainty included) holding the twin-equivalent "
              f"truth after the step: {inside:.0%}")
    print(f"wall time {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
