"""The full-order model's time loop, compiled with numba.

Kept as one module because it is one job, the compiled per-sample solve (steps 0–4 below),
whose physics already lives in ``steampath``, ``metal`` and ``steam.tables``; cutting the solve
itself across files would also let numba serve stale code, since its on-disk cache is not
invalidated by changes to jitted callees in other files (numba docs, "Notes on Caching",
caching limitations).

At each sample the steam path is algebraic (quasi-steady); only the metal carries state. The
loop therefore solves, sample by sample, warm-started from the previous sample:

0. the stage-inlet p·v values of the previous sample are carried to this sample's inputs: a
   backward sweep gives new pressures, the control stage gives the exact p·v of its outlet, and
   each stage inlet's p·v follows along the polytrope p·v ∝ p^m whose exponent m (from the
   control-stage outlet to the last inlet) the previous sample's state measures;
1. a backward sweep of Stodola's law from the HP-exhaust pressure gives the stage pressures and
   the control-stage pressure (each stage's p·v from the previous sweep);
2. the control stage distributes the flow over the nozzle groups in valve order, throttling the
   group whose valve is part open (with a valve overlap, every group the overlapping lift
   schedule leaves part open), expands each group and mixes them (``steampath``); the first
   sweep instead shifts step 0's evaluation linearly to its p1 when that moved little
   (:data:`REUSE_SHARE`);
3. a forward sweep expands the pressure stages; at the end of each stage group the steam gives
   heat to that group's casing and rotor (implicit-Euler conduction step, ``metal``), which is
   taken from the steam enthalpy there; a leakage (spec ``[[leakages]]``) leaves the stage flow
   where it starts, with the enthalpy there and the flow its seal's labyrinth law gives at this
   sweep's pressures, and either mixes into the HP exhaust or leaves the section (the backward
   sweep of step 1 takes the stage flows less the leakages of the previous forward sweep);
4. 1–3 repeat until the estimated error left in the control-stage pressure and the exhaust
   enthalpy is below the tolerances below; then the metal state is committed.

Heat given to the metal in a step is exactly what the implicit metal step stores or loses
through the lagging, so energy is conserved to round-off at every sample.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from steamtwin.cache import njit
from steamtwin.model.metal import (
    dittus_boelter_from_logs,
    dittus_boelter_logs,
    factor_chain,
    finish_chains,
    prepare_chains,
    rotor_relative_velocity,
    surface_heat,
    surface_response,
)
from steamtwin.model.steampath import (
    DISC_FRICTION_CONSTANT,
    KAPPA_SUPERHEATED,
    SECTOR_END_CONSTANT,
    nozzle_flow_function,
    stage_efficiency,
    stodola_inlet_pressure,
    windage_power,
)
from steamtwin.steam.tables import (
    PH_CP,
    PH_K,
    PH_MU,
    PH_S,
    PH_T,
    PH_V,
    enthalpy_ps_at,
    enthalpy_pt_at,
    entropy_and_pv_at,
    heat_transfer_properties_at,
    isentropic_step_at,
    locate_log_pressure,
    locate_pressure,
    ph_domain_position_at,
    ph_property,
    ph_property_and_position_at,
    ph_property_at,
    pressure_in_range,
)

CASING, ROTOR = 0, 1

# Result columns of :func:`run_kernel`, in order (SI units).
RESULT_COLUMNS = (
    "control_stage_pressure",  # Pa
    "control_stage_temperature",  # K
    "hp_exhaust_temperature",  # K
    "hp_inner_casing_temperature",  # K
    "hp_power",  # W
    "heat_to_metal",  # W, all groups
    "extraction_energy_flow",  # W, m_ext·h_ext summed
    "exhaust_energy_flow",  # W, m_exhaust·h_exhaust
    "inlet_energy_flow",  # W, m·h0
    "control_stage_efficiency",  # -
    "active_admission_arc",  # -
    "iterations",  # -
    "metal_heat_content",  # J, Σ capacity·temperature over all metal (from 0 K)
    "lagging_loss",  # W, from the casings through the insulation
    "leakage_energy_flow",  # W, m_leak·h_leak of the leakages that leave the HP section
    "leakage_flow",  # kg/s, all leakages past the pressure stages
)
N_RESULTS = len(RESULT_COLUMNS)

# Convergence of the sweeps. The backward half of the next sweep costs ~1 % of a sweep, so it is
# run as a probe: it gives exactly the pressure change δ_i (relative, at every stage inlet) the
# next sweep would make. The forward sweep is a function of the pressures alone, and along an
# expansion dh = η·v·dp with η < 1 (Gibbs; Dixon & Hall, *Fluid Mechanics and Thermodynamics of
# Turbomachinery*, ch. 2), so the next change of the exhaust enthalpy is about p·v·max δ_i; it
# is taken as the last stage's inlet p·v times max δ_i (on the benchmark's noisy ramp the next
# sweep's actual change stayed below 0.7 × the exhaust's p·v times max δ_i). A sample keeps
# the last full sweep's state when the next changes are within the tolerances — relative
# control-stage pressure, and enthalpy in J/kg (25 J/kg ≈ 0.01 K). The defaults sit 10× and
# 50× below what the DCS resolves (transmitters 0.1 % of reading, thermocouples ±0.5 K noise):
# on a noisy ramp they leave ≤ 1.5e-4 relative control-stage pressure and ≤ 0.02 K against
# sweeps converged to 1e-11 (tests/model/test_fom.py). With the p·v carried over by the
# polytrope (step 0), most samples of a noisy DCS series then take a single sweep.
PRESSURE_TOLERANCE = 1e-4
ENTHALPY_TOLERANCE = 25.0  # J/kg
PREDICTOR_PASSES = 1  # control stage + polytropic p·v update + backward sweep, per sample
MAX_SWEEPS = 200  # per sample; then STATUS_NO_CONVERGENCE
# The first sweep reuses the predictor's control stage shifted linearly to the new p1
# (:func:`_shifted_control_stage`) when the shift (dh1/dp1)·|Δp1| is at most REUSE_SHARE times
# the enthalpy tolerance. The slope dh1/dp1 is a secant measured on an earlier sample that
# evaluated the control stage at two p1 (same inputs, same part-open valve): the stage's
# outlet is smooth in p1 while the same valve throttles, and the slope changes with the inputs
# by ~1 % per 1 % of flow, so the shifted outlet errs by a few % of the shift (≤ 0.005 K on the
# GA's two holds against the full evaluation, tests/model/test_fom.py).
REUSE_SHARE = 4.0
# The steady start converges its sweeps 10⁶× tighter, down to round-off level (relative
# pressure, J/kg), so that a hold that follows does not drift.
START_FLOOR = np.array([1e-11, 1e-5])

# Relative flow residual at which the throttled nozzle group's pressure is accepted: the valve
# outlet pressure then errs by ~1e-7 relative (F ∝ p/sqrt(p·v) when choked, steeper below), its
# entropy by R·1e-7 ≈ 5e-5 J/(kg·K), the group's isentropic drop by T·Δs < 0.05 J/kg: far inside
# ENTHALPY_TOLERANCE. A sample swept to a tighter enthalpy tolerance (the steady start) scales
# it down alike: where the answer lands inside this window depends on the warm start, and at a
# valve point, where the last group alternates between wide open and throttled from sweep to
# sweep, that noise (~1e-3 J/kg) otherwise kept the start's sweeps from converging.
THROTTLE_TOLERANCE = 1e-7

# Status codes per sample (0 = solved).
STATUS_OK = 0
STATUS_OVER_CAPACITY = 1  # flow exceeds what the wide-open valves pass
STATUS_OUT_OF_TABLES = 2  # a state left superheated steam / the property range
STATUS_NO_CONVERGENCE = 3
STATUS_PRESSURE_INVERSION = 4  # stage pressures reach the throttle pressure


class ControlStageConstants(NamedTuple):
    """The governing stage (SI units)."""

    valve_pressure_drop: float  # fraction of throttle pressure lost in wide-open valves
    nozzle_discharge_coefficient: float
    level_area: np.ndarray  # m², nozzle throat area of each valve-opening level
    level_arc: np.ndarray  # fraction of circumference of each level
    level_segments: np.ndarray  # number of nozzle groups (arc segments) of each level
    blade_speed: float  # m/s
    optimum_ratio: float
    peak_efficiency: float  # with the design efficiency scale applied
    friction_loss: float
    diameter: float  # m
    windage_area: float  # m², B_e·π·sin α1·d·l/2 of the idle-arc windage power
    admission_loss_multiplier: float  # on windage and sector-end loss (spec part_load)
    valve_overlap: float  # lift share by which a level opens before the previous is full open
    characteristic_lift: np.ndarray  # valve lift points (0…1) of the flow characteristic
    characteristic_flow: np.ndarray  # share of the wide-open flow at each lift point


class MetalConstants(NamedTuple):
    """Conduction chains and steam-side geometry of the stage groups (SI units).

    Chain 2·group is the group's inner casing, 2·group + 1 its rotor.
    """

    capacity: np.ndarray  # (chains, nodes) J/K
    conductance: np.ndarray  # (chains, nodes-1) W/K
    area: np.ndarray  # (chains,) m², wetted
    half_cell_resistance: np.ndarray  # (chains,) m²·K/W, surface to node 0
    outer_conductance: np.ndarray  # (chains,) W/K to the surroundings
    flow_area: np.ndarray  # (groups,) m², blade-path annulus
    hydraulic_diameter: np.ndarray  # (groups,) m
    rotor_speed: np.ndarray  # (groups,) m/s, rotor surface speed
    ambient_temperature: float  # K


class KernelConstants(NamedTuple):
    """Everything the kernel needs from the spec, derived once (SI units).

    Split in parts so each compiled helper receives only the arrays it uses: every array handed
    to an inlined helper costs reference counting at each call.
    """

    control: ControlStageConstants
    metal: MetalConstants
    stage_capacity: np.ndarray  # m², Stodola constants
    stage_blade_speed: np.ndarray  # m/s
    stage_optimum_ratio: np.ndarray
    stage_peak_efficiency: np.ndarray  # with the design efficiency scale applied
    stage_friction_loss: np.ndarray
    reynolds_exponent: float  # n of the stage loss (m/m_design)^(−n) (spec part_load)
    design_flow: float  # kg/s, main-steam flow at rated load
    extraction_fraction: np.ndarray  # of throttle flow, bled after each stage
    group_first_stage: np.ndarray  # int, 0 = control stage
    group_ending_at_stage: np.ndarray  # int per stage 0…n: the group that ends there, or -1
    sensor_group: int
    sensor_node: int  # the thermocouple lies between node sensor_node and the next (-1: wall)
    sensor_weight: float  # linear weight of the deeper of the two
    stage_tip_passing: np.ndarray  # 1 − tip-leakage share of each stage's flow
    leak_origin: np.ndarray  # int, per leakage: it leaves at pressures[origin] (0 = chamber)
    leak_capacity: np.ndarray  # m², labyrinth constant of each leakage's seal
    leak_sink_ratio: np.ndarray  # its downstream pressure over the HP-exhaust pressure
    leak_rejoins: np.ndarray  # int, 1: rejoins before the HP exhaust, 0: leaves the HP section


# The helpers below allocate nothing, so they are compiled without numba's reference counting
# (``_nrt=False``, numba's flag for code that needs no runtime): a compiled call otherwise
# increments and decrements the count of every array it is handed at entry and exit (~20 pairs
# per control-stage evaluation; docs/benchmarks.md, sessions 18–19). ``run_kernel`` allocates
# its work arrays and keeps the runtime.
@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _nozzle_group_flow(area, p1, pressure, specific_volume):
    """Flow (kg/s) of a nozzle group fed at ``pressure`` (Pa) with ``specific_volume`` (m³/kg).

    Scalars only: a compiled helper taking the table arrays would increment and decrement their
    reference counts at every evaluation.
    """
    return area * nozzle_flow_function(p1 / pressure, KAPPA_SUPERHEATED) * math.sqrt(
        pressure / specific_volume)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _throttled_pressure(flow, area, p1, p_valve, wide_open, h0, tables, guess, slope,
                        tolerance=THROTTLE_TOLERANCE):
    """Pressure after a part-open valve whose nozzle group must pass ``flow`` (kg/s).

    ``wide_open`` is the group's flow at ``p_valve`` (kg/s). Starts from the previous answer
    ``guess`` (Pa) with a Newton step on the previous solve's ``slope`` (kg/s per Pa; ≤ 0: none
    yet), then secant steps, kept inside the bracket (p1, p_valve] by bisection: the flow
    function rises monotonically with the valve-outlet pressure. Returns the pressure and the
    last secant slope, for the next sample's start. ``tolerance``: relative flow residual.
    """
    low, high = p1, p_valve
    if wide_open <= flow:
        return high, slope
    x0 = min(max(guess, low + 1e-3 * (high - low)), high - 1e-3 * (high - low))
    f0 = _nozzle_group_flow(area, p1, x0, ph_property(tables, PH_V, x0, h0)) - flow
    if abs(f0) <= tolerance * flow:
        return x0, slope
    if f0 > 0.0:
        high = x0
    else:
        low = x0
    x1 = x0 - f0 / slope if slope > 0.0 else x0 + 1e-4 * (p_valve - p1) * (
        -1.0 if f0 > 0.0 else 1.0)
    if not low < x1 < high:
        x1 = 0.5 * (low + high)
    for _ in range(60):
        f1 = _nozzle_group_flow(area, p1, x1, ph_property(tables, PH_V, x1, h0)) - flow
        if f1 != f0:
            slope = (f1 - f0) / (x1 - x0)
        if abs(f1) <= tolerance * flow:
            return x1, slope
        if f1 > 0.0:
            high = min(high, x1)
        else:
            low = max(low, x1)
        x2 = x1 - f1 / slope if f1 != f0 else 0.5 * (low + high)
        if not low < x2 < high:
            x2 = 0.5 * (low + high)
        x0, f0, x1 = x1, f1, x2
    return x1, slope


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _nozzle_group_expansion(cs, tables, cell_1, coordinate_1, h0, s_in, friction_coefficient):
    """Outlet enthalpy and isentropic drop (J/kg) of a nozzle group expanding to p1 (located)."""
    drop = max(h0 - enthalpy_ps_at(tables, cell_1, coordinate_1, s_in), 0.0)
    velocity_ratio = cs.blade_speed / math.sqrt(2.0 * drop) if drop > 0.0 else 1e3
    efficiency = stage_efficiency(velocity_ratio, cs.optimum_ratio, cs.peak_efficiency,
                                  friction_coefficient * cs.friction_loss)
    return h0 - efficiency * drop, drop


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _level_lift(overlap, level, demand):
    """Lift (0…1) of opening level ``level`` (0-based) at valve demand ``demand``.

    Each level's lift rises over one unit of demand and the next level starts ``overlap`` of a
    lift before the previous is fully open [Cotton, *Evaluating and Improving Steam Turbine
    Performance*, 1998, ch. 6: valve-point loops and overlap].
    """
    return min(max(demand - level * (1.0 - overlap), 0.0), 1.0)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _characteristic_share(lift_points, flow_shares, lift):
    """The valves' flow characteristic (share of the wide-open flow, piecewise linear in the
    lift) at ``lift`` (0…1).

    A scan of its few points rather than ``np.interp``, whose compiled form checks and searches
    its arrays at every call: at ~80 ns a call it made the valve demand's search most of a
    control-stage evaluation.
    """
    m = 1
    while m < lift_points.size - 1 and lift_points[m] <= lift:
        m += 1
    return flow_shares[m - 1] + (flow_shares[m] - flow_shares[m - 1]) / (
        lift_points[m] - lift_points[m - 1]) * (lift - lift_points[m - 1])


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _level_share(cs, level, demand):
    """Share (0…1) of its wide-open flow that level ``level`` passes at valve demand ``demand``:
    the valves' flow characteristic at the level's scheduled lift."""
    return _characteristic_share(cs.characteristic_lift, cs.characteristic_flow,
                                 _level_lift(cs.valve_overlap, level, demand))


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _scheduled_share(level_area, lift_points, flow_shares, overlap, demand):
    """Σ level area × share at valve ``demand`` (m²): the scheduled flow per open-valve flux.

    Takes the arrays it uses, not the constants: a compiled call counts references to every
    array it is handed.
    """
    total = 0.0
    for level in range(level_area.size):
        total += level_area[level] * _characteristic_share(
            lift_points, flow_shares, _level_lift(overlap, level, demand))
    return total


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _valve_demand(cs, open_flux, flow):
    """Valve demand at which the overlapping lift schedule passes ``flow`` (kg/s).

    The scheduled flow Σ wide-open × share(lift) is piecewise linear and non-decreasing in the
    demand, with corners only where a level's lift passes a point of the characteristic
    (demand = level·(1 − overlap) + lift point). So the demand is found exactly: walk the
    corners upward to the first whose flow reaches ``flow`` and interpolate linearly from the
    corner below — the least demand that passes the flow, as a bisection to round-off would
    give it, at a few evaluations instead of 64. The walk starts at the last level-opening
    corner (demand level·(1 − overlap)) below the flow, found first. A flow above what every
    valve wide open passes gets the full demand (the caller reports over capacity).
    """
    overlap = cs.valve_overlap
    area, points, shares = cs.level_area, cs.characteristic_lift, cs.characteristic_flow
    full = (area.size - 1) * (1.0 - overlap) + 1.0
    target = flow / open_flux  # m²
    low = 0.0
    share_low = _scheduled_share(area, points, shares, overlap, low)
    if share_low >= target:
        return low
    for level in range(1, area.size):  # skip the levels that open below the flow
        start = level * (1.0 - overlap)
        share_start = _scheduled_share(area, points, shares, overlap, start)
        if share_start >= target:
            break
        low, share_low = start, share_start
    while low < full:
        high = full
        for level in range(area.size):  # the next corner above ``low``
            start = level * (1.0 - overlap)
            for m in range(points.size):
                if start + points[m] > low:
                    high = min(high, start + points[m])
                    break
        share_high = _scheduled_share(area, points, shares, overlap, high)
        if share_high >= target:
            return low + (target - share_low) / (share_high - share_low) * (high - low)
        low, share_low = high, share_high
    return full


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _control_stage(cs, tables, flow, p_valve, s_valve, pv_valve, h0, p1, cell_1, coordinate_1,
                   params, throttled, out, throttle_tolerance):
    """Expand the nozzle groups to ``p1`` (located as ``cell_1``, ``coordinate_1``:
    :func:`locate_pressure`); returns the mixed outlet enthalpy (J/kg).

    The wide-open valves pass steam at ``p_valve`` (Pa) with entropy ``s_valve`` and p·v
    ``pv_valve`` (J/kg), set once per sample. ``out`` receives [status, power W, efficiency,
    active arc, 1 + the part-open level (0: none), …]; status :data:`STATUS_OVER_CAPACITY` when the
    wide-open valves pass less than ``flow`` at ``p1``, the outlet then being that of the flow
    they pass; ``throttled`` (2, levels) holds each level's valve-outlet pressure (Pa) and the
    slope of its nozzle group's flow with that pressure (kg/s per Pa): warm start in, solution
    out, each pressure passing its flow to the relative ``throttle_tolerance``.
    """
    flow_coefficient, friction_coefficient = params[0], params[1]
    # every wide-open group expands alike: from the valve outlet (p_valve, h0) to p1
    open_flux = cs.nozzle_discharge_coefficient * flow_coefficient * nozzle_flow_function(
        p1 / p_valve, KAPPA_SUPERHEATED) * p_valve / math.sqrt(pv_valve)
    h_open, drop_open = _nozzle_group_expansion(cs, tables, cell_1, coordinate_1, h0, s_valve,
                                                friction_coefficient)
    remaining = flow
    mixed = 0.0
    available = 0.0
    arc = 0.0
    segments = 0.0
    part_open = 0.0
    demand = _valve_demand(cs, open_flux, flow) if cs.valve_overlap > 0.0 else 0.0
    for level in range(cs.level_area.size):
        if remaining <= 0.0:
            throttled[0, level] = p1
            continue
        area = flow_coefficient * cs.nozzle_discharge_coefficient * cs.level_area[level]
        wide_open = open_flux * cs.level_area[level]
        # the flow this level's valve is asked to pass: what is left (sequential opening), or
        # its share of the overlapping lift schedule
        target = remaining
        if cs.valve_overlap > 0.0:
            target = min(remaining, wide_open * _level_share(cs, level, demand))
            if target <= 1e-12 * flow:  # shut, or round-off left by the demand's bisection
                throttled[0, level] = p1
                continue
        if wide_open <= target * (1.0 + 1e-12):
            level_flow, p_level, h_level, drop = wide_open, p_valve, h_open, drop_open
        else:
            level_flow = target
            part_open = level + 1.0
            p_level, throttled[1, level] = _throttled_pressure(
                target, area, p1, p_valve, wide_open, h0, tables, throttled[0, level],
                throttled[1, level], throttle_tolerance)
            h_level, drop = _nozzle_group_expansion(
                cs, tables, cell_1, coordinate_1, h0, ph_property(tables, PH_S, p_level, h0),
                friction_coefficient)
        throttled[0, level] = p_level
        remaining -= level_flow
        # a part-open valve's arc counts in proportion to its flow, so the admission losses
        # change continuously as a valve opens (a barely open group is almost an idle arc)
        opening = level_flow / wide_open
        arc += cs.level_arc[level] * opening
        segments += cs.level_segments[level] * opening
        mixed += level_flow * h_level
        available += level_flow * drop
    # over capacity: the outlet state is that of the wide-open valves' flow, so that an
    # unconverged sweep can go on; the caller decides on the converged pressures
    passed = flow
    out[0] = STATUS_OK
    if remaining > 1e-9 * flow:
        passed = flow - remaining
        out[0] = STATUS_OVER_CAPACITY
    mean_drop = available / passed
    x_a = cs.blade_speed / math.sqrt(2.0 * mean_drop)
    sector_end = (cs.admission_loss_multiplier * SECTOR_END_CONSTANT * segments
                  / (arc * cs.diameter) * x_a)
    h_mix = mixed / passed
    density = 1.0 / ph_property_at(tables, PH_V, cell_1, coordinate_1, p1, h_mix)
    windage = cs.admission_loss_multiplier * windage_power(cs.windage_area, 1.0 - arc, density,
                                                           cs.blade_speed)
    disc = DISC_FRICTION_CONSTANT * density * cs.blade_speed**3 * cs.diameter**2
    loss_power = sector_end * available + friction_coefficient * (windage + disc)
    h1 = h_mix + loss_power / passed
    out[1] = passed * (h0 - h1)
    out[2] = (h0 - h1) / mean_drop
    out[3] = arc
    out[4] = part_open
    return h1


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _shifted_control_stage(h1, shift, flow, out):
    """Control-stage outlet enthalpy (J/kg) at p1 + ``shift`` (Pa) from its state at p1.

    ``h1`` and ``out`` (as :func:`_control_stage` left them, all flow passed) belong to p1;
    ``out[5]`` holds the measured slope dh1/dp1 (m³/kg; ≈ η·v along the expansion, dh = η·v·dp:
    Dixon & Hall, *Fluid Mechanics and Thermodynamics of Turbomachinery*, ch. 2). The outlet
    moves by slope·shift, the stage's power by −flow times that; efficiency and arc stay.
    """
    dh = out[5] * shift
    out[1] -= flow * dh
    return h1 + dh


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _setup_group_metal(metal, group, flow, htc_multiplier, metal_old, pivot, rhs, surface,
                       properties):
    """Steam-side coefficients and the implicit metal step of one group; its steam T (K).

    Run once per sample (first sweep) with the group's mean steam ``properties`` (PH_*): sets
    row ``surface[chain]`` of the group's casing and rotor chains to [steam-side conductance W/K,
    base K, response] of the new surface temperature base + response·T_steam, so that later
    sweeps only evaluate :func:`_group_heat`. The caller looks the properties up: every array
    handed to a compiled call costs reference counting, and the tables are five.
    """
    temperature = properties[PH_T]
    v, mu, k, cp = properties[PH_V], properties[PH_MU], properties[PH_K], properties[PH_CP]
    axial = flow * v / metal.flow_area[group]
    relative = rotor_relative_velocity(axial, metal.rotor_speed[group])
    diameter = metal.hydraulic_diameter[group]
    log_re_per_velocity, log_prandtl = dittus_boelter_logs(diameter, v, mu, k, cp)
    for body in range(2):
        velocity = axial if body == CASING else relative
        chain = 2 * group + body
        steam_is_heated = metal_old[chain, 0] > temperature
        htc = htc_multiplier * dittus_boelter_from_logs(velocity, log_re_per_velocity,
                                                        log_prandtl, k, diameter,
                                                        steam_is_heated)
        conductance = metal.area[chain] / (1.0 / htc + metal.half_cell_resistance[chain])
        surface[chain, 0] = conductance
        surface[chain, 1], surface[chain, 2] = surface_response(conductance, pivot[chain, 0],
                                                                rhs[chain, 0])
    return temperature


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _group_heat(group, temperature, surface):
    """Heat (W) the casing and rotor of ``group`` take from steam at ``temperature`` (K)."""
    heat = 0.0
    for chain in range(2 * group, 2 * group + 2):
        heat += surface_heat(surface[chain, 0], surface[chain, 1], surface[chain, 2], temperature)
    return heat




@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _backward_sweep(stage_capacity, extraction_fraction, leak_origin, flow, flow_coefficient,
                    p_exhaust, inlet_pv, pressures, leak_flow):
    """Stage inlet pressures (Pa) by Stodola's law from the exhaust, with inlet p·v (J/kg).

    ``stage_capacity``, ``extraction_fraction`` and ``leak_origin`` are the
    :class:`KernelConstants` fields (only these: a compiled call counts references to every
    array it is handed, and the whole constants hold ~30). ``leak_flow`` (kg/s per leakage) is
    taken off every stage after the leakage's origin.
    """
    n = stage_capacity.size
    pressures[n] = p_exhaust
    flow_fraction = 1.0 - extraction_fraction.sum()
    leaks = leak_origin.size
    for i in range(n - 1, -1, -1):
        flow_fraction += extraction_fraction[i]  # stage i carries what is bled after it
        stage_flow = flow * flow_fraction
        for j in range(leaks):
            if leak_origin[j] <= i:
                stage_flow -= leak_flow[j]
        pressures[i] = stodola_inlet_pressure(stage_flow, flow_coefficient * stage_capacity[i],
                                              pressures[i + 1], inlet_pv[i])


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def labyrinth_flow(capacity: float, upstream_pressure: float, upstream_pv: float,
                   downstream_pressure: float) -> float:
    """Flow (kg/s) through a labyrinth seal of fixed geometry, ``capacity`` in m².

    m = C·sqrt((p_up² − p_down²)/(p_up·v_up)): the many-throttle limit of Martin's labyrinth
    formula (Martin, Engineering 85 (1908); Egli, Trans. ASME 57 (1935) 115–122; Traupel,
    *Thermische Turbomaschinen* Bd. 1, labyrinth seals), the same form as Stodola's cone law;
    C (flow coefficient × gap area / sqrt(teeth)) is fixed by the seal's geometry. No flow
    when the downstream pressure is the higher.
    """
    head = upstream_pressure * upstream_pressure - downstream_pressure * downstream_pressure
    return capacity * math.sqrt(head / upstream_pv) if head > 0.0 else 0.0


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _polytropic_pv(reference, pressures, inlet_pv, first_pv):
    """Carry the stage-inlet p·v (J/kg) from the ``reference`` pressures to ``pressures`` (Pa).

    ``first_pv`` is the new p·v at the control-stage outlet (stage 1 inlet). Along a polytropic
    expansion p·v^n = const, p·v ∝ p^m with m = (n − 1)/n (Dixon & Hall, ch. 2; for steam the
    real-gas factor and the efficiency enter m); m is measured over the whole path on the
    reference state, so inlet i moves with the first inlet's p·v and with the change ε of its
    pressure ratio to the first inlet: (1 + ε)^m, to second order (ε ~ 1e-3). Only the number
    of sweeps depends on this estimate, never the converged state.
    """
    last = inlet_pv.size - 1
    exponent = math.log(inlet_pv[last] / inlet_pv[0]) / math.log(reference[last] / reference[0])
    scale = first_pv / inlet_pv[0]
    for i in range(1, last + 1):
        change = (pressures[i] * reference[0]) / (pressures[0] * reference[i]) - 1.0
        inlet_pv[i] *= scale * (1.0 + exponent * change * (1.0 + 0.5 * (exponent - 1.0) * change))
    inlet_pv[0] = first_pv


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _casing_thermocouple(sensor_group, sensor_node, sensor_weight, half_cell_resistance, area,
                         metal, surface, group_temperature):
    """Casing metal temperature (K) at the thermocouple's depth, linear between neighbours.

    The sensor's place and the chains' ``half_cell_resistance`` (m²·K/W) and ``area`` (m²) as
    in :class:`KernelConstants` (only these: a compiled call counts references to every array
    it is handed). Node j's temperature belongs to its cell centre, (j + ½)·Δx under the bore;
    above node 0 the neighbour is the bore surface, where the steam-side flux
    q = G·(T_steam − T_0) gives T_wall = T_0 + q·r_half/A. Interpolating at a physical depth
    keeps the reading independent of the node count (second order in Δx).
    """
    chain = 2 * sensor_group + CASING
    j = sensor_node
    if j >= 0:
        return metal[chain, j] + sensor_weight * (metal[chain, j + 1] - metal[chain, j])
    node_0 = metal[chain, 0]
    flux = surface[chain, 0] * (group_temperature[sensor_group] - node_0)
    wall = node_0 + flux * half_cell_resistance[chain] / area[chain]
    return wall + sensor_weight * (node_0 - wall)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _metal_energy(capacity, outer_conductance, ambient_temperature, metal):
    """Heat content of all metal (J, from 0 K) and the lagging loss (W) of a metal state.

    ``capacity`` (J/K per node), ``outer_conductance`` (W/K per chain) and
    ``ambient_temperature`` (K) as in :class:`MetalConstants`. The content is summed in four
    interleaved partial sums: one running sum is a chain of dependent additions the processor
    cannot overlap (the order changes the sum by round-off only).
    """
    sum_0 = sum_1 = sum_2 = sum_3 = loss = 0.0
    chains, nodes = metal.shape
    for chain in range(chains):
        j = 0
        while j + 4 <= nodes:
            sum_0 += capacity[chain, j] * metal[chain, j]
            sum_1 += capacity[chain, j + 1] * metal[chain, j + 1]
            sum_2 += capacity[chain, j + 2] * metal[chain, j + 2]
            sum_3 += capacity[chain, j + 3] * metal[chain, j + 3]
            j += 4
        for rest in range(j, nodes):
            sum_0 += capacity[chain, rest] * metal[chain, rest]
        loss += outer_conductance[chain] * (metal[chain, nodes - 1] - ambient_temperature)
    return (sum_0 + sum_1) + (sum_2 + sum_3), loss


@njit(cache=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
def _commit_metal(conductance, pivot, rhs, surface, group_temperature, metal):
    """Metal temperatures (K) at the end of the step, from the converged steam temperatures."""
    for chain in range(metal.shape[0]):
        metal[chain, 0] = surface[chain, 1] + surface[chain, 2] * group_temperature[chain // 2]
    finish_chains(conductance, pivot, rhs, metal)


INLET_ROWS = 4  # rows of :func:`inlet_states`' array


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def inlet_states(tables, valve_pressure_drop, design_flow, reynolds_exponent, p0, t0, flow,
                 p_exhaust, inlet):
    """What each sample's solve needs of its inputs alone, whatever the parameters: fills
    ``inlet`` (:data:`INLET_ROWS`, samples) with the main steam's enthalpy h0 (J/kg), its
    entropy (J/(kg·K)) and p·v (J/kg) after the wide-open valves (at p0·(1 −
    ``valve_pressure_drop``)), and the Reynolds factor's excess (m/m_design)^(−n) − 1 of the
    stage losses (see :func:`run_kernel`); h0 NaN where the inputs leave the tables (the
    kernel then reports :data:`STATUS_OUT_OF_TABLES`).

    A calibration runs one series thousands of times: computed once per series
    (``FullOrderModel``), these look-ups and powers leave the time loop.
    """
    for k in range(p0.size):
        inlet[0, k] = math.nan
        if not pressure_in_range(tables, p0[k]) or not pressure_in_range(tables, p_exhaust[k]):
            continue
        cell_0, coordinate_0 = locate_pressure(tables, p0[k])
        h0 = enthalpy_pt_at(tables, cell_0, coordinate_0, t0[k])
        if not 0.0 <= ph_domain_position_at(tables, cell_0, coordinate_0, h0) <= 1.0:
            continue
        inlet[0, k] = h0
        cell_v, coordinate_v = locate_pressure(tables, p0[k] * (1.0 - valve_pressure_drop))
        inlet[1, k], inlet[2, k] = entropy_and_pv_at(tables, cell_v, coordinate_v, h0)
        inlet[3, k] = (flow[k] / design_flow) ** -reynolds_exponent - 1.0


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def run_kernel(c, tables, time_step, p0, t0, flow, p_exhaust, inlet, params, tolerance,
               pressures, enthalpies, metal, results, status, stage_pressures,
               stage_temperatures, throttled, cs_out, leak_flow, inlet_pv, previous, resume):
    """Simulate a series; the first sample starts from steady metal (equilibrium), or, with
    ``resume``, continues the series whose state the carried arrays hold.

    ``inlet``: the series' :func:`inlet_states`. ``params`` (rows, 3): flow, friction and
    heat-transfer coefficients, one row for the whole
    series or one per sample; ``tolerance`` (relative pressure, J/kg) bounds each sample's
    estimated convergence error. ``pressures``/``enthalpies`` (stages + 1) carry the warm start
    in and the last solution out; ``metal`` (chains, nodes) the metal temperatures (K), chain
    2·group + CASING/ROTOR. Fills ``results`` (samples × N_RESULTS), ``status`` (samples,), and,
    when they have rows, the per-stage outlet pressures and temperatures (samples × stages + 1).
    Stops at the first failed sample.

    The state a later call continues from (``resume``; ``time_step[0]`` then the seconds since
    the last sample) is carried in and out by ``pressures``, ``enthalpies`` and ``metal`` and:
    ``throttled`` (2, valve levels: valve-outlet pressure, flow slope), ``cs_out`` (7: the
    control stage's last outputs; [5], [6] the measured dh1/dp1 and its valve level),
    ``leak_flow`` (leakages), ``inlet_pv`` (stages: the last sweep's p·v) and ``previous`` (4:
    the last sample's p0, t0, flow, p_exhaust). Without ``resume`` they are initialised here.
    """
    n_samples = p0.size
    chains = metal.shape[0]
    surface, pivot, rhs = np.zeros((chains, 3)), np.zeros(metal.shape), np.zeros(metal.shape)
    group_temperature = np.zeros(chains // 2)
    factored_inverse_dt = math.nan
    accepted = np.empty(pressures.size)
    properties = np.empty(6)
    log_pressure, coordinate = np.empty(pressures.size), np.empty(pressures.size)
    cell = np.zeros(pressures.size, dtype=np.int64)
    detail = stage_pressures.shape[0] == n_samples
    if not resume:
        throttled[0, :] = p0[0]
        throttled[1, :] = 0.0
        cs_out[:] = 0.0
        leak_flow[:] = 0.0
        for i in range(inlet_pv.size):
            inlet_pv[i] = pressures[i] * ph_property(tables, PH_V, pressures[i], enthalpies[i])
    current = params[0].copy()
    varying = params.shape[0] > 1
    n = c.stage_capacity.size
    control, metal_constants = c.control, c.metal
    leaks = c.leak_origin.size
    # the arrays the loop hands to compiled calls, taken out of the constants once: an array
    # taken out of a tuple inside the loop is reference-counted at every pass
    stage_capacity, extraction_fraction, leak_origin = (c.stage_capacity, c.extraction_fraction,
                                                         c.leak_origin)
    capacity, conductance = metal_constants.capacity, metal_constants.conductance
    outer_conductance = metal_constants.outer_conductance
    before = np.empty_like(metal)  # the steady start's metal before a repeat
    for k in range(n_samples):
        if varying:
            for j in range(current.size):
                current[j] = params[k, j]
        h0 = inlet[0, k]
        if math.isnan(h0):
            status[k] = STATUS_OUT_OF_TABLES
            return k
        # the first sample is steady (infinite step); the chains are factored anew only when the
        # step length changes
        steady = k == 0 and not resume
        inverse_dt = 0.0 if steady else 1.0 / time_step[k]
        if inverse_dt != factored_inverse_dt:
            for chain in range(chains):
                factor_chain(chain, capacity, conductance, outer_conductance[chain], inverse_dt,
                             pivot)
            factored_inverse_dt = inverse_dt
        # the sample's solve (steps 0–4 of the module docstring), written out here rather than
        # called: a compiled call, even one numba inlines, counts references to every array it
        # is handed (~60: the constants, the tables, the carried state) at entry and exit,
        # ~15 % of a window-run (2026-11-27)
        if steady:
            # steady start: repeat the infinite-step (steady) metal solution to equilibrium,
            # with sweeps converged 10⁶× tighter so that a hold continues without drift
            pressure_tolerance = min(tolerance[0], max(tolerance[0] * 1e-6, START_FLOOR[0]))
            enthalpy_tolerance = min(tolerance[1], max(tolerance[1] * 1e-6, START_FLOOR[1]))
            repeats, predict = 50, True
        else:
            if k == 0:  # continuing: against the last sample of the previous call
                predict = (p0[0] != previous[0] or t0[0] != previous[1]
                           or flow[0] != previous[2] or p_exhaust[0] != previous[3] or varying)
            else:
                predict = (p0[k] != p0[k - 1] or t0[k] != t0[k - 1] or flow[k] != flow[k - 1]
                           or p_exhaust[k] != p_exhaust[k - 1] or varying)
            pressure_tolerance, enthalpy_tolerance = tolerance[0], tolerance[1]
            repeats = 1
        sample_flow, exhaust_pressure = flow[k], p_exhaust[k]
        code = STATUS_OK
        for _repeat in range(repeats):
            if steady:
                before[:] = metal
            code = STATUS_NO_CONVERGENCE
            prepare_chains(metal, capacity, conductance, outer_conductance,
                           metal_constants.ambient_temperature, inverse_dt, pivot, rhs)
            flow_coefficient = current[0]
            throttle_tolerance = THROTTLE_TOLERANCE * min(
                enthalpy_tolerance / ENTHALPY_TOLERANCE, 1.0)
            # the state after the wide-open valves depends on the inputs only
            p_valve = p0[k] * (1.0 - control.valve_pressure_drop)
            s_valve, pv_valve = inlet[1, k], inlet[2, k]
            # 0. carry the previous sample's p·v to this sample's inputs
            predicted_p1 = math.nan  # the control stage evaluated there, reused by sweep 1
            predicted_h1 = predicted_level = 0.0
            for _pass in range(PREDICTOR_PASSES if predict else 0):
                accepted[:] = pressures  # the pressures inlet_pv belongs to
                _backward_sweep(stage_capacity, extraction_fraction, leak_origin, sample_flow,
                                flow_coefficient, exhaust_pressure, inlet_pv, pressures,
                                leak_flow)
                if not (pressures[0] < p_valve and pressure_in_range(tables, pressures[0])):
                    break  # the sweeps below report it
                cell_1, coordinate_1 = locate_pressure(tables, pressures[0])
                h1 = _control_stage(control, tables, sample_flow, p_valve, s_valve, pv_valve, h0,
                                    pressures[0], cell_1, coordinate_1, current, throttled,
                                    cs_out, throttle_tolerance)
                v1, position = ph_property_and_position_at(tables, PH_V, cell_1, coordinate_1,
                                                           pressures[0], h1)
                if cs_out[0] != STATUS_OK or not 0.0 <= position <= 1.0:
                    break
                _polytropic_pv(accepted, pressures, inlet_pv, pressures[0] * v1)
                if cs_out[4] > 0.0:  # a valve part open: the flow is passed with a margin
                    predicted_p1, predicted_h1, predicted_level = pressures[0], h1, cs_out[4]
            previous_p1 = pressures[0]
            stage_flow = power = heat_total = extraction_energy = 0.0  # of the last full sweep
            rejoin_flow = rejoin_energy = outside_energy = 0.0  # leakages, of the last full sweep
            over_capacity = False
            for iteration in range(MAX_SWEEPS + 1):
                # 1. backward Stodola sweep; from the second on it also probes the previous
                # sweep's state
                accepted[:] = pressures
                _backward_sweep(stage_capacity, extraction_fraction, leak_origin, sample_flow,
                                flow_coefficient, exhaust_pressure, inlet_pv, pressures,
                                leak_flow)
                change_p = abs(pressures[0] - previous_p1) / pressures[0]
                change_max = 0.0
                for i in range(n):
                    change_max = max(change_max, abs(pressures[i] - accepted[i]) / pressures[i])
                if iteration > 0 and change_p <= pressure_tolerance and (
                        inlet_pv[n - 1] * change_max <= enthalpy_tolerance):
                    pressures[:] = accepted  # the state of the last full sweep
                    if over_capacity:
                        code = STATUS_OVER_CAPACITY
                        break
                    # superheat only falls along an HP expansion: checking the control-stage
                    # outlet and the exhaust keeps every stage within the superheated tables;
                    # both pressures are where the last forward sweep located them
                    temperature_1, position = ph_property_and_position_at(
                        tables, PH_T, cell[0], coordinate[0], pressures[0], enthalpies[0])
                    if not 0.0 <= position <= 1.0 or not 0.0 <= ph_domain_position_at(
                            tables, cell[n], coordinate[n], enthalpies[n]) <= 1.0:
                        code = STATUS_OUT_OF_TABLES
                        break
                    results[k, 0] = pressures[0]
                    results[k, 1] = temperature_1
                    h_exhaust = enthalpies[n]
                    if rejoin_flow > 0.0:  # the exhaust mixes the blading's outlet and leakages
                        h_exhaust = ((stage_flow * enthalpies[n] + rejoin_energy)
                                     / (stage_flow + rejoin_flow))
                    results[k, 2] = ph_property_at(tables, PH_T, cell[n], coordinate[n],
                                                   exhaust_pressure, h_exhaust)
                    _commit_metal(conductance, pivot, rhs, surface, group_temperature, metal)
                    results[k, 3] = _casing_thermocouple(
                        c.sensor_group, c.sensor_node, c.sensor_weight,
                        metal_constants.half_cell_resistance, metal_constants.area, metal,
                        surface, group_temperature)
                    results[k, 4] = power
                    results[k, 5] = heat_total
                    results[k, 6] = extraction_energy
                    results[k, 7] = stage_flow * enthalpies[n] + rejoin_energy
                    results[k, 8] = sample_flow * h0
                    results[k, 9] = cs_out[2]
                    results[k, 10] = cs_out[3]
                    results[k, 11] = iteration
                    results[k, 12], results[k, 13] = _metal_energy(
                        capacity, outer_conductance, metal_constants.ambient_temperature, metal)
                    results[k, 14] = outside_energy
                    results[k, 15] = 0.0
                    for j in range(leaks):
                        results[k, 15] += leak_flow[j]
                    code = STATUS_OK
                    break
                if iteration == MAX_SWEEPS:
                    break
                previous_p1 = pressures[0]
                if not pressures[0] < p_valve:
                    code = STATUS_PRESSURE_INVERSION
                    break
                if not pressure_in_range(tables, pressures[0]):
                    code = STATUS_OUT_OF_TABLES
                    break
                # every pressure of this sweep is located once (one logarithm), for all its
                # look-ups
                log_pressure[0] = math.log(pressures[0])
                cell[0], coordinate[0] = locate_log_pressure(tables, log_pressure[0])
                # 2. control stage; the first sweep reuses the predictor's when p1 moved little
                # since (same part-open valve as where its slope was measured); a full evaluation
                # after the predictor's measures that slope anew
                shift = pressures[0] - predicted_p1
                if iteration == 0 and cs_out[6] == predicted_level and (
                        abs(shift) * cs_out[5] <= REUSE_SHARE * enthalpy_tolerance):
                    h1 = _shifted_control_stage(predicted_h1, shift, sample_flow, cs_out)
                else:
                    h1 = _control_stage(control, tables, sample_flow, p_valve, s_valve, pv_valve,
                                        h0, pressures[0], cell[0], coordinate[0], current,
                                        throttled, cs_out, throttle_tolerance)
                    if iteration == 0 and cs_out[4] == predicted_level and shift != 0.0:
                        cs_out[5], cs_out[6] = (h1 - predicted_h1) / shift, predicted_level
                # over capacity at an unconverged p1 says nothing: from a rough start the first
                # sweeps probe a higher control-stage pressure than the converged one; decided at
                # acceptance
                over_capacity = cs_out[0] == STATUS_OVER_CAPACITY
                if iteration == 0:
                    position = heat_transfer_properties_at(tables, cell[0], coordinate[0],
                                                           pressures[0], h1, properties)
                else:
                    temperature, position = ph_property_and_position_at(
                        tables, PH_T, cell[0], coordinate[0], pressures[0], h1)
                if not 0.0 <= position <= 1.0:
                    code = STATUS_OUT_OF_TABLES
                    break
                heat_total = 0.0
                g = c.group_ending_at_stage[0]
                if iteration == 0:
                    temperature = _setup_group_metal(metal_constants, g, sample_flow, current[2],
                                                     metal, pivot, rhs, surface, properties)
                group_temperature[g] = temperature
                heat = _group_heat(g, temperature, surface)
                heat_total += heat
                enthalpies[0] = h1 - heat / sample_flow
                power = cs_out[1]
                # 3. forward sweep over the pressure stages; the Reynolds correction raises each
                # stage's loss 1 − η by the factor (m/m_design)^(−n), added as
                # (1 − η)·(factor − 1) so that n = 0 leaves η bit for bit
                reynolds_excess = inlet[3, k]
                stage_flow = sample_flow
                extraction_energy = 0.0
                rejoin_flow = rejoin_energy = outside_energy = 0.0
                for i in range(n):
                    log_pressure[i + 1] = math.log(pressures[i + 1])
                    inlet_pv[i], cell[i + 1], coordinate[i + 1], isentropic = (
                        isentropic_step_at(tables, cell[i], coordinate[i], enthalpies[i],
                                           log_pressure[i + 1]))
                    for j in range(leaks):  # leakages leaving here, at this sweep's state
                        if c.leak_origin[j] == i:
                            leak = labyrinth_flow(c.leak_capacity[j], pressures[i], inlet_pv[i],
                                                  c.leak_sink_ratio[j] * exhaust_pressure)
                            leak_flow[j] = leak
                            stage_flow -= leak
                            if c.leak_rejoins[j]:
                                rejoin_flow += leak
                                rejoin_energy += leak * enthalpies[i]
                            else:
                                outside_energy += leak * enthalpies[i]
                    drop = enthalpies[i] - isentropic
                    velocity_ratio = c.stage_blade_speed[i] / math.sqrt(2.0 * drop)
                    efficiency = stage_efficiency(velocity_ratio, c.stage_optimum_ratio[i],
                                                  c.stage_peak_efficiency[i],
                                                  current[1] * c.stage_friction_loss[i])
                    efficiency = max(efficiency - (1.0 - efficiency) * reynolds_excess, 0.0)
                    # tip leakage bypasses the blading and mixes back after it (Traupel, Bd. 1, §8)
                    if c.stage_tip_passing[i] != 1.0:
                        efficiency *= c.stage_tip_passing[i]
                    h_out = enthalpies[i] - efficiency * drop
                    power += stage_flow * efficiency * drop
                    g = c.group_ending_at_stage[i + 1]
                    if g >= 0:
                        first = c.group_first_stage[g]
                        # the geometric mean pressure, located at the mean of the logarithms
                        p_mean = math.sqrt(pressures[first - 1] * pressures[i + 1])
                        cell_mean, coordinate_mean = locate_log_pressure(
                            tables, 0.5 * (log_pressure[first - 1] + log_pressure[i + 1]))
                        h_mean = 0.5 * (enthalpies[first - 1] + h_out)
                        if iteration == 0:
                            heat_transfer_properties_at(tables, cell_mean, coordinate_mean, p_mean,
                                                        h_mean, properties)
                            temperature = _setup_group_metal(
                                metal_constants, g, stage_flow, current[2], metal, pivot, rhs,
                                surface, properties)
                        else:
                            temperature = ph_property_at(tables, PH_T, cell_mean, coordinate_mean,
                                                         p_mean, h_mean)
                        group_temperature[g] = temperature
                        heat = _group_heat(g, temperature, surface)
                        heat_total += heat
                        h_out -= heat / stage_flow
                    enthalpies[i + 1] = h_out
                    if c.extraction_fraction[i] > 0.0:
                        bleed = sample_flow * c.extraction_fraction[i]
                        extraction_energy += bleed * h_out
                        stage_flow -= bleed
            if code != STATUS_OK or not steady or np.abs(metal - before).max() < 1e-9:
                break
        status[k] = code
        if code != STATUS_OK:
            return k
        if detail:
            for i in range(pressures.size):
                stage_pressures[k, i] = pressures[i]
                stage_temperatures[k, i] = ph_property(tables, PH_T, pressures[i], enthalpies[i])
        previous[0], previous[1], previous[2], previous[3] = p0[k], t0[k], flow[k], p_exhaust[k]
    return n_samples
