"""Virtual plant of the reference 600 MW unit: historian-style data the twin did not generate.

Demos and tests need DCS data that look like a real unit's, but data made by the twin's own model
structure would let calibration rediscover its own assumptions. The virtual plant therefore runs
the full-order model (FOM) with hidden parameters *and* a deliberately different structure
(:mod:`steamtwin.dcs.plant_model`: :class:`~steamtwin.dcs.plant_model.PlantTruth`, items 1–9 of
its docstring), then records the result through the instrument models of
:mod:`steamtwin.dcs.sensors`. This module holds the load programmes (:data:`SCENARIOS`), the run
(:func:`run_plant`) with the two structural differences it applies itself, and the historian
files (:func:`write_plant`):

    3. **Boiler dynamics on the boundary conditions.** The turbine follows the load demand L(t)
       with flow m = L·m_rated; main-steam pressure follows the sliding-pressure setpoint through
       a first-order lag (:data:`PRESSURE_LAG_S`, 120 s, boiler storage); main-steam temperature
       dips during load ramps by :data:`TEMPERATURE_DIP_PER_RATE` K per %/min of ramp rate,
       through a first-order lag of :data:`TEMPERATURE_LAG_S` (300 s), recovering likewise after
       the ramp (firing/spray mismatch); HP-exhaust pressure follows flow
       (:func:`~steamtwin.model.operating.operating_point`).
    4. **Instruments.** Lag, noise, bias, drift, quantisation, dropouts and spikes come from
       :func:`~steamtwin.dcs.sensors.measure` with
       :func:`~steamtwin.dcs.sensors.default_sensor_models`; the casing thermocouple's sheath
       has the plant's own time constant
       (:attr:`~steamtwin.dcs.plant_model.PlantTruth.casing_sheath_time_constant`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.plant_model import (
    FIXED_LOSS_W,
    GLAND_TEETH,
    PLANT_GRID_STRETCH,
    PLANT_METAL_NODES,
    START,
    TIP_SEAL_STRIPS,
    TWIN_EQUIVALENT_LOADS,
    PlantTruth,
    generator_power,
    plant_model,
    run_leaking,
    steady_boundary,
    tip_leakage_fractions,
)
from steamtwin.dcs.readers import canonical_to_historian
from steamtwin.dcs.sensor_faults import SensorFault, apply_sensor_faults
from steamtwin.dcs.sensors import (
    Injected,
    SensorModel,
    default_sensor_models,
    first_order_lag,
    measure,
)
from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap, TagSpec, write_tag_map
from steamtwin.progress import ProgressCallback
from steamtwin.spec import TurbineSpec, load_spec
from steamtwin.units import convert

__all__ = [
    "KKS_TAGS",
    "PRESSURE_LAG_S",
    "SCENARIOS",
    "TEMPERATURE_DIP_PER_RATE",
    "TEMPERATURE_LAG_S",
    "PlantRun",
    "Scenario",
    "load_demand",
    "plant_sensor_models",
    "plant_tag_map",
    "run_plant",
    "structure_notes",
    "write_plant",
]

PRESSURE_LAG_S = 120.0
"""Time constant (s) of main-steam pressure following the sliding-pressure setpoint."""
TEMPERATURE_LAG_S = 300.0
"""Time constant (s) of the main-steam temperature dip and its recovery."""
TEMPERATURE_DIP_PER_RATE = 1.2
"""Main-steam temperature dip (K) per %/min of load ramp rate, once settled."""

KKS_TAGS: dict[str, str] = {
    "main_steam_pressure": "10LBA10CP001",
    "main_steam_temperature": "10LBA10CT001",
    "main_steam_flow": "10LBA10CF001",
    "control_stage_pressure": "10MAA10CP001",
    "control_stage_temperature": "10MAA10CT001",
    "hp_exhaust_pressure": "10LBC10CP001",
    "hp_exhaust_temperature": "10LBC10CT001",
    "hp_inner_casing_temperature": "10MAA10CT101",
    "load": "10MKA10CE001",
}
"""KKS-style historian tag of each measured canonical signal."""

# Valid ranges written to the tag map, in wire units (MPa, degC, t/h, MW).
_TAG_RANGES: dict[str, tuple[float, float]] = {
    "main_steam_pressure": (0.0, 25.0),
    "main_steam_temperature": (0.0, 650.0),
    "main_steam_flow": (0.0, 2520.0),
    "control_stage_pressure": (0.0, 20.0),
    "control_stage_temperature": (0.0, 650.0),
    "hp_exhaust_pressure": (0.0, 6.0),
    "hp_exhaust_temperature": (0.0, 500.0),
    "hp_inner_casing_temperature": (0.0, 650.0),
    "load": (0.0, 700.0),
}


# ------------------------------------------------------------------------------------------
# scenarios


@dataclass(frozen=True)
class Scenario:
    """A load-demand programme: segments of (target load fraction, ramp %/min, hold s).

    ``long_hold`` is the index of the segment whose hold ``hours`` overrides; for ``scale_holds``
    scenarios every other hold is scaled by the same factor.
    """

    name: str
    description: str
    start_load: float
    segments: tuple[tuple[float, float, float], ...]
    long_hold: int
    scale_holds: bool = False


def _deep_peak(load: float) -> Scenario:
    return Scenario(
        name=f"deep-peak-{round(load * 100)}",
        description=f"10 min at 100 %, ramp down at 3 %/min, 2-h hold at {load:.0%}",
        start_load=1.0,
        segments=((1.0, 3.0, 600.0), (load, 3.0, 7200.0)),
        long_hold=1,
    )


SCENARIOS: dict[str, Scenario] = {
    "deep-peak-30": _deep_peak(0.30),
    "deep-peak-50": _deep_peak(0.50),
    "day": Scenario(
        name="day",
        description="24 h load following 30–100 %: night at 50 %, morning ramp, noon deep-peak "
        "valley at 30 %, evening peak at 100 %, ramps ≤ 5 %/min",
        start_load=0.5,
        segments=(
            (0.50, 1.0, 6.0 * 3600),    # night
            (0.80, 1.5, 1.0 * 3600),    # morning ramp-up, shoulder
            (1.00, 1.0, 2.5 * 3600),    # morning peak
            (0.30, 3.0, 2.5 * 3600),    # deep-peak valley around noon (solar)
            (0.75, 2.0, 1.5 * 3600),    # afternoon recovery
            (1.00, 1.0, 3.0 * 3600),    # evening peak
            (0.70, 1.0, 2.0 * 3600),    # late evening
            (0.50, 1.0, 0.0),           # back to night load
        ),
        long_hold=3,
        scale_holds=True,
    ),
    "day-2": Scenario(
        name="day-2",
        description="another 24 h at other loads and rates: night at 40 %, morning ramp to "
        "90 %, peak at 100 %, deep-peak valley at 35 % (4 %/min down), 60 % shoulder, evening "
        "95 %, 65 % and 45 % — loads the 'day' never holds, for judging a twin calibrated on it",
        start_load=0.4,
        segments=(
            (0.40, 1.0, 5.0 * 3600),    # night
            (0.90, 2.0, 1.0 * 3600),    # morning ramp-up, shoulder
            (1.00, 1.0, 1.5 * 3600),    # morning peak
            (0.35, 4.0, 3.0 * 3600),    # deep-peak valley
            (0.60, 1.5, 2.0 * 3600),    # afternoon shoulder
            (0.95, 2.5, 2.5 * 3600),    # evening peak
            (0.65, 1.0, 1.5 * 3600),    # late evening
            (0.45, 1.0, 0.0),           # back to night load
        ),
        long_hold=3,
        scale_holds=True,
    ),
}
"""Built-in scenarios by name."""


def load_demand(scenario: Scenario, *, hours: float | None = None,
                ramp_rate: float | None = None, step_s: float = 1.0) -> np.ndarray:
    """Load-demand fractions, one per ``step_s`` s (``ramp_rate`` %/min overrides all ramps).

    The programme is piecewise linear; the ``day`` programme fills up to 24 h with its last
    hold and is smoothed by a 120-s moving average, which rounds the corners without raising
    any ramp rate.
    """
    if ramp_rate is not None and not 1.0 <= ramp_rate <= 5.0:
        raise ValueError(f"ramp_rate must lie within 1…5 %/min (got {ramp_rate!r})")
    if hours is not None and not (math.isfinite(hours) and hours > 0.0):
        raise ValueError(f"hours must be positive (got {hours!r})")
    default_hold = scenario.segments[scenario.long_hold][2]
    factor = 1.0 if hours is None else hours * 3600.0 / default_hold
    times, loads = [0.0], [scenario.start_load]
    for i, (target, rate, hold) in enumerate(scenario.segments):
        rate = ramp_rate if ramp_rate is not None else rate
        change = abs(target - loads[-1])
        if change > 0.0:
            times.append(times[-1] + change * 100.0 / rate * 60.0)
            loads.append(target)
        if i == scenario.long_hold or scenario.scale_holds:
            hold *= factor
        if hold > 0.0:
            times.append(times[-1] + hold)
            loads.append(target)
    if scenario.scale_holds and hours is None:
        times.append(max(times[-1], 24.0 * 3600.0))
        loads.append(loads[-1])
    grid = np.arange(0.0, times[-1] + step_s / 2, step_s)
    demand = np.interp(grid, times, loads)
    if scenario.scale_holds:
        width = max(1, round(120.0 / step_s))
        padded = np.pad(demand, (width // 2, width - 1 - width // 2), mode="edge")
        demand = np.convolve(padded, np.ones(width) / width, mode="valid")
    return demand



# ------------------------------------------------------------------------------------------
# running the plant


@dataclass(frozen=True)
class PlantRun:
    """One virtual-plant run (all SI: Pa, K, kg/s, W).

    ``true_inputs``: boundary conditions as the plant had them (measured main-steam flow, i.e.
    before leakage) plus ``load_demand`` (fraction), ``stage_flow`` (kg/s) and
    ``gland_leakage_fraction``; ``true_outputs``: the plant's true outputs incl. ``hp_power``
    and ``load``; ``measured``: what the DCS recorded (canonical signals incl. ``load``);
    ``injected``: the instruments' record; ``truth``: the hidden truth; ``scenario``: its name.
    """

    true_inputs: pd.DataFrame
    true_outputs: pd.DataFrame
    measured: pd.DataFrame
    injected: Injected
    truth: PlantTruth
    scenario: str = ""



def _boundary_conditions(spec: TurbineSpec, demand: np.ndarray, truth: PlantTruth
                         ) -> pd.DataFrame:
    """Boiler-side boundary conditions (SI) for a load-demand series sampled every 1 s."""
    point = steady_boundary(spec, demand, truth)
    pressure = first_order_lag(point["main_steam_pressure"], 1.0, PRESSURE_LAG_S)
    rate = np.abs(np.gradient(demand)) * 100.0 * 60.0  # %/min
    dip = first_order_lag(TEMPERATURE_DIP_PER_RATE * rate, 1.0, TEMPERATURE_LAG_S, hold="zero")
    index = pd.date_range(START, periods=demand.size, freq="1s")
    return pd.DataFrame({
        "main_steam_pressure": pressure,
        "main_steam_temperature": point["main_steam_temperature"] - dip,
        "main_steam_flow": point["main_steam_flow"],
        "hp_exhaust_pressure": point["hp_exhaust_pressure"],
    }, index=index)



def plant_sensor_models(truth: PlantTruth) -> dict[str, SensorModel]:
    """The plant's instruments: :func:`~steamtwin.dcs.sensors.default_sensor_models` with the
    casing thermocouple's sheath time constant of ``truth``."""
    models = default_sensor_models()
    casing = "hp_inner_casing_temperature"
    models[casing] = replace(models[casing], time_constant_s=truth.casing_sheath_time_constant)
    return models


