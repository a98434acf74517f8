"""Read a turbine spec from TOML, validating every field and naming the offending one.

Kept as one module because it is one job, validating a spec document table by table against
:mod:`steamtwin.spec.schema`, with one error-naming helper (``_Table``) every table reader uses.

Dimensional values are written with their unit (``"16.7 MPa"``, ``"538 degC"``, ``"1800 t/h"``)
and converted to SI with pint; plain numbers are for dimensionless fields only. Each field's
unit and valid range come from :mod:`steamtwin.spec.schema`, the table ``docs/spec.md`` is
generated from.

The schema is strict: each table and array of tables may hold only the keys :data:`SPEC_KEYS`
lists for it, and every one of them is required except the top-level ``[[extractions]]``. An
unknown key is an error with a "did you mean" hint — a misspelled ``[[extraction]]`` would
otherwise drop the bleed without a word. Positions in arrays are counted from 1 in messages:
``stages[3]`` is the third ``[[stages]]`` table, stage 3 (stage 0 is the control stage).
"""

from __future__ import annotations

import itertools
import tomllib
from collections.abc import Mapping
from dataclasses import fields, replace
from importlib import resources
from pathlib import Path
from typing import Any

from steamtwin.dcs.signals import SIGNALS
from steamtwin.errors import SpecAreaError
from steamtwin.keys import unknown_key_message
from steamtwin.spec.schema import FORMAT_VERSION, METAL_DEPTH_RANGE_M, Field, field_for
from steamtwin.spec.turbine import (
    DEFAULT_CASING_THERMOCOUPLE_DEPTH,
    DEFAULT_ROTOR_MATERIAL,
    ControlStage,
    DesignPoint,
    Extraction,
    GoverningValve,
    Leakage,
    Material,
    MetalGeometry,
    MetalGroup,
    PartLoad,
    PressureStage,
    RotorSection,
    RotorSteam,
    SlidingPressureLine,
    StageGeometry,
    TemperatureSchedule,
    TurbineSpec,
)
from steamtwin.steam.tables import lower_boundary_temperature
from steamtwin.textfile import read_utf8_text
from steamtwin.units import UnitError, parse_quantity

__all__ = ["BUILT_IN", "FORMAT_VERSION", "OPTIONAL_KEYS", "SPEC_KEYS", "SpecError", "load_spec",
           "parse_spec"]

BUILT_IN = ("reference",)

_BLADING = frozenset({"mean_diameter", "blade_height", "blade_count", "reaction",
                      "nozzle_exit_angle", "peak_blade_efficiency", "friction_loss"})
_MATERIAL = frozenset({"density", "specific_heat", "thermal_conductivity"})
_PART_LOAD = frozenset(field.name for field in fields(PartLoad))
#: A metal group gives either its masses and areas or its geometry (rotor_bore_radius optional).
_MASS_AND_AREA = ("casing_mass", "casing_area", "rotor_mass", "rotor_area")
_GEOMETRY = ("axial_length", "rotor_radius", "casing_inner_radius", "casing_wall_thickness")

