"""Virtual plant of the reference 600 MW unit: historian-style data the twin did not generate.

Demos and tests need DCS data that look like a real unit's, but data made by the twin's own model
structure would let calibration rediscover its own assumptions. The virtual plant therefore runs
the full-order model (FOM) with hidden parameters *and* a deliberately different structure, then
records the result through the instrument models of :mod:`steamtwin.dcs.sensors`.

Hidden truth (:class:`PlantTruth`, written to ``truth/`` only, never to the historian files):
``flow_coefficient`` 0.965 (deposits), ``friction_coefficient`` 1.3 (rough blading),
``heat_transfer_coefficient`` 1.4 (better than the Dittus–Boelter correlation).

Structural differences from the twin
    1. **Finer metal discretisation.** One metal group per stage (the control stage alone; each
       reference group's casing and rotor mass and wetted area split evenly over its stages)
       and 16 finite volumes per conduction chain instead of 8 (:class:`PlantModel`).
    2. **HP front gland leakage.** A share λ of the measured main-steam flow leaks from the
       control-stage chamber past the HP front-gland labyrinth to the cold-reheat line and never
       reaches the pressure stages: the plant runs the FOM with the stage flow m·(1 − λ) while
       the DCS measures m. The leakage follows Martin's labyrinth formula
       ``m_leak = A·sqrt(p1/v1)·sqrt((1 − (p2/p1)²)/(z − ln(p2/p1)))`` (Martin 1908; Traupel,
       *Thermische Turbomaschinen* Bd. 1, §9 Labyrinthdichtungen; Stodola 1927), i.e. ∝ p1/√T1
       at a given pressure ratio, with p1, T1 the control-stage state, p2 the HP-exhaust
       pressure and z = :data:`GLAND_TEETH` throttlings; the area A is set so that λ =
       :attr:`PlantTruth.gland_leakage_rated` (1.5 %) at the rated point. λ depends on the
       plant's own p1, so the FOM runs twice (fixed-point pass; the second pass changes λ by
       well under 0.1 % of flow).
    3. **Boiler dynamics on the boundary conditions.** The turbine follows the load demand L(t)
       with flow m = L·m_rated; main-steam pressure follows the sliding-pressure setpoint through
       a first-order lag (:data:`PRESSURE_LAG_S`, 120 s, boiler storage); main-steam temperature
       dips during load ramps by :data:`TEMPERATURE_DIP_PER_RATE` K per %/min of ramp rate,
       through a first-order lag of :data:`TEMPERATURE_LAG_S` (300 s), recovering likewise after
       the ramp (firing/spray mismatch); HP-exhaust pressure follows flow
       (:func:`~steamtwin.model.operating.operating_point`).
    4. **Instruments.** Lag, noise, bias, drift, quantisation, dropouts and spikes come from
       :func:`~steamtwin.dcs.sensors.measure` with
       :func:`~steamtwin.dcs.sensors.default_sensor_models`.

Generator output (``load``, W) is an approximation from the HP blading power:
``load = P_HP / s − P_loss`` with a constant HP share ``s = P_HP,rated / (P_gen,rated + P_loss)``
of the internal power (reference heat balance: 177.3 MW HP of 600 MW) and a load-independent
mechanical plus generator loss ``P_loss`` = :data:`FIXED_LOSS_W` (6 MW, 1 % of rating: bearings,
windage, generator iron losses; Cotton 1998 ch. 2). With sliding pressure the HP pressure ratio
stays nearly constant, so a constant HP share is a fair first approximation; it is not a heat
balance of the IP/LP sections.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.readers import canonical_to_historian
from steamtwin.dcs.sensors import (
    FaultConfig,
    Injected,
    default_sensor_models,
    first_order_lag,
    measure,
)
from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap, TagSpec, write_tag_map
from steamtwin.model.design import DesignConstants, kernel_constants
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import MetalGroup, TurbineSpec, load_spec
from steamtwin.units import convert

__all__ = [
    "FIXED_LOSS_W",
    "GLAND_TEETH",
    "KKS_TAGS",
    "PLANT_METAL_NODES",
    "PRESSURE_LAG_S",
    "SCENARIOS",
    "TEMPERATURE_DIP_PER_RATE",
    "TEMPERATURE_LAG_S",
    "ParameterDrift",
    "PlantModel",
    "PlantRun",
    "PlantTruth",
    "Scenario",
    "generator_power",
    "gland_leakage_fraction",
    "load_demand",
    "plant_spec",
    "plant_tag_map",
    "run_plant",
    "write_plant",
]

PLANT_METAL_NODES = 16
"""Finite volumes per metal conduction chain in the plant (the twin uses 8)."""
PRESSURE_LAG_S = 120.0
"""Time constant (s) of main-steam pressure following the sliding-pressure setpoint."""
TEMPERATURE_LAG_S = 300.0
"""Time constant (s) of the main-steam temperature dip and its recovery."""
TEMPERATURE_DIP_PER_RATE = 1.2
"""Main-steam temperature dip (K) per %/min of load ramp rate, once settled."""
GLAND_TEETH = 24
"""Throttlings z of the HP front-gland labyrinth (Martin's formula)."""
FIXED_LOSS_W = 6.0e6
"""Load-independent mechanical and generator losses (W) of the load relation."""
START = "2026-03-01T00:00:00Z"
"""First timestamp of every scenario (UTC)."""

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

ProgressCallback = Callable[[float, str], None]
"""``progress(fraction_done, message)``, fraction in 0…1."""


# ------------------------------------------------------------------------------------------
# truth and structure


@dataclass(frozen=True)
class ParameterDrift:
    """A change of the true parameters during a run: from the run's parameters to ``target``,
    linearly over ``over_hours`` starting ``at_hours`` after the start (e.g. deposits building up
    and lowering the flow coefficient; accelerated to hours so that one day can show it)."""

    at_hours: float
    over_hours: float
    target: ModelParameters

    def __post_init__(self) -> None:
        if not (math.isfinite(self.at_hours) and self.at_hours >= 0.0
                and math.isfinite(self.over_hours) and self.over_hours >= 0.0):
            raise ValueError("at_hours and over_hours must be finite and ≥ 0")

    def schedule(self, start: ModelParameters, seconds: np.ndarray) -> pd.DataFrame:
        """Parameters (columns of ModelParameters) at each time ``seconds`` after the start."""
        begin, duration = self.at_hours * 3600.0, self.over_hours * 3600.0
        share = (np.clip((seconds - begin) / duration, 0.0, 1.0) if duration > 0.0
                 else (seconds >= begin).astype(float))
        before, after = asdict(start), asdict(self.target)
        return pd.DataFrame({name: before[name] + share * (after[name] - before[name])
                             for name in before})


@dataclass(frozen=True)
class PlantTruth:
    """Hidden truth of the virtual plant.

    ``parameters``: the FOM parameters of the real unit; ``gland_leakage_rated``: HP front-gland
    leakage as a fraction of main-steam flow at rated load; ``faults``: fault injection of the
    instruments (:class:`~steamtwin.dcs.sensors.FaultConfig`); ``drift``: an optional change
    of the parameters during the run (:class:`ParameterDrift`).
    """

    parameters: ModelParameters = field(default_factory=lambda: ModelParameters(
        flow_coefficient=0.965, friction_coefficient=1.3, heat_transfer_coefficient=1.4))
    gland_leakage_rated: float = 0.015
    faults: FaultConfig = field(default_factory=FaultConfig)
    drift: ParameterDrift | None = None

    def __post_init__(self) -> None:
        if not 0.0 <= self.gland_leakage_rated < 0.1:
            raise ValueError("gland_leakage_rated must lie within [0, 0.1)")

    @property
    def twin_equivalent(self) -> ModelParameters:
        """The parameters with which the twin, which has no gland leakage, matches this plant.

        The twin is fed the measured flow m, of which λ leaks past the stages; Stodola's law
        m·(1 − λ) = φ·K·sqrt(…) reads m = φ/(1 − λ)·K·sqrt(…) to the twin, so the flow coefficient
        it can identify is φ/(1 − λ) (λ at rated load; it varies by < 0.05 % of flow with load).
        Friction and heat-transfer coefficients carry over unchanged.
        """
        return replace(self.parameters, flow_coefficient=self.parameters.flow_coefficient
                       / (1.0 - self.gland_leakage_rated))


def plant_spec(spec: TurbineSpec) -> TurbineSpec:
    """The plant's spec: one metal group per stage, each group's mass and area (and axial length
    when it is drawn) split evenly."""
    groups: list[MetalGroup] = []
    for group in spec.metal_groups:
        if len(group.stages) == 1:
            groups.append(group)
            continue
        share = 1.0 / len(group.stages)
        geometry = None if group.geometry is None else replace(
            group.geometry, axial_length=group.geometry.axial_length * share)
        for stage in group.stages:
            groups.append(replace(
                group, name=f"{group.name} / stage {stage}", stages=(stage,),
                casing_mass=group.casing_mass * share, casing_area=group.casing_area * share,
                rotor_mass=group.rotor_mass * share, rotor_area=group.rotor_area * share,
                geometry=geometry))
    return replace(spec, metal_groups=tuple(groups))


class PlantModel(FullOrderModel):
    """The FOM with :data:`PLANT_METAL_NODES` finite volumes per metal chain.

    The efficiency scale is solved as in :class:`FullOrderModel` (at steady state the node
    count only changes the small heat loss through the lagging); the final constants are built
    with the finer chains.
    """

    metal_nodes = PLANT_METAL_NODES

    @cached_property
    def design_(self) -> DesignConstants:
        """Kernel constants with the finer metal chains (see the class doc)."""
        control_stage_pressure = self.spec.design.control_stage_pressure
        for _ in range(2):
            scale = self._solve_efficiency_scale(control_stage_pressure)
            constants = kernel_constants(self.spec, scale, control_stage_pressure,
                                         metal_nodes=self.metal_nodes)
            diagnostics = self._design_run(constants)
            control_stage_pressure = float(diagnostics["control_stage_pressure"].iloc[0])
        return DesignConstants(kernel=constants, efficiency_scale=scale)


def _martin(p1: np.ndarray, t1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """Martin's labyrinth flow per unit area and per sqrt(R): ∝ p1/√T1 · ψ(p2/p1, z)."""
    ratio = np.clip(p2 / p1, 1e-6, 0.999)
    return p1 / np.sqrt(t1) * np.sqrt((1.0 - ratio**2) / (GLAND_TEETH - np.log(ratio)))


def gland_leakage_fraction(p1: np.ndarray, t1: np.ndarray, p_exhaust: np.ndarray,
                           flow: np.ndarray, rated: dict[str, float],
                           leakage_rated: float) -> np.ndarray:
    """Leakage share λ of main-steam ``flow`` (kg/s) by Martin's formula (see module doc).

    ``p1``/``t1`` control-stage pressure (Pa) and temperature (K), ``p_exhaust`` (Pa); ``rated``
    holds the same four quantities at the rated point (keys ``p1``, ``t1``, ``p_exhaust``,
    ``flow``), where λ equals ``leakage_rated``.
    """
    reference = _martin(np.array([rated["p1"]]), np.array([rated["t1"]]),
                        np.array([rated["p_exhaust"]]))[0]
    leak = leakage_rated * rated["flow"] * _martin(p1, t1, p_exhaust) / reference
    return np.clip(leak / flow, 0.0, 0.1)


def generator_power(hp_power: np.ndarray | float, spec: TurbineSpec) -> np.ndarray:
    """Approximate generator output (W) from HP blading power (W); see the module doc."""
    design = spec.design
    share = design.hp_power / (design.generator_power + FIXED_LOSS_W)
    return np.asarray(hp_power, dtype=float) / share - FIXED_LOSS_W


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


def _boundary_conditions(spec: TurbineSpec, demand: np.ndarray) -> pd.DataFrame:
    """Boiler-side boundary conditions (SI) for a load-demand series sampled every 1 s."""
    point = operating_point(spec, demand)
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


def run_plant(scenario: str, *, hours: float | None = None, seed: int = 0,
              truth: PlantTruth = PlantTruth(), progress: ProgressCallback | None = None,
              ramp_rate: float | None = None) -> PlantRun:
    """Run the virtual plant through ``scenario`` (a key of :data:`SCENARIOS`).

    ``hours`` overrides the long hold (h); ``seed`` seeds the instruments' generator;
    ``ramp_rate`` (%/min, 1–5) overrides the scenario's ramps. Raises ``KeyError`` listing the
    scenarios for an unknown name.
    """
    if scenario not in SCENARIOS:
        raise KeyError(f"unknown scenario {scenario!r}; known: {', '.join(SCENARIOS)}")

    def report(fraction: float, message: str) -> None:
        if progress is not None:
            progress(fraction, message)

    report(0.0, "boundary conditions")
    spec = plant_spec(load_spec("reference"))
    demand = load_demand(SCENARIOS[scenario], hours=hours, ramp_rate=ramp_rate)
    inputs = _boundary_conditions(spec, demand)
    model = PlantModel(spec)
    report(0.1, "plant design (finer metal chains)")
    rated = model.simulate(model.design_inputs(), truth.parameters).iloc[0]
    design = spec.design
    rated_state = {"p1": float(rated["control_stage_pressure"]),
                   "t1": float(rated["control_stage_temperature"]),
                   "p_exhaust": design.hp_exhaust_pressure, "flow": design.main_steam_flow}
    flow = inputs["main_steam_flow"].to_numpy()
    leakage = np.full(flow.size, truth.gland_leakage_rated)
    schedule = None
    if truth.drift is not None:
        schedule = truth.drift.schedule(truth.parameters, np.arange(flow.size, dtype=float))
        schedule.index = inputs.index
    outputs = pd.DataFrame()
    for k in range(2):  # fixed-point pass on the leakage, which depends on p1 and T1
        report(0.2 + 0.3 * k, f"plant run, pass {k + 1} of 2")
        stage_inputs = inputs.assign(main_steam_flow=flow * (1.0 - leakage))
        if schedule is None:
            outputs = model.simulate(stage_inputs, truth.parameters)
        else:
            outputs = model.simulate_varying(stage_inputs, schedule).outputs
        leakage = gland_leakage_fraction(
            outputs["control_stage_pressure"].to_numpy(),
            outputs["control_stage_temperature"].to_numpy(),
            inputs["hp_exhaust_pressure"].to_numpy(), flow, rated_state,
            truth.gland_leakage_rated)
    outputs = outputs.assign(load=generator_power(outputs["hp_power"].to_numpy(), spec))
    true_inputs = inputs.assign(load_demand=demand, stage_flow=flow * (1.0 - leakage),
                                gland_leakage_fraction=leakage)
    if schedule is not None:  # the true parameters over time, for judging online calibration
        true_inputs = true_inputs.join(schedule.add_prefix("true_"))
    report(0.8, "instruments")
    sensed = [name for name in KKS_TAGS if name in spec.sensors]
    true_frame = inputs.join(outputs)[sensed]
    measurement = measure(true_frame, default_sensor_models(), np.random.default_rng(seed),
                          faults=truth.faults)
    report(1.0, "done")
    return PlantRun(true_inputs=true_inputs, true_outputs=outputs,
                    measured=measurement.measured, injected=measurement.injected, truth=truth,
                    scenario=scenario)


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


STRUCTURE_NOTES = (
    "metal: one group per stage (control stage alone; reference groups split evenly), "
    f"{PLANT_METAL_NODES} finite volumes per chain (twin: 4 groups, 8 volumes)",
    "HP front gland leakage from the control-stage chamber to cold reheat by Martin's labyrinth "
    f"formula (z = {GLAND_TEETH}); stage flow m*(1 - lambda), the DCS measures m",
    f"main-steam pressure lags the sliding-pressure setpoint (tau {PRESSURE_LAG_S:g} s)",
    f"main-steam temperature dips {TEMPERATURE_DIP_PER_RATE:g} K per %/min of ramp rate "
    f"(tau {TEMPERATURE_LAG_S:g} s)",
    "HP-exhaust pressure proportional to main-steam flow (operating_point)",
    f"load = P_HP / s - {FIXED_LOSS_W / 1e6:g} MW with constant HP share s (approximation)",
    "instruments: steamtwin.dcs.sensors.default_sensor_models() via measure()",
)


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
        "gland_leakage_rated": run.truth.gland_leakage_rated,
        "faults_config": asdict(run.truth.faults),
        "drift": None if run.truth.drift is None else asdict(run.truth.drift),
        "structure": list(STRUCTURE_NOTES),
        "sensors": _json_ready(run.injected.sensors),
        "injected_faults": _json_ready(run.injected.faults.set_index("signal")),
    }
    truth_json = truth_dir / "truth.json"
    truth_json.write_text(json.dumps(document, indent=2, ensure_ascii=False) + "\n",
                          encoding="utf-8")
    return {"historian": historian, "tag_map": tags, "true_signals": true_signals,
            "truth": truth_json}