def run_plant(scenario: str, *, hours: float | None = None, random_state: int = 0,
              truth: PlantTruth = PlantTruth(), progress: ProgressCallback | None = None,
              ramp_rate: float | None = None,
              instruments: pd.DataFrame | None = None,
              sensor_faults: Sequence[SensorFault] = ()) -> PlantRun:
    """Run the virtual plant through ``scenario`` (a key of :data:`SCENARIOS`).

    ``hours`` overrides the long hold (h); ``random_state`` seeds the instruments' generator;
    ``ramp_rate`` (%/min, 1–5) overrides the scenario's ramps; ``instruments``: an earlier
    run's ``injected.sensors`` — the same instruments (calibration errors and drift rates) on
    another day, with noise and faults drawn from ``random_state``; ``sensor_faults``: faults
    scheduled on purpose after the instruments (drift, bias step, stuck reading;
    :mod:`steamtwin.dcs.sensor_faults`), recorded in ``injected.faults``. Raises ``KeyError``
    listing the scenarios for an unknown name.
    """
    if scenario not in SCENARIOS:
        raise KeyError(f"unknown scenario {scenario!r}; known: {', '.join(SCENARIOS)}")

    def report(fraction: float, message: str) -> None:
        if progress is not None:
            progress(fraction, message)

    report(0.0, "boundary conditions")
    model = plant_model(truth)
    spec = model.spec
    demand = load_demand(SCENARIOS[scenario], hours=hours, ramp_rate=ramp_rate)
    inputs = _boundary_conditions(spec, demand, truth)
    report(0.1, "plant design (its own metal, valves and clearances)")
    schedule = None
    if truth.drift is not None:
        schedule = truth.drift.schedule(truth.parameters, np.arange(demand.size, dtype=float))
        schedule.index = inputs.index
    outputs, leakage = run_leaking(model, inputs, truth, schedule, report=report)
    flow = inputs["main_steam_flow"].to_numpy()
    outputs = outputs.assign(load=generator_power(outputs["hp_power"].to_numpy(), spec))
    true_inputs = inputs.assign(load_demand=demand, stage_flow=flow * (1.0 - leakage),
                                gland_leakage_fraction=leakage)
    if schedule is not None:  # the true parameters over time, for judging online calibration
        true_inputs = true_inputs.join(schedule.add_prefix("true_"))
    report(0.8, "instruments")
    sensed = [name for name in KKS_TAGS if name in spec.sensors]
    true_frame = inputs.join(outputs)[sensed]
    measurement = measure(true_frame, plant_sensor_models(truth),
                          np.random.default_rng(random_state), faults=truth.faults,
                          instruments=instruments)
    measured, injected = measurement.measured, measurement.injected
    if sensor_faults:
        measured, scheduled = apply_sensor_faults(measured, sensor_faults)
        injected = replace(injected, faults=pd.concat([injected.faults, scheduled],
                                                      ignore_index=True))
    report(1.0, "done")
    return PlantRun(true_inputs=true_inputs, true_outputs=outputs, measured=measured,
                    injected=injected, truth=truth, scenario=scenario)


