"""The turbine spec format: one table of every field, the single source of its rules.

Kept as one module because :data:`FIELDS` is meant to be the one table of every spec field;
its renderers (Markdown, JSON Schema) are short and read nothing else.

:data:`FIELDS` lists each field of a turbine spec by its TOML path (``design.main_steam_pressure``,
``control_stage.valves[].admission_arc``, ``stages[].flow_capacity``; ``[]`` marks an array of
tables) with its kind, SI unit, valid range, default, meaning and a hint where a plant engineer
finds the figure. The loader (:mod:`steamtwin.spec.loader`) takes every range from here;
``docs/spec.md`` (:func:`render_markdown`) and the editors' JSON Schema ``docs/spec.schema.json``
(:func:`json_schema`) are generated from it. Regenerate both with::

    python -m steamtwin.spec.schema --markdown > docs/spec.md
    python -m steamtwin.spec.schema --json-schema > docs/spec.schema.json
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from steamtwin.dcs.signals import SIGNALS
from steamtwin.spec.turbine import DEFAULT_ROTOR_MATERIAL
from steamtwin.units import convert

FORMAT_VERSION = 1

Kind = Literal["quantity", "number", "integer", "string", "boolean", "array", "table", "tables"]

#: "value unit" text, e.g. ``"16.7 MPa"``: a decimal number, then a unit (ECMA-262 and Python
#: regular-expression syntax alike, for the JSON Schema's ``pattern``).
QUANTITY_PATTERN = r"^\s*[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?\s*[^\s0-9.+-].*$"

#: Plausible heated metal depth mass / (density · wetted area) of a metal group, in m.
METAL_DEPTH_RANGE_M = (0.01, 1.0)
_BY_GEOMETRY = "computed from the geometry fields when the group gives them"
_BY_MASS = "left out when the group gives masses and areas"


@dataclass(frozen=True)
class Field:
    """One field of the spec.

    ``unit`` is the SI unit the loader converts a quantity to (``""`` for plain numbers);
    ``example`` a value as written in a spec (``"16.7 MPa"``, ``0.97``). ``low``/``high`` bound
    the value in SI (None: no static bound, ``bound_note`` then says what limits it); for arrays
    they bound each entry and ``items`` is the entries' kind. ``default`` is None for a required
    field, else what leaving it out means.
    """

    path: str
    kind: Kind
    meaning: str
    source: str
    unit: str = ""
    example: str | float | int = ""
    low: float | None = None
    high: float | None = None
    low_inclusive: bool = True
    high_inclusive: bool = True
    default: str | None = None
    items: Kind | None = None
    min_items: int = 0
    choices: tuple[str, ...] = ()
    bound_note: str = ""

    @property
    def key(self) -> str:
        """The path without array markers, as the loader names tables: ``stages.reaction``."""
        return self.path.replace("[]", "")

    @property
    def name(self) -> str:
        """The last key of the path: ``flow_capacity``."""
        return self.path.rsplit(".", 1)[-1].removesuffix("[]")

    @property
    def parent(self) -> str:
        """The path of the table holding the field (``""`` at top level): ``stages[]``."""
        return self.path.rsplit(".", 1)[0] if "." in self.path else ""

    @property
    def required(self) -> bool:
        """Whether a spec must give the field (it has no default)."""
        return self.default is None

    @property
    def display_unit(self) -> str:
        """The unit of the example (``"MPa"`` for ``"16.7 MPa"``), ``""`` for plain numbers."""
        if not isinstance(self.example, str) or not self.unit:
            return ""
        return self.example.split(maxsplit=1)[1]

    def contains(self, value: float) -> bool:
        """Whether a finite value (SI) lies in the valid range."""
        if not math.isfinite(value):
            return False
        above = self.low is None or (value >= self.low if self.low_inclusive else value > self.low)
        below = self.high is None or (
            value <= self.high if self.high_inclusive else value < self.high)
        return above and below

    def range_text(self, display: bool = False) -> str:
        """The valid range as an interval, in SI (``"[1e+06, 2.5e+07] Pa"``) or in the example's
        unit with ``display`` (``"[1, 25] MPa"``); ``""`` without static bounds."""
        if self.low is None and self.high is None:
            return ""
        unit = self.display_unit if display and self.display_unit else self.unit

        def shown(value: float | None, infinity: str) -> str:
            if value is None:
                return infinity
            if unit != self.unit:
                value = float(convert(value, self.unit, unit))
            return f"{value:g}"

        interval = (f"{'[' if self.low_inclusive else '('}{shown(self.low, '−∞')}, "
                    f"{shown(self.high, '∞')}{']' if self.high_inclusive else ')'}")
        return f"{interval} {unit or '(dimensionless)'}" if self.kind != "integer" else interval


def _blading(table: str, what: str) -> tuple[Field, ...]:
    """The blade-row fields shared by the control stage and the pressure stages."""
    drawing = "OEM flow-path (blade-path) drawing"
    return (
        Field(f"{table}.mean_diameter", "quantity",
              f"Mean (pitch) diameter of the {what} rotor blade row.",
              f"{drawing}; mean of root and tip diameter.", "m", "1.10 m", 0.2, 3.5),
        Field(f"{table}.blade_height", "quantity",
              f"Blade height (span) of the {what} row at its exit.",
              f"{drawing} or blade drawing; tip minus root radius.", "m", "0.032 m", 0.005, 1.5),
        Field(f"{table}.blade_count", "integer",
              f"Number of rotor blades in the {what} row.",
              "OEM blade drawing or rotor blading list.", example=110, low=4, high=1000),
        Field(f"{table}.reaction", "number",
              "Degree of reaction at the mean diameter: share of the stage's isentropic drop "
              "taken in the rotor.",
              "OEM stage design data; about 0.05 for impulse, 0.3-0.5 for reaction blading "
              "[Traupel].", example=0.05, low=0.0, high=0.9),
        Field(f"{table}.nozzle_exit_angle", "quantity",
              "Stator (nozzle) exit flow angle, measured from the wheel plane.",
              "OEM blade drawing or profile data; 11-15 deg for impulse nozzles, 14-20 deg for "
              "reaction stators [Traupel].", "rad", "13 deg", math.radians(5), math.radians(40)),
        Field(f"{table}.peak_blade_efficiency", "number",
              "Stage efficiency at the optimum velocity ratio, before friction losses.",
              "OEM stage performance data; about 0.86 impulse, 0.93 reaction blading "
              "[Traupel].", example=0.86, low=0.3, high=1.0),
        Field(f"{table}.friction_loss", "number",
              "Share of the isentropic drop lost to profile friction at design.",
              "Loss correlations [Traupel]; 0.02-0.03 typical. Calibration scales it.",
              example=0.03, low=0.0, high=0.3),
    )


def _material(table: str, what: str) -> tuple[Field, ...]:
    sheet = f"Material data sheet of the {what} steel, near 500 °C (ASME II-D, Table TCD)"
    return (
        Field(f"{table}.density", "quantity", f"Density of the {what} steel.", f"{sheet}.",
              "kg/m^3", "7800 kg/m^3", 1000.0, 20000.0),
        Field(f"{table}.specific_heat", "quantity", f"Specific heat capacity of the {what} steel.",
              f"{sheet}.", "J/(kg*K)", "600 J/(kg*K)", 100.0, 2000.0),
        Field(f"{table}.thermal_conductivity", "quantity",
              f"Thermal conductivity of the {what} steel.", f"{sheet}.", "W/(m*K)",
              "34 W/(m*K)", 1.0, 200.0),
    )


HBD = "Rated-load (THA) heat-balance diagram of the OEM thermal kit"
ROTOR_DRAWING = "OEM rotor drawing (longitudinal section)"
FIT = "Fitted to the thermal kit's part-load heat balances (steamtwin.model.design_fit)"

#: Every field of the spec, in document order; tables and arrays of tables are fields too.
FIELDS: tuple[Field, ...] = (
    Field("format_version", "integer", "Version of this spec format.",
          f"Always {FORMAT_VERSION}.", example=FORMAT_VERSION, low=FORMAT_VERSION,
          high=FORMAT_VERSION),
    Field("name", "string", "Short name of the unit, shown in outputs.",
          "Your choice, e.g. plant and unit number.", example="Unit 3"),
    Field("description", "string", "One line describing the unit.",
          "Your choice: rating, steam conditions, governing.", example="600 MW subcritical"),
    Field("sensors", "array", "The canonical DCS signals the unit has.",
          "DCS point list, translated to the canonical signal names.",
          example="main_steam_pressure", items="string", min_items=1, choices=tuple(SIGNALS)),
    Field("design", "table", "The design heat balance at rated load.", HBD + "."),
    Field("design.main_steam_pressure", "quantity",
          "Main-steam (throttle) pressure before the stop valves.", HBD + ", turbine inlet.",
          "Pa", "16.7 MPa", 1e6, 25e6),
    Field("design.main_steam_temperature", "quantity",
          "Main-steam (throttle) temperature before the stop valves.", HBD + ", turbine inlet.",
          "K", "538 degC", 573.15, 923.15),
    Field("design.main_steam_flow", "quantity", "Main-steam mass flow into the HP section.",
          HBD + ", turbine inlet.", "kg/s", "1800 t/h", 1.0, 2000.0),
    Field("design.control_stage_pressure", "quantity",
          "Pressure in the governing-stage (impulse) chamber, after the control stage.",
          "Thermal kit: governing-stage pressure on the rated-load heat balance; else an "
          "acceptance-test record.",
          "Pa", "13.03 MPa", 0.1e6, 25e6),
    Field("design.hp_exhaust_pressure", "quantity", "HP exhaust (cold reheat) pressure.",
          HBD + ", HP exhaust.", "Pa", "3.90 MPa", 0.05e6, 25e6),
    Field("design.hp_exhaust_temperature", "quantity", "HP exhaust (cold reheat) temperature.",
          HBD + ", HP exhaust.", "K", "326.7 degC", 373.15, 923.15),
    Field("design.hp_power", "quantity",
          "Internal (blading) power of the HP section, bleeds included.",
          "Thermal kit section powers, or flows times enthalpy drops of the rated-load heat "
          "balance.",
          "W", "177.3 MW", 1e5, 2e9),
    Field("design.generator_power", "quantity", "Generator output at rated load.",
          HBD + "; nameplate rating.", "W", "600 MW", 1e5, 2e9),
    Field("design.rotational_speed", "quantity", "Shaft speed.",
          "Nameplate: 3000 rpm on 50 Hz, 3600 rpm on 60 Hz grids.", "rad/s", "3000 rpm",
          100.0, 420.0),
    Field("design.valve_pressure_drop", "number",
          "Fractional pressure loss across a wide-open stop plus governing valve pair.",
          "Thermal kit or OEM valve data; 0.02-0.04 typical [Cotton, ch. 6].",
          example=0.03, low=0.0, high=0.2),
    Field("design.valve_outlet_pressure", "quantity",
          "Nozzle-chest pressure after the governing valves of the last opening group open at "
          "rated load: below the wide-open valve outlet p0·(1 − valve_pressure_drop) when the "
          "rated point lies between valve points (that group part-open), above the "
          "control-stage pressure. The throat areas are then sized for that group throttled "
          "to it.",
          "Thermal kit: pressure after the governing valves (nozzle chest) on the rated-load "
          "heat balance, or the DEH valve-point table [Cotton, ch. 6: valve points].",
          "Pa", "15.9 MPa", 0.1e6, 25e6,
          default="p0·(1 − valve_pressure_drop): the rated point is a valve point"),
    Field("control_stage", "table",
          "The governing (control) stage: impulse blading with nozzle governing.",
          "OEM flow-path drawing and nozzle-box drawing."),
    *_blading("control_stage", "control-stage"),
    Field("control_stage.nozzle_discharge_coefficient", "number",
          "Discharge coefficient of the governing-stage nozzles.",
          "OEM nozzle test data; 0.95-0.98 for steam nozzles [Cotton, ch. 6].",
          example=0.97, low=0.8, high=1.0),
    Field("control_stage.valve_overlap", "number",
          "Overlap of opening: the share of a valve's lift by which the next opening group "
          "starts before the previous one is fully open, so that near a valve point two groups "
          "throttle at once; each group passes the share of its wide-open flow that "
          "valve_characteristic gives at its lift. Without it a twin misses the throttling "
          "near a valve point where its unit's valves overlap (the reference unit: up to 2x "
          "the instruments' error at 80 % load, docs/benchmarks.md).",
          "OEM valve lift diagram or DEH valve-management curve (thermal kit "
          "`machine.valve_overlap`); 0.05-0.15 usual [Cotton, ch. 6: valve-point loops; "
          "Traupel, Bd. 2, nozzle governing]; the reference unit states 0.10.",
          example=0.1, low=0.0, high=0.5, default="0: strictly sequential opening"),
    Field("control_stage.valve_characteristic", "table",
          "Flow characteristic of the governing valves (all alike): the share of its wide-open "
          "flow a valve passes against its lift, linearly interpolated; used where the lift "
          "schedule (valve_overlap) sets several lifts at once, and to report lifts.",
          "OEM valve test or the DEH valve flow-characteristic curve; poppet valves pass "
          "most of their flow in the first third of their lift [Cotton, ch. 6]; from the "
          "valve drawing: curtain area pi*d*L in series with the seat area pi*d^2/4 "
          "[Heywood 1988, sec. 6.3] (the reference unit: full lift 0.3 d, at 20 % steps).",
          default="linear: flow share = lift"),
    Field("control_stage.valve_characteristic.lift", "array",
          "Valve lift as a share of full lift, strictly increasing from 0 to 1.",
          "Valve characteristic curve, lift axis.", items="number", low=0.0, high=1.0,
          min_items=2, example=0.3),
    Field("control_stage.valve_characteristic.flow", "array",
          "Share of the wide-open flow at each lift (same length), rising from 0 to 1.",
          "Valve characteristic curve, flow axis.", items="number", low=0.0, high=1.0,
          min_items=2, example=0.8),
    Field("control_stage.valves", "tables",
          "One table per governing valve and the nozzle group it feeds, at least one.",
          "DEH valve-management documentation and the nozzle-box drawing.", min_items=1),
    Field("control_stage.valves[].name", "string", "Name of the valve, unique.",
          "P&ID or DCS tag, e.g. GV1.", example="GV1"),
    Field("control_stage.valves[].opening_order", "integer",
          "Place in the opening sequence; valves with the same number open together.",
          "DEH valve sequence (valve-management) table.", example=1, low=1, high=32),
    Field("control_stage.valves[].admission_arc", "number",
          "Share of the circumference fed by the valve's nozzle group; all arcs add up to ≤ 1.",
          "Nozzle-box drawing: nozzles in the group divided by nozzle pitches on the full circle.",
          example=0.25, low=1e-3, high=1.0),
    Field("control_stage.valves[].open_at_design", "boolean",
          "Whether the valve admits steam at rated load (the valves of the first opening "
          "orders): wide open, the last of these orders throttled to design.valve_outlet_pressure "
          "when that is given.",
          "DEH valve-point table or the thermal kit's valve point at THA.", example=True),
    Field("control_stage.valves[].throat_area", "quantity",
          "Total throat area of the valve's nozzle group; give it for every valve or for none.",
          "Nozzle-box drawing: nozzles in the group times throat width times height.",
          "m^2", "0.0085 m^2", 1e-5, 1.0,
          default="sized: the design flow passes the valves open at design at the design "
                  "control-stage pressure, area in proportion to admission arc"),
    Field("stages", "tables",
          "The pressure stages after the control stage, in steam-flow order, at least one; "
          "the k-th table is stage k (stage 0 is the control stage).",
          "OEM flow-path drawing and stage table of the thermal kit.", min_items=1),
    *_blading("stages[]", "stage's"),
    Field("stages[].flow_capacity", "quantity",
          "Stodola flow capacity K of the stage cone law m = K·sqrt((p_in² − p_out²)/(p_in·v_in)),"
          " an equivalent throat area.",
          "From the stage pressures of the thermal kit's design expansion (see "
          "tools/derive_reference_spec.py), or the stator throat area.",
          "m^2", "0.05533 m^2", 1e-5, 10.0),
    Field("stages[].tip_leakage", "number",
          "Share of the stage's flow that leaks over the blade tips (or shroud seals), bypassing "
          "the blading and rejoining after the stage: the stage's efficiency is taken times "
          "(1 − tip_leakage).",
          "Tip-leakage loss correlations [Traupel, Bd. 1, §8: clearance-gap flow share; "
          "Dixon & Hall, ch. 4]; 0.005-0.02 for shrouded HP blading.",
          example=0.01, low=0.0, high=0.2, default="0: no tip leakage"),
    Field("extractions", "tables", "HP bleeds (heater extractions), one table each.",
          "Heat-balance diagram: extraction lines to the HP heaters.",
          min_items=1, default="none: the unit has no HP bleed"),
    Field("extractions[].name", "string", "Name of the bleed.",
          "Heat-balance diagram, e.g. the heater it feeds.", example="HP heater 1"),
    Field("extractions[].after_stage", "integer",
          "Pressure stage (1-based) after which the steam is bled.",
          "OEM flow-path drawing: position of the extraction belt.", example=8, low=1,
          bound_note="at most the number of [[stages]] − 1"),
    Field("extractions[].design_flow", "quantity", "Bleed mass flow at rated load.",
          HBD + ", extraction line.", "kg/s", "120 t/h", 0.0, 500.0),
    Field("extractions[].design_pressure", "quantity",
          "Pressure at the extraction point at rated load; between the control-stage and "
          "HP-exhaust pressures.",
          HBD + ", extraction line (at the turbine, before the line loss).",
          "Pa", "6.17 MPa", 0.05e6, 25e6),
    Field("leakages", "tables",
          "Leakages past the pressure stages (balance piston, HP–IP gland, front shaft seal), "
          "one table each, as design data at rated load. Off design each follows the labyrinth "
          "law of its fixed seal, m ∝ sqrt((p_up² − p_down²)/(p_up·v_up)), its constant fixed "
          "at the design point by design_flow and the model's design state at from_stage.",
          "Thermal kit: throttle flow less HP-exhaust flow and bleeds, or the OEM's leakage "
          "(gland) flows on the heat balance; labyrinth law [Martin 1908; Egli, Trans. ASME 57 "
          "(1935) 115-122; Traupel, Bd. 1].",
          min_items=1, default="none: every kg of throttle steam passes the pressure stages"),
    Field("leakages[].name", "string", "Name of the leakage.",
          "Heat-balance diagram or seal drawing, e.g. the gland it passes.",
          example="HP-IP gland"),
    Field("leakages[].from_stage", "integer",
          "Where the leakage leaves the steam path: 0 = the control-stage chamber, k = after "
          "pressure stage k.",
          "OEM flow-path drawing: position of the balance piston or gland on the rotor.",
          example=0, low=0, bound_note="at most the number of [[stages]] − 1"),
    Field("leakages[].to", "string",
          "Where it goes: `hp_exhaust` rejoins the steam before the HP exhaust (it bypasses the "
          "stages after from_stage); `outside` leaves the HP section (HP–IP gland to the IP "
          "inlet, front shaft seal to a leak-off or gland-steam line).",
          "OEM gland-steam / leak-off diagram.", example="outside",
          choices=("hp_exhaust", "outside")),
    Field("leakages[].design_flow", "quantity", "Leakage mass flow at rated load.",
          HBD + ": throttle flow less HP-exhaust flow and bleeds; 1-2 % of throttle flow usual "
          "[Cotton, ch. 6].", "kg/s", "17.5 t/h", 0.0, 100.0),
    Field("leakages[].sink_pressure", "quantity",
          "Pressure the leakage discharges into at rated load (to = outside only); off design "
          "it moves in proportion with the HP-exhaust pressure.",
          "Heat-balance diagram: IP-inlet (hot-reheat) pressure for an HP–IP gland, the "
          "leak-off line's pressure for a shaft seal. Below ~0.3 of the upstream pressure the "
          "seal's flow barely depends on it [Egli 1935].",
          "Pa", "3.26 MPa", 1e4, 25e6,
          default="required for to = outside; for hp_exhaust the HP-exhaust pressure"),
    Field("metal", "table", "The rotor and inner-casing metal the steam heats.",
          "OEM casing and rotor drawings, weights list, material data sheets."),
    Field("metal.casing_sensor_group", "string",
          "Name of the metal group whose inner-casing wall carries the DCS casing thermocouple.",
          "DCS point list and the casing drawing (thermocouple position).",
          example="control stage"),
    Field("metal.ambient_temperature", "quantity", "Turbine-hall air around the lagging.",
          "Plant records; 30-40 °C typical.", "K", "35 degC", 223.15, 373.15),
    Field("metal.casing_thermocouple_depth", "quantity",
          "Depth of the DCS casing thermocouple's hot junction under the inner-casing bore of "
          "metal.casing_sensor_group; at most that group's wall depth.",
          "Casing drawing or the thermocouple's installation sheet (drilled-hole depth).",
          "m", "14 mm", 0.0, 0.2,
          default="14 mm: an assumed installation depth near the steam-side surface"),
    Field("metal.casing_material", "table", "Inner-casing steel.", "Material data sheet."),
    *_material("metal.casing_material", "inner-casing"),
    Field("metal.rotor_material", "table", "Rotor steel.", "Material data sheet."),
    *_material("metal.rotor_material", "rotor"),
    Field("metal.groups", "tables",
          "Metal wetted by the steam of consecutive stages, one table per group, at least one; "
          "together they cover stages 0 to the last pressure stage exactly once.",
          "OEM casing and rotor drawings, weights list.", min_items=1),
    Field("metal.groups[].name", "string", "Name of the group, unique.", "Your choice.",
          example="HP stages 1-4"),
    Field("metal.groups[].stages", "array",
          "Consecutive stage numbers of the group (0 = control stage, which is a group of its "
          "own).", "OEM flow-path drawing.", example=1, items="integer", min_items=1, low=0,
          bound_note="at most the number of [[stages]]"),
    Field("metal.groups[].casing_mass", "quantity",
          "Inner-casing metal mass heated by the group's steam.",
          "OEM weights list or casing drawing (wall volume times density).",
          "kg", "7020 kg", 1.0, 1e6, default=_BY_GEOMETRY),
    Field("metal.groups[].casing_area", "quantity",
          "Inner-casing surface wetted by the group's steam.",
          "Casing drawing: bore circumference times the group's axial length.",
          "m^2", "4.5 m^2", 1e-3, 1e3, default=_BY_GEOMETRY),
    Field("metal.groups[].rotor_mass", "quantity", "Rotor metal mass heated by the group's steam.",
          "OEM weights list or rotor drawing.", "kg", "4680 kg", 1.0, 1e6, default=_BY_GEOMETRY),
    Field("metal.groups[].rotor_area", "quantity", "Rotor surface wetted by the group's steam.",
          "Rotor drawing: drum circumference times the group's axial length.",
          "m^2", "3.0 m^2", 1e-3, 1e3, default=_BY_GEOMETRY),
    Field("metal.groups[].axial_length", "quantity",
          "Axial length of rotor and inner casing wetted by the group's steam (geometry fields: "
          "give these instead of the masses and areas).",
          "OEM flow-path drawing: from the group's first stator inlet to its last rotor exit "
          "(with the nozzle chamber for the control stage).",
          "m", "0.60 m", 0.01, 10.0, default=_BY_MASS),
    Field("metal.groups[].rotor_radius", "quantity",
          "Outer radius of the drum or rotor body the group's steam wets (the blade roots' "
          "radius for a drum rotor, the hub between the discs for a disc rotor); below the "
          "group's blade mean radii.",
          "OEM rotor drawing.", "m", "0.45 m", 0.05, 1.5, default=_BY_MASS),
    Field("metal.groups[].rotor_bore_radius", "quantity",
          "Radius of the rotor's central bore, below rotor_radius by at least "
          f"{METAL_DEPTH_RANGE_M[0]:g} m; the bore is taken as adiabatic.",
          "OEM rotor drawing (bore for inspection / material removal).",
          "m", "0.05 m", 0.0, 1.0, default="0 m: a solid forging (geometry fields only)"),
    Field("metal.groups[].casing_inner_radius", "quantity",
          "Bore radius of the inner casing over the group (its steam-side surface); above the "
          "group's blade mean radii and rotor_radius.",
          "OEM casing drawing: blade tip radius plus the tip seals and stator shrouds.",
          "m", "0.62 m", 0.1, 2.0, default=_BY_MASS),
    Field("metal.groups[].casing_wall_thickness", "quantity",
          "Radial wall thickness of the inner casing over the group.",
          "OEM casing drawing (wall between the bore and the outer surface under the lagging).",
          "m", "0.15 m", *METAL_DEPTH_RANGE_M, default=_BY_MASS),
    Field("metal.groups[].insulation_conductance", "quantity",
          "Heat-loss conductance from the casing's outer surface to the turbine hall.",
          "Lagging specification (ASTM C680 method); about 0.6 W/(m²·K) for lagging designed "
          "for 0.3 kW/m².", "W/(m^2*K)", "0.6 W/(m^2*K)", 0.0, 50.0),
    Field("sliding_pressure", "table",
          "Main-steam pressure against load, linearly interpolated.",
          "DEH / coordinated-control sliding-pressure curve."),
    Field("sliding_pressure.load_fraction", "array",
          "Load as a fraction of rated output, strictly increasing.",
          "Sliding-pressure curve, load axis.", items="number", low=0.0, high=1.2, min_items=2,
          example=0.27),
    Field("sliding_pressure.pressure", "array",
          "Main-steam pressure at each load_fraction (same length).",
          "Sliding-pressure curve, pressure axis.", "Pa", "16.7 MPa", 1e5, 25e6,
          items="quantity", min_items=2),
    Field("temperature_schedule", "table",
          "Main-steam and hot-reheat temperature against load (the boiler's steam-temperature "
          "schedule), linearly interpolated between its points and held flat outside them.",
          "DEH / coordinated-control steam-temperature setpoint curve; the thermal kit's "
          "part-load heat balances (`steamtwin turbine derive` writes it from them).",
          default="design.main_steam_temperature at every load"),
    Field("temperature_schedule.load_fraction", "array",
          "Load as a fraction of rated output, strictly increasing.",
          "Steam-temperature schedule, load axis.", items="number", low=0.0, high=1.2,
          min_items=2, example=0.3),
    Field("temperature_schedule.main_steam_temperature", "array",
          "Main-steam (throttle) temperature at each load_fraction (same length).",
          "Steam-temperature schedule, main-steam axis; part-load heat balances, turbine inlet.",
          "K", "532 degC", 573.15, 923.15, items="quantity", min_items=2),
    Field("temperature_schedule.reheat_temperature", "array",
          "Hot-reheat temperature at each load_fraction (same length); the HP-exhaust "
          "pressure of the operating line follows √T_rh (Stodola's cone law of the IP "
          "section).",
          "Steam-temperature schedule, reheat axis; part-load heat balances, IP inlet.",
          "K", "515 degC", 573.15, 923.15, items="quantity", min_items=2,
          default="not scheduled: the HP-exhaust pressure follows the flow alone"),
    Field("rotor", "table",
          "The HP rotor section around the control stage as drawn (r, z half-section), for the "
          "2-D rotor thermal-stress and fatigue-life model (docs/rotor.md): outer radii, bore, "
          "heat-relief groove and where each metal group's steam wets it.",
          "OEM rotor drawing (longitudinal section) and rotor forging certificate.",
          default="none: the unit has no rotor stress model; `steamtwin.rotor` asks for it"),
    Field("rotor.axial_length", "quantity",
          "Axial length of the modelled section, z = 0 at its upstream end; both ends are cuts "
          "taken as adiabatic, so place them a rotor radius or more from the groove.",
          f"{ROTOR_DRAWING}: from the front gland side of the control-stage wheel to past the "
          "first pressure stages.", "m", "0.60 m", 0.05, 10.0),
    Field("rotor.control_stage_radius", "quantity",
          "Outer radius of the rotor body at the control stage (beside its wheel, where the "
          "heat-relief groove usually is), from z = 0 to stage_start.",
          f"{ROTOR_DRAWING}.", "m", "0.36 m", 0.05, 1.5),
    Field("rotor.stage_radius", "quantity",
          "Outer radius of the rotor drum at the first pressure stages (their blade-root "
          "radius), from stage_start to axial_length.",
          f"{ROTOR_DRAWING}; root diameter of the first pressure stages / 2.",
          "m", "0.43 m", 0.05, 1.5),
    Field("rotor.stage_start", "quantity",
          "Axial position (from the section's start) where the drum radius changes from "
          "control_stage_radius to stage_radius; equal to axial_length for one radius throughout.",
          f"{ROTOR_DRAWING}.", "m", "0.25 m", 0.0, 10.0, low_inclusive=False,
          bound_note="in (0, rotor.axial_length]"),
    Field("rotor.bore_radius", "quantity",
          "Radius of the central bore; 0 for a solid forging. The bore is adiabatic.",
          f"{ROTOR_DRAWING} (inspection bore).", "m", "0 m", 0.0, 1.0,
          default="0 m: a solid forging"),
    Field("rotor.groove_radius", "quantity",
          "Root (fillet) radius of the heat-relief groove.",
          f"{ROTOR_DRAWING}, groove detail; 5-15 mm usual [Leyzerovich].", "m", "8 mm",
          1e-3, 0.1),
    Field("rotor.groove_depth", "quantity",
          "Depth of the groove below the local outer radius: a circular segment up to "
          "groove_radius, a U (semicircular root, parallel flanks) beyond; it must leave "
          f"{METAL_DEPTH_RANGE_M[0]:g} m of metal above the bore.",
          f"{ROTOR_DRAWING}, groove detail.", "m", "25 mm", 1e-3, 0.5),
    Field("rotor.groove_position", "quantity",
          "Axial position of the groove's centre; the whole groove lies on one side of "
          "stage_start.", f"{ROTOR_DRAWING}.", "m", "0.10 m", 0.0, 10.0, low_inclusive=False,
          bound_note="inside (0, rotor.axial_length), clear of rotor.stage_start"),
    Field("rotor.material", "string",
          "Rotor steel, by the name the rotor life model knows its properties under.",
          "Rotor forging certificate; 30CrMoNiV5-11 (1CrMoV class, GB 30Cr1Mo1V) for HP rotors "
          "of this class.", example=DEFAULT_ROTOR_MATERIAL,
          default=f"{DEFAULT_ROTOR_MATERIAL}"),
    Field("rotor.rotational_speed", "quantity", "Shaft speed for the rotor's centrifugal load.",
          "Nameplate.", "rad/s", "3000 rpm", 100.0, 420.0,
          default="design.rotational_speed"),
    Field("rotor.steam", "tables",
          "Where each metal group's steam wets the modelled surface: one table per wetted "
          "interval, intervals not overlapping; surface outside them is adiabatic (e.g. under a "
          "seal). Its temperature and heat-transfer coefficient come from the model's group.",
          f"{ROTOR_DRAWING} with the flow-path drawing.", min_items=1),
    Field("rotor.steam[].group", "string", "Name of the metal group (metal.groups[].name).",
          "As in [[metal.groups]].", example="control stage"),
    Field("rotor.steam[].start", "quantity", "Axial start of the wetted interval.",
          f"{ROTOR_DRAWING}.", "m", "0 m", 0.0, 10.0),
    Field("rotor.steam[].end", "quantity", "Axial end of the wetted interval, above start.",
          f"{ROTOR_DRAWING}.", "m", "0.25 m", 0.0, 10.0),
    Field("part_load", "table",
          "Design-level part-load laws the off-design points of a thermal kit identify; every "
          "field optional, the defaults leave the blading laws alone.",
          f"`steamtwin turbine fit` against the thermal kit ({FIT}); else leave out.",
          default="all defaults"),
    Field("part_load.reynolds_exponent", "number",
          "Exponent n of the pressure stages' Reynolds correction: each stage's loss 1 − η "
          "grows as (m/m_design)^(−n) at part load (Reynolds number ∝ flow).",
          f"{FIT}. Loss ∝ Re^(−0.1…−0.25) in the transition range [Traupel, Bd. 1, §7]; HP "
          "part-load efficiency vs volume flow [Spencer, Cotton & Cannon 1963].",
          example=0.2, low=0.0, high=0.5, default="0: no Reynolds correction"),
    Field("part_load.admission_loss_multiplier", "number",
          "Factor on the control stage's partial-admission losses (idle-arc windage and "
          "sector-end loss, B_e = 0.15 and C_e = 0.012 m of a single-row wheel).",
          f"{FIT}. The windage and sector-end coefficients of the literature spread by a factor "
          "of 2-3 [Kang et al., §3.5; Traupel, Bd. 1, §8].",
          example=1.0, low=0.2, high=4.0, default="1: the textbook coefficients"),
    Field("part_load.control_stage_velocity_ratio_factor", "number",
          "Factor on the control stage's optimum velocity ratio cos α1 / (2·sqrt(1 − R)) of "
          "the ideal impulse blade: where its efficiency peaks against u/c0.",
          f"{FIT}. Real single-row wheels peak at u/c0 ≈ 0.40-0.50, below the ideal "
          "cos α1/2 ≈ 0.49 [Traupel, Bd. 1, §8; Cotton, ch. 6].",
          example=1.0, low=0.8, high=1.25, default="1: the ideal blade's optimum"),
    Field("part_load.flow_capacity_multiplier", "number",
          "Factor on every pressure stage's Stodola flow capacity (stages[].flow_capacity).",
          f"{FIT}: the control-stage pressures of the off-design points fix it [Stodola 1927; "
          "Cooke 1985].", example=1.0, low=0.8, high=1.25,
          default="1: the capacities as given"),
)

#: Each field by its path without array markers, as the loader looks it up.
FIELD_BY_KEY: Mapping[str, Field] = {field.key: field for field in FIELDS}

#: Cross-field rules the loader checks after every field is valid, in the words of docs/spec.md.
CONSISTENCY_RULES: tuple[str, ...] = (
    "Design pressures fall along the steam path: `design.main_steam_pressure` > "
    "`design.control_stage_pressure` > `design.hp_exhaust_pressure`.",
    "`design.hp_exhaust_temperature` is below `design.main_steam_temperature` and superheated "
    "at `design.hp_exhaust_pressure`.",
    "`design.hp_power` is below `design.generator_power`.",
    "Governing valves: names unique, admission arcs add up to ≤ 1, at least one valve open at "
    "design; valves of one `opening_order` agree on `open_at_design`, and the valves open at "
    "design are exactly the first opening orders.",
    "Each `extractions[].design_pressure` lies between the control-stage and HP-exhaust design "
    "pressures; the bleeds together take less than `design.main_steam_flow`.",
    "Leakages: names unique; `leakages[].sink_pressure` is given exactly when `to = "
    "\"outside\"`, below `design.control_stage_pressure`; all leakages and bleeds together "
    "take less than `design.main_steam_flow`.",
    "`metal.groups`: names unique; the control stage (stage 0) is a group of its own; the groups "
    "cover stages 0 to the last pressure stage exactly once; `metal.casing_sensor_group` names "
    "one of them.",
    "Each group gives either `casing_mass`, `casing_area`, `rotor_mass` and `rotor_area` or "
    "the geometry `axial_length`, `rotor_radius`, `casing_inner_radius`, "
    "`casing_wall_thickness` (and optionally `rotor_bore_radius`), never a mix. With masses and "
    "areas, `casing_mass / (density × casing_area)` and `rotor_mass / (density × rotor_area)` "
    f"are plausible heated metal depths, {METAL_DEPTH_RANGE_M[0]:g}–{METAL_DEPTH_RANGE_M[1]:g} "
    "m; with the geometry, `rotor_bore_radius` lies at least "
    f"{METAL_DEPTH_RANGE_M[0]:g} m below `rotor_radius`, `rotor_radius` below and "
    "`casing_inner_radius` above every mean blade radius of the group's stages.",
    "`[rotor]`: `stage_start` ≤ `axial_length`; `bore_radius` and the groove each leave "
    f"≥ {METAL_DEPTH_RANGE_M[0]:g} m of metal; the groove lies within one constant-radius part "
    "of the section; `rotor.steam` intervals lie within the section, do not overlap and name "
    "metal groups.",
    "`metal.casing_thermocouple_depth` is at most the wall depth of the "
    "`metal.casing_sensor_group` (its `casing_wall_thickness`, or `casing_mass / (density × "
    "casing_area)`).",
)


def limits_text(field: Field) -> str:
    """The valid range in the example's unit, or the bounds in words (``""`` if none)."""
    if field.bound_note:
        low = "" if field.low is None else f"≥ {field.low:g}, "
        return f"{low}{field.bound_note}"
    return field.range_text(display=True)


