"""Stage physics of the quasi-steady steam path, as scalar numba functions.

Equations and their sources:

* Stage flow, Stodola's cone law (Stodola 1927; Cooke, J. Eng. Gas Turbines Power 107 (1985)
  596–606): m = φ·K·sqrt((p_in² − p_out²)/(p_in·v_in)); solved for p_in given p_out and the
  product p_in·v_in: p_in = sqrt(p_out² + (m/(φK))²·p_in·v_in).
* Nozzle-group flow of the control stage, Saint-Venant–Wantzel:
  m = μ·A·Ψ(π)·sqrt(p/v), Ψ(π) = sqrt(2κ/(κ−1)·(π^(2/κ) − π^((κ+1)/κ))), choked below
  π* = (2/(κ+1))^(κ/(κ−1)) = 0.546 for superheated steam with κ = 1.3 (Dixon & Hall 2014, ch. 3).
* Stage efficiency against velocity ratio ν = u/c0, c0 = sqrt(2Δh_s): the parabolic law
  η = η_peak·x·(2 − x), x = ν/ν_opt, exact for the ideal impulse blade (Dixon & Hall 2014, ch. 4),
  with ν_opt = cos α1 / (2·sqrt(1 − R)) (impulse limit cos α1/2, 50 % reaction cos α1/√2),
  less the friction loss share ζ_f scaled by the friction coefficient.
* Control-stage partial-admission and friction losses (Kang et al., *Principles of Steam
  Turbines*, China Electric Power Press, §3.5): idle-arc windage ζ_w = B_e·(1/e)·(1 − e)·x_a³ of
  the available energy E0, B_e = 0.15; sector-end loss ζ_s = C_e·(S_n/(e·d))·x_a, C_e = 0.012 m;
  disc friction P_df = 1e-3·K1·ρ·u³·d² W, K1 = 1.05. The windage is used as the power it stands
  for: with the flow through the admitting arc m/e = ρ·c1·π·d·l·sin α1 and c1 ≈ c_a = sqrt(2·E0),
  ζ_w·m·E0 = (B_e·π·sin α1/2)·(1 − e)·ρ·d·l·u³ — the idle blades pump whatever the flow, which
  keeps the loss finite as a valve closes (Stodola's windage form, ∝ ρ·u³·d·l·(1 − e)).
* Part-load laws of the spec's ``[part_load]`` table (fitted to a thermal kit by
  ``model.design_fit``): a factor on both admission losses; a Reynolds correction of each
  pressure stage, loss 1 − η ∝ Re^(−n) with Re ∝ m at the stage (Traupel, *Thermische
  Turbomaschinen* Bd. 1, §7: n ≈ 0.1–0.25 in the transition range; Spencer, Cotton & Cannon,
  ASME J. Eng. Power 85 (1963) 249–301, for HP part-load efficiency).
"""

from __future__ import annotations

import math

from steamtwin.cache import njit

KAPPA_SUPERHEATED = 1.3  # isentropic exponent of superheated steam for nozzle flow (Dixon & Hall)
WINDAGE_CONSTANT = 0.15  # B_e, single-row wheel (Kang et al.)
SECTOR_END_CONSTANT = 0.012  # C_e, single-row wheel (Kang et al.)
DISC_FRICTION_CONSTANT = 1.05e-3  # 1e-3·K1, K1 = 1.05 (Kang et al.; textbook range 1.0–1.3)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def critical_pressure_ratio(kappa: float) -> float:
    """Pressure ratio below which a convergent nozzle is choked (dimensionless)."""
    return (2.0 / (kappa + 1.0)) ** (kappa / (kappa - 1.0))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def nozzle_flow_function(pressure_ratio: float, kappa: float) -> float:
    """Saint-Venant–Wantzel flow function Ψ(p_out/p_in); constant below the critical ratio."""
    ratio = max(pressure_ratio, critical_pressure_ratio(kappa))
    if ratio >= 1.0:
        return 0.0
    root = ratio ** (1.0 / kappa)  # π^(2/κ) − π^((κ+1)/κ) = root² − π·root
    bracket = root * root - ratio * root
    return math.sqrt(2.0 * kappa / (kappa - 1.0) * max(bracket, 0.0))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def stodola_inlet_pressure(flow: float, capacity: float, outlet_pressure: float,
                           inlet_pv: float) -> float:
    """Inlet pressure (Pa) of a stage passing ``flow`` (kg/s) by Stodola's cone law.

    ``inlet_pv`` is p_in·v_in (J/kg), which depends on temperature and only weakly on pressure,
    so solving p_in² = p_out² + (m/K)²·p_in·v_in with it held fixed converges fast.
    """
    return math.sqrt(outlet_pressure * outlet_pressure + (flow / capacity) ** 2 * inlet_pv)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def optimum_velocity_ratio(nozzle_exit_angle: float, reaction: float) -> float:
    """ν_opt = cos α1 / (2·sqrt(1 − R)) (dimensionless; α1 in rad)."""
    return math.cos(nozzle_exit_angle) / (2.0 * math.sqrt(1.0 - reaction))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def stage_efficiency(velocity_ratio: float, optimum_ratio: float, peak_efficiency: float,
                     friction_loss: float) -> float:
    """Internal stage efficiency from the parabolic velocity-ratio law less friction, ≥ 0."""
    x = velocity_ratio / optimum_ratio
    return max(peak_efficiency * x * (2.0 - x) - friction_loss, 0.0)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def windage_power(windage_area: float, idle_arc: float, density: float, blade_speed: float
                  ) -> float:
    """Idle-arc windage (W): B_e·π·sin α1/2 · d·l folded into ``windage_area`` (m²)."""
    return windage_area * idle_arc * density * blade_speed**3
