"""Design, then off-design: derive the model's constants from the turbine spec.

Following the TESPy habit (a plant described once at its design point), the spec's geometry and
design heat balance give every constant the kernel needs:

* the control stage's nozzle throat areas, given by the spec or sized so that the design flow
  passes the valves open at design at the design control-stage pressure, the last of them
  throttled when the rated point lies between valve points (Saint-Venant nozzle flow);
* blade speeds, optimum velocity ratios, extraction fractions and stage-group flow geometry;
* the metal conduction chains of casing and rotor per stage group: from the drawn geometry
  (cylindrical casing wall, solid or bored rotor) when the spec gives it, else from masses and
  wetted areas (plane casing wall, solid rotor);
* one efficiency scale on all stages so the design HP-exhaust temperature of the heat balance is
  met with the empirical parameter values — the single design "tuning" (reported, bounded);
* each leakage's labyrinth constant, so that its seal passes the spec's design flow at the
  model's design state where it leaves (``FullOrderModel.design_`` iterates that state).

The design control-stage pressure and HP power are *not* imposed: the tests check that the model
reproduces them from the spec's flow capacities and efficiencies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from steamtwin.model.kernel import ControlStageConstants, KernelConstants, MetalConstants
from steamtwin.model.steampath import (
    KAPPA_SUPERHEATED,
    WINDAGE_CONSTANT,
    nozzle_flow_function,
    optimum_velocity_ratio,
)
from steamtwin.spec import Leakage, Material, MetalGeometry, SpecError, TurbineSpec
from steamtwin.steam import if97

METAL_NODES = 8
EFFICIENCY_SCALE_RANGE = (0.8, 1.2)


@dataclass(frozen=True)
class DesignConstants:
    """The kernel constants plus what the design step found (SI units)."""

    kernel: KernelConstants
    efficiency_scale: float


def kernel_constants(spec: TurbineSpec, efficiency_scale: float = 1.0,
                     control_stage_pressure: float | None = None,
                     metal_nodes: int = METAL_NODES,
                     leakage_capacity: np.ndarray | None = None) -> KernelConstants:
    """Constants for the kernel at a given efficiency scale (the scale is solved elsewhere).

    The nozzle throat area passes the design flow through the valves open at design at
    ``control_stage_pressure`` (Pa; default: the heat balance's), so the design point is the
    valve point the spec names. ``leakage_capacity`` (m², one per :func:`active_leakages`):
    the seals' labyrinth constants; default: :func:`leakage_capacities` at the states
    :func:`estimated_leakage_origins` gives.
    """
    design = spec.design
    omega = design.rotational_speed
    cs = spec.control_stage
    part_load = spec.part_load
    orders = sorted({valve.opening_order for valve in cs.valves})
    level_arc = np.array(
        [sum(v.admission_arc for v in cs.valves if v.opening_order == o) for o in orders]
    )
    level_segments = np.array(
        [float(sum(1 for v in cs.valves if v.opening_order == o)) for o in orders]
    )
    level_area = _level_throat_areas(spec, orders, level_arc,
                                     control_stage_pressure or design.control_stage_pressure)
    n = len(spec.stages)
    extraction_fraction = np.zeros(n)
    for extraction in spec.extractions:
        extraction_fraction[extraction.after_stage - 1] += (
            extraction.design_flow / design.main_steam_flow
        )
    groups = spec.metal_groups
    chains = 2 * len(groups)  # chain 2·g is group g's casing, 2·g + 1 its rotor
    capacity = np.zeros((chains, metal_nodes))
    conductance = np.zeros((chains, metal_nodes - 1))
    area = np.zeros(chains)
    half_cell = np.zeros(chains)
    outer = np.zeros(chains)
    hydraulic_diameter = np.zeros(len(groups))
    flow_area = np.zeros(len(groups))
    rotor_speed = np.zeros(len(groups))
    for g, group in enumerate(groups):
        blading = [cs.blading if s == 0 else spec.stages[s - 1].blading for s in group.stages]
        height = float(np.mean([b.blade_height for b in blading]))
        diameter = float(np.mean([b.mean_diameter for b in blading]))
        hydraulic_diameter[g] = 2.0 * height
        flow_area[g] = math.pi * diameter * height
        if group.geometry is None:
            casing = _plane_wall(group.casing_mass, group.casing_area, spec.casing_material,
                                 group.insulation_conductance, metal_nodes)
            rotor = _solid_cylinder(group.rotor_mass, group.rotor_area, spec.rotor_material,
                                    metal_nodes)
            rotor_radius = 2.0 * group.rotor_mass / (spec.rotor_material.density
                                                     * group.rotor_area)
        else:
            casing = cylindrical_wall(group.geometry, spec.casing_material,
                                      group.insulation_conductance, metal_nodes)
            rotor = hollow_cylinder(group.geometry, spec.rotor_material, metal_nodes)
            rotor_radius = group.geometry.rotor_radius
        for body, chain in enumerate((casing, rotor)):
            row = 2 * g + body
            capacity[row], conductance[row], half_cell[row], outer[row] = chain
        area[2 * g], area[2 * g + 1] = group.casing_area, group.rotor_area
        rotor_speed[g] = omega * rotor_radius
    sensor_group = [group.name for group in groups].index(spec.casing_sensor_group)
    sensor_node, sensor_weight = _thermocouple_position(
        groups[sensor_group].casing_wall_depth(spec.casing_material.density), metal_nodes,
        spec.casing_thermocouple_depth)
    control = ControlStageConstants(
        valve_pressure_drop=design.valve_pressure_drop,
        nozzle_discharge_coefficient=cs.nozzle_discharge_coefficient,
        level_area=level_area,
        level_arc=level_arc,
        level_segments=level_segments,
        blade_speed=omega * cs.blading.mean_diameter / 2.0,
        optimum_ratio=part_load.control_stage_velocity_ratio_factor
        * optimum_velocity_ratio(cs.blading.nozzle_exit_angle, cs.blading.reaction),
        peak_efficiency=efficiency_scale * cs.blading.peak_blade_efficiency,
        friction_loss=cs.blading.friction_loss,
        diameter=cs.blading.mean_diameter,
        windage_area=WINDAGE_CONSTANT * math.pi * math.sin(cs.blading.nozzle_exit_angle)
        * cs.blading.mean_diameter * cs.blading.blade_height / 2.0,
        admission_loss_multiplier=part_load.admission_loss_multiplier,
        valve_overlap=cs.valve_overlap,
        characteristic_lift=np.array(cs.valve_characteristic[0]),
        characteristic_flow=np.array(cs.valve_characteristic[1]),
    )
    metal = MetalConstants(
        capacity=capacity,
        conductance=conductance,
        area=area,
        half_cell_resistance=half_cell,
        outer_conductance=outer,
        flow_area=flow_area,
        hydraulic_diameter=hydraulic_diameter,
        rotor_speed=rotor_speed,
        ambient_temperature=spec.ambient_temperature,
    )
    leakages = active_leakages(spec)
    if leakage_capacity is None:
        leakage_capacity = leakage_capacities(spec, *estimated_leakage_origins(spec))
    return KernelConstants(
        control=control,
        metal=metal,
        stage_capacity=part_load.flow_capacity_multiplier
        * np.array([s.flow_capacity for s in spec.stages]),
        stage_blade_speed=np.array([omega * s.blading.mean_diameter / 2.0 for s in spec.stages]),
        stage_optimum_ratio=np.array(
            [optimum_velocity_ratio(s.blading.nozzle_exit_angle, s.blading.reaction)
             for s in spec.stages]
        ),
        stage_peak_efficiency=efficiency_scale
        * np.array([s.blading.peak_blade_efficiency for s in spec.stages]),
        stage_friction_loss=np.array([s.blading.friction_loss for s in spec.stages]),
        reynolds_exponent=part_load.reynolds_exponent,
        design_flow=design.main_steam_flow,
        extraction_fraction=extraction_fraction,
        group_first_stage=np.array([group.stages[0] for group in groups], dtype=np.int64),
        group_ending_at_stage=np.array(
            [next((g for g, group in enumerate(groups) if group.stages[-1] == stage), -1)
             for stage in range(n + 1)], dtype=np.int64),
        sensor_group=sensor_group,
        sensor_node=sensor_node,
        sensor_weight=sensor_weight,
        stage_tip_passing=np.array([1.0 - s.tip_leakage for s in spec.stages]),
        leak_origin=np.array([leak.from_stage for leak in leakages], dtype=np.int64),
        leak_capacity=np.asarray(leakage_capacity, dtype=float).reshape(len(leakages)),
        leak_sink_ratio=np.array([leakage_sink_ratio(spec, leak) for leak in leakages]),
        leak_rejoins=np.array([leak.to == "hp_exhaust" for leak in leakages], dtype=np.int64),
    )


def active_leakages(spec: TurbineSpec) -> tuple[Leakage, ...]:
    """The spec's leakages with a design flow: one of zero flow is no leakage at all."""
    return tuple(leak for leak in spec.leakages if leak.design_flow > 0.0)


def leakage_sink_ratio(spec: TurbineSpec, leakage: Leakage) -> float:
    """A leakage's downstream pressure over the HP-exhaust pressure (dimensionless).

    A leakage to the HP exhaust discharges at its pressure (1). One to the outside discharges
    into the IP inlet or a leak-off line downstream of the HP; their pressures move in
    proportion with the HP-exhaust pressure, as Stodola's law of the sections downstream
    makes their inlet pressures proportional to flow at large pressure ratios (Stodola 1927;
    Cooke, J. Eng. Gas Turbines Power 107 (1985) 596–606). For a sink far below the upstream
    pressure the seal's flow barely depends on it (Egli 1935).
    """
    if leakage.sink_pressure is None:
        return 1.0
    return leakage.sink_pressure / spec.design.hp_exhaust_pressure


def leakage_capacities(spec: TurbineSpec, origin_pressure: np.ndarray,
                       origin_pv: np.ndarray) -> np.ndarray:
    """Labyrinth constants (m²) passing each active leakage's design flow at design.

    ``origin_pressure`` (Pa) and ``origin_pv`` (p·v, J/kg): the design state where each leaves.
    C = m / sqrt((p_up² − p_down²)/(p_up·v_up)) (Martin 1908; Egli 1935; ``kernel``).
    """
    leakages = active_leakages(spec)
    capacity = np.zeros(len(leakages))
    for j, leak in enumerate(leakages):
        sink = leakage_sink_ratio(spec, leak) * spec.design.hp_exhaust_pressure
        head = origin_pressure[j] ** 2 - sink**2
        if not head > 0.0:
            raise SpecError(
                f"turbine {spec.name!r}: leakage {leak.name!r} discharges at "
                f"{sink / 1e6:.3f} MPa, not below the design pressure where it leaves "
                f"({origin_pressure[j] / 1e6:.3f} MPa after stage {leak.from_stage})")
        capacity[j] = leak.design_flow / math.sqrt(head / origin_pv[j])
    return capacity


def estimated_leakage_origins(spec: TurbineSpec) -> tuple[np.ndarray, np.ndarray]:
    """Design pressure (Pa) and p·v (J/kg) where each active leakage leaves, estimated.

    A backward Stodola sweep of the spec's flow capacities from the design HP exhaust with the
    design flows (bleeds and leakages off), p·v held at the exhaust's (IAPWS-IF97): a start
    that the design step replaces by the model's own design state.
    """
    leakages = active_leakages(spec)
    design = spec.design
    h_exhaust = float(if97.enthalpy_pt(design.hp_exhaust_pressure, design.hp_exhaust_temperature))
    pv = design.hp_exhaust_pressure * float(if97.specific_volume_ph(design.hp_exhaust_pressure,
                                                                       h_exhaust))
    n = len(spec.stages)
    bled = np.zeros(n)
    for extraction in spec.extractions:
        bled[extraction.after_stage - 1] += extraction.design_flow
    pressures = np.empty(n + 1)
    pressures[n] = design.hp_exhaust_pressure
    for i in range(n - 1, -1, -1):  # stage i + 1 (pressures[i] is its inlet)
        flow = design.main_steam_flow - bled[:i].sum() - sum(
            leak.design_flow for leak in leakages if leak.from_stage <= i)
        capacity = spec.part_load.flow_capacity_multiplier * spec.stages[i].flow_capacity
        pressures[i] = math.sqrt(pressures[i + 1] ** 2 + (flow / capacity) ** 2 * pv)
    origin = np.array([pressures[leak.from_stage] for leak in leakages])
    return origin, np.full(len(leakages), pv)


def _level_throat_areas(spec: TurbineSpec, orders: list[int], level_arc: np.ndarray,
                        control_stage_pressure: float) -> np.ndarray:
    """Nozzle throat area (m²) of each opening level: the spec's throat areas, or sized.

    Sized, the area is in proportion to admission arc and passes the design flow through the
    valves open at design at ``control_stage_pressure`` (Pa): the levels before the last open
    one wide open at p0·(1 − valve drop), the last one at ``design.valve_outlet_pressure`` when
    the rated point lies between valve points. Saint-Venant nozzle flow through each group,
    throttling isenthalpic (h0 kept).
    """
    design = spec.design
    cs = spec.control_stage
    if all(valve.throat_area is not None for valve in cs.valves):
        return np.array([sum(v.throat_area for v in cs.valves if v.opening_order == order)
                         for order in orders])
    h0 = float(if97.enthalpy_pt(design.main_steam_pressure, design.main_steam_temperature))

    def flux(p_valve: float) -> float:
        """Flow per unit throat area (kg/(s·m²)) fed at ``p_valve`` (Pa)."""
        psi = nozzle_flow_function(control_stage_pressure / p_valve, KAPPA_SUPERHEATED)
        if psi <= 0.0:
            raise SpecError("design control-stage pressure is not below the valve outlet "
                            "pressure")
        v_valve = float(if97.specific_volume_ph(p_valve, h0))
        return cs.nozzle_discharge_coefficient * psi * math.sqrt(p_valve / v_valve)

    wide_open = design.main_steam_pressure * (1.0 - design.valve_pressure_drop)
    open_levels = [level for level, order in enumerate(orders)
                   if any(v.open_at_design for v in cs.valves if v.opening_order == order)]
    if design.valve_outlet_pressure is None:
        open_arc = sum(v.admission_arc for v in cs.valves if v.open_at_design)
        area_per_arc = design.main_steam_flow / flux(wide_open) / open_arc
    else:
        last = open_levels[-1]
        passed_per_arc = (sum(level_arc[level] for level in open_levels[:-1]) * flux(wide_open)
                          + level_arc[last] * flux(design.valve_outlet_pressure))
        area_per_arc = design.main_steam_flow / passed_per_arc
    return level_arc * area_per_arc


def _thermocouple_position(wall_depth: float, nodes: int, thermocouple_depth: float
                           ) -> tuple[int, float]:
    """(node, weight) of the casing thermocouple ``thermocouple_depth`` m under the bore.

    Node j's centre lies (j + ½)·Δx under the bore (Δx = wall depth / nodes, plane or
    cylindrical wall alike); node −1 stands for the bore surface. The reading is
    node + weight·(next − node), linear in depth.
    """
    dx = wall_depth / nodes
    depth = min(thermocouple_depth, wall_depth - dx / 2.0)
    if depth <= dx / 2.0:
        return -1, depth / (dx / 2.0)
    node = min(int(depth / dx - 0.5), nodes - 2)
    return node, (depth - (node + 0.5) * dx) / dx


def _plane_wall(mass, area, material, insulation, nodes):
    """Finite-volume chain of a plane wall (capacity J/K, conductance W/K, half-cell, outer)."""
    depth = mass / (material.density * area)
    dx = depth / nodes
    capacity = np.full(nodes, material.density * material.specific_heat * area * dx)
    conductance = np.full(nodes - 1, material.thermal_conductivity * area / dx)
    half_cell = dx / (2.0 * material.thermal_conductivity)
    outer = area / (1.0 / insulation + half_cell) if insulation > 0.0 else 0.0
    return capacity, conductance, half_cell, outer


def _solid_cylinder(mass, area, material, nodes):
    """Finite-volume chain of a solid cylinder, node 0 at the surface, no outer loss."""
    radius = 2.0 * mass / (material.density * area)
    length = area / (2.0 * math.pi * radius)
    dr = radius / nodes
    outer_radii = radius - dr * np.arange(nodes)
    inner_radii = np.maximum(outer_radii - dr, 0.0)
    capacity = (material.density * material.specific_heat * math.pi
                * (outer_radii**2 - inner_radii**2) * length)
    conductance = material.thermal_conductivity * 2.0 * math.pi * inner_radii[:-1] * length / dr
    return capacity, conductance, dr / (2.0 * material.thermal_conductivity), 0.0


@dataclass(frozen=True)
class RadialChain:
    """Finite volumes of a cylindrical shell, node 0 at the steam-wetted surface (SI units).

    ``capacity`` J/K per node, ``conductance`` W/K between nodes j and j+1, ``half_cell`` the
    resistance from the wetted surface to node 0 times the wetted area (m²·K/W), ``far_resistance``
    K/W from the last node to the far surface (infinite for a solid core).
    """

    capacity: np.ndarray
    conductance: np.ndarray
    half_cell: float
    far_resistance: float


def radial_chain(wetted_radius: float, far_radius: float, length: float, material: Material,
                 nodes: int) -> RadialChain:
    """Equal-thickness shells from the wetted radius to the far radius (m), ``length`` m long.

    Each node sits at its shell's mid-radius; nodes are joined by the exact steady resistance
    of a cylindrical shell, ln(r_b/r_a)/(2πkL) (Incropera & DeWitt, *Fundamentals of Heat and
    Mass Transfer*, 6th ed., eq. 3.33), so the chain's steady resistance from surface to surface
    is the hollow cylinder's at any node count; capacities add up to ρ·c·π·|r_far² − r_wet²|·L.
    """
    edges = np.linspace(wetted_radius, far_radius, nodes + 1)
    centres = 0.5 * (edges[:-1] + edges[1:])
    two_pi_k_length = 2.0 * math.pi * material.thermal_conductivity * length
    capacity = (material.density * material.specific_heat * math.pi * length
                * np.abs(edges[1:] ** 2 - edges[:-1] ** 2))
    conductance = two_pi_k_length / np.abs(np.log(centres[1:] / centres[:-1]))
    half_cell = (wetted_radius * abs(math.log(centres[0] / wetted_radius))
                 / material.thermal_conductivity)
    far_resistance = (abs(math.log(far_radius / centres[-1])) / two_pi_k_length
                      if far_radius > 0.0 else math.inf)
    return RadialChain(capacity, conductance, half_cell, far_resistance)


def cylindrical_wall(geometry: MetalGeometry, material: Material, insulation: float,
                     nodes: int) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Chain of the inner casing as a cylindrical wall wetted on its bore (capacity J/K,
    conductance W/K, half-cell m²·K/W, outer conductance W/K through the lagging of
    ``insulation`` W/(m²·K) on the outer surface)."""
    outer_radius = geometry.casing_inner_radius + geometry.casing_wall_thickness
    chain = radial_chain(geometry.casing_inner_radius, outer_radius, geometry.axial_length,
                         material, nodes)
    lagging = insulation * 2.0 * math.pi * outer_radius * geometry.axial_length
    outer = 1.0 / (1.0 / lagging + chain.far_resistance) if insulation > 0.0 else 0.0
    return chain.capacity, chain.conductance, chain.half_cell, outer


def hollow_cylinder(geometry: MetalGeometry, material: Material, nodes: int
                    ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Chain of the rotor wetted on its outer surface, solid or bored, the bore adiabatic
    (capacity J/K, conductance W/K, half-cell m²·K/W, no outer loss)."""
    chain = radial_chain(geometry.rotor_radius, geometry.rotor_bore_radius,
                         geometry.axial_length, material, nodes)
    return chain.capacity, chain.conductance, chain.half_cell, 0.0
