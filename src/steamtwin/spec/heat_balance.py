"""Read an OEM thermal kit — one design point per heat-balance diagram — from TOML.

Kept as one module because it is one job, reading and checking a thermal kit: the checks on
each point and between points (docs/heat-balance.md) share one error-naming helper (``_Fields``).

A plant engineer's description of their unit starts from the thermal kit: heat-balance diagrams
at VWO, THA, 75 %, 50 %, 40 %, 30 % load. This module reads them, with the few figures of the
drawings the design model needs (``[machine]``), into frozen SI dataclasses and refuses anything
the later steps (derive, fit, check) could not trust. The format is described field by field in
``docs/heat-balance.md``; values with a dimension are ``"value unit"`` strings (``"16.7 MPa"``,
``"538 degC"``, ``"1700 t/h"``) converted to SI (Pa, K, kg/s, W, rad/s, m).

The schema is strict: an unknown key anywhere is an error with a "did you mean" hint. Messages
name the file, the point by its 1-based position and label (``points[3] ("50 %")``), the field
and the expected unit or range. Points are listed by strictly decreasing load (VWO first, as a
thermal kit lists its diagrams); the checks on each point and between points are those listed in
``docs/heat-balance.md``.
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from steamtwin.errors import SpecAreaError
from steamtwin.keys import unknown_key_message
from steamtwin.steam import if97
from steamtwin.steam.tables import lower_boundary_temperature
from steamtwin.textfile import read_utf8_text
from steamtwin.units import UnitError, convert, parse_quantity

__all__ = [
    "BUILT_IN_KITS",
    "HEAT_BALANCE_KEYS",
    "HeatBalance",
    "HeatBalanceError",
    "HeatBalanceExtraction",
    "HeatBalancePoint",
    "MachineDescription",
    "load_heat_balance",
    "parse_heat_balance",
]

_MACHINE_REQUIRED = ("pressure_stages", "rotational_speed", "control_stage_mean_diameter",
                     "valve_arcs", "valve_opening_order")
_POINT_REQUIRED = ("label", "load", "main_steam_pressure", "main_steam_temperature",
                   "main_steam_flow", "control_stage_pressure", "hp_exhaust_pressure",
                   "hp_exhaust_temperature")

#: The keys each table may hold, by its path without array positions ("" is the top level).
HEAT_BALANCE_KEYS: Mapping[str, frozenset[str]] = {
    "": frozenset({"name", "description", "machine", "points"}),
    "machine": frozenset({*_MACHINE_REQUIRED, "valve_names", "valve_overlap", "rated_load",
                          "valve_pressure_drop", "rotor_bore_diameter",
                          "casing_wall_thickness"}),
    "points": frozenset({*_POINT_REQUIRED, "control_stage_temperature", "hp_exhaust_flow",
                         "valve_outlet_pressure",
                         "hp_power", "reheat_temperature", "feedwater_temperature",
                         "extractions"}),
    "points.extractions": frozenset({"name", "flow", "pressure"}),
}

#: Plausibility ranges of the quantities: (SI unit, low, high, unit shown in messages).
_RANGES: Mapping[str, tuple[str, float, float, str]] = {
    "load": ("W", 0.1e6, 2000e6, "MW"),
    "main_steam_pressure": ("Pa", 0.5e6, 35e6, "MPa"),
    "main_steam_temperature": ("K", 373.15, 923.15, "degC"),
    "main_steam_flow": ("kg/s", 1 / 3.6, 5000 / 3.6, "t/h"),
    "control_stage_pressure": ("Pa", 0.05e6, 35e6, "MPa"),
    "valve_outlet_pressure": ("Pa", 0.05e6, 35e6, "MPa"),
    "control_stage_temperature": ("K", 373.15, 923.15, "degC"),
    "hp_exhaust_pressure": ("Pa", 0.01e6, 35e6, "MPa"),
    "hp_exhaust_temperature": ("K", 323.15, 923.15, "degC"),
    "hp_exhaust_flow": ("kg/s", 1 / 3.6, 5000 / 3.6, "t/h"),
    "hp_power": ("W", 0.1e6, 1000e6, "MW"),
    "reheat_temperature": ("K", 573.15, 923.15, "degC"),
    "feedwater_temperature": ("K", 323.15, 623.15, "degC"),
    "extractions.flow": ("kg/s", 0.01 / 3.6, 5000 / 3.6, "t/h"),
    "extractions.pressure": ("Pa", 0.01e6, 35e6, "MPa"),
    "rotational_speed": ("rad/s", 300 * math.pi / 30, 30000 * math.pi / 30, "rpm"),
    "control_stage_mean_diameter": ("m", 0.2, 3.0, "m"),
    "rated_load": ("W", 0.1e6, 2000e6, "MW"),
    "rotor_bore_diameter": ("m", 0.0, 2.0, "m"),
    "casing_wall_thickness": ("m", 0.01, 1.0, "m"),
}

#: Band of the whole-HP isentropic efficiency (main steam to HP exhaust, valves included):
#: HP sections of large units reach 0.85-0.90 at rated load [Cotton, Evaluating and Improving
#: Steam Turbine Performance, 1998, ch. 2]; below 0.5 or above 0.95 the data are inconsistent.
HP_EFFICIENCY_BAND = (0.5, 0.95)
#: Largest wide-open stop + governing valve pressure loss accepted, fraction of the main-steam
#: pressure (the spec's design.valve_pressure_drop bound; 2-4 % usual [Cotton, ch. 6]).
MAX_VALVE_PRESSURE_DROP = 0.2
#: Mean blade speed limit of the control stage, m/s (forged HP discs stay well below it).
MAX_BLADE_SPEED = 400.0
#: A heater with a desuperheating zone heats the feedwater at most a few kelvin above the bleed's
#: saturation temperature (terminal difference down to about −1.7 K, HEI Standards for Closed
#: Feedwater Heaters); 3 K allows for rounding of the kit.
FEEDWATER_SUPERHEAT_ALLOWANCE = 3.0
#: Most of the throttle flow leaves the HP at its exhaust: bleeds and leakages before it take
#: a few per cent [Cotton, ch. 6]; the HP power lies between the exhaust flow and the whole
#: throttle flow expanding over the whole HP drop (2 % allowance for the kit's rounding).
MIN_EXHAUST_FLOW_SHARE = 0.5
HP_POWER_BAND = (0.85, 1.02)


class HeatBalanceError(SpecAreaError):
    """A heat-balance file is unreadable, incomplete, out of range or inconsistent."""


@dataclass(frozen=True)
class HeatBalanceExtraction:
    """A bleed from the HP section at one design point."""

    name: str  #: heater or user fed, e.g. "HP heater 1"
    flow_kg_s: float  #: bleed flow, kg/s
    pressure_pa: float  #: pressure at the bleed point, Pa (between HP exhaust and control stage)


@dataclass(frozen=True)
class HeatBalancePoint:
    """One heat-balance diagram, SI. Optional figures the kit does not give are ``None``."""

    label: str  #: the diagram's name, e.g. "THA" or "50 %"
    load_w: float  #: generator output, W
    main_steam_pressure_pa: float  #: ahead of the stop valves, Pa
    main_steam_temperature_k: float  #: ahead of the stop valves, K
    main_steam_flow_kg_s: float  #: throttle flow, kg/s
    control_stage_pressure_pa: float  #: control-stage (governing-stage) chamber, Pa
    control_stage_temperature_k: float | None  #: control-stage chamber, K
    hp_exhaust_pressure_pa: float  #: HP exhaust (cold reheat), Pa
    hp_exhaust_temperature_k: float  #: HP exhaust (cold reheat), K
    hp_isentropic_efficiency: float  #: computed: (h0 − h_exh)/(h0 − h_exh,s), IAPWS-IF97
    valve_outlet_pressure_pa: float | None = None  #: after the governing valves (nozzle chest), Pa
    hp_exhaust_flow_kg_s: float | None = None  #: leaving the HP blading, kg/s
    hp_power_w: float | None = None  #: HP blading (internal) power, W
    reheat_temperature_k: float | None = None  #: hot reheat at the IP inlet, K
    feedwater_temperature_k: float | None = None  #: final feedwater (top heater outlet), K
    extractions: tuple[HeatBalanceExtraction, ...] = ()  #: HP bleeds, as listed


@dataclass(frozen=True)
class MachineDescription:
    """What the drawings give about the HP section, SI."""

    pressure_stages: int  #: pressure stages after the control stage
    rotational_speed_rad_s: float  #: shaft speed, rad/s
    control_stage_mean_diameter_m: float  #: control-stage blade mean diameter, m
    valve_arcs: tuple[float, ...]  #: admission arc of each governing valve, fraction of 2π
    valve_opening_order: tuple[int, ...]  #: opening group of each valve, 1 opens first
    valve_names: tuple[str, ...]  #: "GV1", "GV2", ... unless the file names them
    valve_overlap: float | None = None  #: lift fraction left when the next group opens
    rated_load_w: float | None = None  #: nameplate (THA) rating, W
    valve_pressure_drop: float | None = None  #: wide-open stop + governing valve loss, of p0
    rotor_bore_diameter_m: float | None = None  #: central bore of the rotor forging, m
    casing_wall_thickness_m: float | None = None  #: inner-casing wall over the blading, m


@dataclass(frozen=True)
class HeatBalance:
    """A validated thermal kit: the machine and its points by strictly decreasing load."""

    name: str
    machine: MachineDescription
    points: tuple[HeatBalancePoint, ...]
    source: str  #: the file (or "<string>") it was read from
    description: str | None = None

    @property
    def loads_w(self) -> np.ndarray:
        """The points' generator outputs in W, in file order (decreasing)."""
        return np.array([point.load_w for point in self.points], dtype=float)

    def point(self, label: str) -> HeatBalancePoint:
        """The point labelled ``label``; HeatBalanceError listing the labels if there is none."""
        for point in self.points:
            if point.label == label:
                return point
        labels = ", ".join(repr(point.label) for point in self.points)
        raise HeatBalanceError(f"{self.source}: no point labelled {label!r}; the points are "
                               f"{labels}")


