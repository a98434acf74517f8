"""The residual alarms and the online recalibration through the live service (issue 21, items
5–6 acceptance): the virtual plant's ``day`` replayed through ``LiveTwin`` — streaming gate,
streamed FOM, clock-aligned 60-s blocks, ``ResidualMonitor`` with J per load band
(``SensitivityCache``), ``LiveRecalibration`` (10-min tracker steps, swaps on schedule every
24 h and on a degradation alarm) and the DuckDB historian.

Per case: the alarms (kind, signal, start, end), the sensor-fault alarm time after the fault's
onset (sensor-hours, open alarms counted to the day's end) and the parameter swaps the database
holds; for the fouling step (flow coefficient −2 % at noon): the degradation alarm's delay and
the live flow coefficient against the new twin-equivalent truth 30 min after the step. The twin's
parameters and the monitor come from a healthy calibration day (``day`` seed 100, the same
instruments): the tracker run over it gives the parameters, the monitor is fitted on that day's
residuals at them. Plant runs are shared with ``bench_alarms.py``'s cache.

Run: python benchmarks/bench_live_alarms.py [--cache DIR] [--cases clean0,drift,fouling]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from bench_alarms import (
    BLOCK_S,
    DRIFT,
    FAULT_AT,
    SENSORS,
    _fouling_truth,
    _instrument_sigma,
    _plant,
    _replay,
)
from steamtwin.calibration.tracking import ParameterTracker
from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.sensor_faults import apply_sensor_faults, parse_sensor_fault
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.recalibration import LiveRecalibration
from steamtwin.live.residuals import MonitorSettings, ResidualMonitor
from steamtwin.live.sensitivity import SensitivityCache
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import SourceBlock
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import DEFAULT_PRIORS, ModelParameters
from steamtwin.spec import load_spec

TRACKED_SIGMA_KEYS = SENSORS


def _tracker(model: FullOrderModel, instruments: pd.DataFrame,
             centre: ModelParameters | None) -> ParameterTracker:
    sigma = {s: float(np.hypot(instruments.loc[s, "noise_sigma"],
                               instruments.loc[s, "resolution"] / np.sqrt(12.0)))
             for s in SENSORS}
    priors = dict(DEFAULT_PRIORS)
    if centre is not None:
        priors = {name: dataclasses.replace(prior, center=getattr(centre, name))
                  for name, prior in priors.items()}
    return ParameterTracker(model, sigma=sigma, priors=priors, step_s=600.0)


def _calibration(model: FullOrderModel, calib: dict) -> tuple[ModelParameters, ResidualMonitor]:
    """The healthy day's tracked parameters and the monitor fitted at them."""
    tracker = _tracker(model, calib["sensors"], None)
    gate = StreamGate(gate_options(plant_tag_map(), calib["sensors"]))
    parts = [gate.push(calib["measured"].iloc[i:i + 3600]).data
             for i in range(0, len(calib["measured"]), 3600)]
    parts.append(gate.flush().data)
    tracker.run(pd.concat([p for p in parts if len(p)]), chunk_s=3600.0)
    params = tracker.params_
    healthy = _replay(model, calib["measured"], calib["sensors"], params)
    monitor = ResidualMonitor(SENSORS, _instrument_sigma(calib["sensors"]), MonitorSettings())
    monitor.fit(healthy[list(SENSORS)], load=healthy["load"])
    return params, monitor


def _run_case(model: FullOrderModel, case: dict, params: ModelParameters,
              monitor: ResidualMonitor, folder: Path) -> tuple[pd.DataFrame, pd.DataFrame, float]:
    fresh = {"statistics": {}, "active": {}, "filtered_load": None, "last_time": None}
    monitor = ResidualMonitor(SENSORS, monitor.instrument_sigma, monitor.settings).set_state(
        monitor.get_state() | fresh)
    twin = LiveTwin("unit1", model, params,
                    StreamGate(gate_options(plant_tag_map(), case["sensors"])),
                    LiveHistorian(folder / "live.duckdb"), monitor=monitor, monitored=SENSORS,
                    sensitivity=SensitivityCache(model, SENSORS),
                    recalibration=LiveRecalibration(_tracker(model, case["sensors"], params)))
    twin.start()
    clock = time.perf_counter()
    measured = case["measured"]
    for first in range(0, len(measured), 60):
        frame = measured.iloc[first:first + 60]
        twin.process(SourceBlock(frame, pd.DataFrame(False, index=frame.index,
                                                     columns=frame.columns)))
    twin.finish()
    seconds = time.perf_counter() - clock
    alarms = twin.historian.alarms("unit1")
    swaps = twin.historian.connection.execute(
        "SELECT time, value, reason, low, high FROM parameters "
        "WHERE name = 'flow_coefficient' ORDER BY time").df()
    twin.close()
    return alarms, swaps, seconds