# ------------------------------------------------------------------------------------------
# writing


def plant_tag_map(layout: str = "wide", time_zone: str = "Asia/Shanghai") -> TagMap:
    """The plant historian's tag map: KKS tags in wire units with valid ranges."""
    if layout not in ("wide", "long"):
        raise ValueError(f"layout must be 'wide' or 'long' (got {layout!r})")
    signals = {}
    for name, tag in KKS_TAGS.items():
        unit = SIGNALS[name].wire_unit
        low, high = _TAG_RANGES[name]
        si_low, si_high = convert([low, high], unit, SIGNALS[name].si_unit).tolist()
        signals[name] = TagSpec(signal=name, column=tag, unit=unit,
                                valid_range_si=(si_low, si_high))
    long = layout == "long"
    return TagMap(layout=layout, time_column="Timestamp", time_zone=time_zone,
                  tag_column="Tag" if long else None, value_column="Value" if long else None,
                  quality_column=None, signals=signals, source="tags.toml")


def _json_ready(frame: pd.DataFrame) -> list[dict[str, object]]:
    records = []
    for row in frame.reset_index().to_dict(orient="records"):
        clean: dict[str, object] = {}
        for key, value in row.items():
            if isinstance(value, pd.Timestamp):
                clean[str(key)] = value.isoformat()
            elif isinstance(value, float | np.floating):
                clean[str(key)] = float(value) if math.isfinite(value) else None
            elif isinstance(value, np.integer):
                clean[str(key)] = int(value)
            else:
                clean[str(key)] = value
        records.append(clean)
    return records