def _type_name(value: Any) -> str:
    names = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    return names.get(type(value), "a date/time")


#: The SI unit of each engineering unit used in messages.
_SI_OF_SHOWN = {"MW": "W", "MPa": "Pa", "degC": "K", "t/h": "kg/s", "rpm": "rad/s", "m": "m"}


def _show(value_si: float, unit: str) -> str:
    """An SI value in the engineering unit of messages, e.g. ``'13.01 MPa'``."""
    value = float(convert(value_si, _SI_OF_SHOWN[unit], unit))
    return f"{value:.4g} {unit.replace('degC', '°C')}"


class _Fields:
    """One TOML table with its place in the file, so that every message names it.

    ``context`` is the table's place (``'points[3] ("50 %")'``, ``"machine"``, empty for the
    top level); unknown keys are refused on construction.
    """

    def __init__(self, data: Any, schema: str, source: str, context: str) -> None:
        self.source, self.schema, self.context = source, schema, context
        if not isinstance(data, dict):
            raise HeatBalanceError(f"{self.prefix} is {_type_name(data)}: expected a table")
        message = unknown_key_message(data, HEAT_BALANCE_KEYS[schema], "", self.prefix,
                                      "heat balance")
        if message is not None:
            raise HeatBalanceError(message)
        self.data = data

    @property
    def prefix(self) -> str:
        return f"{self.source}: {self.context}" if self.context else self.source

    def where(self, key: str) -> str:
        return f"{self.prefix}: {key}"

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str) -> Any:
        if key not in self.data:
            raise HeatBalanceError(f"{self.where(key)} is missing (a required field)")
        return self.data[key]

    def quantity(self, key: str, range_key: str | None = None) -> float:
        """The value of ``key`` in SI, inside its plausibility range from :data:`_RANGES`."""
        si_unit, low, high, shown = _RANGES[range_key or key]
        value = self.raw(key)
        where = self.where(key)
        if isinstance(value, bool) or not isinstance(value, str | int | float):
            raise HeatBalanceError(f"{where} is {_type_name(value)}: expected a string "
                                   f"'value unit' in {shown} or another unit of {si_unit}")
        try:
            result = parse_quantity(value, si_unit, where)
        except UnitError as error:
            raise HeatBalanceError(str(error)) from None
        if not math.isfinite(result) or not low <= result <= high:
            raise HeatBalanceError(f"{where} = {value!r} is outside the plausible range "
                                   f"[{_show(low, shown)}, {_show(high, shown)}]")
        return result

    def text(self, key: str) -> str:
        value = self.raw(key)
        if not isinstance(value, str) or not value.strip():
            raise HeatBalanceError(f"{self.where(key)} = {value!r}: expected a non-empty string")
        return value

    def tables(self, key: str, schema: str) -> list[Any]:
        """The raw entries of the array of tables ``key`` (non-empty)."""
        value = self.raw(key)
        if not isinstance(value, list) or not value:
            raise HeatBalanceError(f"{self.where(key)}: expected a non-empty array of tables "
                                   f"([[{schema}]])")
        return value


