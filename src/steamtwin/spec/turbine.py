"""The turbine description: validated, immutable dataclasses in SI units.

A :class:`TurbineSpec` holds the design heat balance at rated load, the control stage with its
governing valves, the pressure stages, extractions, the metal of rotor and inner casing per stage
group, the sliding-pressure line, the DCS sensors the unit has and, optionally, the boiler's
steam-temperature schedule against load and, optionally, the drawn HP rotor section
(:class:`RotorSection`). It is built from TOML by
:func:`steamtwin.spec.load_spec`; all values are SI (Pa, K, kg/s, W, m, m², kg, rad, rad/s).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

#: Depth (m) of the inner-casing metal thermocouple under the bore when the spec does not give
#: it. Metal thermocouples of HP inner casings sit in drilled holes near the steam-side surface
#: so that they see the bore's transients (they feed the thermal-stress limiter); 14 mm is an
#: assumed installation depth (node 0's centre, L/16 of the reference unit's 225 mm wall, before
#: the reading became an interpolation at a physical depth).
DEFAULT_CASING_THERMOCOUPLE_DEPTH = 0.014


@dataclass(frozen=True)
class DesignPoint:
    """Design heat balance at rated load (SI units).

    Pressures in Pa, temperatures in K, flow in kg/s, powers in W, ``rotational_speed`` in rad/s.
    ``valve_pressure_drop`` is the fractional pressure loss across a fully open stop + governing
    valve pair (dimensionless). ``valve_outlet_pressure`` (Pa) is the nozzle-chest pressure after
    the last opening group open at rated load when the rated point lies between valve points
    (that group part-open); None: the rated point is a valve point.
    """

    main_steam_pressure: float
    main_steam_temperature: float
    main_steam_flow: float
    control_stage_pressure: float
    hp_exhaust_pressure: float
    hp_exhaust_temperature: float
    hp_power: float
    generator_power: float
    rotational_speed: float
    valve_pressure_drop: float
    valve_outlet_pressure: float | None = None


@dataclass(frozen=True)
class GoverningValve:
    """A governing valve and the nozzle group it feeds.

    ``admission_arc`` is the group's share of the circumference (0–1); valves with the same
    ``opening_order`` open together; ``open_at_design`` marks the valves admitting steam at rated
    load. ``throat_area`` (m²) is the nozzle group's throat area, None when the model sizes it.
    """

    name: str
    opening_order: int
    admission_arc: float
    open_at_design: bool
    throat_area: float | None = None


@dataclass(frozen=True)
class StageGeometry:
    """Blading of one stage: diameters and heights in m, ``nozzle_exit_angle`` in rad.

    ``peak_blade_efficiency`` is the stage efficiency at the optimum velocity ratio before
    friction losses; ``friction_loss`` the share of the isentropic drop lost to profile friction at
    design (both dimensionless).
    """

    mean_diameter: float
    blade_height: float
    blade_count: int
    reaction: float
    nozzle_exit_angle: float
    peak_blade_efficiency: float
    friction_loss: float


@dataclass(frozen=True)
class ControlStage:
    """The governing (control) stage: an impulse stage with nozzle governing.

    ``valve_overlap``: share of a valve's lift by which the next opening group starts before
    the previous one is fully open (0: strictly sequential opening). ``valve_characteristic``:
    (lift, flow share) points of the valves' flow characteristic, both 0…1, linearly
    interpolated (default linear).
    """

    blading: StageGeometry
    nozzle_discharge_coefficient: float
    valves: tuple[GoverningValve, ...]
    valve_overlap: float = 0.0
    valve_characteristic: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0, 1.0), (0.0, 1.0))


@dataclass(frozen=True)
class PressureStage:
    """A pressure stage: blading plus its Stodola flow capacity ``flow_capacity`` in m².

    The flow capacity K is the constant of the stage cone law
    m = K·sqrt((p_in² − p_out²)/(p_in·v_in)) (Stodola 1927; Cooke 1985), an equivalent throat area.
    """

    blading: StageGeometry
    flow_capacity: float
    tip_leakage: float = 0.0


@dataclass(frozen=True)
class Extraction:
    """A bleed after pressure stage ``after_stage`` (1-based); flow in kg/s, pressure in Pa."""

    name: str
    after_stage: int
    design_flow: float
    design_pressure: float


@dataclass(frozen=True)
class Leakage:
    """A leakage past the pressure stages (design data; flows kg/s, pressures Pa).

    It leaves the steam path after stage ``from_stage`` (0 = the control-stage chamber) and
    either rejoins before the HP exhaust (``to == "hp_exhaust"``) or leaves the HP section
    (``to == "outside"``, into a sink at ``sink_pressure`` at rated load). ``design_flow`` is
    its flow at rated load; off design it follows the labyrinth law of its fixed seal.
    """

    name: str
    from_stage: int
    to: str
    design_flow: float
    sink_pressure: float | None = None


@dataclass(frozen=True)
class Material:
    """Metal properties: density kg/m³, specific heat J/(kg·K), conductivity W/(m·K)."""

    density: float
    specific_heat: float
    thermal_conductivity: float


@dataclass(frozen=True)
class MetalGeometry:
    """The drawn shape of a metal group's rotor and inner casing, lengths in m.

    The rotor is a cylinder of ``rotor_radius`` (the drum or rotor body the steam wets) with a
    central bore of ``rotor_bore_radius`` (0: a solid forging); the inner casing a cylindrical
    wall from ``casing_inner_radius`` (its bore) to ``casing_inner_radius +
    casing_wall_thickness``; both over the group's ``axial_length``.
    """

    axial_length: float
    rotor_radius: float
    rotor_bore_radius: float
    casing_inner_radius: float
    casing_wall_thickness: float

    def masses_and_areas(self, casing_density: float, rotor_density: float
                         ) -> tuple[float, float, float, float]:
        """(casing mass kg, casing wetted area m², rotor mass kg, rotor wetted area m²) of the
        cylinders at the densities given (kg/m³)."""
        length, outer = self.axial_length, self.casing_inner_radius + self.casing_wall_thickness
        return (casing_density * math.pi * (outer**2 - self.casing_inner_radius**2) * length,
                2.0 * math.pi * self.casing_inner_radius * length,
                rotor_density * math.pi * (self.rotor_radius**2 - self.rotor_bore_radius**2)
                * length,
                2.0 * math.pi * self.rotor_radius * length)


@dataclass(frozen=True)
class MetalGroup:
    """Rotor and inner-casing metal wetted by the steam of a group of stages.

    ``stages`` lists stage numbers (0 = control stage, 1… = pressure stages). Masses in kg, wetted
    areas in m², ``insulation_conductance`` in W/(m²·K) from the casing's outer surface to the
    surroundings. ``geometry`` is the drawn shape when the spec gives it (masses and areas are
    then the cylinders'); None when the spec gives masses and areas, the model then takes the
    casing as a plane wall of depth mass/(ρ·area) and the rotor as a solid cylinder of radius
    2·mass/(ρ·area).
    """

    name: str
    stages: tuple[int, ...]
    casing_mass: float
    casing_area: float
    rotor_mass: float
    rotor_area: float
    insulation_conductance: float
    geometry: MetalGeometry | None = None

    def casing_wall_depth(self, casing_density: float) -> float:
        """Depth (m) of the inner-casing wall: the drawn thickness, else mass/(ρ·area) with the
        casing steel's density ρ in kg/m³."""
        if self.geometry is not None:
            return self.geometry.casing_wall_thickness
        return self.casing_mass / (casing_density * self.casing_area)


@dataclass(frozen=True)
class SlidingPressureLine:
    """Main-steam pressure (Pa) against load fraction (0–1), linearly interpolated."""

    load_fraction: tuple[float, ...]
    pressure: tuple[float, ...]


@dataclass(frozen=True)
class TemperatureSchedule:
    """Main-steam and, optionally, hot-reheat temperature (K) against load fraction (0–1).

    Linearly interpolated between its points and held flat outside them; ``reheat_temperature``
    None: the unit's hot-reheat temperature is not scheduled (held at its rated value).
    """

    load_fraction: tuple[float, ...]
    main_steam_temperature: tuple[float, ...]
    reheat_temperature: tuple[float, ...] | None = None


@dataclass(frozen=True)
class PartLoad:
    """Design-level part-load laws that a thermal kit's off-design points identify.

    All dimensionless; the defaults leave the model's part-load behaviour as the blading laws
    alone give it (the fit of :mod:`steamtwin.model.design_fit` adjusts them).

    ``reynolds_exponent`` n: a pressure stage's loss 1 − η grows as (m/m_design)^(−n) (Reynolds
    number ∝ flow). ``admission_loss_multiplier`` scales the control stage's partial-admission
    losses (idle-arc windage and sector ends). ``control_stage_velocity_ratio_factor`` scales
    the control stage's optimum velocity ratio. ``flow_capacity_multiplier`` scales every pressure
    stage's Stodola flow capacity.
    """

    reynolds_exponent: float = 0.0
    admission_loss_multiplier: float = 1.0
    control_stage_velocity_ratio_factor: float = 1.0
    flow_capacity_multiplier: float = 1.0


#: Rotor steel of :class:`RotorSection` when the spec names none: the CrMoNiV forging steel of
#: HP/IP rotors (EN 10269 / SEW 555 grade 30CrMoNiV5-11, the 1CrMoV class of GB 30Cr1Mo1V).
DEFAULT_ROTOR_MATERIAL = "30CrMoNiV5-11"


@dataclass(frozen=True)
class RotorSteam:
    """The rotor surface wetted by one metal group's steam: axial interval ``start``–``end`` (m)."""

    group: str
    start: float
    end: float


@dataclass(frozen=True)
class RotorSection:
    """The HP rotor around the control stage as drawn, for the 2-D thermal and stress models.

    Axial coordinate z from 0 to ``axial_length`` (m) along the modelled section; the rotor body
    has outer radius ``control_stage_radius`` for z < ``stage_start`` and ``stage_radius`` from
    there on (m), a central bore of ``bore_radius`` (0: solid). The heat-relief groove is a
    notch of root (fillet) radius ``groove_radius``, ``groove_depth`` deep below the local outer
    radius, centred at z = ``groove_position`` (m): a circular segment when the depth is at most
    the radius, else a U (semicircular root, parallel flanks). ``steam`` lists the wetted
    intervals; surface outside them is adiabatic. ``rotational_speed`` in rad/s.
    """

    axial_length: float
    control_stage_radius: float
    stage_radius: float
    stage_start: float
    groove_radius: float
    groove_depth: float
    groove_position: float
    steam: tuple[RotorSteam, ...]
    rotational_speed: float
    bore_radius: float = 0.0
    material: str = DEFAULT_ROTOR_MATERIAL

    def outer_radius(self, z: float) -> float:
        """Outer radius (m) of the rotor body at axial position ``z`` (m), groove aside."""
        return self.control_stage_radius if z < self.stage_start else self.stage_radius

    @property
    def groove_half_width(self) -> float:
        """Half the groove's width at the surface (m)."""
        rho, depth = self.groove_radius, self.groove_depth
        return rho if depth >= rho else math.sqrt(rho**2 - (rho - depth) ** 2)

    def problems(self, thinnest: float) -> list[str]:
        """What makes the drawn section impossible, each naming the ``rotor.`` fields; empty
        when it is drawable. ``thinnest`` (m): the least metal to leave under groove and bore."""
        found = []
        if not 0.0 < self.stage_start <= self.axial_length:
            found.append(f"rotor.stage_start = {self.stage_start:g} m must lie in "
                         f"(0, rotor.axial_length = {self.axial_length:g} m]")
        smallest = min(self.control_stage_radius, self.stage_radius)
        if self.bore_radius > smallest - thinnest:
            found.append(f"rotor.bore_radius = {self.bore_radius:g} m leaves less than "
                         f"{thinnest:g} m of metal under the smallest outer radius {smallest:g} m")
        radius = self.outer_radius(self.groove_position)
        if self.groove_depth > radius - self.bore_radius - thinnest:
            found.append(f"rotor.groove_depth = {self.groove_depth:g} m leaves less than "
                         f"{thinnest:g} m of metal between the groove root and the bore "
                         f"(outer radius {radius:g} m, bore {self.bore_radius:g} m there)")
        left = self.groove_position - self.groove_half_width
        right = self.groove_position + self.groove_half_width
        segment = ((0.0, self.stage_start) if self.groove_position < self.stage_start
                   else (self.stage_start, self.axial_length))
        if left <= segment[0] or right >= segment[1]:
            found.append(f"rotor.groove_position = {self.groove_position:g} m: the groove "
                         f"({left:g}–{right:g} m) must lie inside one constant-radius part of "
                         f"the section, {segment[0]:g}–{segment[1]:g} m (rotor.stage_start "
                         "splits it)")
        for number, steam in enumerate(self.steam, start=1):
            if not 0.0 <= steam.start < steam.end <= self.axial_length:
                found.append(f"rotor.steam[{number}] ({steam.group!r}): start = {steam.start:g} "
                             f"m and end = {steam.end:g} m must satisfy 0 ≤ start < end ≤ "
                             f"rotor.axial_length = {self.axial_length:g} m")
        ordered = sorted(self.steam, key=lambda steam: steam.start)
        for before, after in itertools.pairwise(ordered):
            if after.start < before.end:
                found.append(f"rotor.steam: the intervals of {before.group!r} and "
                             f"{after.group!r} overlap ({before.end:g} m > {after.start:g} m)")
        return found


@dataclass(frozen=True)
class TurbineSpec:
    """A complete, validated turbine description (SI units)."""

    name: str
    description: str
    design: DesignPoint
    control_stage: ControlStage
    stages: tuple[PressureStage, ...]
    extractions: tuple[Extraction, ...]
    casing_material: Material
    rotor_material: Material
    metal_groups: tuple[MetalGroup, ...]
    casing_sensor_group: str
    ambient_temperature: float
    sliding_pressure: SlidingPressureLine
    sensors: tuple[str, ...]
    part_load: PartLoad = PartLoad()
    temperature_schedule: TemperatureSchedule | None = None
    leakages: tuple[Leakage, ...] = ()
    casing_thermocouple_depth: float = DEFAULT_CASING_THERMOCOUPLE_DEPTH
    rotor: RotorSection | None = None

