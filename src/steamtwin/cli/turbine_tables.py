"""The tables ``steamtwin turbine show|check`` print, in engineering units (MPa, °C, t/h, MW,
%): the design heat balance beside the model's design point, the off-design line, the valves
and the stages."""

from __future__ import annotations

import math

import pandas as pd
from rich.table import Table

from steamtwin.model.design_check import line_in_engineering_units
from steamtwin.spec import TurbineSpec

__all__ = ["design_point_table", "heat_balance_table", "line_table", "rotor_table",
           "stage_table", "valve_table"]

_KELVIN = 273.15
_LINE_HEADERS = ("p0 (MPa)", "T0 (°C)", "flow (t/h)", "p1 (MPa)", "T1 (°C)", "p ex (MPa)",
                 "T ex (°C)", "HP power (MW)", "η cs (%)", "arc (%)")
_LINE_DECIMALS = (2, 1, 0, 3, 1, 3, 1, 1, 1, 1)


def heat_balance_table(spec: TurbineSpec, model_point: pd.DataFrame | None) -> Table:
    """The spec's design heat balance, with the model's design point beside it when given."""
    design = spec.design
    title = "Design heat balance (rated load)" + (
        ", the model's own design point beside it" if model_point is not None else "")
    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    if model_point is not None:
        table.add_column("model", justify="right")
        table.add_column("model − spec", justify="right")
    predicted = _design_point_rows(model_point) if model_point is not None else {}
    rows = [
        ("main-steam pressure", f"{design.main_steam_pressure / 1e6:.2f} MPa"),
        ("main-steam temperature", f"{design.main_steam_temperature - _KELVIN:.1f} °C"),
        ("main-steam flow", f"{design.main_steam_flow * 3.6:.0f} t/h"),
        ("control-stage pressure", f"{design.control_stage_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust pressure", f"{design.hp_exhaust_pressure / 1e6:.2f} MPa"),
        ("HP-exhaust temperature", f"{design.hp_exhaust_temperature - _KELVIN:.1f} °C"),
        ("HP power", f"{design.hp_power / 1e6:.1f} MW"),
        ("generator power", f"{design.generator_power / 1e6:.0f} MW"),
        ("speed", f"{design.rotational_speed * 60 / (2 * math.pi):.0f} rpm"),
    ]
    for extraction in spec.extractions:
        rows.append((f"bleed '{extraction.name}' after stage {extraction.after_stage}",
                     f"{extraction.design_flow * 3.6:.0f} t/h at "
                     f"{extraction.design_pressure / 1e6:.2f} MPa"))
    for name, value in rows:
        extra = predicted.get(name, ("", "", ""))[1:] if model_point is not None else ()
        table.add_row(name, value, *extra)
    return table


def _design_point_rows(model_point: pd.DataFrame) -> dict[str, tuple[str, str, str]]:
    """Quantity → (spec, model, model − spec) in engineering units."""
    p1, t_ex, power = (model_point.loc[name] for name in
                       ("control_stage_pressure", "hp_exhaust_temperature", "hp_power"))
    return {
        "control-stage pressure": (
            f"{p1.spec / 1e6:.2f} MPa", f"{p1.model / 1e6:.3f} MPa",
            f"{p1.difference / 1e6:+.3f} MPa ({p1.difference / p1.spec:+.2%})"),
        "HP-exhaust temperature": (
            f"{t_ex.spec - _KELVIN:.1f} °C", f"{t_ex.model - _KELVIN:.2f} °C",
            f"{t_ex.difference:+.2f} K"),
        "HP power": (
            f"{power.spec / 1e6:.1f} MW", f"{power.model / 1e6:.2f} MW",
            f"{power.difference / 1e6:+.2f} MW ({power.difference / power.spec:+.2%})"),
    }


def design_point_table(model_point: pd.DataFrame) -> Table:
    """The model's design point beside the heat balance (``model.design_check.design_point``)."""
    table = Table(title="Design point (rated load): heat balance and model")
    for column in ("quantity", "spec", "model", "model − spec"):
        table.add_column(column, justify="right" if column != "quantity" else "left")
    for name, values in _design_point_rows(model_point).items():
        table.add_row(name, *values)
    return table


def line_table(spec: TurbineSpec, line: pd.DataFrame) -> Table:
    """The steady off-design line, one column per load."""
    table = Table(title="The model's steady off-design line (sliding pressure); a valve's "
                        "opening is its lift, % of full lift (control_stage.valve_characteristic "
                        "gives its flow)")
    shown = line_in_engineering_units(spec, line)
    table.add_column("load")
    for load in shown.index:
        table.add_column(f"{load:g} %", justify="right")
    valves = spec.control_stage.valves
    headers = [*_LINE_HEADERS, *(f"{valve.name} opening (%)" for valve in valves)]
    decimals = [*_LINE_DECIMALS, *(1 for _ in valves)]
    for header, column, d in zip(headers, shown.columns, decimals, strict=True):
        table.add_row(header, *(f"{value:.{d}f}" for value in shown[column]))
    return table


def valve_table(spec: TurbineSpec) -> Table:
    """The governing valves: opening order, admission arc, open at design."""
    table = Table(title="Governing valves (nozzle governing)")
    for column in ("valve", "opening order", "admission arc", "open at design"):
        table.add_column(column, justify="right")
    for valve in spec.control_stage.valves:
        table.add_row(valve.name, str(valve.opening_order), f"{valve.admission_arc:.2f}",
                      "yes" if valve.open_at_design else "no")
    return table


def rotor_table(spec: TurbineSpec) -> Table | None:
    """The drawn HP rotor section (spec ``[rotor]``, mm, rpm) and its steam-wetted intervals;
    None when the spec has no ``[rotor]``."""
    rotor = spec.rotor
    if rotor is None:
        return None
    table = Table(title=f"HP rotor section ({rotor.material}, "
                        f"{rotor.rotational_speed * 30.0 / math.pi:.0f} rpm)")
    for column in ("item", "value (mm)"):
        table.add_column(column, justify="right")
    rows = (("section length", rotor.axial_length), ("radius at the control stage",
            rotor.control_stage_radius), ("radius from the first stage", rotor.stage_radius),
            ("first stage starts at z", rotor.stage_start), ("bore radius", rotor.bore_radius),
            ("groove root radius", rotor.groove_radius), ("groove depth", rotor.groove_depth),
            ("groove centre at z", rotor.groove_position))
    for name, metres in rows:
        table.add_row(name, f"{metres * 1e3:.1f}")
    for steam in rotor.steam:
        table.add_row(f"steam of {steam.group}", f"z {steam.start * 1e3:.1f}–{steam.end * 1e3:.1f}")
    return table


def stage_table(spec: TurbineSpec) -> Table:
    """The control stage and pressure stages: blading and flow capacity."""
    table = Table(title="Stages")
    for column in ("stage", "d (m)", "l (mm)", "blades", "reaction", "α1 (°)",
                   "η peak", "flow capacity K (cm²)"):
        table.add_column(column, justify="right")
    cs = spec.control_stage
    rows = [("control", cs.blading, "nozzle groups")]
    rows += [(str(i), stage.blading, f"{stage.flow_capacity * 1e4:.1f}")
             for i, stage in enumerate(spec.stages, start=1)]
    for name, blading, capacity in rows:
        table.add_row(name, f"{blading.mean_diameter:.4f}", f"{blading.blade_height * 1e3:.1f}",
                      str(blading.blade_count), f"{blading.reaction:.2f}",
                      f"{math.degrees(blading.nozzle_exit_angle):.1f}",
                      f"{blading.peak_blade_efficiency:.3f}", capacity)
    return table