def field_for(table: str, key: str) -> Field:
    """The field ``key`` of the table ``table`` (path without array markers, ``""`` = top)."""
    return FIELD_BY_KEY[f"{table}.{key}" if table else key]


def children(path: str) -> tuple[Field, ...]:
    """The fields directly inside the table at ``path`` (``"stages[]"``, ``""`` = top level)."""
    return tuple(field for field in FIELDS if field.parent == path)


# --- JSON Schema --------------------------------------------------------------------------------

def _description(field: Field) -> str:
    parts = [field.meaning]
    if field.kind == "quantity" or field.items == "quantity":
        parts.append(f"A string 'value unit' with a unit convertible to {field.unit} "
                     f"(e.g. \"{field.example}\").")
    if limits_text(field):
        parts.append(f"Valid range: {limits_text(field)}.")
    parts.append(f"Source: {field.source}")
    return " ".join(parts)


def _value_schema(field: Field, kind: Kind) -> dict[str, Any]:
    """The JSON Schema of one value of ``kind`` carrying ``field``'s bounds."""
    if kind == "quantity":
        return {"type": "string", "pattern": QUANTITY_PATTERN}
    if kind == "string":
        return {"enum": list(field.choices)} if field.choices else {"type": "string",
                                                                    "pattern": r"\S"}
    if kind == "boolean":
        return {"type": "boolean"}
    schema: dict[str, Any] = {"type": "integer" if kind == "integer" else "number"}
    for bound, inclusive, name in ((field.low, field.low_inclusive, "minimum"),
                                   (field.high, field.high_inclusive, "maximum")):
        if bound is not None:
            keyword = name if inclusive else f"exclusive{name.capitalize()}"
            schema[keyword] = int(bound) if kind == "integer" else bound
    return schema