def structure_notes(truth: PlantTruth) -> list[str]:
    """How the plant of ``truth`` differs from the twin, one line each (for ``truth.json``)."""
    notes = [
        "metal: one group per stage (control stage alone; reference groups split evenly), "
        f"{PLANT_METAL_NODES} finite volumes per chain (twin: 4 groups, 8 volumes)",
        "HP front gland leakage from the control-stage chamber to cold reheat by Martin's "
        f"labyrinth formula (z = {GLAND_TEETH}); stage flow m*(1 - lambda), the DCS measures m",
        f"main-steam pressure lags the sliding-pressure setpoint (tau {PRESSURE_LAG_S:g} s)",
        f"main-steam temperature dips {TEMPERATURE_DIP_PER_RATE:g} K per %/min of ramp rate "
        f"(tau {TEMPERATURE_LAG_S:g} s)",
        "HP-exhaust pressure proportional to main-steam flow (operating_point)",
        f"load = P_HP / s - {FIXED_LOSS_W / 1e6:g} MW with constant HP share s (approximation)",
        "instruments: steamtwin.dcs.sensors.default_sensor_models() via measure(), casing "
        f"thermocouple sheath tau {truth.casing_sheath_time_constant:g} s",
    ]
    if any(clearance > 0.0 for clearance in truth.tip_clearances):
        notes.append("tip leakage over the shrouds of every pressure stage (Traupel), radial "
                     "clearances " + ", ".join(f"{c * 1e3:g}" for c in truth.tip_clearances)
                     + f" mm per stage group, z = {TIP_SEAL_STRIPS}; the heat balance is the "
                     "as-designed unit")
    if truth.valve_overlap > 0.0:
        notes.append(f"governing valves overlap by {truth.valve_overlap:g} of lift, poppet "
                     f"characteristic (full lift {truth.valve_lift_ratio:g} of seat diameter)")
    for name, schedule in (("main-steam", truth.main_steam_schedule),
                           ("hot-reheat", truth.reheat_schedule)):
        if schedule is not None:
            notes.append(f"{name} temperature schedule " + ", ".join(
                f"{t - 273.15:g} degC at {load:.0%}" for load, t in schedule))
    notes.append(f"casing thermocouple {truth.casing_thermocouple_depth * 1e3:g} mm under the "
                 "bore (twin: 14 mm)")
    if truth.graded_metal:
        notes.append(f"casing walls and rotors in volumes graded by {PLANT_GRID_STRETCH:g} from "
                     f"the steam side; rotors hollow, bore radius "
                     f"{truth.rotor_bore_radius * 1e3:g} mm, cylindrical-shell conductances")
    return notes


