"""IP stator rows ``ip1``…``ip9``: an engineering estimate, because the spec has no IP stages.

The turbine spec describes the HP section only. The nine IP stator (nozzle) rows are sized here
from the spec's cold-reheat state with stated assumptions, each with its source:

* hot-reheat pressure = cold-reheat pressure × (1 − 0.10): reheater and reheat piping lose about
  10 % of the cold-reheat pressure (Spencer, Cotton & Cannon 1963, ASME J. Eng. Power 85, the
  heat-balance assumptions; Cotton 1998 ch. 2);
* hot-reheat temperature = main-steam temperature (538/538 °C unit, GB/T 754-2007);
* IP exhaust (crossover) pressure 0.9 MPa, within the 0.8–1.1 MPa of 600 MW subcritical reheat
  heat balances (Cotton 1998 ch. 2);
* reheat flow = main-steam flow − the spec's HP bleeds − 7 % of main-steam flow for the HP
  heater fed from cold reheat (a typical bleed share of the top heaters, Cotton 1998 ch. 2);
* nine stages of equal isentropic drop at 90 % IP section efficiency (Cotton 1998 ch. 2 for the
  efficiency level of IP sections);
* the blading of the HP pressure stages carried over (spec: 30 % reaction, 16° stator exit angle
  from the wheel plane; velocity ratio u/c0 = 0.642 as in ``reference.toml``'s stage table);
* stator axial chord 50 mm (IP diaphragm nozzles of this class, 40–60 mm) and the pitch from
  Zweifel's Z = 0.8 (see :mod:`steamtwin.geometry.profile`);
* a constant root radius (the flow path flares outward, as in the spec's HP stages with their
  constant 0.86 m root diameter), set by the first stage, whose mean diameter follows from the
  velocity ratio; every stage repeats the first stage's velocity triangle at its mean radius;
* blade height from continuity at the stator exit, m·v = 2π·r_m·h·c1·sin α1 with
  r_m = r_root + h/2.

Stator sections use a mirrored tangential axis (y points against the rotation), so that
Pritchard's sign convention (outlet angle < 0) holds for nozzles as for rotor blades.
"""

from __future__ import annotations

import math

import numpy as np

from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.row_sizing import (
    IP_ROWS,
    ZWEIFEL,
    RowDesign,
    free_vortex_angles,
    section_from_angles,
)
from steamtwin.spec import TurbineSpec
from steamtwin.steam import if97

REHEAT_PRESSURE_LOSS = 0.10
CROSSOVER_PRESSURE = 0.9e6  # Pa
COLD_REHEAT_BLEED_SHARE = 0.07
IP_EFFICIENCY = 0.90
VELOCITY_RATIO = 0.642
STATOR_AXIAL_CHORD = 0.050  # m
IP_REACTION = 0.3
IP_STATOR_EXIT_ANGLE = math.radians(16.0)  # from the wheel plane


def ip_expansion(spec: TurbineSpec) -> dict[str, np.ndarray | float]:
    """States of the estimated IP expansion: per-stage inlet pressure/enthalpy, flow (SI)."""
    design = spec.design
    p_in = design.hp_exhaust_pressure * (1.0 - REHEAT_PRESSURE_LOSS)
    t_in = design.main_steam_temperature
    flow = (design.main_steam_flow - sum(e.design_flow for e in spec.extractions)
            - COLD_REHEAT_BLEED_SHARE * design.main_steam_flow)
    h_in = float(if97.enthalpy_pt(p_in, t_in))
    s_in = float(if97.entropy_pt(p_in, t_in))
    drop_total = h_in - float(if97.enthalpy_ps(CROSSOVER_PRESSURE, s_in))
    count = len(IP_ROWS)
    # stage pressures: equal isentropic drops of the stage-by-stage expansion line
    drop_stage = drop_total / count * 1.03  # reheat factor ≈ 1.03 (Dixon & Hall §2.6)
    pressures, enthalpies = [p_in], [h_in]
    for _ in range(count):
        p, h = pressures[-1], enthalpies[-1]
        s = float(if97.entropy_ph(p, h))
        h_is_out = h - drop_stage
        # pressure at which the isentrope reaches h_is_out
        lo, hi = CROSSOVER_PRESSURE * 0.5, p
        for _ in range(60):
            mid = math.sqrt(lo * hi)
            if float(if97.enthalpy_ps(mid, s)) > h_is_out:
                hi = mid
            else:
                lo = mid
        pressures.append(math.sqrt(lo * hi))
        enthalpies.append(h - IP_EFFICIENCY * drop_stage)
    return {"pressure": np.array(pressures), "enthalpy": np.array(enthalpies),
            "flow": flow, "stage_drop": drop_stage}