BUILT_IN_KITS = ("example-600mw",)
"""Thermal kits shipped with the package, by name: an independent 600 MW unit (not the
reference unit), ``data/example-600mw-heat-balance.toml``."""


def load_heat_balance(path: str | Path) -> HeatBalance:
    """Read and validate a heat-balance TOML file (see ``docs/heat-balance.md``), or the shipped
    example kit by its name (:data:`BUILT_IN_KITS`).

    Raises :class:`HeatBalanceError` naming the file, the point and the field for anything
    unreadable, unknown, missing, out of range or inconsistent.
    """
    if str(path) in BUILT_IN_KITS:
        resource = resources.files("steamtwin.spec") / "data" / f"{path}-heat-balance.toml"
        return parse_heat_balance(resource.read_text(encoding="utf-8"), f"built-in '{path}'")
    text = read_utf8_text(path, "heat balance", "TOML", HeatBalanceError)
    return parse_heat_balance(text, str(path))


def parse_heat_balance(text: str, source: str = "<string>") -> HeatBalance:
    """Parse and validate the TOML text of a heat balance; ``source`` names it in errors."""
    try:
        data = tomllib.loads(text)
    except (ValueError, RecursionError) as error:  # TOMLDecodeError, over-long integers, nesting
        raise HeatBalanceError(f"{source}: not valid TOML: {error}") from None
    document = _Fields(data, "", source, "")
    name = document.text("name")
    description = document.text("description") if document.has("description") else None
    machine = _machine(_Fields(document.raw("machine"), "machine", source, "machine"))
    entries = document.tables("points", "points")
    points = tuple(_point(entry, number, source) for number, entry in
                   enumerate(entries, start=1))
    _check_between_points(points, source)
    return HeatBalance(name=name, machine=machine, points=points, source=source,
                       description=description)


