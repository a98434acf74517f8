"""Metal heat transfer: 1-D conduction in the inner-casing wall and the rotor, as numba code.

Each body of a stage group is a chain of finite volumes (Patankar, *Numerical Heat Transfer and
Fluid Flow*, 1980, ch. 4), built in :mod:`steamtwin.model.design`: the casing wetted by steam on
its bore and losing heat through the lagging outside, the rotor wetted on its surface — a
cylindrical wall and a solid or bored cylinder when the spec draws them, else a plane wall of
depth mass/(ρ·area) and a solid cylinder of radius 2·mass/(ρ·area). Time integration is implicit
Euler, unconditionally stable; with an infinite step it returns the steady state, so a run
starts from equilibrium.

Steam-side heat-transfer coefficient: Dittus–Boelter, Nu = 0.023·Re^0.8·Pr^n, n = 0.4 when the
wall heats the steam and 0.3 when the steam heats the wall (Dittus & Boelter, Univ. Calif. Publ.
Eng. 2 (1930) 443; Incropera & DeWitt, eq. 8.60) on the blade-path annulus,
hydraulic diameter 2·blade height, axial velocity m·v/(π·d·l); for the rotor the velocity is the
vector sum of axial velocity and the core swirl, taken as half the rotor surface speed
(Owen & Rogers, *Flow and Heat Transfer in Rotating-Disc Systems*, 1989: core rotation ≈ 0.4–0.5).
The calibrated heat-transfer coefficient multiplies the correlation.
"""

from __future__ import annotations

import math

import numpy as np

from steamtwin.cache import njit