def _stator_exit_volume_flow(expansion: dict, k: int) -> float:
    """Volume flow (m³/s) at the exit of stator ``k``: (1 − Λ) of the stage drop spent there."""
    p_in, p_out = expansion["pressure"][k], expansion["pressure"][k + 1]
    h_exit = (expansion["enthalpy"][k]
              - (1.0 - IP_REACTION) * IP_EFFICIENCY * float(expansion["stage_drop"]))
    p_exit = p_out * (p_in / p_out) ** IP_REACTION  # reaction share of the pressure ratio
    return float(expansion["flow"]) * float(if97.specific_volume_ph(p_exit, h_exit))


def ip_row_design(spec: TurbineSpec, row: str) -> RowDesign:
    """Size IP stator row ``row`` (``ip1``…``ip9``) by the estimate in the module docstring."""
    if row not in IP_ROWS:
        raise GeometryError(f"unknown IP row {row!r}; known: {', '.join(IP_ROWS)}")
    k = IP_ROWS.index(row)
    expansion = ip_expansion(spec)
    omega = spec.design.rotational_speed
    c0 = math.sqrt(2.0 * float(expansion["stage_drop"]))
    alpha1 = IP_STATOR_EXIT_ANGLE
    c1 = VELOCITY_RATIO * c0 * 2.0 * (1.0 - IP_REACTION) / math.cos(alpha1)
    axial_velocity = c1 * math.sin(alpha1)
    first_mean_radius = VELOCITY_RATIO * c0 / omega
    volume_flows = [_stator_exit_volume_flow(expansion, j) for j in range(len(IP_ROWS))]
    first_height = volume_flows[0] / (2.0 * math.pi * first_mean_radius * axial_velocity)
    root_radius = first_mean_radius - 0.5 * first_height
    # Q = 2π (r_root + h/2) h c_a  ->  π c_a h² + 2π r_root c_a h − Q = 0
    a_coef, b_coef = math.pi * axial_velocity, 2.0 * math.pi * root_radius * axial_velocity
    height = (-b_coef + math.sqrt(b_coef**2 + 4.0 * a_coef * volume_flows[k])) / (2.0 * a_coef)
    radius = root_radius + 0.5 * height
    swirl_out = -c1 * math.cos(alpha1) * radius  # mirrored frame: swirl towards -y
    inlet, outlet = free_vortex_angles(radius, 0.0, axial_velocity, 0.0, swirl_out)
    # blade count from Zweifel's pitch for the chosen axial chord, rounded to an even number
    pitch = (ZWEIFEL * STATOR_AXIAL_CHORD
             / (2.0 * math.cos(outlet) ** 2 * (math.tan(inlet) - math.tan(outlet))))
    count = 2 * round(math.pi * radius / pitch)
    return RowDesign(
        row=row,
        kind="stator",
        mean_section=section_from_angles(radius, count, float(inlet), float(outlet),
                                         "reaction"),
        hub_radius=radius - 0.5 * height,
        tip_radius=radius + 0.5 * height,
        taper_ratio=1.0,  # diaphragm nozzles are not centrifugally loaded: prismatic
        axial_velocity=axial_velocity,
        inlet_swirl_radius=0.0,
        outlet_swirl_radius=swirl_out,
        angular_speed=0.0,
    )
