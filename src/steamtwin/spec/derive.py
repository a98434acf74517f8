"""Derive a complete turbine spec from an OEM thermal kit (heat-balance points).

Kept as one module because the derivation writes each figure with the comment saying how it
was obtained in the same step (the TOML blocks at the end compute the metal, sliding-pressure
and temperature figures as they write them), so the rules, the derived figures and their
commented text share every intermediate value.

A plant engineer starts from the heat-balance diagrams, not from a stage table. This module turns
a validated :class:`~steamtwin.spec.heat_balance.HeatBalance` into the TOML text of a complete
spec (``docs/spec.md``), every derived figure followed by a comment saying how it was obtained:
the heat-balance point and field it comes from, or the rule and its source. The rules are listed
in ``docs/heat-balance.md`` ("Deriving a spec from a heat balance"); in short:

* **Design point**: the point labelled "THA"; else the point whose load is
  ``machine.rated_load``; else the highest load, skipping a first point labelled "VWO".
* **Control stage**: the machine's mean diameter; impulse blading as in the reference unit; its
  blade efficiency from the design point's control-stage temperature (IAPWS-IF97), less the
  partial-admission losses the model adds (Kang et al.); the valves open at design are all but
  the last opening group (the overload reserve).
* **Pressure stages**: the expansion from the design point's control-stage state to its HP-exhaust
  pressure over ``machine.pressure_stages`` stages at a common velocity ratio u/c0 with a constant
  root diameter (:func:`expand_pressure_stages`); the root diameter and the common stage
  efficiency are solved together so that the expansion ends at the point's HP-exhaust pressure
  and temperature; Stodola flow capacities, mean diameters and blade heights (continuity) follow.
* **Steam-temperature schedule**: every point's main-steam temperature and, if every point
  gives one, hot-reheat temperature against its load / design load (``[temperature_schedule]``).
* **Metal**: written as drawn geometry: the rotor a drum of the blading's root radius (solid
  unless the kit gives its bore), the inner casing a cylindrical wall beyond the blade tips of
  the kit's wall thickness, else the thin-wall hoop-stress thickness at an allowable stress of a
  Cr-Mo steel.

Every value is checked against the spec's ranges (:data:`steamtwin.spec.schema.FIELD_BY_KEY`):
nothing is clamped; a value out of range raises :class:`DeriveError` naming the heat-balance
point and field responsible. Uses IAPWS-IF97 (:mod:`steamtwin.steam.if97`) only, not the model.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from steamtwin.errors import SpecAreaError
from steamtwin.spec.heat_balance import HeatBalance, HeatBalancePoint
from steamtwin.spec.loader import SpecError, parse_spec
from steamtwin.spec.schema import FIELD_BY_KEY, FORMAT_VERSION, METAL_DEPTH_RANGE_M
from steamtwin.steam import if97

__all__ = ["DeriveError", "DerivedSpec", "StageRow", "derive_spec", "design_point_of",
           "expand_pressure_stages"]

# --- rules and their sources -------------------------------------------------------------------
#: Stop- plus governing-valve loss when wide open, share of the throttle pressure: 2-4 % [Cotton,
#: Evaluating and Improving Steam Turbine Performance, 1998, ch. 6]; taken when the kit gives
#: neither machine.valve_pressure_drop nor a VWO point's valve_outlet_pressure.
VALVE_PRESSURE_DROP = 0.03
#: A design point's valve outlet pressure this far (share of the main-steam pressure) below the
#: wide-open valve outlet makes the rated point one between valve points; closer, it is taken
#: as the valve point itself (the kit's rounding).
VALVE_POINT_TOLERANCE = 1e-3
#: Control stage: impulse blading with slight reaction, 13 deg nozzles (11-15 deg usual), friction
#: share 0.03, nozzle discharge coefficient 0.97 (0.95-0.98) [Traupel, Thermische
#: Turbomaschinen, 2001, §8; Cotton ch. 6] — the reference unit's figures.
CONTROL_REACTION = 0.05
CONTROL_NOZZLE_ANGLE = math.radians(13.0)
CONTROL_FRICTION_LOSS = 0.03
NOZZLE_DISCHARGE_COEFFICIENT = 0.97
#: Peak blade efficiency of an impulse stage when the kit gives no control-stage temperature:
#: ~cos²(α1) less blade losses [Dixon & Hall, Fluid Mechanics and Thermodynamics of
#: Turbomachinery, 2014, ch. 4].
CONTROL_PEAK_EFFICIENCY = 0.86
#: Pressure stages: 30 % reaction, 16 deg stators (14-20 deg usual), friction share 0.025
#: [Traupel] — the reference unit's figures.
STAGE_REACTION = 0.3
STAGE_NOZZLE_ANGLE = math.radians(16.0)
STAGE_FRICTION_LOSS = 0.025
#: Common velocity ratio u/c0 of the pressure stages at design: the reference unit's 0.642
#: (x = ν/ν_opt = 1.12, just above the optimum of its reaction blading, where HP reaction
#: stages are designed for a flat efficiency curve [Traupel, §8]).
STAGE_VELOCITY_RATIO = 0.642
#: Mean blade pitch (m) for the blade counts: the reference unit's ~31 mm control stage and
#: ~33 mm pressure stages (HP blading of 600 MW units).
CONTROL_BLADE_PITCH = 0.0314
STAGE_BLADE_PITCH = 0.033
#: Partial-admission losses of the control stage (Kang et al., Principles of Steam Turbines,
#: §3.5; the constants of steamtwin's model): idle-arc windage B_e, sector-end C_e (m) and disc
#: friction 1e-3·K1.
WINDAGE_CONSTANT = 0.15
SECTOR_END_CONSTANT = 0.012
DISC_FRICTION_CONSTANT = 1.05e-3
#: Metal. Axial length wetted per pressure stage (stator + rotor row with gaps) and of the
#: control-stage wheel with its nozzle chamber, m: engineering assumptions for HP blading of
#: this class (rows of 40-60 mm chord).
STAGE_AXIAL_PITCH = 0.15
CONTROL_STAGE_AXIAL_LENGTH = 0.30
#: Radial distance from the blade tips to the inner-casing bore (tip seals, stator shrouds), m.
BORE_CLEARANCE = 0.05
#: Allowable stress of the inner-casing steel at its design temperature, Pa: 2¼Cr-1Mo cast steel
#: (SA-217 WC9 class) near 538 °C, about 7.8 ksi, creep-governed [ASME BPVC II-D, Table 1A];
#: thin-wall hoop stress t = p·r/S.
CASING_ALLOWABLE_STRESS = 54e6
#: Pressure stages per metal group (the reference unit groups them by four).
STAGES_PER_GROUP = 4
#: Depth of the DCS casing thermocouple under the inner-casing bore, m: an assumed installation
#: depth near the steam-side surface (the spec's default, the reference unit's).
CASING_THERMOCOUPLE_DEPTH = 0.014
#: Lagging conductance, W/(m²·K): designed for ~0.3 kW/m² at ~500 K over ambient (ASTM C680).
INSULATION_CONDUCTANCE = 0.6
#: Low-alloy Cr-Mo-V steel near 500 °C [ASME II-D Table TCD, Group C]: k ~ 34 W/(m K),
#: diffusivity ~ 7.3e-6 m²/s, ρ = 7800 kg/m³ → c ~ 600 J/(kg K).
STEEL_DENSITY, STEEL_SPECIFIC_HEAT, STEEL_CONDUCTIVITY = 7800.0, 600.0, 34.0
#: Turbine-hall air around the lagging, K (30-40 °C typical).
AMBIENT_TEMPERATURE = 308.15
#: The standard DCS point list of an HP section (canonical signal names).
SENSORS = ("main_steam_pressure", "main_steam_temperature", "main_steam_flow",
           "control_stage_pressure", "control_stage_temperature", "hp_exhaust_pressure",
           "hp_exhaust_temperature", "hp_inner_casing_temperature", "load")
#: A bleed within this share of the HP-exhaust pressure is taken from cold reheat (after the HP).
COLD_REHEAT_TOLERANCE = 0.01
#: Pressure the HP–IP gland discharges into (the IP inlet), as a share of the HP-exhaust
#: pressure: the reheater and its piping lose ~10 % of the cold-reheat pressure, the usual
#: heat-balance allowance (an engineering assumption to review against the kit; below ~0.3 of
#: the control-stage pressure the seal's flow barely depends on it [Egli 1935]).
GLAND_SINK_RATIO = 0.9
#: Isentropic exponent of superheated steam, for the first guess of a stage's outlet pressure.
_KAPPA = 1.3


class DeriveError(SpecAreaError):
    """A heat balance from which no valid spec can be derived; the message names the point and
    the field responsible."""


@dataclass(frozen=True)
class DerivedSpec:
    """The derived spec: ``toml`` (complete, commented) and ``notes`` on what was assumed."""

    toml: str
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class StageRow:
    """One pressure stage of a design expansion, SI."""

    inlet_pressure_pa: float
    outlet_pressure_pa: float
    inlet_enthalpy_j_kg: float
    outlet_enthalpy_j_kg: float
    flow_kg_s: float  #: steam through the stage
    mean_diameter_m: float
    blade_height_m: float  #: from continuity at the stator exit
    flow_capacity_m2: float  #: Stodola K = m/sqrt((p_in² − p_out²)/(p_in·v_in))


def _f(value: object) -> float:
    return float(value)  # type: ignore[arg-type]  # the if97 functions return 0-d arrays


def _outlet_pressure(p_in: float, h_in: float, s_in: float, pv_in: float, drop: float) -> float:
    """Pressure (Pa) where the isentrope from (p_in, s_in) has fallen ``drop`` J/kg (Newton on
    dh/dp|s = v)."""
    base = 1.0 - drop * (_KAPPA - 1.0) / (_KAPPA * pv_in)
    pressure = p_in * max(base, 0.05) ** (_KAPPA / (_KAPPA - 1.0))
    target = h_in - drop
    for _ in range(8):
        h = _f(if97.enthalpy_ps(pressure, s_in))
        step = (h - target) / _f(if97.specific_volume_ph(pressure, h))
        pressure = max(pressure - step, 0.5 * pressure)
        if abs(step) < 1e-9 * pressure:
            break
    return pressure


def expand_pressure_stages(inlet_pressure_pa: float, inlet_enthalpy_j_kg: float,
                           stage_flows_kg_s: Sequence[float], speed_rad_s: float,
                           root_diameter_m: float, velocity_ratio: float, efficiency: float,
                           heights_m: Sequence[float] | None = None,
                           floor_pressure_pa: float = 0.0) -> list[StageRow] | None:
    """March the pressure stages at a common velocity ratio with a constant root diameter.

    Stage i has mean diameter D = root + l_i, isentropic drop ½(u/ν)² with u = ω·D/2, actual
    drop ``efficiency`` times that (IAPWS-IF97); its blade height l_i follows from continuity at
    the stator exit, m·v_out = π·D·l·c1·sin α1 with c1 = sqrt(2(1 − R)Δh_s) (R, α1: the pressure
    stages' reaction and stator angle). Heights and diameters are iterated to agreement, starting
    from ``heights_m`` (default 0.1 m). ``stage_flows_kg_s``: the flow through each stage (its
    length is the number of stages). Returns None when the expansion falls below
    ``floor_pressure_pa`` or leaves the steam tables (the diameter is too large).
    """
    count = len(stage_flows_kg_s)
    heights = list(heights_m) if heights_m is not None else [0.1] * count
    rows: list[StageRow] = []
    for _ in range(30):
        rows = []
        p_in, h_in = inlet_pressure_pa, inlet_enthalpy_j_kg
        try:
            v_in = _f(if97.specific_volume_ph(p_in, h_in))
            for flow, height in zip(stage_flows_kg_s, heights, strict=True):
                diameter = root_diameter_m + height
                drop = 0.5 * (speed_rad_s * diameter / 2.0 / velocity_ratio) ** 2
                s_in = _f(if97.entropy_ph(p_in, h_in))
                p_out = _outlet_pressure(p_in, h_in, s_in, p_in * v_in, drop)
                if p_out <= floor_pressure_pa:
                    return None
                h_out = h_in - efficiency * drop
                v_out = _f(if97.specific_volume_ph(p_out, h_out))
                c1 = math.sqrt(2.0 * (1.0 - STAGE_REACTION) * drop)
                rows.append(StageRow(
                    p_in, p_out, h_in, h_out, flow, diameter,
                    flow * v_out / (math.pi * diameter * c1 * math.sin(STAGE_NOZZLE_ANGLE)),
                    flow / math.sqrt((p_in**2 - p_out**2) / (p_in * v_in))))
                p_in, h_in, v_in = p_out, h_out, v_out
        except ValueError:  # SteamPropertyError: left the tables
            return None
        new = [row.blade_height_m for row in rows]
        change = max(abs(a - b) for a, b in zip(new, heights, strict=True))
        heights = new
        if change < 1e-6:
            break
    return rows


def design_point_of(heat_balance: HeatBalance) -> tuple[int, str]:
    """Index of the design (rated) point in ``heat_balance.points`` and the rule that chose it.

    The point labelled "THA" (case ignored); else the point whose load equals
    ``machine.rated_load`` (within 0.1 %); else the highest load, skipping a first point
    labelled "VWO" when there are others.
    """
    points = heat_balance.points
    for index, point in enumerate(points):
        if point.label.strip().upper() == "THA":
            return index, 'the point labelled "THA"'
    rated = heat_balance.machine.rated_load_w
    if rated is not None:
        for index, point in enumerate(points):
            if abs(point.load_w / rated - 1.0) <= 1e-3:
                return index, "the point at machine.rated_load"
    if len(points) > 1 and points[0].label.strip().upper() == "VWO":
        return 1, 'the highest load below the point labelled "VWO"'
    return 0, "the highest load (no THA label, no machine.rated_load point)"


@dataclass(frozen=True)
class _Valves:
    """The governing valves' pressure drops at the design point (SI)."""

    drop: float  # wide-open stop + governing valve loss, share of the main-steam pressure
    drop_how: str  # where the drop comes from, for the spec's comment
    drop_origin: str  # the heat-balance field responsible, for errors
    design_outlet: float | None  # nozzle-chest pressure at design between valve points, Pa

    def outlet(self, point: HeatBalancePoint) -> float:
        """Pressure (Pa) after the valves open at design, at the design point."""
        return (self.design_outlet if self.design_outlet is not None
                else point.main_steam_pressure_pa * (1.0 - self.drop))


def _valves(hb: HeatBalance, point: HeatBalancePoint, where: str) -> _Valves:
    """The wide-open valve drop (machine data, a VWO point, or the rule) and whether the rated
    point lies between valve points (its valve outlet below the wide-open one)."""
    drop, how, origin = (VALVE_PRESSURE_DROP, "rule: wide-open stop + governing valve loss, "
                         "2-4 % [Cotton ch. 6]; the kit does not give it", "valve_pressure_drop")
    vwo = next((number for number, candidate in enumerate(hb.points, start=1)
                if candidate.label.strip().upper() == "VWO"
                and candidate.valve_outlet_pressure_pa is not None), None)
    if hb.machine.valve_pressure_drop is not None:
        drop, how = hb.machine.valve_pressure_drop, "machine.valve_pressure_drop"
        origin = "machine: valve_pressure_drop"
    elif vwo is not None:
        wide = hb.points[vwo - 1]
        drop = 1.0 - wide.valve_outlet_pressure_pa / wide.main_steam_pressure_pa
        how = "VWO: 1 - valve_outlet_pressure / main_steam_pressure (valves wide open)"
        origin = f"points[{vwo}] ('VWO'): valve_outlet_pressure"
    outlet = point.valve_outlet_pressure_pa
    p0 = point.main_steam_pressure_pa
    if outlet is not None and outlet > p0 * (1.0 - drop) * (1.0 + VALVE_POINT_TOLERANCE):
        raise DeriveError(
            f"{where}: valve_outlet_pressure = {outlet / 1e6:.4g} MPa is above the wide-open "
            f"valve outlet {p0 * (1.0 - drop) / 1e6:.4g} MPa ({how} = {drop:.4g}): check the "
            "point's valve outlet pressure or the valve pressure drop")
    throttled = outlet is not None and outlet < p0 * (1.0 - drop - VALVE_POINT_TOLERANCE)
    return _Valves(drop, how, origin, outlet if throttled else None)


# --- formatting --------------------------------------------------------------------------------

def _mpa(value: float) -> str:
    return f'"{value / 1e6:.5g} MPa"'


def _degc(value: float) -> str:
    return f'"{value - 273.15:.2f} degC"'


def _t_h(value: float) -> str:
    return f'"{value * 3.6:.5g} t/h"'


def _mw(value: float) -> str:
    return f'"{value / 1e6:.5g} MW"'


def _metres(value: float) -> str:
    return f'"{value:.4f} m"'


class _Writer:
    """Collects TOML lines; each value is range-checked against the schema before it is kept."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.lines: list[str] = []

    def raw(self, text: str = "") -> None:
        self.lines.append(text)

    def value(self, key: str, schema_key: str, si_value: float, text: str, comment: str,
              origin: str) -> None:
        """``key = text  # comment`` after checking ``si_value`` against ``schema_key``'s range;
        ``origin`` names the heat-balance point/field responsible in the error."""
        spec_field = FIELD_BY_KEY[schema_key]
        if not spec_field.contains(si_value):
            where = origin if origin.startswith(self.source) else f"{self.source}: {origin}"
            raise DeriveError(
                f"{where}: the derived {schema_key} = {text.strip(chr(34))} is "
                f"outside the spec's range {spec_field.range_text(display=True)}")
        line = f"{key} = {text}"
        self.lines.append(f"{line:<40} # {comment}")

    @property
    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


# --- the derivation ----------------------------------------------------------------------------

def _optimum_ratio(angle: float, reaction: float) -> float:
    """ν_opt = cos α1 / (2·sqrt(1 − R)) [Dixon & Hall, ch. 4] — the model's efficiency law."""
    return math.cos(angle) / (2.0 * math.sqrt(1.0 - reaction))


def _parabola(velocity_ratio: float, optimum: float) -> float:
    x = velocity_ratio / optimum
    return x * (2.0 - x)


@dataclass
class _ControlStage:
    p_valve: float
    h_out: float
    drop: float  # isentropic, valve outlet to control-stage pressure, J/kg
    efficiency: float  # actual, as the kit says (or by rule)
    peak: float
    height: float
    velocity_ratio: float
    open_arc: float
    origin: str


def _control_stage(hb: HeatBalance, point: HeatBalancePoint, where: str, valves: _Valves,
                   open_valves: int, open_arc: float, notes: list[str]) -> _ControlStage:
    machine = hb.machine
    p0, t0, flow = (point.main_steam_pressure_pa, point.main_steam_temperature_k,
                    point.main_steam_flow_kg_s)
    h0 = _f(if97.enthalpy_pt(p0, t0))
    p_valve = valves.outlet(point)
    p_cs = point.control_stage_pressure_pa
    if not p_cs < p_valve:
        raise DeriveError(
            f"{where}: control_stage_pressure = {p_cs / 1e6:.4g} MPa is not below the pressure "
            f"after the wide-open valves ({p_valve / 1e6:.4g} MPa, a {valves.drop:.1%} "
            "valve drop from main_steam_pressure)")
    drop = h0 - _f(if97.enthalpy_ps(p_cs, if97.entropy_ph(p_valve, h0)))
    speed = machine.rotational_speed_rad_s * machine.control_stage_mean_diameter_m / 2.0
    ratio = speed / math.sqrt(2.0 * drop)
    optimum = _optimum_ratio(CONTROL_NOZZLE_ANGLE, CONTROL_REACTION)
    c1 = math.sqrt(2.0 * (1.0 - CONTROL_REACTION) * drop)
    diameter = machine.control_stage_mean_diameter_m
    # continuity at the nozzle exit of the arc open at design, state at the chamber
    h_guess = h0 - 0.7 * drop
    height = flow * _f(if97.specific_volume_ph(p_cs, h_guess)) / (
        math.pi * diameter * open_arc * c1 * math.sin(CONTROL_NOZZLE_ANGLE))
    if point.control_stage_temperature_k is not None:
        h_out = _f(if97.enthalpy_pt(p_cs, point.control_stage_temperature_k))
        efficiency = (h0 - h_out) / drop
        origin = f"{where}: control_stage_temperature"
        if not 0.0 < efficiency < 1.0:
            raise DeriveError(
                f"{origin} = {point.control_stage_temperature_k - 273.15:.1f} °C implies a "
                f"control-stage efficiency of {efficiency:.3f} over the isentropic drop from the "
                "valve outlet; expected between 0 and 1")
        density = 1.0 / _f(if97.specific_volume_ph(p_cs, h_out))
        losses = _partial_admission_loss(density, speed, diameter, height, open_arc,
                                         open_valves, ratio, flow, drop)
        peak = (efficiency + CONTROL_FRICTION_LOSS + losses) / _parabola(ratio, optimum)
    else:
        origin = f"{where}: main_steam_pressure, control_stage_pressure (no control-stage "\
                 "temperature)"
        peak = CONTROL_PEAK_EFFICIENCY
        density = 1.0 / _f(if97.specific_volume_ph(p_cs, h_guess))
        losses = _partial_admission_loss(density, speed, diameter, height, open_arc,
                                         open_valves, ratio, flow, drop)
        efficiency = peak * _parabola(ratio, optimum) - CONTROL_FRICTION_LOSS - losses
        h_out = h0 - efficiency * drop
        notes.append(f"{point.label}: no control_stage_temperature; the control stage is given "
                     f"the peak blade efficiency {peak:g} (impulse-stage rule), an efficiency "
                     f"of {efficiency:.3f} at design")
    return _ControlStage(p_valve, h_out, drop, efficiency, peak, height, ratio, open_arc, origin)


def _partial_admission_loss(density: float, speed: float, diameter: float, height: float,
                            arc: float, segments: int, ratio: float, flow: float,
                            drop: float) -> float:
    """Sector-end, idle-arc windage and disc-friction losses as a share of the isentropic drop
    (Kang et al. §3.5, as the model counts them at a valve point)."""
    sector_end = SECTOR_END_CONSTANT * segments / (arc * diameter) * ratio
    windage_area = WINDAGE_CONSTANT * math.pi * math.sin(CONTROL_NOZZLE_ANGLE) * diameter \
        * height / 2.0
    windage = windage_area * (1.0 - arc) * density * speed**3
    disc = DISC_FRICTION_CONSTANT * density * speed**3 * diameter**2
    return sector_end + (windage + disc) / (flow * drop)


@dataclass
class _Expansion:
    rows: list[StageRow]
    root_diameter: float
    efficiency: float
    bleed_after: list[int]  # per HP bleed, 1-based stage


def _stage_flows(flow: float, count: int, bleeds: Sequence[float], after: Sequence[int]
                 ) -> list[float]:
    flows, current = [], flow
    for stage in range(1, count + 1):
        flows.append(current)
        current -= sum(b for b, a in zip(bleeds, after, strict=True) if a == stage)
    return flows


def _solve_expansion(hb: HeatBalance, point: HeatBalancePoint, where: str, h_cs: float,
                     bleeds: Sequence[tuple[str, float, float]], leak: float = 0.0
                     ) -> _Expansion:
    """Root diameter and stage efficiency putting the expansion's end on the point's HP-exhaust
    pressure and temperature (2×2 Newton with finite differences), bleeds re-placed until they
    sit after the stage whose outlet pressure is nearest theirs."""
    machine = hb.machine
    count = machine.pressure_stages
    omega = machine.rotational_speed_rad_s
    p_cs, p_exh = point.control_stage_pressure_pa, point.hp_exhaust_pressure_pa
    h_exh = _f(if97.enthalpy_pt(p_exh, point.hp_exhaust_temperature_k))
    s_cs = _f(if97.entropy_ph(p_cs, h_cs))
    total_drop = h_cs - _f(if97.enthalpy_ps(p_exh, s_cs))
    efficiency = (h_cs - h_exh) / total_drop
    if not 0.3 < efficiency < 1.0:
        raise DeriveError(
            f"{where}: hp_exhaust_temperature = {point.hp_exhaust_temperature_k - 273.15:.1f} °C"
            f" implies an efficiency of {efficiency:.3f} from the control-stage state to the "
            "HP exhaust; expected between 0.3 and 1")
    mean = 2.0 * STAGE_VELOCITY_RATIO / omega * math.sqrt(2.0 * total_drop / count)
    root = mean - 0.1
    flow = point.main_steam_flow_kg_s - leak  # the leakage leaves the control-stage chamber
    log_span = math.log(p_cs / p_exh)
    after = [min(max(round(count * math.log(p_cs / p) / log_span), 1), count - 1)
             for _, _, p in bleeds]
    heights: list[float] | None = None

    def residual(x: tuple[float, float]) -> tuple[np.ndarray, list[StageRow]] | None:
        rows = expand_pressure_stages(p_cs, h_cs, _stage_flows(flow, count, [b[1] for b in
                                                                                bleeds], after),
                                      omega, x[0], STAGE_VELOCITY_RATIO, x[1], heights,
                                      0.3 * p_exh)
        if rows is None:
            return None
        end = rows[-1]
        return np.array([math.log(end.outlet_pressure_pa / p_exh),
                         (end.outlet_enthalpy_j_kg - h_exh) / 1e4]), rows

    x = np.array([root, efficiency])
    for _placement in range(5):
        for _ in range(40):
            base = residual(tuple(x))
            if base is None:
                raise DeriveError(
                    f"{where}: the expansion from control_stage_pressure to hp_exhaust_pressure "
                    f"over machine.pressure_stages = {count} stages cannot be laid out at a "
                    f"velocity ratio of {STAGE_VELOCITY_RATIO}")
            r, rows = base
            heights = [row.blade_height_m for row in rows]
            if abs(r[0]) < 1e-7 and abs(r[1]) < 1e-5:
                break
            jacobian = np.empty((2, 2))
            for j, step in enumerate((1e-4, 1e-4)):
                probe = x.copy()
                probe[j] += step
                moved = residual(tuple(probe))
                if moved is None:
                    raise DeriveError(f"{where}: the expansion cannot be laid out "
                                      "(machine.pressure_stages, hp_exhaust_pressure)")
                jacobian[:, j] = (moved[0] - r) / step
            delta = np.linalg.solve(jacobian, -r)
            for _ in range(20):  # damped step: stay inside the tables
                trial = x + delta
                if trial[0] > 0.05 and 0.05 < trial[1] < 1.5 and residual(tuple(trial)):
                    break
                delta /= 2.0
            x = x + delta
        else:
            raise DeriveError(f"{where}: the expansion to hp_exhaust_pressure and "
                              "hp_exhaust_temperature did not converge")
        placed = [min(range(1, count), key=lambda k: abs(math.log(rows[k - 1].outlet_pressure_pa
                                                                    / p)))
                  for _, _, p in bleeds]
        if placed == after:
            break
        after = placed
    return _Expansion(rows, float(x[0]), float(x[1]), after)


def derive_spec(heat_balance: HeatBalance, *, name: str | None = None) -> DerivedSpec:
    """Build a complete spec from a thermal kit (see the module docstring for the rules).

    ``name``: the spec's name (default: the heat balance's). Returns the commented TOML text,
    which :func:`~steamtwin.spec.loader.parse_spec` accepts, and notes on what was assumed.
    Raises :class:`DeriveError` naming the heat-balance point and field when a derived figure
    falls outside the spec's ranges or the data admit no expansion.
    """
    hb = heat_balance
    machine = hb.machine
    notes: list[str] = []
    index, rule = design_point_of(hb)
    point = hb.points[index]
    where = f"{hb.source}: points[{index + 1}] ({point.label!r})"
    notes.append(f"design point: {point.label!r} ({point.load_w / 1e6:.1f} MW), {rule}")

    # valves: all but the last opening group open at design
    orders = sorted(set(machine.valve_opening_order))
    if len(orders) < 2:
        raise DeriveError(
            f"{hb.source}: machine.valve_opening_order = {list(machine.valve_opening_order)}: "
            "every valve opens together, so every valve would be open at rated load and the "
            "spec could not pass an overload; expected at least two opening groups")
    last = orders[-1]
    open_flags = [order != last for order in machine.valve_opening_order]
    open_arc = sum(a for a, o in zip(machine.valve_arcs, open_flags, strict=True) if o)
    open_count = sum(open_flags)

    valves = _valves(hb, point, where)
    cs = _control_stage(hb, point, where, valves, open_count, open_arc, notes)
    p_exh = point.hp_exhaust_pressure_pa
    hp_bleeds, cold = [], []
    for bleed in point.extractions:
        if bleed.pressure_pa <= p_exh * (1.0 + COLD_REHEAT_TOLERANCE):
            cold.append(bleed.name)
        else:
            hp_bleeds.append((bleed.name, bleed.flow_kg_s, bleed.pressure_pa))
    if cold:
        notes.append(f"bleeds at the HP-exhaust pressure ({', '.join(cold)}) are taken from cold "
                     "reheat, after the HP blading: not HP extractions of the spec")
    flow = point.main_steam_flow_kg_s
    leak = 0.0
    if point.hp_exhaust_flow_kg_s is not None:
        leak = flow - point.hp_exhaust_flow_kg_s - sum(b[1] for b in hp_bleeds)
        if leak > 1e-3 * flow:
            notes.append(
                f"{point.label}: hp_exhaust_flow implies {leak * 3.6:.1f} t/h "
                f"({leak / flow:.1%}) of leakage past the pressure stages; written as a "
                "[[leakages]] entry from the control-stage chamber to the IP (HP–IP gland), "
                "the pressure stages sized for the flow without it")
        else:
            leak = 0.0
    expansion = _solve_expansion(hb, point, where, cs.h_out, hp_bleeds, leak)
    rows = expansion.rows
    h0 = _f(if97.enthalpy_pt(point.main_steam_pressure_pa, point.main_steam_temperature_k))
    expansion_power = flow * (h0 - cs.h_out) + sum(
        row.flow_kg_s * (row.inlet_enthalpy_j_kg - row.outlet_enthalpy_j_kg) for row in rows)

    w = _Writer(hb.source)
    _header(w, hb, point, rule, name)
    _design_block(w, point, where, rule, machine.rotational_speed_rad_s, expansion_power, valves)
    _control_block(w, hb, point, where, cs, open_flags)
    _stage_blocks(w, point, where, expansion)
    _extraction_blocks(w, point, where, hp_bleeds, expansion)
    if leak > 0.0:
        _leakage_block(w, point, where, leak)
    _metal_block(w, hb, point, where, cs, expansion)
    _sliding_block(w, hb, point, where)
    _temperature_block(w, hb, point, notes)
    notes.append(
        f"pressure stages: efficiency {expansion.efficiency:.4f} at u/c0 = "
        f"{STAGE_VELOCITY_RATIO} and root diameter {expansion.root_diameter:.4f} m reach "
        f"{point.label}'s HP exhaust; control stage efficiency {cs.efficiency:.4f} at u/c0 = "
        f"{cs.velocity_ratio:.3f}")
    try:
        parse_spec(w.text, "<derived spec>")
    except SpecError as error:
        raise DeriveError(f"{where}: the derived spec does not load: {error}") from None
    return DerivedSpec(w.text, notes)


def _header(w: _Writer, hb: HeatBalance, point: HeatBalancePoint, rule: str,
            name: str | None) -> None:
    w.raw(f"# Derived by `steamtwin turbine derive` from the heat balance {hb.name!r}")
    w.raw(f"# ({hb.source}); design point {point.label!r}: {rule}. Each figure says how it was")
    w.raw("# obtained; the rules and sources are in docs/heat-balance.md ('Deriving a spec from a")
    w.raw("# heat balance'). Review the figures marked 'rule' against the OEM drawings.")
    w.raw()
    w.raw(f"format_version = {FORMAT_VERSION}")
    w.raw(f"name = {_toml_string(name or hb.name)}")
    w.raw(f"description = {_toml_string(f'Derived from the heat balance {hb.name!r}')}")
    w.raw("sensors = [  # the standard DCS point list of an HP section")
    w.lines.extend(f'    "{sensor}",' for sensor in SENSORS)
    w.raw("]")


def _toml_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"')
    return f'"{escaped}"'


def _design_block(w: _Writer, point: HeatBalancePoint, where: str, rule: str,
                  hb_speed_rad_s: float, expansion_power: float, valves: _Valves) -> None:
    w.raw()
    w.raw("[design]")
    w.raw(f"# Rated point: {point.label!r} ({rule}).")
    label = point.label
    w.value("main_steam_pressure", "design.main_steam_pressure", point.main_steam_pressure_pa,
            _mpa(point.main_steam_pressure_pa), f"{label}: main_steam_pressure",
            f"{where}: main_steam_pressure")
    w.value("main_steam_temperature", "design.main_steam_temperature",
            point.main_steam_temperature_k, _degc(point.main_steam_temperature_k),
            f"{label}: main_steam_temperature", f"{where}: main_steam_temperature")
    w.value("main_steam_flow", "design.main_steam_flow", point.main_steam_flow_kg_s,
            _t_h(point.main_steam_flow_kg_s), f"{label}: main_steam_flow",
            f"{where}: main_steam_flow")
    w.value("control_stage_pressure", "design.control_stage_pressure",
            point.control_stage_pressure_pa, _mpa(point.control_stage_pressure_pa),
            f"{label}: control_stage_pressure", f"{where}: control_stage_pressure")
    w.value("hp_exhaust_pressure", "design.hp_exhaust_pressure", point.hp_exhaust_pressure_pa,
            _mpa(point.hp_exhaust_pressure_pa), f"{label}: hp_exhaust_pressure",
            f"{where}: hp_exhaust_pressure")
    w.value("hp_exhaust_temperature", "design.hp_exhaust_temperature",
            point.hp_exhaust_temperature_k, _degc(point.hp_exhaust_temperature_k),
            f"{label}: hp_exhaust_temperature", f"{where}: hp_exhaust_temperature")
    if point.hp_power_w is not None:
        power, how = point.hp_power_w, f"{label}: hp_power"
    else:
        power = expansion_power
        how = f"IF97 expansion of {label}: flows × enthalpy drops (no hp_power in the kit)"
    w.value("hp_power", "design.hp_power", power, _mw(power), how, f"{where}: hp_power")
    w.value("generator_power", "design.generator_power", point.load_w, _mw(point.load_w),
            f"{label}: load", f"{where}: load")
    speed = hb_speed_rad_s
    w.value("rotational_speed", "design.rotational_speed", speed,
            f'"{speed * 30.0 / math.pi:.6g} rpm"', "machine.rotational_speed",
            "machine: rotational_speed")
    w.value("valve_pressure_drop", "design.valve_pressure_drop", valves.drop,
            f"{valves.drop:.4g}", valves.drop_how, valves.drop_origin)
    if valves.design_outlet is not None:
        w.value("valve_outlet_pressure", "design.valve_outlet_pressure", valves.design_outlet,
                _mpa(valves.design_outlet), f"{label}: valve_outlet_pressure (between valve "
                "points: the last group open at design throttles)",
                f"{where}: valve_outlet_pressure")



def _control_block(w: _Writer, hb: HeatBalance, point: HeatBalancePoint, where: str,
                   cs: _ControlStage, open_flags: Sequence[bool]) -> None:
    machine = hb.machine
    diameter = machine.control_stage_mean_diameter_m
    w.raw()
    w.raw("[control_stage]")
    w.raw("# Impulse governing stage with partial admission [Traupel §8]; blading figures by the")
    w.raw("# reference unit's rules unless the kit gives them.")
    w.value("mean_diameter", "control_stage.mean_diameter", diameter, _metres(diameter),
            "machine.control_stage_mean_diameter", "machine: control_stage_mean_diameter")
    w.value("blade_height", "control_stage.blade_height", cs.height, _metres(cs.height),
            f"continuity at the nozzle exit through the arc open at design ({cs.open_arc:.2f}), "
            f"{point.label}", f"{where}: main_steam_flow, control_stage_pressure")
    count = round(math.pi * diameter / CONTROL_BLADE_PITCH)
    w.value("blade_count", "control_stage.blade_count", count, str(count),
            f"rule: pi·D / {CONTROL_BLADE_PITCH * 1e3:g} mm pitch", "machine: "
            "control_stage_mean_diameter")
    w.value("reaction", "control_stage.reaction", CONTROL_REACTION, f"{CONTROL_REACTION:g}",
            "rule: impulse stage, slight reaction at the mean line [Traupel]", "reaction")
    w.value("nozzle_exit_angle", "control_stage.nozzle_exit_angle", CONTROL_NOZZLE_ANGLE,
            f'"{math.degrees(CONTROL_NOZZLE_ANGLE):g} deg"',
            "rule: 11-15 deg usual for impulse nozzles [Traupel]", "nozzle_exit_angle")
    w.value("peak_blade_efficiency", "control_stage.peak_blade_efficiency", cs.peak,
            f"{cs.peak:.4f}",
            f"{point.label}: efficiency {cs.efficiency:.4f} at u/c0 = {cs.velocity_ratio:.3f} "
            "plus friction and partial-admission losses (Kang et al. §3.5)", cs.origin)
    w.value("friction_loss", "control_stage.friction_loss", CONTROL_FRICTION_LOSS,
            f"{CONTROL_FRICTION_LOSS:g}", "rule: profile friction share [Traupel]",
            "friction_loss")
    w.value("nozzle_discharge_coefficient", "control_stage.nozzle_discharge_coefficient",
            NOZZLE_DISCHARGE_COEFFICIENT, f"{NOZZLE_DISCHARGE_COEFFICIENT:g}",
            "rule: 0.95-0.98 for steam nozzles [Cotton ch. 6]", "nozzle_discharge_coefficient")
    if machine.valve_overlap is not None:
        w.value("valve_overlap", "control_stage.valve_overlap", machine.valve_overlap,
                f"{machine.valve_overlap:g}", "machine.valve_overlap: next group opens at "
                f"{1.0 - machine.valve_overlap:.0%} lift", "machine: valve_overlap")
    w.raw()
    w.raw("# Governing valves from [machine]; open at design: all but the last opening group")
    w.raw("# (a nozzle-governed unit reaches rated load with its overload valve still shut).")
    for name, order, arc, is_open in zip(machine.valve_names, machine.valve_opening_order,
                                         machine.valve_arcs, open_flags, strict=True):
        w.raw("[[control_stage.valves]]")
        w.raw(f"name = {_toml_string(name)}")
        w.raw(f"opening_order = {order}")
        w.value("admission_arc", "control_stage.valves.admission_arc", arc, f"{arc:g}",
                "machine.valve_arcs", "machine: valve_arcs")
        w.raw(f"open_at_design = {'true' if is_open else 'false'}")
        w.raw()


def _stage_blocks(w: _Writer, point: HeatBalancePoint, where: str, expansion: _Expansion
                  ) -> None:
    optimum = _optimum_ratio(STAGE_NOZZLE_ANGLE, STAGE_REACTION)
    peak = (expansion.efficiency + STAGE_FRICTION_LOSS) / _parabola(STAGE_VELOCITY_RATIO,
                                                                   optimum)
    origin = f"{where}: hp_exhaust_temperature"
    w.raw(f"# Pressure stages: IF97 expansion of {point.label} from the control-stage state to")
    w.raw(f"# the HP-exhaust pressure at a common u/c0 = {STAGE_VELOCITY_RATIO} and a constant "
          f"root diameter of {expansion.root_diameter:.4f} m,")
    w.raw(f"# both solved with the stage efficiency ({expansion.efficiency:.4f}) so that the "
          "expansion ends at the")
    w.raw("# point's HP-exhaust pressure and temperature; blade heights from continuity at the")
    w.raw("# stator exit; K = m / sqrt((p_in^2 - p_out^2)/(p_in v_in)) (Stodola).")
    for number, row in enumerate(expansion.rows, start=1):
        stage = f"{origin} (stage {number})"
        w.raw("[[stages]]")
        w.value("mean_diameter", "stages.mean_diameter", row.mean_diameter_m,
                _metres(row.mean_diameter_m), "root diameter + blade height", stage)
        w.value("blade_height", "stages.blade_height", row.blade_height_m,
                _metres(row.blade_height_m),
                f"continuity, {row.flow_kg_s * 3.6:.0f} t/h at "
                f"{row.outlet_pressure_pa / 1e6:.4g} MPa", stage)
        count = round(math.pi * row.mean_diameter_m / STAGE_BLADE_PITCH)
        w.value("blade_count", "stages.blade_count", count, str(count),
                f"rule: pi·D / {STAGE_BLADE_PITCH * 1e3:g} mm pitch", stage)
        w.value("reaction", "stages.reaction", STAGE_REACTION, f"{STAGE_REACTION:g}",
                "rule: HP reaction blading [Traupel]", stage)
        w.value("nozzle_exit_angle", "stages.nozzle_exit_angle", STAGE_NOZZLE_ANGLE,
                f'"{math.degrees(STAGE_NOZZLE_ANGLE):g} deg"', "rule: 14-20 deg [Traupel]",
                stage)
        w.value("peak_blade_efficiency", "stages.peak_blade_efficiency", peak, f"{peak:.4f}",
                f"solved: efficiency {expansion.efficiency:.4f} at u/c0 = "
                f"{STAGE_VELOCITY_RATIO} plus friction", stage)
        w.value("friction_loss", "stages.friction_loss", STAGE_FRICTION_LOSS,
                f"{STAGE_FRICTION_LOSS:g}", "rule: HP reaction blading [Traupel]", stage)
        w.value("flow_capacity", "stages.flow_capacity", row.flow_capacity_m2,
                f'"{row.flow_capacity_m2:.5g} m^2"',
                f"Stodola, p_in {row.inlet_pressure_pa / 1e6:.4g} -> "
                f"{row.outlet_pressure_pa / 1e6:.4g} MPa", stage)
        w.raw()


def _extraction_blocks(w: _Writer, point: HeatBalancePoint, where: str,
                       bleeds: Sequence[tuple[str, float, float]], expansion: _Expansion
                       ) -> None:
    for (name, flow, pressure), after in zip(bleeds, expansion.bleed_after, strict=True):
        origin = f"{where}: extractions ({name!r})"
        outlet = expansion.rows[after - 1].outlet_pressure_pa
        w.raw("[[extractions]]")
        w.raw(f"name = {_toml_string(name)}")
        w.raw(f"after_stage = {after}  # the stage whose outlet pressure "
              f"({outlet / 1e6:.4g} MPa) is nearest the bleed's")
        w.value("design_flow", "extractions.design_flow", flow, _t_h(flow),
                f"{point.label}: extractions.flow", origin)
        w.value("design_pressure", "extractions.design_pressure", pressure, _mpa(pressure),
                f"{point.label}: extractions.pressure", origin)
        w.raw()


def _leakage_block(w: _Writer, point: HeatBalancePoint, where: str, leak: float) -> None:
    """The leakage the kit's flow balance implies: throttle flow less HP-exhaust flow and HP
    bleeds, taken as the HP–IP gland (balance piston) from the control-stage chamber."""
    origin = f"{where}: main_steam_flow, hp_exhaust_flow, extractions"
    sink = GLAND_SINK_RATIO * point.hp_exhaust_pressure_pa
    w.raw("[[leakages]]")
    w.raw('name = "HP-IP gland"')
    w.raw("from_stage = 0  # rule: the balance piston / HP-IP gland sits at the control-stage "
          "chamber")
    w.raw('to = "outside"  # to the IP inlet: it does not reach the HP exhaust')
    w.value("design_flow", "leakages.design_flow", leak, _t_h(leak),
            f"{point.label}: main_steam_flow - hp_exhaust_flow - HP bleeds", origin)
    w.value("sink_pressure", "leakages.sink_pressure", sink, _mpa(sink),
            f"rule: IP inlet, {GLAND_SINK_RATIO:g} x hp_exhaust_pressure (reheater loss)",
            f"{where}: hp_exhaust_pressure")
    w.raw()


def _metal_groups(count: int) -> list[list[int]]:
    """Pressure stages 1..count in consecutive groups of at most STAGES_PER_GROUP, even sizes."""
    groups = math.ceil(count / STAGES_PER_GROUP)
    sizes = [count // groups + (1 if g < count % groups else 0) for g in range(groups)]
    result, first = [], 1
    for size in sizes:
        result.append(list(range(first, first + size)))
        first += size
    return result


def _metal_block(w: _Writer, hb: HeatBalance, point: HeatBalancePoint, where: str,
                 cs: _ControlStage, expansion: _Expansion) -> None:
    w.raw("[metal]")
    w.raw('casing_sensor_group = "control stage"  # the DCS thermocouple sits in the inner-'
          "casing wall at the governing stage")
    w.value("ambient_temperature", "metal.ambient_temperature", AMBIENT_TEMPERATURE,
            _degc(AMBIENT_TEMPERATURE), "rule: turbine-hall air, 30-40 °C typical",
            "ambient_temperature")
    w.value("casing_thermocouple_depth", "metal.casing_thermocouple_depth",
            CASING_THERMOCOUPLE_DEPTH, f'"{CASING_THERMOCOUPLE_DEPTH * 1e3:g} mm"',
            "rule: assumed installation depth; take it from the casing drawing",
            "casing_thermocouple_depth")
    w.raw()
    w.raw("# Low-alloy Cr-Mo-V steels (cast inner casing, forged rotor): [ASME II-D] Table TCD,")
    w.raw("# Group C near 500 °C: k ~ 34 W/(m K), diffusivity ~ 7.3e-6 m^2/s, rho 7800 kg/m^3.")
    for table in ("casing_material", "rotor_material"):
        w.raw(f"[metal.{table}]")
        w.raw(f'density = "{STEEL_DENSITY:g} kg/m^3"')
        w.raw(f'specific_heat = "{STEEL_SPECIFIC_HEAT:g} J/(kg*K)"')
        w.raw(f'thermal_conductivity = "{STEEL_CONDUCTIVITY:g} W/(m*K)"')
        w.raw()
    machine = hb.machine
    bore = (machine.rotor_bore_diameter_m or 0.0) / 2.0
    w.raw("# Drawn geometry over the group's axial length "
          f"({STAGE_AXIAL_PITCH:g} m per pressure stage,")
    w.raw(f"# {CONTROL_STAGE_AXIAL_LENGTH:g} m for the control-stage wheel and chamber). "
          "Rotor: a drum of the blading's root radius,")
    w.raw("# " + ("bored as the kit's machine.rotor_bore_diameter says;" if bore > 0.0
                  else "solid (the kit gives no machine.rotor_bore_diameter);")
          + f" inner casing: bore = blade tip radius + {BORE_CLEARANCE:g} m,")
    if machine.casing_wall_thickness_m is not None:
        w.raw("# wall = the kit's machine.casing_wall_thickness.")
    else:
        w.raw("# wall = thin-wall hoop thickness p·r/S at the group's inlet pressure, "
              f"S = {CASING_ALLOWABLE_STRESS / 1e6:g} MPa")
        w.raw("# (2¼Cr-1Mo cast steel near 538 °C, ASME BPVC II-D Table 1A).")
    rows = expansion.rows
    groups: list[tuple[str, list[int], float, float, float, float]] = []
    cs_root = machine.control_stage_mean_diameter_m / 2.0 - cs.height / 2.0
    cs_tip = machine.control_stage_mean_diameter_m / 2.0 + cs.height / 2.0
    groups.append(("control stage", [0], cs_root, cs_tip, CONTROL_STAGE_AXIAL_LENGTH,
                   point.control_stage_pressure_pa))
    for stages in _metal_groups(len(rows)):
        group_rows = [rows[s - 1] for s in stages]
        tip = max(r.mean_diameter_m + r.blade_height_m for r in group_rows) / 2.0
        groups.append((f"HP stages {stages[0]}-{stages[-1]}" if len(stages) > 1
                       else f"HP stage {stages[0]}", stages, expansion.root_diameter / 2.0, tip,
                       STAGE_AXIAL_PITCH * len(stages), group_rows[0].inlet_pressure_pa))
    for name, stages, rotor_radius, tip, length, pressure in groups:
        origin = f"{where}: control_stage_pressure, hp_exhaust_pressure (metal group {name!r})"
        casing_radius = tip + BORE_CLEARANCE
        w.raw("[[metal.groups]]")
        w.raw(f"name = {_toml_string(name)}")
        w.raw(f"stages = [{', '.join(str(s) for s in stages)}]")
        w.value("axial_length", "metal.groups.axial_length", length, f'"{length:g} m"',
                "rule: " + (f"{STAGE_AXIAL_PITCH:g} m per pressure stage" if stages != [0]
                            else "control-stage wheel and nozzle chamber"), origin)
        w.value("rotor_radius", "metal.groups.rotor_radius", rotor_radius,
                f'"{rotor_radius:.4f} m"', "the blading's root radius (drum rotor)", origin)
        if bore > rotor_radius - METAL_DEPTH_RANGE_M[0]:
            raise DeriveError(
                f"{hb.source}: machine.rotor_bore_diameter = {2.0 * bore:g} m leaves less than "
                f"{METAL_DEPTH_RANGE_M[0]:g} m of metal under the root radius "
                f"{rotor_radius:.4f} m of metal group {name!r}")
        w.value("rotor_bore_radius", "metal.groups.rotor_bore_radius", bore, f'"{bore:.4g} m"',
                "machine.rotor_bore_diameter / 2" if bore > 0.0 else "solid forging", origin)
        w.value("casing_inner_radius", "metal.groups.casing_inner_radius", casing_radius,
                f'"{casing_radius:.4f} m"',
                f"blade tip radius {tip:.4f} m + {BORE_CLEARANCE:g} m", origin)
        if machine.casing_wall_thickness_m is not None:
            wall = machine.casing_wall_thickness_m
            w.value("casing_wall_thickness", "metal.groups.casing_wall_thickness", wall,
                    f'"{wall:.4g} m"', "machine.casing_wall_thickness",
                    f"{hb.source}: machine.casing_wall_thickness")
        else:
            wall = pressure * casing_radius / CASING_ALLOWABLE_STRESS
            w.value("casing_wall_thickness", "metal.groups.casing_wall_thickness", wall,
                    f'"{wall:.4f} m"', f"hoop p·r/S: p {pressure / 1e6:.3g} MPa, r "
                    f"{casing_radius:.3f} m, S {CASING_ALLOWABLE_STRESS / 1e6:g} MPa", origin)
        w.value("insulation_conductance", "metal.groups.insulation_conductance",
                INSULATION_CONDUCTANCE, f'"{INSULATION_CONDUCTANCE:g} W/(m^2*K)"',
                "rule: lagging for ~0.3 kW/m^2 (ASTM C680)", "insulation_conductance")
        w.raw()


def _sliding_block(w: _Writer, hb: HeatBalance, point: HeatBalancePoint, where: str) -> None:
    design_load = point.load_w
    fractions = [p.load_w / design_load for p in reversed(hb.points)]
    pressures = [p.main_steam_pressure_pa for p in reversed(hb.points)]
    labels = [p.label for p in reversed(hb.points)]
    high = FIELD_BY_KEY["sliding_pressure.load_fraction"].high or math.inf
    for number, (fraction, label) in enumerate(zip(fractions, labels, strict=True)):
        if fraction > high:
            raise DeriveError(
                f"{hb.source}: points[{len(fractions) - number}] ({label!r}): load is "
                f"{fraction:.3f} of the design point's load; the sliding-pressure line ends at "
                f"{high:g}")
    notes = [f"{label} at {fraction:.3f}" for label, fraction in zip(labels, fractions,
                                                                     strict=True)]
    if fractions[0] > 0.0:  # below the lowest diagram: its pressure held (minimum pressure)
        fractions.insert(0, 0.0)
        pressures.insert(0, pressures[0])
        notes.insert(0, "0 held at the lowest point's pressure")
    if fractions[-1] < 1.1:  # above the highest diagram: rated pressure held
        fractions.append(1.1)
        pressures.append(pressures[-1])
        notes.append("1.1 held at the highest point's pressure")
    w.raw("[sliding_pressure]")
    w.raw("# Every heat-balance point: load / design load vs main_steam_pressure; "
          "held flat beyond them.")
    w.raw(f"# ({'; '.join(notes)})")
    for value in pressures:
        if not FIELD_BY_KEY["sliding_pressure.pressure"].contains(value):
            raise DeriveError(f"{where}: main_steam_pressure: {value / 1e6:.4g} MPa is outside "
                              "the sliding-pressure line's range")
    w.raw("load_fraction = [" + ", ".join(f"{f:.6g}" for f in fractions) + "]")
    w.raw("pressure = [" + ", ".join(_mpa(p) for p in pressures) + "]")


def _temperature_block(w: _Writer, hb: HeatBalance, point: HeatBalancePoint,
                       notes: list[str]) -> None:
    """``[temperature_schedule]``: every point's main-steam (and hot-reheat) temperature against
    load / design load, ascending; the reheat axis only if every point gives it. A kit of one
    point (the design point) has no schedule: the design temperature at every load."""
    points = list(reversed(hb.points))  # the kit lists them by decreasing load
    if len(points) < 2:
        return
    fractions = [p.load_w / point.load_w for p in points]
    first = len(points)  # 1-based position in the kit of points[0]
    for axis, key in (("main_steam_temperature", "main_steam_temperature_k"),
                      ("reheat_temperature", "reheat_temperature_k")):
        spec_field = FIELD_BY_KEY[f"temperature_schedule.{axis}"]
        for offset, p in enumerate(points):
            value = getattr(p, key)
            if value is not None and not spec_field.contains(value):
                raise DeriveError(
                    f"{hb.source}: points[{first - offset}] ({p.label!r}): {axis} "
                    f"{value - 273.15:.1f} °C is outside the temperature schedule's range "
                    f"{spec_field.range_text(display=True)}")
    w.raw()
    w.raw("[temperature_schedule]")
    w.raw("# Every heat-balance point: load / design load vs its main-steam (and hot-reheat)")
    w.raw("# temperature, the boiler's steam-temperature schedule; held flat beyond the points.")
    labels = ", ".join(p.label for p in points)
    w.raw("load_fraction = [" + ", ".join(f"{f:.6g}" for f in fractions)
          + f"]  # {labels}: load / {point.label} load")
    w.raw("main_steam_temperature = ["
          + ", ".join(_degc(p.main_steam_temperature_k) for p in points)
          + "]  # the same points: main_steam_temperature")
    reheats = [p.reheat_temperature_k for p in points if p.reheat_temperature_k is not None]
    missing = [p.label for p in points if p.reheat_temperature_k is None]
    if not missing:
        w.raw("reheat_temperature = [" + ", ".join(_degc(t) for t in reheats)
              + "]  # the same points: reheat_temperature")
    elif reheats:
        notes.append(f"temperature schedule: no reheat_temperature at {', '.join(missing)}, so "
                     "the reheat axis is left out (the HP-exhaust pressure follows the flow alone)")