def _object_schema(path: str) -> dict[str, Any]:
    fields = children(path)
    return {
        "type": "object",
        "properties": {field.name: _field_schema(field) for field in fields},
        "required": [field.name for field in fields if field.required],
        "additionalProperties": False,
    }


def _field_schema(field: Field) -> dict[str, Any]:
    if field.kind == "table":
        schema = _object_schema(field.path)
    elif field.kind == "tables":
        schema = {"type": "array", "minItems": field.min_items,
                  "items": _object_schema(f"{field.path}[]")}
    elif field.kind == "array":
        assert field.items is not None
        schema = {"type": "array", "minItems": field.min_items,
                  "items": _value_schema(field, field.items)}
    else:
        schema = _value_schema(field, field.kind)
    schema = {"description": _description(field), **schema}
    if field.example != "" and field.kind not in ("array", "table", "tables"):
        schema["examples"] = [field.example]
    return schema


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a turbine spec as parsed from TOML, for editors.

    It checks types, required and unknown keys, numeric ranges of plain numbers and the form of
    "value unit" strings; unit kinds, quantity ranges and cross-field rules are the loader's.
    """
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "steamtwin turbine spec",
        "description": (f"A steamtwin turbine spec, format version {FORMAT_VERSION} "
                        "(docs/spec.md). Quantities are strings 'value unit', e.g. '16.7 MPa'."),
        **_object_schema(""),
    }


# --- Markdown -----------------------------------------------------------------------------------

_INTRO = """\
# The turbine spec format