# ---------------------------------------------------------------------------------------------
# [machine]
# ---------------------------------------------------------------------------------------------


def _number_list(table: _Fields, key: str) -> list[Any]:
    value = table.raw(key)
    if not isinstance(value, list) or not value:
        raise HeatBalanceError(f"{table.where(key)} = {value!r}: expected a non-empty array")
    return value


def _machine(table: _Fields) -> MachineDescription:
    stages = table.raw("pressure_stages")
    if isinstance(stages, bool) or not isinstance(stages, int) or not 1 <= stages <= 30:
        raise HeatBalanceError(f"{table.where('pressure_stages')} = {stages!r}: expected an "
                               "integer in [1, 30]")
    speed = table.quantity("rotational_speed")
    diameter = table.quantity("control_stage_mean_diameter")
    blade_speed = speed * diameter / 2.0
    if blade_speed >= MAX_BLADE_SPEED:
        raise HeatBalanceError(
            f"{table.where('control_stage_mean_diameter')}: a mean blade speed of "
            f"{blade_speed:.0f} m/s at {_show(speed, 'rpm')} is not plausible; expected below "
            f"{MAX_BLADE_SPEED:.0f} m/s (check the diameter's unit and rotational_speed)")
    arcs = _number_list(table, "valve_arcs")
    for number, arc in enumerate(arcs, start=1):
        if (isinstance(arc, bool) or not isinstance(arc, int | float)
                or not math.isfinite(arc) or not 0.0 < arc <= 1.0):
            raise HeatBalanceError(f"{table.where('valve_arcs')}[{number}] = {arc!r}: expected "
                                   "a fraction of the circumference in (0, 1]")
    if sum(arcs) > 1.0 + 1e-9:
        raise HeatBalanceError(f"{table.where('valve_arcs')}: the arcs sum to {sum(arcs):.4g}; "
                               "the nozzle groups can cover at most the whole circumference (1)")
    order = _number_list(table, "valve_opening_order")
    if len(order) != len(arcs):
        raise HeatBalanceError(f"{table.where('valve_opening_order')} has {len(order)} entries "
                               f"but valve_arcs has {len(arcs)}: expected one per valve")
    for number, group in enumerate(order, start=1):
        if isinstance(group, bool) or not isinstance(group, int) or group < 1:
            raise HeatBalanceError(f"{table.where('valve_opening_order')}[{number}] = "
                                   f"{group!r}: expected an integer ≥ 1 (1 opens first)")
    missing = sorted(set(range(1, max(order) + 1)) - set(order))
    if missing:
        raise HeatBalanceError(f"{table.where('valve_opening_order')} = {order!r}: no valve "
                               f"opens at step {missing[0]}; expected the steps 1, 2, … "
                               "without gaps")
    names = tuple(f"GV{number}" for number in range(1, len(arcs) + 1))
    if table.has("valve_names"):
        given = table.raw("valve_names")
        if (not isinstance(given, list) or len(given) != len(arcs)
                or not all(isinstance(n, str) and n.strip() for n in given)
                or len(set(given)) != len(given)):
            raise HeatBalanceError(f"{table.where('valve_names')} = {given!r}: expected "
                                   f"{len(arcs)} distinct non-empty strings, one per valve")
        names = tuple(given)
    overlap = None
    if table.has("valve_overlap"):
        overlap = table.raw("valve_overlap")
        if (isinstance(overlap, bool) or not isinstance(overlap, int | float)
                or not 0.0 <= overlap < 0.5):
            raise HeatBalanceError(f"{table.where('valve_overlap')} = {overlap!r}: expected a "
                                   "plain number in [0, 0.5), the fraction of a valve's lift "
                                   "left when the next opening group starts to open")
        if max(order) < 2:
            raise HeatBalanceError(f"{table.where('valve_overlap')}: every valve opens at step "
                                   "1, so there is no next group to overlap with")
        overlap = float(overlap)
    rated = table.quantity("rated_load") if table.has("rated_load") else None
    bore, wall = (table.quantity(key) if table.has(key) else None
                  for key in ("rotor_bore_diameter", "casing_wall_thickness"))
    drop = None
    if table.has("valve_pressure_drop"):
        drop = table.raw("valve_pressure_drop")
        if (isinstance(drop, bool) or not isinstance(drop, int | float)
                or not 0.0 <= drop <= MAX_VALVE_PRESSURE_DROP):
            raise HeatBalanceError(f"{table.where('valve_pressure_drop')} = {drop!r}: expected "
                                   f"a plain number in [0, {MAX_VALVE_PRESSURE_DROP}], the "
                                   "fraction of the main-steam pressure lost across the "
                                   "wide-open stop and governing valves (0.02-0.04 usual)")
        drop = float(drop)
    return MachineDescription(
        pressure_stages=stages, rotational_speed_rad_s=speed,
        control_stage_mean_diameter_m=diameter, valve_arcs=tuple(float(a) for a in arcs),
        valve_opening_order=tuple(order), valve_names=names, valve_overlap=overlap,
        rated_load_w=rated, valve_pressure_drop=drop, rotor_bore_diameter_m=bore,
        casing_wall_thickness_m=wall)


