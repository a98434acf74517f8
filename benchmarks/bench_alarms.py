"""Residual alarms on the virtual plant's ``day`` (issue 21, item 5 acceptance): an exhaust
thermocouple drifting 2 K/h flagged as a sensor fault within 15 min; a fouling step (flow
coefficient −2 %) flagged as degradation within 10 min; no alarm in 24 h on clean days over
three instrument seeds.

Each case replays the plant's 24-h ``day`` (1-s samples) in 600-sample blocks through the
streaming gate (``live.StreamGate``), the streamed full-order model (reference spec, default
parameters, typical thermocouple lags, ``simulate_stream``) and 60-s residual block means into
``live.ResidualMonitor``, with the twin's sensitivity J to the flow coefficient
(``model_sensitivity``, cached per 5 %-load band). The monitor is fitted on a calibration day:
``day`` seed 100 with the same instruments (``instruments=`` the case's instrument table: a
plant's own sensors on another healthy day), independent of the seeds 0–2 it is judged on.
Cases: clean seeds 0, 1, 2; seed 0 with ``hp_exhaust_temperature:drift:2@12h``; seed 0 with the
true flow coefficient stepped −2 % at noon (``PlantTruth.drift``). Prints every alarm (kind,
signal, time) and the detection delays. Plant runs are cached in ``--cache`` (≈ 45 s each).

Run: python benchmarks/bench_alarms.py [--cache DIR] [--band 0.02] [--plain]
(``--band``: width of the monitor's load bands; ``--plain``: the monitor fitted without the
load — one offset and one MAD σ per sensor — for comparison)
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

from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.plant_model import ParameterDrift, PlantTruth
from steamtwin.dcs.sensor_faults import apply_sensor_faults, parse_sensor_fault
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.residuals import (
    MonitorSettings,
    ResidualMonitor,
    block_means,
    model_sensitivity,
)
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import load_spec

SENSORS = ("control_stage_temperature", "hp_exhaust_temperature",
           "hp_inner_casing_temperature", "control_stage_pressure")
BLOCK_S = 60.0
DRIFT = "hp_exhaust_temperature:drift:2@12h"
FAULT_AT = pd.Timedelta(hours=12)


def _plant(cache: Path, name: str, make) -> dict:
    """The run's measured frame and instrument record, cached as Parquet (data only)."""
    measured_path = cache / f"{name}.measured.parquet"
    sensors_path = cache / f"{name}.sensors.parquet"
    if measured_path.exists() and sensors_path.exists():
        return {"measured": pd.read_parquet(measured_path),
                "sensors": pd.read_parquet(sensors_path)}
    run = make()
    run.measured.to_parquet(measured_path)
    run.injected.sensors.to_parquet(sensors_path)
    return {"measured": run.measured, "sensors": run.injected.sensors}


def _fouling_truth() -> PlantTruth:
    truth = PlantTruth()
    target = dataclasses.replace(truth.parameters,
                                 flow_coefficient=0.98 * truth.parameters.flow_coefficient)
    return dataclasses.replace(truth, drift=ParameterDrift(at_hours=12.0, over_hours=0.0,
                                                           target=target))


def _replay(model: FullOrderModel, measured: pd.DataFrame, instruments: pd.DataFrame,
            params: ModelParameters) -> pd.DataFrame:
    """Residual block means of SENSORS, with the block's load fraction and load rate (1/min)
    and the block's model inputs kept for J."""
    gate = StreamGate(gate_options(plant_tag_map(), instruments))
    state, parts = None, []
    for start in range(0, len(measured), 600):
        out = gate.push(measured.iloc[start:start + 600])
        if out.data.empty:
            continue
        inputs = out.data[list(INPUT_SIGNALS)]
        complete = inputs.notna().all(axis=1).to_numpy()
        twin = pd.DataFrame(np.nan, index=out.data.index, columns=list(SENSORS))
        if complete.any():
            outputs, state = model.simulate_stream(inputs[complete], params, state)
            twin.loc[outputs.index] = outputs[list(SENSORS)].to_numpy()
        parts.append((out.data[list(SENSORS)] - twin).assign(
            load=out.data["load"] / model.spec.design.generator_power))
    residual = pd.concat(parts)
    blocks = block_means(residual, BLOCK_S)
    return blocks


