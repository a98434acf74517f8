"""Canonical DCS signals: the names every part of steamtwin uses, their SI and wire units.

The table follows shared DESIGN.md ("Canonical DCS signals (HP section)"). A plant's historian
names these differently; tag maps (issue: DCS data layer) translate to these names.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Signal:
    """One canonical signal: ``si_unit`` inside the package, ``wire_unit`` in files and plots."""

    name: str
    meaning: str
    si_unit: str
    wire_unit: str


SIGNALS: dict[str, Signal] = {
    signal.name: signal
    for signal in (
        Signal("main_steam_pressure", "throttle pressure before the stop valves", "Pa", "MPa"),
        Signal("main_steam_temperature", "throttle temperature", "K", "degC"),
        Signal("main_steam_flow", "HP inlet mass flow", "kg/s", "t/h"),
        Signal(
            "control_stage_pressure", "governing-stage (impulse chamber) outlet pressure",
            "Pa", "MPa",
        ),
        Signal(
            "control_stage_temperature", "governing-stage outlet steam temperature", "K", "degC"
        ),
        Signal("hp_exhaust_pressure", "HP exhaust (cold reheat) pressure", "Pa", "MPa"),
        Signal("hp_exhaust_temperature", "HP exhaust steam temperature", "K", "degC"),
        Signal(
            "hp_inner_casing_temperature",
            "HP inner casing metal temperature at the governing stage (inner wall)",
            "K", "degC",
        ),
        Signal("load", "generator output", "W", "MW"),
        Signal("hp_power", "HP section internal (blading) power", "W", "MW"),
    )
}