#: The keys each table may hold, by its path without array positions ("" is the top level).
SPEC_KEYS: Mapping[str, frozenset[str]] = {
    "": frozenset({"format_version", "name", "description", "sensors", "design",
                   "control_stage", "stages", "extractions", "metal", "sliding_pressure",
                   "part_load", "temperature_schedule", "leakages", "rotor"}),
    "design": frozenset({"main_steam_pressure", "main_steam_temperature", "main_steam_flow",
                         "control_stage_pressure", "hp_exhaust_pressure",
                         "hp_exhaust_temperature", "hp_power", "generator_power",
                         "rotational_speed", "valve_pressure_drop", "valve_outlet_pressure"}),
    "control_stage": _BLADING | {"nozzle_discharge_coefficient", "valves", "valve_overlap",
                                 "valve_characteristic"},
    "control_stage.valve_characteristic": frozenset({"lift", "flow"}),
    "control_stage.valves": frozenset({"name", "opening_order", "admission_arc",
                                       "open_at_design", "throat_area"}),
    "stages": _BLADING | {"flow_capacity", "tip_leakage"},
    "extractions": frozenset({"name", "after_stage", "design_flow", "design_pressure"}),
    "leakages": frozenset({"name", "from_stage", "to", "design_flow", "sink_pressure"}),
    "metal": frozenset({"casing_sensor_group", "ambient_temperature", "casing_material",
                        "rotor_material", "groups", "casing_thermocouple_depth"}),
    "metal.casing_material": _MATERIAL,
    "metal.rotor_material": _MATERIAL,
    "metal.groups": frozenset({"name", "stages", "insulation_conductance", *_MASS_AND_AREA,
                               *_GEOMETRY, "rotor_bore_radius"}),
    "rotor": frozenset({"axial_length", "control_stage_radius", "stage_radius", "stage_start",
                        "bore_radius", "groove_radius", "groove_depth", "groove_position",
                        "material", "rotational_speed", "steam"}),
    "rotor.steam": frozenset({"group", "start", "end"}),
    "sliding_pressure": frozenset({"load_fraction", "pressure"}),
    "part_load": _PART_LOAD,
    "temperature_schedule": frozenset({"load_fraction", "main_steam_temperature",
                                       "reheat_temperature"}),
}
#: Keys that may be left out, by their path: a unit without HP bleeds has no extractions; the
#: part-load laws and each of their fields have defaults (:class:`PartLoad`); valves without
#: overlap open strictly one group after the other, with a linear flow characteristic; the
#: rated point is a valve point unless its valve outlet pressure is given; the model sizes the
#: nozzle throat areas unless they are given; without a temperature schedule the boiler holds
#: the design main-steam temperature at every load; a unit may state no leakages and no tip
#: leakage, and only a leakage to the outside has a sink pressure; a metal group gives either
#: its masses and areas or its geometry; the casing thermocouple depth has a default; a unit
#: without a rotor stress model has no ``[rotor]``, whose bore, steel and speed have defaults.
OPTIONAL_KEYS = frozenset({"extractions", "part_load", "control_stage.valve_overlap",
                           "control_stage.valve_characteristic", "design.valve_outlet_pressure",
                           "control_stage.valves.throat_area",
                           *(f"part_load.{key}" for key in _PART_LOAD),
                           "temperature_schedule", "temperature_schedule.reheat_temperature",
                           "leakages", "leakages.sink_pressure", "stages.tip_leakage",
                           *(f"metal.groups.{key}" for key in (*_MASS_AND_AREA, *_GEOMETRY)),
                           "metal.groups.rotor_bore_radius", "metal.casing_thermocouple_depth",
                           "rotor", "rotor.bore_radius", "rotor.material",
                           "rotor.rotational_speed"})


class SpecError(SpecAreaError):
    """A turbine spec is missing a field, has a bad value or is inconsistent."""


def _type_name(value: Any) -> str:
    """The TOML name of a value's type, for messages."""
    names = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    return names.get(type(value), "a date/time")


def _parse_quantity(value: Any, si_unit: str, where: str) -> float:
    """``value`` (``"16.7 MPa"``, or a plain number if dimensionless) in ``si_unit``.

    ``where`` is the file and field, e.g. ``"unit.toml: design.hp_power"``.
    """
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        expected = (f"a string 'value unit' with a unit convertible to {si_unit}"
                    if si_unit else "a plain number")
        raise SpecError(f"{where} is {_type_name(value)}: expected {expected}")
    try:
        return parse_quantity(value, si_unit, where)
    except UnitError as error:
        raise SpecError(str(error)) from None


def _checked_quantity(raw: Any, field: Field, where: str) -> float:
    """``raw`` in ``field``'s SI unit, refused outside its valid range; ``where`` names it."""
    value = _parse_quantity(raw, field.unit, where)
    if not field.contains(value):
        shown = field.range_text(display=True)
        also = f" = {shown}" if field.display_unit not in ("", field.unit) else ""
        raise SpecError(
            f"{where} = {raw!r} is outside the valid range {field.range_text()}{also}"
        )
    return value