# ---------------------------------------------------------------------------------------------
# [[points]]
# ---------------------------------------------------------------------------------------------


def _named(number: int, label: Any) -> str:
    """``points[3] ("50 %")``: a point by its 1-based position and (if readable) its label."""
    if not isinstance(label, str):
        return f"points[{number}]"
    return f"points[{number}] ({json.dumps(label, ensure_ascii=False)})"


def _point_context(entry: Any, number: int) -> str:
    return _named(number, entry.get("label") if isinstance(entry, dict) else None)


def _steam(function: Any, where: str, *args: float) -> float:
    """An IF97 property, its failure reported as a HeatBalanceError naming the field."""
    try:
        return float(function(*args))
    except if97.SteamPropertyError as error:
        raise HeatBalanceError(f"{where}: steam properties cannot be evaluated: {error}") from None


def _superheated(table: _Fields, key: str, temperature: float, pressure: float) -> None:
    """Refuse a temperature at or below the steam region's lower boundary at ``pressure``."""
    boundary = float(lower_boundary_temperature(pressure))
    if temperature <= boundary:
        raise HeatBalanceError(
            f"{table.where(key)} = {table.raw(key)!r} is not superheated steam: at "
            f"{_show(pressure, 'MPa')} it must exceed {_show(boundary, 'degC')} (IAPWS-IF97 "
            "saturation / region-2 boundary)")