<!-- Generated by `python -m steamtwin.spec.schema --markdown > docs/spec.md` from
src/steamtwin/spec/schema.py; edit that table, not this file. -->

A turbine spec is a TOML file describing one unit's HP section at its design point: the design
heat balance, the governing stage and its valves, the pressure stages, the HP bleeds, the metal of
rotor and inner casing, the sliding-pressure line and the DCS signals the unit has. Every command
that takes `--turbine` reads one; `reference` is the built-in 600 MW unit
(`src/steamtwin/spec/data/reference.toml`, every figure with its source), a good starting point
for your own. `steamtwin turbine show unit.toml` checks a spec and prints it.

```toml
format_version = 1
name = "Unit 3"
description = "600 MW subcritical, 16.7 MPa / 538 °C, nozzle governing"
sensors = ["main_steam_pressure", "main_steam_temperature", "main_steam_flow",
           "control_stage_pressure", "hp_exhaust_pressure", "hp_exhaust_temperature", "load"]

[design]
main_steam_pressure = "16.7 MPa"
main_steam_temperature = "538 degC"
main_steam_flow = "1800 t/h"
valve_pressure_drop = 0.03
# ... every field of [design] below

[[control_stage.valves]]      # one table per governing valve
name = "GV1"
opening_order = 1
admission_arc = 0.25
open_at_design = true

[[stages]]                    # stage 1; the next [[stages]] is stage 2, ...
mean_diameter = "0.9434 m"
blade_count = 96
flow_capacity = "0.05533 m^2"
# ...
```