class _Table:
    """A TOML table with its dotted path, so every error names the field.

    ``schema`` is the table's entry in :data:`SPEC_KEYS`; ``context`` (e.g. ``"stage 3"``)
    follows the file name in messages. Unknown keys are refused on construction.
    """

    def __init__(self, data: Any, path: str, source: str, schema: str = "",
                 context: str = "") -> None:
        label = f"{source}: {context}" if context else source
        if not isinstance(data, dict):
            raise SpecError(f"{label}: {path} is {_type_name(data)}: expected a table")
        message = unknown_key_message(data, SPEC_KEYS[schema], path, label, "turbine spec")
        if message is not None:
            raise SpecError(message)
        self.data, self.path, self.source, self.label = data, path, source, label
        self.schema, self.context = schema, context

    def _where(self, key: str) -> str:
        return f"{self.label}: {self.path}.{key}" if self.path else f"{self.label}: {key}"

    def raw(self, key: str) -> Any:
        if key not in self.data:
            raise SpecError(f"{self._where(key)} is missing")
        return self.data[key]

    def field(self, key: str) -> Field:
        """The schema's entry for ``key`` of this table (unit and valid range)."""
        return field_for(self.schema, key)

    def quantity(self, key: str) -> float:
        """A quantity or plain number in its SI unit, within the schema's range."""
        field = self.field(key)
        return _checked_quantity(self.raw(key), field, self._where(key))

    def integer(self, key: str, high: int | None = None) -> int:
        """An integer within the schema's range; ``high`` for a bound the schema leaves open."""
        field = self.field(key)
        low = int(field.low) if field.low is not None else None
        high = int(field.high) if field.high is not None else high
        value = self.raw(key)
        if (isinstance(value, bool) or not isinstance(value, int)
                or (low is not None and value < low) or (high is not None and value > high)):
            raise SpecError(
                f"{self._where(key)} = {value!r}: expected an integer in [{low}, {high}]"
            )
        return value

    def text(self, key: str) -> str:
        value = self.raw(key)
        if not isinstance(value, str) or not value.strip():
            raise SpecError(f"{self._where(key)}: expected a non-empty string")
        return value

    def flag(self, key: str) -> bool:
        value = self.raw(key)
        if not isinstance(value, bool):
            raise SpecError(f"{self._where(key)} = {value!r}: expected true or false")
        return value

    def _child(self, key: str) -> tuple[str, str]:
        """Path and schema entry of the sub-table ``key``."""
        return (f"{self.path}.{key}" if self.path else key,
                f"{self.schema}.{key}" if self.schema else key)

    def table(self, key: str) -> _Table:
        path, schema = self._child(key)
        return _Table(self.raw(key), path, self.source, schema, self.context)

    def tables(self, key: str, item: str = "") -> list[_Table]:
        """The array of tables ``key``; ``item`` (e.g. ``"stage"``) labels each in messages."""
        value = self.raw(key)
        path, schema = self._child(key)
        if not isinstance(value, list) or not value:
            raise SpecError(f"{self._where(key)}: expected a non-empty array of tables")
        return [_Table(entry, f"{path}[{number}]", self.source, schema,
                       f"{item} {number}" if item else self.context)
                for number, entry in enumerate(value, start=1)]


def load_spec(source: str | Path) -> TurbineSpec:
    """Load a built-in turbine (``"reference"``) or a TOML file and validate it.

    Raises :class:`SpecError` naming the file and field for anything unreadable (not UTF-8 text,
    not TOML), unknown, missing, out of range or inconsistent.
    """
    if str(source) in BUILT_IN:
        resource = resources.files("steamtwin.spec") / "data" / f"{source}.toml"
        return parse_spec(resource.read_text(encoding="utf-8"), f"built-in '{source}'")
    path = Path(source)
    if not path.is_file():
        raise SpecError(
            f"turbine spec {str(source)!r} is neither a built-in ({', '.join(BUILT_IN)}) nor a file"
        )
    text = read_utf8_text(path, "turbine spec", "TOML", SpecError)
    return parse_spec(text, str(path))


def parse_spec(text: str, source: str = "<string>") -> TurbineSpec:
    """Parse and validate the TOML text of a turbine spec; ``source`` names it in errors."""
    if not text.strip():
        raise SpecError(f"{source}: the file is empty; expected a turbine spec in TOML")
    try:
        data = tomllib.loads(text)
    except (ValueError, RecursionError) as error:  # TOMLDecodeError, over-long integers, nesting
        raise SpecError(f"{source}: not valid TOML: {error}") from None
    document = _Table(data, "", source)
    document.integer("format_version")
    design = _design(document.table("design"))
    control_stage = _control_stage(document.table("control_stage"))
    stages = tuple(_pressure_stage(table) for table in document.tables("stages", "stage"))
    bleeds = document.tables("extractions") if "extractions" in document.data else []
    extractions = tuple(_extraction(table, len(stages)) for table in bleeds)
    metal = document.table("metal")
    casing_material = _material(metal.table("casing_material"))
    rotor_material = _material(metal.table("rotor_material"))
    groups = tuple(_metal_group(table, len(stages), casing_material, rotor_material)
                   for table in metal.tables("groups"))
    spec = TurbineSpec(
        name=document.text("name"),
        description=document.text("description"),
        design=design,
        control_stage=control_stage,
        stages=stages,
        extractions=extractions,
        casing_material=casing_material,
        rotor_material=rotor_material,
        metal_groups=groups,
        casing_sensor_group=metal.text("casing_sensor_group"),
        ambient_temperature=metal.quantity("ambient_temperature"),
        sliding_pressure=_sliding_pressure(document.table("sliding_pressure")),
        sensors=_sensors(document),
        part_load=_part_load(document.table("part_load")) if "part_load" in document.data
        else PartLoad(),
        temperature_schedule=_temperature_schedule(document.table("temperature_schedule"))
        if "temperature_schedule" in document.data else None,
        leakages=tuple(_leakage(table, len(stages), design)
                       for table in (document.tables("leakages")
                                     if "leakages" in document.data else [])),
        casing_thermocouple_depth=metal.quantity("casing_thermocouple_depth")
        if "casing_thermocouple_depth" in metal.data else DEFAULT_CASING_THERMOCOUPLE_DEPTH,
    )
    _check_consistency(spec, source)
    if "rotor" in document.data:  # after the groups it names are known to be consistent
        spec = replace(spec, rotor=_rotor(document.table("rotor"), design,
                                          {group.name for group in groups}))
    return spec