def _point(entry: Any, number: int, source: str) -> HeatBalancePoint:
    table = _Fields(entry, "points", source, _point_context(entry, number))
    label = table.text("label")
    load = table.quantity("load")
    p0 = table.quantity("main_steam_pressure")
    t0 = table.quantity("main_steam_temperature")
    flow = table.quantity("main_steam_flow")
    p_cs = table.quantity("control_stage_pressure")
    p_exh = table.quantity("hp_exhaust_pressure")
    t_exh = table.quantity("hp_exhaust_temperature")
    if p_cs >= p0:
        raise HeatBalanceError(
            f"{table.where('control_stage_pressure')} = {_show(p_cs, 'MPa')} is not below "
            f"main_steam_pressure ({_show(p0, 'MPa')}): pressures must fall through the HP")
    if p_exh >= p_cs:
        raise HeatBalanceError(
            f"{table.where('hp_exhaust_pressure')} = {_show(p_exh, 'MPa')} is not below "
            f"control_stage_pressure ({_show(p_cs, 'MPa')}): pressures must fall through the HP")
    _superheated(table, "main_steam_temperature", t0, p0)
    p_valve = None
    if table.has("valve_outlet_pressure"):
        p_valve = table.quantity("valve_outlet_pressure")
        if not p_cs < p_valve <= p0:
            raise HeatBalanceError(
                f"{table.where('valve_outlet_pressure')} = {_show(p_valve, 'MPa')} is not "
                f"between control_stage_pressure ({_show(p_cs, 'MPa')}) and "
                f"main_steam_pressure ({_show(p0, 'MPa')}): the governing valves only throttle")
    if t_exh >= t0:
        raise HeatBalanceError(
            f"{table.where('hp_exhaust_temperature')} = {_show(t_exh, 'degC')} is not below "
            f"main_steam_temperature ({_show(t0, 'degC')}): the exhaust cannot be hotter than "
            "the inlet")
    _superheated(table, "hp_exhaust_temperature", t_exh, p_exh)
    t_cs = None
    if table.has("control_stage_temperature"):
        t_cs = table.quantity("control_stage_temperature")
        if not t_exh < t_cs < t0:
            raise HeatBalanceError(
                f"{table.where('control_stage_temperature')} = {_show(t_cs, 'degC')} is not "
                f"between hp_exhaust_temperature ({_show(t_exh, 'degC')}) and "
                f"main_steam_temperature ({_show(t0, 'degC')})")
        _superheated(table, "control_stage_temperature", t_cs, p_cs)
    where = table.where("hp_exhaust_temperature")
    h0 = _steam(if97.enthalpy_pt, where, p0, t0)
    h_exh = _steam(if97.enthalpy_pt, where, p_exh, t_exh)
    h_exh_s = _steam(if97.enthalpy_ps, where, p_exh, _steam(if97.entropy_pt, where, p0, t0))
    efficiency = (h0 - h_exh) / (h0 - h_exh_s)
    low, high = HP_EFFICIENCY_BAND
    if not low <= efficiency <= high:
        raise HeatBalanceError(
            f"{where} = {_show(t_exh, 'degC')} implies an HP isentropic efficiency of "
            f"{efficiency:.3f} from the main steam to the exhaust; expected [{low}, {high}] "
            "(check the temperatures and pressures of this point)")
    extractions = _extractions(table, flow, p_cs, p_exh)
    return HeatBalancePoint(
        label=label, load_w=load, main_steam_pressure_pa=p0, main_steam_temperature_k=t0,
        main_steam_flow_kg_s=flow, control_stage_pressure_pa=p_cs,
        control_stage_temperature_k=t_cs, hp_exhaust_pressure_pa=p_exh,
        hp_exhaust_temperature_k=t_exh, hp_isentropic_efficiency=efficiency,
        valve_outlet_pressure_pa=p_valve,
        hp_exhaust_flow_kg_s=_exhaust_flow(table, flow, p_exh, extractions),
        hp_power_w=_hp_power(table, flow * (h0 - h_exh)),
        reheat_temperature_k=_reheat_temperature(table, t_exh),
        feedwater_temperature_k=_feedwater_temperature(table, t0, p_cs, extractions),
        extractions=extractions)