DITTUS_BOELTER_CONSTANT = 0.023
CORE_SWIRL_RATIO = 0.5


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def dittus_boelter_htc(velocity: float, hydraulic_diameter: float, specific_volume: float,
                       viscosity: float, conductivity: float, heat_capacity: float,
                       fluid_is_heated: bool) -> float:
    """Heat-transfer coefficient W/(m²·K) for turbulent flow at ``velocity`` m/s.

    Prandtl exponent 0.4 when the wall heats the steam, 0.3 when the steam heats the wall.
    """
    log_re_per_velocity, log_prandtl = dittus_boelter_logs(hydraulic_diameter, specific_volume,
                                                           viscosity, conductivity, heat_capacity)
    return dittus_boelter_from_logs(velocity, log_re_per_velocity, log_prandtl, conductivity,
                                    hydraulic_diameter, fluid_is_heated)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def dittus_boelter_logs(hydraulic_diameter: float, specific_volume: float, viscosity: float,
                        conductivity: float, heat_capacity: float) -> tuple[float, float]:
    """ln(Re/velocity) (velocity in m/s) and ln Pr of a steam state (SI inputs).

    The part of :func:`dittus_boelter_htc` that the casing and the rotor of a stage group share:
    the kernel takes these two logarithms once per group instead of two powers per body.
    """
    return (math.log(hydraulic_diameter / (viscosity * specific_volume)),
            math.log(heat_capacity * viscosity / conductivity))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def dittus_boelter_from_logs(velocity: float, log_re_per_velocity: float, log_prandtl: float,
                             conductivity: float, hydraulic_diameter: float,
                             fluid_is_heated: bool) -> float:
    """:func:`dittus_boelter_htc` (W/(m²·K)) from :func:`dittus_boelter_logs`' logarithms:
    Nu = 0.023·exp(0.8·ln Re + n·ln Pr)."""
    exponent = 0.4 if fluid_is_heated else 0.3
    nusselt = DITTUS_BOELTER_CONSTANT * math.exp(
        0.8 * (math.log(velocity) + log_re_per_velocity) + exponent * log_prandtl)
    return nusselt * conductivity / hydraulic_diameter


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def rotor_relative_velocity(axial_velocity: float, rotor_surface_speed: float) -> float:
    """Steam velocity relative to the rotor surface, m/s (axial + core swirl deficit)."""
    swirl = (1.0 - CORE_SWIRL_RATIO) * rotor_surface_speed
    return math.sqrt(axial_velocity * axial_velocity + swirl * swirl)


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def factor_chain(chain: int, capacity: np.ndarray, conductance: np.ndarray,
                 outer_conductance: float, inverse_dt: float, pivot: np.ndarray) -> None:
    """Eliminate the implicit-Euler matrix of chain ``chain`` from the lagging end to the steam.

    Row ``chain`` of the 2-D arrays describes the chain: ``capacity`` (J/K) of its nodes,
    ``conductance`` (W/K) between nodes j and j+1. Node 0 faces the steam, the last node the
    surroundings through ``outer_conductance`` (W/K); ``inverse_dt`` in 1/s (0 gives the steady
    state). Thomas algorithm on the symmetric tridiagonal system (off-diagonals −conductance),
    run towards node 0 so that the steam-side conductance, which changes every sample, enters
    only node 0's pivot: everything here depends on the step length alone and is done once per
    run. ``pivot[chain, j]`` receives 1/pivot of node j ≥ 1 and ``pivot[chain, 0]`` node 0's
    pivot without the steam-side conductance (W/K). Rows are indexed element-wise, never sliced:
    slices are array views whose reference counting costs more than the solve.
    """
    n = capacity.shape[1]
    for j in range(n - 1, -1, -1):
        diagonal = capacity[chain, j] * inverse_dt
        if j > 0:
            diagonal += conductance[chain, j - 1]
        if j < n - 1:
            g = conductance[chain, j]
            diagonal += g - g * g * pivot[chain, j + 1]
        else:
            diagonal += outer_conductance
        pivot[chain, j] = 1.0 / diagonal if j > 0 else diagonal


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def prepare_chain(chain: int, old: np.ndarray, capacity: np.ndarray, conductance: np.ndarray,
                  outer_conductance: float, ambient_temperature: float, inverse_dt: float,
                  pivot: np.ndarray, rhs: np.ndarray) -> None:
    """Eliminate the right-hand side of a step from ``old`` temperatures (K) of chain ``chain``.

    With ``pivot`` from :func:`factor_chain` (same step); ``rhs[chain]`` receives the eliminated
    right-hand side (W). Independent of the steam, so done once per sample; no divisions.
    """
    n = capacity.shape[1]
    for j in range(n - 1, -1, -1):
        value = capacity[chain, j] * inverse_dt * old[chain, j]
        if j < n - 1:
            value += conductance[chain, j] * pivot[chain, j + 1] * rhs[chain, j + 1]
        else:
            value += outer_conductance * ambient_temperature
        rhs[chain, j] = value


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def prepare_chains(old: np.ndarray, capacity: np.ndarray, conductance: np.ndarray,
                   outer_conductance: np.ndarray, ambient_temperature: float,
                   inverse_dt: float, pivot: np.ndarray, rhs: np.ndarray) -> None:
    """:func:`prepare_chain` for every chain at once, ``outer_conductance`` (W/K) per chain.

    Node by node across the chains: each chain's elimination is a recurrence whose steps wait
    for the previous one, and the chains are independent, so taking one node of every chain in
    turn lets the processor overlap them. The same operations in the same order per chain as
    :func:`prepare_chain`, so the same numbers up to round-off (the compiler may fuse
    multiply-adds differently).
    """
    chains, n = capacity.shape
    for chain in range(chains):
        value = capacity[chain, n - 1] * inverse_dt * old[chain, n - 1]
        value += outer_conductance[chain] * ambient_temperature
        rhs[chain, n - 1] = value
    for j in range(n - 2, -1, -1):
        for chain in range(chains):
            value = capacity[chain, j] * inverse_dt * old[chain, j]
            value += conductance[chain, j] * pivot[chain, j + 1] * rhs[chain, j + 1]
            rhs[chain, j] = value


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def surface_response(surface_conductance: float, pivot_surface: float, rhs_surface: float
                     ) -> tuple[float, float]:
    """The new surface temperature as ``base + response·T_steam`` (K), for any steam T (K).

    ``pivot_surface`` and ``rhs_surface`` are node 0's from :func:`factor_chain` and
    :func:`prepare_chain`, ``surface_conductance`` (W/K) the steam side's; so iterating the steam
    path costs no further solves.
    """
    inverse = 1.0 / (pivot_surface + surface_conductance)
    return rhs_surface * inverse, surface_conductance * inverse


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def surface_heat(surface_conductance: float, base_surface: float, response_surface: float,
                 fluid_temperature: float) -> float:
    """Heat (W) a chain takes from steam at that temperature (K), with :func:`surface_response`."""
    return surface_conductance * (
        fluid_temperature - (base_surface + response_surface * fluid_temperature))


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def finish_chain(chain: int, surface_temperature: float, conductance: np.ndarray,
                 pivot: np.ndarray, rhs: np.ndarray, new: np.ndarray) -> None:
    """Back-substitute the new temperatures (K) of chain ``chain`` into ``new[chain]``."""
    new[chain, 0] = surface_temperature
    for j in range(1, new.shape[1]):
        new[chain, j] = (rhs[chain, j] + conductance[chain, j - 1] * new[chain, j - 1]) * pivot[
            chain, j]


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def finish_chains(conductance: np.ndarray, pivot: np.ndarray, rhs: np.ndarray,
                  new: np.ndarray) -> None:
    """:func:`finish_chain` for every chain at once; ``new[:, 0]`` holds each chain's new
    surface temperature (K) on entry.

    Node by node across the chains, like :func:`prepare_chains` (the same numbers as chain by
    chain, up to round-off).
    """
    chains, n = new.shape
    for j in range(1, n):
        for chain in range(chains):
            new[chain, j] = (rhs[chain, j] + conductance[chain, j - 1] * new[chain, j - 1]) * pivot[
                chain, j]