def _design(table: _Table) -> DesignPoint:
    return DesignPoint(
        main_steam_pressure=table.quantity("main_steam_pressure"),
        main_steam_temperature=table.quantity("main_steam_temperature"),
        main_steam_flow=table.quantity("main_steam_flow"),
        control_stage_pressure=table.quantity("control_stage_pressure"),
        hp_exhaust_pressure=table.quantity("hp_exhaust_pressure"),
        hp_exhaust_temperature=table.quantity("hp_exhaust_temperature"),
        hp_power=table.quantity("hp_power"),
        generator_power=table.quantity("generator_power"),
        rotational_speed=table.quantity("rotational_speed"),
        valve_pressure_drop=table.quantity("valve_pressure_drop"),
        valve_outlet_pressure=table.quantity("valve_outlet_pressure")
        if "valve_outlet_pressure" in table.data else None,
    )


def _blading(table: _Table) -> StageGeometry:
    return StageGeometry(
        mean_diameter=table.quantity("mean_diameter"),
        blade_height=table.quantity("blade_height"),
        blade_count=table.integer("blade_count"),
        reaction=table.quantity("reaction"),
        nozzle_exit_angle=table.quantity("nozzle_exit_angle"),
        peak_blade_efficiency=table.quantity("peak_blade_efficiency"),
        friction_loss=table.quantity("friction_loss"),
    )


def _control_stage(table: _Table) -> ControlStage:
    valves = tuple(
        GoverningValve(
            name=valve.text("name"),
            opening_order=valve.integer("opening_order"),
            admission_arc=valve.quantity("admission_arc"),
            open_at_design=valve.flag("open_at_design"),
            throat_area=valve.quantity("throat_area") if "throat_area" in valve.data else None,
        )
        for valve in table.tables("valves")
    )
    given = [valve.throat_area is not None for valve in valves]
    if any(given) and not all(given):
        missing = [valve.name for valve in valves if valve.throat_area is None]
        raise SpecError(f"{table.source}: control_stage.valves[].throat_area is given for some "
                        f"valves but not for {', '.join(missing)}: give it for every valve or "
                        "for none (the model then sizes the throats)")
    total_arc = sum(valve.admission_arc for valve in valves)
    if total_arc > 1.0 + 1e-9:
        raise SpecError(
            f"{table.source}: control_stage.valves: admission arcs add up to {total_arc:.3f} "
            "of the circumference (must be ≤ 1)"
        )
    names = [valve.name for valve in valves]
    if len(set(names)) != len(names):
        raise SpecError(f"{table.source}: control_stage.valves: valve names repeat: {names}")
    if not any(valve.open_at_design for valve in valves):
        raise SpecError(f"{table.source}: control_stage.valves: no valve is open at design")
    _check_valve_sequence(valves, table.source)
    return ControlStage(
        blading=_blading(table),
        nozzle_discharge_coefficient=table.quantity("nozzle_discharge_coefficient"),
        valves=valves,
        valve_overlap=table.quantity("valve_overlap") if "valve_overlap" in table.data else 0.0,
        valve_characteristic=_valve_characteristic(table.table("valve_characteristic"))
        if "valve_characteristic" in table.data else ControlStage.valve_characteristic,
    )