def _extractions(table: _Fields, flow: float, p_cs: float,
                 p_exh: float) -> tuple[HeatBalanceExtraction, ...]:
    if not table.has("extractions"):
        return ()
    result: list[HeatBalanceExtraction] = []
    entries = table.tables("extractions", "points.extractions")
    for number, entry in enumerate(entries, start=1):
        bleed = _Fields(entry, "points.extractions", table.source,
                        f"{table.context}: extractions[{number}]")
        name = bleed.text("name")
        if any(name == other.name for other in result):
            raise HeatBalanceError(f"{bleed.where('name')} = {name!r} is listed twice in this "
                                   "point")
        bleed_flow = bleed.quantity("flow", "extractions.flow")
        pressure = bleed.quantity("pressure", "extractions.pressure")
        if not p_exh <= pressure <= p_cs:
            raise HeatBalanceError(
                f"{bleed.where('pressure')} = {_show(pressure, 'MPa')} is outside the HP "
                f"section: expected between hp_exhaust_pressure ({_show(p_exh, 'MPa')}) and "
                f"control_stage_pressure ({_show(p_cs, 'MPa')})")
        result.append(HeatBalanceExtraction(name=name, flow_kg_s=bleed_flow,
                                            pressure_pa=pressure))
    total = sum(bleed.flow_kg_s for bleed in result)
    if total >= MIN_EXHAUST_FLOW_SHARE * flow:
        raise HeatBalanceError(
            f"{table.where('extractions')}: the bleeds take {_show(total, 't/h')}, "
            f"{total / flow:.0%} of main_steam_flow; expected less than "
            f"{MIN_EXHAUST_FLOW_SHARE:.0%}")
    return tuple(result)


def _exhaust_flow(table: _Fields, flow: float, p_exh: float,
                  extractions: tuple[HeatBalanceExtraction, ...]) -> float | None:
    if not table.has("hp_exhaust_flow"):
        return None
    exhaust = table.quantity("hp_exhaust_flow")
    inner = sum(bleed.flow_kg_s for bleed in extractions if bleed.pressure_pa > p_exh)
    most = flow - inner
    if not MIN_EXHAUST_FLOW_SHARE * flow <= exhaust <= most * (1 + 1e-6):
        raise HeatBalanceError(
            f"{table.where('hp_exhaust_flow')} = {_show(exhaust, 't/h')}: expected between "
            f"{MIN_EXHAUST_FLOW_SHARE:.0%} of main_steam_flow ({_show(flow, 't/h')}) and "
            f"main_steam_flow less the bleeds above the exhaust ({_show(most, 't/h')})")
    return exhaust


def _hp_power(table: _Fields, throttle_power: float) -> float | None:
    """``throttle_power`` is the throttle flow times the whole HP enthalpy drop, W."""
    if not table.has("hp_power"):
        return None
    power = table.quantity("hp_power")
    low, high = (share * throttle_power for share in HP_POWER_BAND)
    if not low <= power <= high:
        raise HeatBalanceError(
            f"{table.where('hp_power')} = {_show(power, 'MW')} does not match the expansion: "
            f"main_steam_flow over the HP enthalpy drop gives {_show(throttle_power, 'MW')}; "
            f"expected between {_show(low, 'MW')} and {_show(high, 'MW')}")
    return power