def write_plant(run: PlantRun, out_dir: str | Path, layout: str = "wide",
                file_format: str = "parquet") -> dict[str, Path]:
    """Write the historian export, its ``tags.toml`` and the ``truth/`` folder; return the paths.

    Historian: KKS tags in wire units (MPa, °C, t/h, MW), local time with UTC offset
    (Asia/Shanghai); ``layout`` ``"wide"`` or ``"long"``, ``file_format`` ``"parquet"`` or
    ``"csv"``. ``truth/`` holds ``true_signals.parquet`` (SI) and ``truth.json`` (hidden
    parameters, structure notes, instrument record and injected faults); the twin never reads it.
    """
    if file_format not in ("parquet", "csv"):
        raise ValueError(f"file_format must be 'parquet' or 'csv' (got {file_format!r})")
    tag_map = plant_tag_map(layout)
    out = Path(out_dir)
    truth_dir = out / "truth"
    truth_dir.mkdir(parents=True, exist_ok=True)
    wide = canonical_to_historian(run.measured, tag_map)
    if layout == "long":
        frame = wide.melt(id_vars=[tag_map.time_column], var_name="Tag", value_name="Value",
                          ignore_index=False)
        frame = frame.reset_index().sort_values(["index"], kind="stable").drop(columns="index")
        frame = frame.dropna(subset=["Value"]).reset_index(drop=True)
    else:
        frame = wide
    historian = out / f"historian.{file_format}"
    if file_format == "csv":
        frame.to_csv(historian, index=False)
    else:
        frame.to_parquet(historian, index=False)
    tags = out / "tags.toml"
    write_tag_map(tag_map, tags)

    true_signals = truth_dir / "true_signals.parquet"
    run.true_inputs.join(run.true_outputs).rename_axis("time").to_parquet(true_signals)
    document = {
        "scenario": run.scenario,
        "parameters": asdict(run.truth.parameters),
        "twin_equivalent_parameters": asdict(run.truth.twin_equivalent),
        "twin_equivalent_method": "noise-free fit of the twin's flow and friction coefficients "
        "to the plant's steady states at " + ", ".join(f"{load:.0%}" for load in
                                                       TWIN_EQUIVALENT_LOADS)
        + "; heat_transfer_coefficient carried over (steady states do not see it)",
        "gland_leakage_rated": run.truth.gland_leakage_rated,
        "plant_structure": {name: value for name, value in asdict(run.truth).items()
                            if name not in ("parameters", "gland_leakage_rated", "faults",
                                            "drift")},
        "tip_leakage_fractions": tip_leakage_fractions(
            load_spec("reference"), run.truth.tip_clearances).tolist(),
        "faults_config": asdict(run.truth.faults),
        "drift": None if run.truth.drift is None else asdict(run.truth.drift),
        "structure": structure_notes(run.truth),
        "sensors": _json_ready(run.injected.sensors),
        "injected_faults": _json_ready(run.injected.faults.set_index("signal")),
    }
    truth_json = truth_dir / "truth.json"
    truth_json.write_text(json.dumps(document, indent=2, ensure_ascii=False) + "\n",
                          encoding="utf-8")
    return {"historian": historian, "tag_map": tags, "true_signals": true_signals,
            "truth": truth_json}
