"""Metal heat transfer: 1-D conduction in the inner-casing wall and the rotor, as numba code.

Each body of a stage group is a chain of finite volumes (Patankar, *Numerical Heat Transfer and
Fluid Flow*, 1980, ch. 4): the casing a plane wall of depth L = mass/(ρ·area) wetted by steam on
its bore and losing heat through the lagging outside; the rotor a solid cylinder of radius
R = 2·mass/(ρ·area) wetted on its surface. Time integration is implicit Euler, unconditionally
stable; with an infinite step it returns the steady state, so a run starts from equilibrium.

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
from numba import njit

DITTUS_BOELTER_CONSTANT = 0.023
CORE_SWIRL_RATIO = 0.5


@njit(cache=True)
def dittus_boelter_htc(velocity: float, hydraulic_diameter: float, specific_volume: float,
                       viscosity: float, conductivity: float, heat_capacity: float,
                       fluid_is_heated: bool) -> float:
    """Heat-transfer coefficient W/(m²·K) for turbulent flow at ``velocity`` m/s.

    Prandtl exponent 0.4 when the wall heats the steam, 0.3 when the steam heats the wall.
    """
    reynolds = velocity * hydraulic_diameter / (viscosity * specific_volume)
    prandtl = heat_capacity * viscosity / conductivity
    exponent = 0.4 if fluid_is_heated else 0.3
    nusselt = DITTUS_BOELTER_CONSTANT * reynolds**0.8 * prandtl**exponent
    return nusselt * conductivity / hydraulic_diameter


@njit(cache=True)
def rotor_relative_velocity(axial_velocity: float, rotor_surface_speed: float) -> float:
    """Steam velocity relative to the rotor surface, m/s (axial + core swirl deficit)."""
    swirl = (1.0 - CORE_SWIRL_RATIO) * rotor_surface_speed
    return math.sqrt(axial_velocity * axial_velocity + swirl * swirl)


@njit(cache=True)
def prepare_chain(chain: int, old: np.ndarray, capacity: np.ndarray, conductance: np.ndarray,
                  surface_conductance: float, outer_conductance: float,
                  ambient_temperature: float, inverse_dt: float, base: np.ndarray,
                  response: np.ndarray, work: np.ndarray) -> None:
    """Set up one implicit-Euler step of chain ``chain``, affine in the steam temperature.

    Row ``chain`` of the 2-D arrays describes the chain: ``old`` temperatures (K), ``capacity``
    (J/K), ``conductance`` (W/K) between nodes j and j+1. Afterwards its new temperatures are
    ``base[chain] + response[chain]·T_steam`` (K) whatever steam temperature the steam path settles
    on, so iterating the steam path costs no further solves. Node 0 faces the steam through
    ``surface_conductance`` (W/K), the last node the surroundings through ``outer_conductance``
    (W/K); ``inverse_dt`` in 1/s (0 gives the steady state). ``work`` is scratch of a chain's
    length. Thomas algorithm on the symmetric tridiagonal system (off-diagonals −conductance).
    Rows are indexed element-wise, never sliced: slices are array views whose reference counting
    costs more than the solve.
    """
    n = old.shape[1]
    for j in range(n):
        storage = capacity[chain, j] * inverse_dt
        work[j] = storage  # diagonal
        base[chain, j] = storage * old[chain, j]
        response[chain, j] = 0.0
        if j > 0:
            work[j] += conductance[chain, j - 1]
        if j < n - 1:
            work[j] += conductance[chain, j]
    work[0] += surface_conductance
    response[chain, 0] = surface_conductance
    work[n - 1] += outer_conductance
    base[chain, n - 1] += outer_conductance * ambient_temperature
    for j in range(1, n):
        factor = conductance[chain, j - 1] / work[j - 1]
        work[j] -= factor * conductance[chain, j - 1]
        base[chain, j] += factor * base[chain, j - 1]
        response[chain, j] += factor * response[chain, j - 1]
    inverse = 1.0 / work[n - 1]
    base[chain, n - 1] *= inverse
    response[chain, n - 1] *= inverse
    for j in range(n - 2, -1, -1):
        inverse = 1.0 / work[j]
        base[chain, j] = (base[chain, j] + conductance[chain, j] * base[chain, j + 1]) * inverse
        response[chain, j] = (
            response[chain, j] + conductance[chain, j] * response[chain, j + 1]) * inverse


@njit(cache=True)
def surface_heat(surface_conductance: float, base_surface: float, response_surface: float,
                 fluid_temperature: float) -> float:
    """Heat (W) a chain set up by :func:`prepare_chain` takes from steam at that temperature (K)."""
    return surface_conductance * (
        fluid_temperature - (base_surface + response_surface * fluid_temperature))