def _reheat_temperature(table: _Fields, t_exh: float) -> float | None:
    if not table.has("reheat_temperature"):
        return None
    t_rh = table.quantity("reheat_temperature")
    if t_rh <= t_exh:
        raise HeatBalanceError(
            f"{table.where('reheat_temperature')} = {_show(t_rh, 'degC')} is not above "
            f"hp_exhaust_temperature ({_show(t_exh, 'degC')}): the reheater heats the steam")
    return t_rh


def _feedwater_temperature(table: _Fields, t0: float, p_cs: float,
                           extractions: tuple[HeatBalanceExtraction, ...]) -> float | None:
    if not table.has("feedwater_temperature"):
        return None
    t_fw = table.quantity("feedwater_temperature")
    top = max((bleed.pressure_pa for bleed in extractions), default=p_cs)
    limit = float(if97.saturation_temperature(min(top, if97.P_CRIT)))
    limit += FEEDWATER_SUPERHEAT_ALLOWANCE
    what = "the highest bleed" if extractions else "control_stage_pressure"
    if t_fw >= min(limit, t0):
        raise HeatBalanceError(
            f"{table.where('feedwater_temperature')} = {_show(t_fw, 'degC')}: the top heater "
            f"cannot heat the feedwater above {_show(min(limit, t0), 'degC')} (saturation at "
            f"{what}, {_show(top, 'MPa')}, plus {FEEDWATER_SUPERHEAT_ALLOWANCE:g} K)")
    return t_fw


# ---------------------------------------------------------------------------------------------
# Between points
# ---------------------------------------------------------------------------------------------


#: Point figures that must fall with load: (field, HeatBalancePoint attribute, unit shown).
_FALLING_WITH_LOAD = (("main_steam_flow", "main_steam_flow_kg_s", "t/h"),
                      ("control_stage_pressure", "control_stage_pressure_pa", "MPa"),
                      ("hp_exhaust_pressure", "hp_exhaust_pressure_pa", "MPa"))


def _check_between_points(points: tuple[HeatBalancePoint, ...], source: str) -> None:
    """Labels unique, loads strictly decreasing, flow and pressures falling with load, and the
    same bleeds at every point."""
    def where(number: int, field: str) -> str:
        return f"{source}: {_named(number, points[number - 1].label)}: {field}"

    for number in range(2, len(points) + 1):
        point, before = points[number - 1], points[number - 2]
        for earlier, other in enumerate(points[:number - 1], start=1):
            if other.label == point.label:
                raise HeatBalanceError(f"{where(number, 'label')} repeats the label of "
                                       f"points[{earlier}]; expected one label per point")
            if other.load_w == point.load_w:
                raise HeatBalanceError(
                    f"{where(number, 'load')} = {_show(point.load_w, 'MW')} duplicates the load "
                    f"of {_named(earlier, other.label)}; expected one point per load")
        if point.load_w > before.load_w:
            raise HeatBalanceError(
                f"{where(number, 'load')} = {_show(point.load_w, 'MW')} is above the load of "
                f"points[{number - 1}] ({_show(before.load_w, 'MW')}): points are out of order; "
                "list them by strictly decreasing load (VWO first)")
        for field, attribute, unit in _FALLING_WITH_LOAD:
            value, previous = getattr(point, attribute), getattr(before, attribute)
            if value >= previous:
                raise HeatBalanceError(
                    f"{where(number, field)} = {_show(value, unit)} is not below that of "
                    f"points[{number - 1}] ({_show(previous, unit)}) at a higher load: it must "
                    "fall with load")
    names = [tuple(bleed.name for bleed in point.extractions) for point in points]
    for number, bleeds in enumerate(names, start=1):
        if bleeds != names[0]:
            raise HeatBalanceError(
                f"{where(number, 'extractions')} lists {list(bleeds)} but points[1] lists "
                f"{list(names[0])}; expected the same bleeds in the same order at every point")