def _valve_characteristic(table: _Table) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(lift, flow share) of the valve characteristic: both 0…1, lift strictly increasing from
    0 to 1, flow share rising (non-decreasing) from 0 to 1."""
    where = f"{table.source}: {table.path}"
    columns = []
    for key in ("lift", "flow"):
        field, values = table.field(key), table.raw(key)
        if not isinstance(values, list) or len(values) < field.min_items:
            raise SpecError(f"{where}.{key} must be an array of ≥ {field.min_items} numbers")
        columns.append(tuple(_checked_quantity(value, field, f"{where}.{key}[{number}]")
                             for number, value in enumerate(values, start=1)))
    lift, flow = columns
    if len(lift) != len(flow):
        raise SpecError(f"{where}: lift has {len(lift)} values but flow has {len(flow)}")
    if lift[0] != 0.0 or lift[-1] != 1.0 or any(b <= a for a, b in itertools.pairwise(lift)):
        raise SpecError(f"{where}.lift must rise strictly from 0 to 1, got {list(lift)}")
    if flow[0] != 0.0 or flow[-1] != 1.0 or any(b < a for a, b in itertools.pairwise(flow)):
        raise SpecError(f"{where}.flow must rise from 0 to 1 (never fall), got {list(flow)}")
    return lift, flow


def _check_valve_sequence(valves: tuple[GoverningValve, ...], source: str) -> None:
    """Valves open at design must be exactly the first opening orders (no gaps in the sequence)."""
    for order in sorted({valve.opening_order for valve in valves}):
        group = [valve for valve in valves if valve.opening_order == order]
        if len({valve.open_at_design for valve in group}) > 1:
            raise SpecError(
                f"{source}: control_stage.valves: valves of opening_order {order} "
                "disagree on open_at_design"
            )
    open_orders = {v.opening_order for v in valves if v.open_at_design}
    closed_orders = {v.opening_order for v in valves if not v.open_at_design}
    if closed_orders and open_orders and max(open_orders) > min(closed_orders):
        raise SpecError(
            f"{source}: control_stage.valves: a valve open at design opens after a closed one "
            f"(open orders {sorted(open_orders)}, closed orders {sorted(closed_orders)})"
        )


def _pressure_stage(table: _Table) -> PressureStage:
    return PressureStage(
        blading=_blading(table), flow_capacity=table.quantity("flow_capacity"),
        tip_leakage=table.quantity("tip_leakage") if "tip_leakage" in table.data else 0.0,
    )


def _extraction(table: _Table, stage_count: int) -> Extraction:
    return Extraction(
        name=table.text("name"),
        after_stage=table.integer("after_stage", high=stage_count - 1),
        design_flow=table.quantity("design_flow"),
        design_pressure=table.quantity("design_pressure"),
    )


def _leakage(table: _Table, stage_count: int, design: DesignPoint) -> Leakage:
    """A leakage; its sink pressure is given exactly when it leaves the HP section."""
    to = table.text("to")
    choices = table.field("to").choices
    if to not in choices:
        raise SpecError(f"{table._where('to')} = {to!r}: expected one of {list(choices)}")
    given = "sink_pressure" in table.data
    if to == "outside" and not given:
        raise SpecError(f"{table._where('sink_pressure')} is missing: a leakage to the outside "
                        "needs the pressure it discharges into at rated load (Pa)")
    if to == "hp_exhaust" and given:
        raise SpecError(f"{table._where('sink_pressure')}: a leakage to the hp_exhaust "
                        "discharges at the HP-exhaust pressure; leave sink_pressure out")
    sink = table.quantity("sink_pressure") if given else None
    if sink is not None and sink >= design.control_stage_pressure:
        raise SpecError(
            f"{table._where('sink_pressure')} = {sink / 1e6:g} MPa must lie below "
            f"design.control_stage_pressure ({design.control_stage_pressure / 1e6:g} MPa)")
    return Leakage(
        name=table.text("name"),
        from_stage=table.integer("from_stage", high=stage_count - 1),
        to=to,
        design_flow=table.quantity("design_flow"),
        sink_pressure=sink,
    )


def _material(table: _Table) -> Material:
    return Material(
        density=table.quantity("density"),
        specific_heat=table.quantity("specific_heat"),
        thermal_conductivity=table.quantity("thermal_conductivity"),
    )


def _metal_group(table: _Table, stage_count: int, casing_material: Material,
                 rotor_material: Material) -> MetalGroup:
    stages = table.raw("stages")
    first = int(table.field("stages").low or 0)
    if (
        not isinstance(stages, list)
        or not stages
        or not all(isinstance(s, int) and not isinstance(s, bool) for s in stages)
        or stages != list(range(stages[0], stages[0] + len(stages)))
        or not first <= stages[0] <= stages[-1] <= stage_count
    ):
        raise SpecError(
            f"{table.label}: {table.path}.stages = {stages!r}: expected consecutive stage numbers "
            f"within {first}…{stage_count} (0 = control stage)"
        )
    name = table.text("name")
    given = {key: table.quantity(key) for key in (*_MASS_AND_AREA, *_GEOMETRY,
                                                  "rotor_bore_radius") if key in table.data}
    insulation = table.quantity("insulation_conductance")
    geometry = _metal_geometry(table, given)
    if geometry is None:
        return MetalGroup(name=name, stages=tuple(stages),
                          **{key: given[key] for key in _MASS_AND_AREA},
                          insulation_conductance=insulation)
    casing_mass, casing_area, rotor_mass, rotor_area = geometry.masses_and_areas(
        casing_material.density, rotor_material.density)
    return MetalGroup(name=name, stages=tuple(stages), casing_mass=casing_mass,
                      casing_area=casing_area, rotor_mass=rotor_mass, rotor_area=rotor_area,
                      insulation_conductance=insulation, geometry=geometry)


def _metal_geometry(table: _Table, given: Mapping[str, float]) -> MetalGeometry | None:
    """The group's geometry (None when it gives masses and areas), refusing a mix or a part."""
    mass_keys = [key for key in _MASS_AND_AREA if key in given]
    geometry_keys = [key for key in (*_GEOMETRY, "rotor_bore_radius") if key in given]
    either = (f"a metal group gives either {', '.join(_MASS_AND_AREA)} or the geometry "
              f"{', '.join(_GEOMETRY)} (and optionally rotor_bore_radius)")
    if mass_keys and geometry_keys:
        raise SpecError(f"{table.label}: {table.path} mixes masses/areas ({', '.join(mass_keys)}) "
                        f"with geometry ({', '.join(geometry_keys)}): {either}")
    if not geometry_keys:
        for key in _MASS_AND_AREA:
            if key not in given:
                raise SpecError(f"{table.label}: {table.path}.{key} is missing ({either})")
        return None
    missing = [key for key in _GEOMETRY if key not in given]
    if missing:
        raise SpecError(f"{table.label}: {table.path} gives the geometry fields "
                        f"{', '.join(geometry_keys)} but not {', '.join(missing)} ({either})")
    bore, radius = given.get("rotor_bore_radius", 0.0), given["rotor_radius"]
    thinnest = METAL_DEPTH_RANGE_M[0]
    if bore > radius - thinnest:
        raise SpecError(
            f"{table.label}: {table.path}.rotor_bore_radius = {bore:g} m leaves less than "
            f"{thinnest:g} m of metal under {table.path}.rotor_radius = {radius:g} m")
    if given["casing_inner_radius"] <= radius:
        raise SpecError(
            f"{table.label}: {table.path}.casing_inner_radius = "
            f"{given['casing_inner_radius']:g} m must exceed {table.path}.rotor_radius = "
            f"{radius:g} m (the steam flows between rotor and casing)")
    return MetalGeometry(axial_length=given["axial_length"], rotor_radius=radius,
                         rotor_bore_radius=bore,
                         casing_inner_radius=given["casing_inner_radius"],
                         casing_wall_thickness=given["casing_wall_thickness"])


