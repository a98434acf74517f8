"""The allowable equivalent stress at a rotor's critical point, for the ramp-rate advisor.

The advisor keeps the signed equivalent stress σ (Pa; the scalar fatigue uses, see
:mod:`steamtwin.rotor.model`) at each critical point inside a window ``lower ≤ σ ≤ upper``:

* **user-set** allowable a (Pa): the window is [−a, a] — the magnitude of the equivalent stress
  stays within a, whichever way the transient pushes it;
* **from a number of cycles** N: the window is the standing stress (centrifugal + steady
  thermal, at the ramp's end loads) widened by the elastic stress range whose *design* fatigue
  life is N cycles. A ramp and the return to steady state make one cycle of range
  |σ_peak − σ_standing| (rainflow of standing → peak → standing: two half cycles); that range is
  found by Brent's method (Brent, *Algorithms for Minimization without Derivatives*, 1973,
  ch. 4) on the Miner damage of that cycle, computed exactly as the life accounting does
  (:func:`steamtwin.rotor.fatigue.fatigue_damage`: Neuber's rule on the steel's cyclic curve,
  Manson–Coffin–Basquin with Morrow's mean-stress correction), with the **ASME BPVC III design
  factors** (2 on strain amplitude, 20 on cycles: Langer, J. Basic Eng. 84 (1962) 389) on the
  steel's strain-life curve — so "N cycles allowed" means "damage 1/N per ramp cycle".
  EN 12952-3 clause 13 and TRD 301 Anlage 1 allow fatigue design from a design curve for a
  specified number of load cycles in this way; their own design curves and factors are *not*
  implemented here (their text was not at hand), only the ASME factors on the steel's
  strain-life curve named above. The upper and lower widths are solved separately, since the
  mean-stress correction treats a tensile and a compressive excursion differently; the cycle is
  taken at the hotter end of the ramp (strength falls with temperature). Each range is also
  capped at the primary-plus-secondary stress range limit 3·S_m of ASME BPVC III NB-3222.2
  (the shakedown limit, beyond which the elastic stress analysis behind the fatigue check no
  longer holds), with 3·S_m taken as the tensile strength R_m(T) (S_m ≤ R_m/3; no yield table
  of the steel is at hand) — the same bound ``steamtwin rotor stress`` reports against.

An allowable whose window does not contain the standing stress at both end loads is refused
(:class:`~steamtwin.errors.RotorAreaError`): not even a steady unit would meet it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.fatigue import ASME_DESIGN_FACTORS, DesignFactors, fatigue_damage
from steamtwin.rotor.steel import TabulatedSteel

__all__ = ["StressLimit", "cycle_limit", "design_stress_range", "user_limit"]

RANGE_CEILING_PA = 5e9
"""Largest elastic stress range (Pa) searched for: far beyond any steel's strength."""
RANGE_TOLERANCE_PA = 1e5
"""Brent's tolerance on the allowed range (Pa): 0.1 MPa, far below the stress model's accuracy."""


@dataclass(frozen=True)
class StressLimit:
    """The window a critical point's signed equivalent stress must stay in (Pa)."""

    location: str
    lower_pa: float
    upper_pa: float
    standing_pa: tuple[float, float]
    """Steady equivalent stress at the ramp's start and end loads (Pa)."""
    basis: str
    """How the window was set, in words (user value, or cycles and code)."""

    def shrunk(self, fraction: float) -> StressLimit:
        """The window with each edge moved toward the standing stress by ``fraction`` of its
        distance from it (a margin for the stress model's own error)."""
        if not 0.0 <= fraction < 1.0:
            raise RotorAreaError(f"margin must lie in [0, 1) (fraction of the allowed "
                                 f"excursion), got {fraction!r}")
        low, high = min(self.standing_pa), max(self.standing_pa)
        return StressLimit(self.location, high - (1.0 - fraction) * (high - self.lower_pa),
                           low + (1.0 - fraction) * (self.upper_pa - low), self.standing_pa,
                           f"{self.basis}, less a {fraction:.0%} margin")

    def excess(self, stress_pa: np.ndarray) -> np.ndarray:
        """How far (Pa) each stress lies outside the window; ≤ 0 inside."""
        s = np.asarray(stress_pa, dtype=float)
        return np.maximum(s - self.upper_pa, self.lower_pa - s)