def _sensitivity(model: FullOrderModel, measured: pd.DataFrame, params: ModelParameters,
                 blocks: pd.DataFrame) -> dict[float, pd.DataFrame]:
    """J per 5 %-load band, from the first 60-s block of the day in the band."""
    cache: dict[float, pd.DataFrame] = {}
    inputs = measured[list(INPUT_SIGNALS)].ffill().bfill()
    for stamp, load in blocks["load"].items():
        band = round(float(load) * 20.0) / 20.0
        if band in cache or not np.isfinite(load):
            continue
        window = inputs.loc[stamp - pd.Timedelta(seconds=BLOCK_S):stamp]
        cache[band] = model_sensitivity(model, window, params, SENSORS)
    return cache


def _instrument_sigma(instruments: pd.DataFrame) -> dict[str, float]:
    """Instrument error of a 60-s block mean: noise σ/√n and the resolution's uniform
    quantisation error q/√12 (JCGM 100:2008, GUM, §F.2.2.1), combined in quadrature."""
    n = BLOCK_S
    return {s: float(np.hypot(instruments.loc[s, "noise_sigma"] / np.sqrt(n),
                              instruments.loc[s, "resolution"] / np.sqrt(12.0)))
            for s in SENSORS}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "alarms-cache")
    parser.add_argument("--plain", action="store_true")
    parser.add_argument("--band", type=float, default=0.02)
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    clock = time.perf_counter()
    model = FullOrderModel(load_spec("reference"), sensor_time_constants=TYPICAL_TIME_CONSTANTS_S)
    params = ModelParameters()
    cases = []
    for seed in (0, 1, 2):
        clean = _plant(args.cache, f"clean{seed}", lambda s=seed: run_plant("day", random_state=s))
        calib = _plant(args.cache, f"calib{seed}", lambda c=clean: run_plant(
            "day", random_state=100, instruments=c["sensors"]))
        cases.append((f"clean seed {seed}", clean, calib, None))
        if seed == 0:
            drifted, _ = apply_sensor_faults(clean["measured"], [parse_sensor_fault(DRIFT)])
            cases.append(("exhaust TC drift 2 K/h @12 h", {**clean, "measured": drifted},
                          calib, ("sensor_fault", "hp_exhaust_temperature")))
            fouled = _plant(args.cache, "fouling0", lambda: run_plant(
                "day", random_state=0, truth=_fouling_truth()))
            cases.append(("flow coefficient −2 % @12 h", fouled, calib,
                          ("degradation", "flow_coefficient")))
    fitted: dict[int, tuple[ResidualMonitor, pd.DataFrame]] = {}
    variant = ("plain (one σ, one offset)" if args.plain
               else "load-band + transient baseline, transient σ")
    print(f"monitor: {variant}; fitted on day seed 100 (same instruments)")
    print("| case | alarms (kind signal start) | detection delay |\n|---|---|---|")
    for name, case, calib, expected in cases:
        key = id(calib)
        if key not in fitted:
            healthy = _replay(model, calib["measured"], calib["sensors"], params)
            monitor = ResidualMonitor(SENSORS, _instrument_sigma(calib["sensors"]),
                                      MonitorSettings(load_band=args.band))
            if args.plain:
                monitor.fit(healthy[list(SENSORS)])
            else:
                monitor.fit(healthy[list(SENSORS)], load=healthy["load"])
            fitted[key] = (monitor, healthy)
        monitor, _ = fitted[key]
        fresh = {"statistics": {}, "active": {}, "filtered_load": None, "last_time": None}
        monitor.set_state(monitor.get_state() | fresh)  # a new day, the fitted model kept
        blocks = _replay(model, case["measured"], case["sensors"], params)
        bands = _sensitivity(model, case["measured"], params, blocks)
        start = blocks.index[0]
        alarms = []
        for stamp, row in blocks.iterrows():
            band = round(float(row["load"]) * 20.0) / 20.0 if np.isfinite(row["load"]) else None
            extra = {} if args.plain else {"load": float(row["load"])}
            for event in monitor.update(stamp, row[list(SENSORS)], bands.get(band), **extra):
                if not event.ended:
                    alarms.append(event)
        listed = ", ".join(f"{e.kind} {e.signal} {(e.time - start) / pd.Timedelta(hours=1):.2f} h"
                           for e in alarms) or "none"
        delay = "—"
        if expected is not None:
            hits = [e for e in alarms if (e.kind, e.signal) == expected
                    and e.time - start >= FAULT_AT]
            delay = (f"{(hits[0].time - start - FAULT_AT) / pd.Timedelta(minutes=1):.0f} min"
                     if hits else "not flagged")
        print(f"| {name} | {len(alarms)}: {listed} | {delay} |", flush=True)
    print(f"{time.perf_counter() - clock:.0f} s wall; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