def _rotor(table: _Table, design: DesignPoint, group_names: set[str]) -> RotorSection:
    """The drawn rotor section: every dimension in range, the groove and bore drawable, each
    wetted interval inside the section and naming a metal group."""
    steam = []
    for interval in table.tables("steam"):
        group = interval.text("group")
        if group not in group_names:
            raise SpecError(f"{interval.label}: {interval.path}.group = {group!r} names no "
                            f"metal group (known: {', '.join(sorted(group_names))})")
        steam.append(RotorSteam(group=group, start=interval.quantity("start"),
                                end=interval.quantity("end")))
    section = RotorSection(
        **{key: table.quantity(key) for key in (
            "axial_length", "control_stage_radius", "stage_radius", "stage_start",
            "groove_radius", "groove_depth", "groove_position")},
        steam=tuple(steam),
        rotational_speed=table.quantity("rotational_speed")
        if "rotational_speed" in table.data else design.rotational_speed,
        bore_radius=table.quantity("bore_radius") if "bore_radius" in table.data else 0.0,
        material=table.text("material") if "material" in table.data
        else DEFAULT_ROTOR_MATERIAL)
    problems = section.problems(METAL_DEPTH_RANGE_M[0])
    if problems:
        raise SpecError(f"{table.source}: {problems[0]}")
    return section


def _sliding_pressure(table: _Table) -> SlidingPressureLine:
    loads = table.raw("load_fraction")
    pressures = table.raw("pressure")
    where = f"{table.source}: sliding_pressure"
    load_field, pressure_field = table.field("load_fraction"), table.field("pressure")
    least = max(load_field.min_items, pressure_field.min_items)
    if not isinstance(loads, list) or not isinstance(pressures, list) or len(loads) < least:
        raise SpecError(f"{where}: load_fraction and pressure must be arrays of ≥ {least} values")
    if len(loads) != len(pressures):
        raise SpecError(
            f"{where}: load_fraction has {len(loads)} values but pressure has {len(pressures)}"
        )
    load_values = tuple(_parse_quantity(value, load_field.unit, f"{where}.load_fraction[{number}]")
                        for number, value in enumerate(loads, start=1))
    if (not all(load_field.contains(value) for value in load_values)
            or any(b <= a for a, b in itertools.pairwise(load_values))):
        raise SpecError(f"{where}.load_fraction must increase within "
                        f"{load_field.low:g}…{load_field.high:g}, got {list(loads)}")
    pressure_values = tuple(
        _checked_quantity(value, pressure_field, f"{where}.pressure[{number}]")
        for number, value in enumerate(pressures, start=1)
    )
    return SlidingPressureLine(load_values, pressure_values)


