"""The full-order model's time loop, compiled with numba.

At each sample the steam path is algebraic (quasi-steady); only the metal carries state. The
loop therefore solves, sample by sample, warm-started from the previous sample:

1. a backward sweep of Stodola's law from the HP-exhaust pressure gives the stage pressures and
   the control-stage pressure (specific volumes from the previous iterate);
2. the control stage distributes the flow over the nozzle groups in valve order, throttling the
   group whose valve is part open, expands each group and mixes them (``steampath``);
3. a forward sweep expands the pressure stages; at the end of each stage group the steam gives
   heat to that group's casing and rotor (implicit-Euler conduction step, ``metal``), which is
   taken from the steam enthalpy there;
4. 1–3 repeat until the control-stage pressure and exhaust enthalpy stop changing; then the
   metal state is committed.

Heat given to the metal in a step is exactly what the implicit metal step stores or loses
through the lagging, so energy is conserved to round-off at every sample.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from steamtwin.model.metal import advance_chain, dittus_boelter_htc, rotor_relative_velocity
from steamtwin.model.steampath import (
    DISC_FRICTION_CONSTANT,
    KAPPA_SUPERHEATED,
    SECTOR_END_CONSTANT,
    WINDAGE_CONSTANT,
    nozzle_flow_function,
    stage_efficiency,
    stodola_inlet_pressure,
)
from steamtwin.steam.tables import (
    PH_CP,
    PH_K,
    PH_MU,
    PH_S,
    PH_T,
    PH_V,
    enthalpy_ps,
    enthalpy_pt,
    ph_domain_position,
    ph_property,
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
)
N_RESULTS = len(RESULT_COLUMNS)

# Convergence of the sweeps: relative control-stage pressure change and exhaust-enthalpy change
# (J/kg; 1e-3 J/kg is ~4e-7 K) between two sweeps.
PRESSURE_TOLERANCE = 1e-9
ENTHALPY_TOLERANCE = 1e-3

# Status codes per sample (0 = solved).
STATUS_OK = 0
STATUS_OVER_CAPACITY = 1  # flow exceeds what the wide-open valves pass
STATUS_OUT_OF_TABLES = 2  # a state left superheated steam / the property range
STATUS_NO_CONVERGENCE = 3
STATUS_PRESSURE_INVERSION = 4  # stage pressures reach the throttle pressure


class KernelConstants(NamedTuple):
    """Everything the kernel needs from the spec, derived once (SI units)."""

    rotational_speed: float  # rad/s
    valve_pressure_drop: float  # fraction of throttle pressure lost in wide-open valves
    nozzle_discharge_coefficient: float
    level_area: np.ndarray  # m², nozzle throat area of each valve-opening level
    level_arc: np.ndarray  # fraction of circumference of each level
    level_segments: np.ndarray  # number of nozzle groups (arc segments) of each level
    cs_blade_speed: float  # m/s
    cs_optimum_ratio: float
    cs_peak_efficiency: float
    cs_friction_loss: float
    cs_diameter: float  # m
    stage_capacity: np.ndarray  # m², Stodola constants
    stage_blade_speed: np.ndarray  # m/s
    stage_optimum_ratio: np.ndarray
    stage_peak_efficiency: np.ndarray
    stage_friction_loss: np.ndarray
    extraction_fraction: np.ndarray  # of throttle flow, bled after each stage
    efficiency_scale: float  # matches the design heat balance
    group_first_stage: np.ndarray  # int, 0 = control stage
    group_last_stage: np.ndarray  # int
    group_ending_at_stage: np.ndarray  # int per stage 0…n: the group that ends there, or -1
    group_hydraulic_diameter: np.ndarray  # m
    group_flow_area: np.ndarray  # m²
    group_rotor_speed: np.ndarray  # m/s, rotor surface speed
    metal_capacity: np.ndarray  # (groups, 2 bodies, nodes) J/K
    metal_conductance: np.ndarray  # (groups, 2, nodes-1) W/K
    metal_area: np.ndarray  # (groups, 2) m²
    metal_half_cell_resistance: np.ndarray  # (groups, 2) m²·K/W, surface to node 0
    metal_outer_conductance: np.ndarray  # (groups, 2) W/K to the surroundings
    ambient_temperature: float  # K
    sensor_group: int


@njit(cache=True, inline="always")
def _throttled_pressure(flow, area, p1, p_valve, h0, tables, guess):
    """Pressure after a part-open valve whose nozzle group must pass ``flow`` (kg/s).

    Safeguarded secant on p ∈ (p1, p_valve]: μA·Ψ(p1/p)·sqrt(p/v(p, h0)) = flow.
    """
    low, high = p1, p_valve
    f_high = area * nozzle_flow_function(p1 / high, KAPPA_SUPERHEATED) * math.sqrt(
        high / ph_property(tables, PH_V, high, h0)) - flow
    if f_high <= 0.0:
        return high
    f_low = -flow
    p = min(max(guess, low + 1e-6 * (high - low)), high)
    for _ in range(60):
        f = area * nozzle_flow_function(p1 / p, KAPPA_SUPERHEATED) * math.sqrt(
            p / ph_property(tables, PH_V, p, h0)) - flow
        if abs(f) <= 1e-10 * flow:
            return p
        if f > 0.0:
            high, f_high = p, f
        else:
            low, f_low = p, f
        p_next = high - f_high * (high - low) / (f_high - f_low)
        if not low < p_next < high or (high - low) < 1e-12 * high:
            p_next = 0.5 * (low + high)
        p = p_next
    return p


@njit(cache=True, inline="always")
def _control_stage(c, tables, flow, p_throttle, h0, p1, params, throttled, out):
    """Expand the nozzle groups to ``p1``; returns the mixed outlet enthalpy (J/kg).

    ``out`` receives [status, power W, efficiency, active arc]; ``throttled`` holds each level's
    valve-outlet pressure (warm start in, solution out).
    """
    flow_coefficient, friction_coefficient = params[0], params[1]
    p_valve = p_throttle * (1.0 - c.valve_pressure_drop)
    v_valve = ph_property(tables, PH_V, p_valve, h0)
    remaining = flow
    mixed = 0.0
    available = 0.0
    arc = 0.0
    segments = 0.0
    for level in range(c.level_area.size):
        area = flow_coefficient * c.nozzle_discharge_coefficient * c.level_area[level]
        if remaining <= 0.0:
            throttled[level] = p1
            continue
        wide_open = area * nozzle_flow_function(p1 / p_valve, KAPPA_SUPERHEATED) * math.sqrt(
            p_valve / v_valve)
        if wide_open <= remaining * (1.0 + 1e-12):
            level_flow, p_level = wide_open, p_valve
        else:
            level_flow = remaining
            p_level = _throttled_pressure(remaining, area, p1, p_valve, h0, tables,
                                          throttled[level])
        throttled[level] = p_level
        remaining -= level_flow
        # a part-open valve's arc counts in proportion to its flow, so the admission losses
        # change continuously as a valve opens (a barely open group is almost an idle arc)
        opening = level_flow / wide_open
        arc += c.level_arc[level] * opening
        segments += c.level_segments[level] * opening
        s_level = ph_property(tables, PH_S, p_level, h0)
        drop = max(h0 - enthalpy_ps(tables, p1, s_level), 0.0)
        velocity_ratio = c.cs_blade_speed / math.sqrt(2.0 * drop) if drop > 0.0 else 1e3
        efficiency = stage_efficiency(velocity_ratio, c.cs_optimum_ratio,
                                      c.efficiency_scale * c.cs_peak_efficiency,
                                      friction_coefficient * c.cs_friction_loss)
        mixed += level_flow * (h0 - efficiency * drop)
        available += level_flow * drop
    if remaining > 1e-9 * flow:
        out[0] = STATUS_OVER_CAPACITY
        return h0
    mean_drop = available / flow
    x_a = c.cs_blade_speed / math.sqrt(2.0 * mean_drop)
    windage = WINDAGE_CONSTANT * (1.0 - arc) / arc * x_a**3
    sector_end = SECTOR_END_CONSTANT * segments / (arc * c.cs_diameter) * x_a
    h_mix = mixed / flow
    density = 1.0 / ph_property(tables, PH_V, p1, h_mix)
    disc = DISC_FRICTION_CONSTANT * density * c.cs_blade_speed**3 * c.cs_diameter**2
    loss_power = (friction_coefficient * windage + sector_end) * available \
        + friction_coefficient * disc
    h1 = h_mix + loss_power / flow
    out[0] = STATUS_OK
    out[1] = flow * (h0 - h1)
    out[2] = (h0 - h1) / mean_drop
    out[3] = arc
    return h1


@njit(cache=True, inline="always")
def _group_heat(c, tables, group, p_mean, h_mean, flow, params, htc, first_iteration,
                metal_old, metal_new, dt, scratch_a, scratch_b):
    """Advance the casing and rotor of ``group`` one step; returns heat from the steam, W."""
    temperature = ph_property(tables, PH_T, p_mean, h_mean)
    if first_iteration:
        v = ph_property(tables, PH_V, p_mean, h_mean)
        mu = ph_property(tables, PH_MU, p_mean, h_mean)
        k = ph_property(tables, PH_K, p_mean, h_mean)
        cp = ph_property(tables, PH_CP, p_mean, h_mean)
        axial = flow * v / c.group_flow_area[group]
        d_h = c.group_hydraulic_diameter[group]
        htc[group, CASING] = params[2] * dittus_boelter_htc(axial, d_h, v, mu, k, cp)
        relative = rotor_relative_velocity(axial, c.group_rotor_speed[group])
        htc[group, ROTOR] = params[2] * dittus_boelter_htc(relative, d_h, v, mu, k, cp)
    heat = 0.0
    for body in range(2):
        surface = c.metal_area[group, body] / (
            1.0 / htc[group, body] + c.metal_half_cell_resistance[group, body])
        heat += advance_chain(metal_old[group, body], metal_new[group, body],
                              c.metal_capacity[group, body], c.metal_conductance[group, body],
                              surface, c.metal_outer_conductance[group, body], temperature,
                              c.ambient_temperature, dt, scratch_a, scratch_b)
    return heat


@njit(cache=True)
def _solve_sample(c, tables, p0, h0, flow, p_exhaust, params, dt, pressures, enthalpies,
                  inlet_pv, throttled, metal_old, metal_new, htc, scratch_a, scratch_b, cs_out,
                  result, max_iter):
    """Solve one sample in place; returns a status code."""
    n = c.stage_capacity.size
    flow_coefficient = params[0]
    previous_p1 = pressures[0]  # the warm start: unchanged inputs converge in one sweep
    previous_h_exhaust = enthalpies[n]
    for iteration in range(max_iter):
        # 1. backward Stodola sweep
        pressures[n] = p_exhaust
        flow_fraction = 1.0 - c.extraction_fraction.sum()
        for i in range(n - 1, -1, -1):
            flow_fraction += c.extraction_fraction[i]  # stage i carries what is bled after it
            stage_flow = flow * flow_fraction
            pressures[i] = stodola_inlet_pressure(
                stage_flow, flow_coefficient * c.stage_capacity[i], pressures[i + 1], inlet_pv[i])
        if not pressures[0] < p0 * (1.0 - c.valve_pressure_drop):
            return STATUS_PRESSURE_INVERSION
        if not pressure_in_range(tables, pressures[0]):
            return STATUS_OUT_OF_TABLES
        # 2. control stage
        h1 = _control_stage(c, tables, flow, p0, h0, pressures[0], params, throttled, cs_out)
        if cs_out[0] != STATUS_OK:
            return int(cs_out[0])
        heat_total = 0.0
        g = c.group_ending_at_stage[0]
        heat = _group_heat(c, tables, g, pressures[0], h1, flow, params, htc, iteration == 0,
                           metal_old, metal_new, dt, scratch_a, scratch_b)
        heat_total += heat
        enthalpies[0] = h1 - heat / flow
        power = cs_out[1]
        # 3. forward sweep over the pressure stages
        stage_flow = flow
        extraction_energy = 0.0
        for i in range(n):
            s_in = ph_property(tables, PH_S, pressures[i], enthalpies[i])
            inlet_pv[i] = pressures[i] * ph_property(tables, PH_V, pressures[i], enthalpies[i])
            drop = enthalpies[i] - enthalpy_ps(tables, pressures[i + 1], s_in)
            velocity_ratio = c.stage_blade_speed[i] / math.sqrt(2.0 * drop)
            efficiency = stage_efficiency(velocity_ratio, c.stage_optimum_ratio[i],
                                          c.efficiency_scale * c.stage_peak_efficiency[i],
                                          params[1] * c.stage_friction_loss[i])
            h_out = enthalpies[i] - efficiency * drop
            power += stage_flow * efficiency * drop
            g = c.group_ending_at_stage[i + 1]
            if g >= 0:
                first = c.group_first_stage[g]
                p_mean = math.sqrt(pressures[first - 1] * pressures[i + 1])
                h_mean = 0.5 * (enthalpies[first - 1] + h_out)
                heat = _group_heat(c, tables, g, p_mean, h_mean, stage_flow, params, htc,
                                   iteration == 0, metal_old, metal_new, dt, scratch_a,
                                   scratch_b)
                heat_total += heat
                h_out -= heat / stage_flow
            enthalpies[i + 1] = h_out
            if c.extraction_fraction[i] > 0.0:
                bleed = flow * c.extraction_fraction[i]
                extraction_energy += bleed * h_out
                stage_flow -= bleed
        converged = (abs(pressures[0] - previous_p1) <= PRESSURE_TOLERANCE * pressures[0]
                     and abs(enthalpies[n] - previous_h_exhaust) <= ENTHALPY_TOLERANCE)
        previous_p1, previous_h_exhaust = pressures[0], enthalpies[n]
        if converged:
            for i in range(n + 1):  # every stage outlet still superheated, within the tables
                if not 0.0 <= ph_domain_position(tables, pressures[i], enthalpies[i]) <= 1.0:
                    return STATUS_OUT_OF_TABLES
            result[0] = pressures[0]
            result[1] = ph_property(tables, PH_T, pressures[0], enthalpies[0])
            result[2] = ph_property(tables, PH_T, p_exhaust, enthalpies[n])
            result[3] = metal_new[c.sensor_group, CASING, 0]
            result[4] = power
            result[5] = heat_total
            result[6] = extraction_energy
            result[7] = stage_flow * enthalpies[n]
            result[8] = flow * h0
            result[9] = cs_out[2]
            result[10] = cs_out[3]
            result[11] = iteration + 1
            return STATUS_OK
    return STATUS_NO_CONVERGENCE


@njit(cache=True)
def run_kernel(c, tables, time_step, p0, t0, flow, p_exhaust, params, pressures, enthalpies,
               metal, results, status, stage_pressures, stage_temperatures):
    """Simulate a series; the first sample starts from steady metal (equilibrium).

    ``pressures``/``enthalpies`` (stages + 1) carry the warm start in and the last solution out;
    ``metal`` (groups, 2, nodes) the metal temperatures (K). Fills ``results`` (samples ×
    N_RESULTS), ``status`` (samples,), and, when they have rows, the per-stage outlet pressures
    and temperatures (samples × stages + 1). Stops at the first failed sample.
    """
    n_samples = p0.size
    groups, bodies, nodes = metal.shape
    metal_new = metal.copy()
    htc = np.zeros((groups, bodies))
    throttled = np.empty(c.level_area.size)
    throttled[:] = p0[0]
    scratch_a = np.empty(nodes)
    scratch_b = np.empty(nodes)
    cs_out = np.zeros(4)
    detail = stage_pressures.shape[0] == n_samples
    inlet_pv = np.empty(pressures.size - 1)
    for i in range(inlet_pv.size):
        inlet_pv[i] = pressures[i] * ph_property(tables, PH_V, pressures[i], enthalpies[i])
    for k in range(n_samples):
        if not pressure_in_range(tables, p0[k]) or not pressure_in_range(tables, p_exhaust[k]):
            status[k] = STATUS_OUT_OF_TABLES
            return k
        h0 = enthalpy_pt(tables, p0[k], t0[k])
        if not 0.0 <= ph_domain_position(tables, p0[k], h0) <= 1.0:
            status[k] = STATUS_OUT_OF_TABLES
            return k
        if k == 0:
            # steady start: iterate the infinite-step metal solution to equilibrium
            code = STATUS_OK
            for _ in range(50):
                code = _solve_sample(c, tables, p0[k], h0, flow[k], p_exhaust[k], params,
                                     math.inf, pressures, enthalpies, inlet_pv, throttled, metal,
                                     metal_new, htc, scratch_a, scratch_b, cs_out, results[k], 200)
                if code != STATUS_OK:
                    break
                change = np.abs(metal_new - metal).max()
                metal[:] = metal_new
                if change < 1e-9:
                    break
        else:
            code = _solve_sample(c, tables, p0[k], h0, flow[k], p_exhaust[k], params,
                                 time_step[k], pressures, enthalpies, inlet_pv, throttled, metal,
                                 metal_new, htc, scratch_a, scratch_b, cs_out, results[k], 200)
            metal[:] = metal_new
        status[k] = code
        if code != STATUS_OK:
            return k
        if detail:
            for i in range(pressures.size):
                stage_pressures[k, i] = pressures[i]
                stage_temperatures[k, i] = ph_property(tables, PH_T, pressures[i], enthalpies[i])
    return n_samples