def _check_standing(limit: StressLimit) -> StressLimit:
    for stress in limit.standing_pa:
        if not limit.lower_pa < stress < limit.upper_pa:
            raise RotorAreaError(
                f"allowable at the {limit.location} ({limit.basis}): window "
                f"{limit.lower_pa / 1e6:.1f}…{limit.upper_pa / 1e6:.1f} MPa does not contain the "
                f"standing (centrifugal + steady thermal) equivalent stress "
                f"{stress / 1e6:.1f} MPa; raise the allowable or lower the cycle count")
    return limit


def user_limit(location: str, allowable_pa: float, standing_pa: tuple[float, float]
               ) -> StressLimit:
    """The window [−a, a] for a user's allowable ``allowable_pa`` (Pa, > the standing stress's
    magnitude at both end loads)."""
    if not (np.isfinite(allowable_pa) and allowable_pa > 0.0):
        raise RotorAreaError(f"allowable stress must be a positive number of Pa, got "
                             f"{allowable_pa!r}")
    return _check_standing(StressLimit(location, -float(allowable_pa), float(allowable_pa),
                                       standing_pa, f"user-set {allowable_pa / 1e6:.1f} MPa"))


def design_stress_range(cycles: float, standing_pa: float, temperature_k: float,
                        steel: TabulatedSteel, direction: int = 1, *,
                        design: DesignFactors = ASME_DESIGN_FACTORS) -> float:
    """Elastic equivalent-stress range (Pa) of an excursion standing → standing ± range →
    standing whose design fatigue life is ``cycles`` (module docstring); ``direction`` +1 for
    a tensile-going excursion, −1 for a compressive-going one; temperature in K."""
    if not (np.isfinite(cycles) and cycles >= 1.0):
        raise RotorAreaError(f"design cycle count must be ≥ 1, got {cycles!r}")
    if direction not in (1, -1):
        raise RotorAreaError(f"direction must be +1 or −1, got {direction!r}")
    temperatures = np.full(3, float(temperature_k))

    def excess_damage(stress_range: float) -> float:
        series = np.array([standing_pa, standing_pa + direction * stress_range, standing_pa])
        damage = fatigue_damage(series, temperatures, steel, design=design).total_damage
        return np.log(max(damage, 1e-300) * cycles)

    if excess_damage(RANGE_CEILING_PA) < 0.0:
        raise RotorAreaError(f"no stress range below {RANGE_CEILING_PA / 1e6:.0f} MPa has a "
                             f"design life as short as {cycles!r} cycles")
    return float(brentq(excess_damage, RANGE_TOLERANCE_PA, RANGE_CEILING_PA,
                        xtol=RANGE_TOLERANCE_PA))


def cycle_limit(location: str, cycles: float, standing_pa: tuple[float, float],
                temperature_k: float, steel: TabulatedSteel, *,
                design: DesignFactors = ASME_DESIGN_FACTORS) -> StressLimit:
    """The window for ``cycles`` ramp cycles of design fatigue life at ``temperature_k`` (K):
    [max standing − compressive range, min standing + tensile range] (Pa), each range at most
    the shakedown limit (module docstring)."""
    low, high = min(standing_pa), max(standing_pa)
    shakedown = float(steel.tensile_strength(temperature_k))
    upper = low + min(design_stress_range(cycles, low, temperature_k, steel, 1, design=design),
                      shakedown)
    lower = high - min(design_stress_range(cycles, high, temperature_k, steel, -1,
                                           design=design), shakedown)
    basis = (f"{cycles:g} cycles of design fatigue life (ASME III factors 2 on strain, 20 on "
             f"cycles, on the {steel.name} strain-life curve at {temperature_k - 273.15:.0f} °C), "
             f"range at most 3 S_m = {shakedown / 1e6:.0f} MPa")
    return _check_standing(StressLimit(location, float(lower), float(upper),
                                       (float(standing_pa[0]), float(standing_pa[1])), basis))