def _quantity_array(table: _Table, key: str, count: int | None = None) -> tuple[float, ...]:
    """The array ``key`` of ``table``, each entry in the schema's unit and range; ``count``: the
    length it must have (that of the table's load axis)."""
    field, where = table.field(key), table._where(key)
    values = table.raw(key)
    if not isinstance(values, list) or len(values) < field.min_items:
        given = (f"has {len(values)} value{'s' * (len(values) != 1)}"
                 if isinstance(values, list) else f"is {_type_name(values)}")
        raise SpecError(f"{where} {given}: expected an array of ≥ {field.min_items} values")
    if count is not None and len(values) != count:
        raise SpecError(f"{where} has {len(values)} values but load_fraction has {count}")
    return tuple(_checked_quantity(value, field, f"{where}[{number}]")
                 for number, value in enumerate(values, start=1))


def _temperature_schedule(table: _Table) -> TemperatureSchedule:
    """The steam-temperature schedule: a strictly increasing load axis and, at each load, the
    main-steam and (if given) hot-reheat temperature."""
    loads = _quantity_array(table, "load_fraction")
    for number, (low, high) in enumerate(itertools.pairwise(loads), start=2):
        if high <= low:
            raise SpecError(
                f"{table._where('load_fraction')}[{number}] = {high:g} is not above "
                f"load_fraction[{number - 1}] = {low:g}: the load axis must increase strictly")
    return TemperatureSchedule(
        load_fraction=loads,
        main_steam_temperature=_quantity_array(table, "main_steam_temperature", len(loads)),
        reheat_temperature=_quantity_array(table, "reheat_temperature", len(loads))
        if "reheat_temperature" in table.data else None,
    )


def _part_load(table: _Table) -> PartLoad:
    """The part-load laws: the fields given, the others at their defaults."""
    return PartLoad(**{key: table.quantity(key) for key in _PART_LOAD if key in table.data})


def _sensors(document: _Table) -> tuple[str, ...]:
    names = document.raw("sensors")
    if not isinstance(names, list) or not names:
        raise SpecError(f"{document.source}: sensors must be a non-empty array of signal names")
    for number, name in enumerate(names, start=1):
        if not isinstance(name, str) or name not in SIGNALS:
            raise SpecError(
                f"{document.source}: sensors[{number}] = {name!r} is not a canonical signal "
                f"(known: {', '.join(SIGNALS)})"
            )
    return tuple(names)