def _hours(time: object, start: pd.Timestamp) -> str:
    if pd.isna(time):
        return "open"
    return f"{(pd.Timestamp(time) - start) / pd.Timedelta(hours=1):.2f}"


def _fault_hours(alarms: pd.DataFrame, start: pd.Timestamp, case: dict) -> float:
    """Sensor-hours of sensor-fault alarms from the fault's onset (``FAULT_AT``) on, an open
    alarm counted to the day's last sample."""
    onset, last = start + FAULT_AT, case["measured"].index[-1]
    faults = alarms[alarms["kind"] == "sensor_fault"]
    begin = pd.to_datetime(faults["start"], utc=True).clip(lower=onset)
    end = pd.to_datetime(faults["end"], utc=True).fillna(last)
    return float(((end - begin).clip(lower=pd.Timedelta(0)) / pd.Timedelta(hours=1)).sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "alarms-cache")
    parser.add_argument("--cases", default="clean0,clean1,clean2,drift,fouling")
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    wanted = args.cases.split(",")
    model = FullOrderModel(load_spec("reference"), sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    new_truth = _fouling_truth().drift.target
    truth_after = dataclasses.replace(PlantTruth(), parameters=new_truth).twin_equivalent
    print(f"twin-equivalent flow coefficient after the step: "
          f"{truth_after.flow_coefficient:.4f}")
    calibrated: dict[int, tuple[ModelParameters, ResidualMonitor]] = {}
    print("| case | alarms (kind signal start–end, h) | sensor-fault h after the onset | swaps "
          "| delay | live φ at +30 min (error) | run |\n|---|---|---|---|---|---|---|")
    for name in wanted:
        seed = int(name[-1]) if name.startswith("clean") else 0
        clean = _plant(args.cache, f"clean{seed}", lambda s=seed: run_plant("day", random_state=s))
        calib = _plant(args.cache, f"calib{seed}", lambda c=clean: run_plant(
            "day", random_state=100, instruments=c["sensors"]))
        if seed not in calibrated:
            calibrated[seed] = _calibration(model, calib)
        params, monitor = calibrated[seed]
        case, expected = clean, None
        if name == "drift":
            drifted, _ = apply_sensor_faults(clean["measured"], [parse_sensor_fault(DRIFT)])
            case, expected = {**clean, "measured": drifted}, ("sensor_fault",
                                                             "hp_exhaust_temperature")
        elif name == "fouling":
            case = _plant(args.cache, "fouling0", lambda: run_plant(
                "day", random_state=0, truth=_fouling_truth()))
            expected = ("degradation", "flow_coefficient")
        with tempfile.TemporaryDirectory() as folder:
            alarms, swaps, seconds = _run_case(model, case, params, monitor, Path(folder))
        start = case["measured"].index[0]

        listed = "; ".join(f"{a.kind} {a.signal} {_hours(a.start, start)}–"
                           f"{_hours(a.end, start)}" for a in alarms.itertuples()) or "none"
        delay, live = "—", "—"
        if expected is not None:
            hits = alarms[(alarms["kind"] == expected[0]) & (alarms["signal"] == expected[1])
                          & (pd.to_datetime(alarms["start"], utc=True) - start >= FAULT_AT)]
            late = pd.Timestamp(hits["start"].iloc[0]) - start - FAULT_AT if len(hits) else None
            delay = "not flagged" if late is None else f"{late / pd.Timedelta(minutes=1):.0f} min"
        if name == "fouling":
            at = start + FAULT_AT + pd.Timedelta(minutes=30)
            times = pd.to_datetime(swaps["time"], utc=True)
            before = swaps[times <= at]
            value = before["value"].iloc[-1] if len(before) else params.flow_coefficient
            live = f"{value:.4f} ({value - truth_after.flow_coefficient:+.4f})"
            if len(before) and pd.notna(before["low"].iloc[-1]):  # the filter's 95 % interval
                low, high = before["low"].iloc[-1], before["high"].iloc[-1]
                holds = low <= truth_after.flow_coefficient <= high
                live += f", 95 % [{low:.4f}, {high:.4f}] {'holds' if holds else 'misses'} the truth"
        print(f"| {name} | {len(alarms)}: {listed} | {_fault_hours(alarms, start, case):.2f} | "
              f"{len(swaps)} | {delay} | {live} | {seconds:.0f} s |", flush=True)
    print(f"block {BLOCK_S:.0f} s; params from the calibration day's tracker: "
          + ", ".join(f"{k} {v:.4f}" for k, v in dataclasses.asdict(
              next(iter(calibrated.values()))[0]).items())
          + f"; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