## Rules

- **Units are written as strings** `"value unit"` (`"16.7 MPa"`, `"538 degC"`, `"1800 t/h"`,
  `"3000 rpm"`, `"13 deg"`); any unit of the right kind is converted to SI (pint). A number
  without a unit is refused for a dimensioned field; dimensionless fields take plain numbers.
- **Every field is required** unless its default below says otherwise; nothing is guessed.
- **Unknown keys are refused** with a "did you mean" hint: a misspelled `[[extraction]]` would
  otherwise drop a bleed without a word.
- **Errors name the file and the field by its TOML path**, with array positions counted from 1:
  `unit.toml: stage 3: stages[3].flow_capacity = '0 m^2' is outside the valid range ...`.
  `stages[3]` is the third `[[stages]]` table, stage 3; stage 0 is the control stage.
- Ranges are inclusive `[low, high]` unless written with `(` or `)`; they are the loader's own
  (this page is generated from the table it checks against), shown in the example's unit.

## Editor support

`docs/spec.schema.json` is a JSON Schema (draft 2020-12) of the same format: types, required and
unknown keys, ranges of plain numbers, the form of "value unit" strings and a description of
every field on hover. With Taplo or the *Even Better TOML* extension of VS Code, name it in a
schema directive on the first line of the spec, by a path (here: the schema copied next to the
spec) or a URL:

```toml
#:schema ./spec.schema.json
```

or associate your specs with it by a `[[rule]]` in `.taplo.toml`. The loader ignores the
directive (a TOML comment). The schema cannot check unit kinds, the
ranges of quantities or the cross-field rules below: `steamtwin turbine show unit.toml` does.
"""


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _kind_text(field: Field) -> str:
    if field.kind == "quantity":
        return f"quantity, SI {field.unit}; e.g. `\"{field.example}\"`"
    if field.kind == "array":
        entry = {"quantity": f"quantities (SI {field.unit}; e.g. `\"{field.example}\"`)",
                 "number": "numbers", "integer": "integers", "string": "strings"}
        assert field.items is not None
        return f"array of ≥ {field.min_items} {entry[field.items]}"
    if field.kind == "tables":
        return f"array of ≥ {field.min_items} tables"
    return field.kind


def _range_cell(field: Field) -> str:
    if field.choices:
        return "one of: " + ", ".join(f"`{choice}`" for choice in field.choices)
    return limits_text(field) or "—"


def _section(table: Field | None) -> list[str]:
    if table is None:
        path, title, meaning = "", "Top level", ""
    else:
        path = f"{table.path}[]" if table.kind == "tables" else table.path
        header = f"[[{table.path}]]" if table.kind == "tables" else f"[{table.path}]"
        title, meaning = f"`{header}`", f"{table.meaning} *Source:* {table.source}"
        if table.default is not None:
            meaning += f" *Optional* ({table.default})."
    lines = [f"## {title}", ""]
    if meaning:
        lines += [meaning, ""]
    lines += ["| field | kind / unit | range | default | meaning | source hint |",
              "|---|---|---|---|---|---|"]
    for field in children(path):
        default = "required" if field.required else field.default
        lines.append("| " + " | ".join(_cell(text) for text in (
            f"`{field.path}`", _kind_text(field), _range_cell(field), default, field.meaning,
            field.source)) + " |")
    return [*lines, ""]


def render_markdown() -> str:
    """docs/spec.md: the rules, then a table of every field per section, then the cross-checks."""
    lines = [_INTRO, *_section(None)]
    for field in FIELDS:
        if field.kind in ("table", "tables"):
            lines += _section(field)
    lines += ["## Cross-field checks", "",
              "After every field is valid on its own, the loader checks:", ""]
    lines += [f"- {rule}" for rule in CONSISTENCY_RULES]
    return "\n".join(lines) + "\n"


def json_schema_text() -> str:
    """docs/spec.schema.json: :func:`json_schema` as indented JSON with a final newline."""
    return json.dumps(json_schema(), indent=2, ensure_ascii=False) + "\n"


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m steamtwin.spec.schema --markdown | --json-schema``: write it to stdout."""
    parser = argparse.ArgumentParser(prog="python -m steamtwin.spec.schema",
                                     description="Write the turbine spec format's docs.")
    choice = parser.add_mutually_exclusive_group(required=True)
    choice.add_argument("--markdown", action="store_true", help="docs/spec.md")
    choice.add_argument("--json-schema", action="store_true", help="docs/spec.schema.json")
    arguments = parser.parse_args(argv)
    sys.stdout.write(render_markdown() if arguments.markdown else json_schema_text())


if __name__ == "__main__":
    main()