def _check_consistency(spec: TurbineSpec, source: str) -> None:
    """Cross-field checks: pressures fall along the path, groups cover the stages once."""
    design = spec.design
    if not design.main_steam_pressure > design.control_stage_pressure > design.hp_exhaust_pressure:
        raise SpecError(
            f"{source}: design pressures must fall along the steam path: "
            f"design.main_steam_pressure {design.main_steam_pressure / 1e6:g} MPa > "
            f"design.control_stage_pressure {design.control_stage_pressure / 1e6:g} MPa > "
            f"design.hp_exhaust_pressure {design.hp_exhaust_pressure / 1e6:g} MPa"
        )
    if design.hp_exhaust_temperature >= design.main_steam_temperature:
        raise SpecError(
            f"{source}: design.hp_exhaust_temperature must be below design.main_steam_temperature"
        )
    if design.hp_power >= design.generator_power:
        raise SpecError(f"{source}: design.hp_power must be below design.generator_power")
    wide_open = design.main_steam_pressure * (1.0 - design.valve_pressure_drop)
    if design.valve_outlet_pressure is not None and not (
            wide_open >= design.valve_outlet_pressure > design.control_stage_pressure):
        raise SpecError(
            f"{source}: design.valve_outlet_pressure {design.valve_outlet_pressure / 1e6:g} MPa "
            f"must lie above design.control_stage_pressure "
            f"{design.control_stage_pressure / 1e6:g} MPa and not above the wide-open valve "
            f"outlet, design.main_steam_pressure × (1 − design.valve_pressure_drop) = "
            f"{wide_open / 1e6:g} MPa")
    for number, extraction in enumerate(spec.extractions, start=1):
        upstream, downstream = design.control_stage_pressure, design.hp_exhaust_pressure
        if not upstream > extraction.design_pressure > downstream:
            raise SpecError(
                f"{source}: extractions[{number}].design_pressure ({extraction.name!r}, "
                f"{extraction.design_pressure / 1e6:g} MPa) must lie between the control-stage "
                f"and HP-exhaust design pressures ({upstream / 1e6:g} and {downstream / 1e6:g} MPa)"
            )
    bled = sum(extraction.design_flow for extraction in spec.extractions)
    if bled >= design.main_steam_flow:
        raise SpecError(
            f"{source}: extractions bleed {bled:.1f} kg/s in all, not less than the main-steam "
            f"flow {design.main_steam_flow:.1f} kg/s"
        )
    leakage_names = [leakage.name for leakage in spec.leakages]
    if len(set(leakage_names)) != len(leakage_names):
        raise SpecError(f"{source}: leakages names repeat: {leakage_names}")
    leaked = sum(leakage.design_flow for leakage in spec.leakages)
    if leaked and bled + leaked >= design.main_steam_flow:
        raise SpecError(
            f"{source}: leakages ({leaked:.1f} kg/s) and extractions ({bled:.1f} kg/s) take "
            f"together not less than the main-steam flow {design.main_steam_flow:.1f} kg/s"
        )
    exhaust_boundary = float(lower_boundary_temperature(design.hp_exhaust_pressure))
    if design.hp_exhaust_temperature <= exhaust_boundary:
        raise SpecError(
            f"{source}: design.hp_exhaust_temperature {design.hp_exhaust_temperature - 273.15:.1f}"
            f" °C is not superheated at {design.hp_exhaust_pressure / 1e6:g} MPa (must exceed "
            f"{exhaust_boundary - 273.15:.1f} °C)"
        )
    names = [group.name for group in spec.metal_groups]
    if len(set(names)) != len(names):
        raise SpecError(f"{source}: metal.groups names repeat: {names}")
    for number, group in enumerate(spec.metal_groups, start=1):
        if 0 in group.stages and group.stages != (0,):
            raise SpecError(
                f"{source}: metal.groups[{number}] ({group.name!r}): the control stage (stage 0) "
                "must be a group of its own — its chamber carries the casing thermocouple"
            )
    covered = [stage for group in spec.metal_groups for stage in group.stages]
    expected = list(range(len(spec.stages) + 1))
    if sorted(covered) != expected:
        raise SpecError(
            f"{source}: metal.groups must cover stages 0…{len(spec.stages)} exactly once, "
            f"got {sorted(covered)}"
        )
    if spec.casing_sensor_group not in {group.name for group in spec.metal_groups}:
        raise SpecError(
            f"{source}: metal.casing_sensor_group {spec.casing_sensor_group!r} names no group"
        )
    shallowest, deepest = METAL_DEPTH_RANGE_M
    for number, group in enumerate(spec.metal_groups, start=1):
        if group.geometry is not None:
            _check_geometry_against_blading(spec, number, group, group.geometry, source)
            continue
        for body, mass, area, material in (
            ("casing", group.casing_mass, group.casing_area, spec.casing_material),
            ("rotor", group.rotor_mass, group.rotor_area, spec.rotor_material),
        ):
            thickness = mass / (material.density * area)
            if not shallowest <= thickness <= deepest:
                raise SpecError(
                    f"{source}: metal.groups[{number}] ({group.name!r}): {body}_mass/{body}_area "
                    f"imply a metal depth of {thickness:.3f} m (expected {shallowest:g}–"
                    f"{deepest:g} m)"
                )
    _check_thermocouple_depth(spec, source)


def _check_geometry_against_blading(spec: TurbineSpec, number: int, group: MetalGroup,
                                    geometry: MetalGeometry, source: str) -> None:
    """The drawn rotor lies inside, the casing bore outside every blade row's mean radius."""
    mean_radii = [(spec.control_stage.blading if stage == 0
                   else spec.stages[stage - 1].blading).mean_diameter / 2.0
                  for stage in group.stages]
    where = f"{source}: metal.groups[{number}]"
    if geometry.rotor_radius >= min(mean_radii):
        raise SpecError(f"{where}.rotor_radius = {geometry.rotor_radius:g} m ({group.name!r}) "
                        "must lie below the group's smallest blade mean radius "
                        f"{min(mean_radii):g} m (the rotor body is inside the blading)")
    if geometry.casing_inner_radius <= max(mean_radii):
        raise SpecError(f"{where}.casing_inner_radius = {geometry.casing_inner_radius:g} m "
                        f"({group.name!r}) must lie above the group's largest blade mean "
                        f"radius {max(mean_radii):g} m (the casing bore is outside the blading)")


def _check_thermocouple_depth(spec: TurbineSpec, source: str) -> None:
    """The casing thermocouple lies within the sensor group's wall."""
    number, group = next((number, group) for number, group in
                         enumerate(spec.metal_groups, start=1)
                         if group.name == spec.casing_sensor_group)
    depth = group.casing_wall_depth(spec.casing_material.density)
    if spec.casing_thermocouple_depth > depth:
        raise SpecError(
            f"{source}: metal.casing_thermocouple_depth = {spec.casing_thermocouple_depth:g} m "
            f"lies beyond the inner-casing wall of metal.groups[{number}] ({group.name!r}), "
            f"{depth:g} m deep")
