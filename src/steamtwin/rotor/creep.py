"""Creep damage of the rotor by the Larson–Miller time-fraction rule.

Rupture time from the Larson–Miller parameter (Larson & Miller, Trans. ASME 74 (1952) 765):
P = T·(C + log10 t_r), T in K, t_r in h, with a master curve log10 σ = a₀ + a₁·P + a₂·P² fitted by
least squares to the steel's rupture points (:class:`CreepRuptureData`). Damage is Robinson's
life-fraction sum D = Σ Δt / t_r(σ, T) (Robinson, Trans. ASME 74 (1952) 777; Viswanathan,
*Damage Mechanisms and Life Assessment of High-Temperature Components*, ASM, 1989, ch. 5),
integrated with the trapezoidal rule on the rate 1/t_r (exact for a constant hold).

Scope, stated so nothing is extrapolated silently:

* below 371 °C (700 °F) creep is neglected: the limit of ASME BPVC III Division 1 (Subsection
  NB) for ferritic steels, above which Division 5 requires creep to be considered;
* temperatures above the highest rupture-data temperature are refused;
* stresses above the highest rupture-data stress are refused where creep counts; stresses
  below the lowest one use the rupture time at the lowest one (conservative: shorter than the
  extrapolated time);
* compressive and zero stresses do no creep damage (pass a tensile equivalent stress).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.steel import CreepRuptureData, TabulatedSteel

__all__ = ["CREEP_THRESHOLD", "CreepResult", "LarsonMillerCurve", "creep_damage"]

CREEP_THRESHOLD = (700.0 - 32.0) / 1.8 + 273.15
"""K: 371 °C (700 °F), below which ferritic-steel creep is neglected (ASME III Div. 1 NB limit)."""
SECONDS_PER_HOUR = 3600.0


@dataclass(frozen=True)
class LarsonMillerCurve:
    """The Larson–Miller master curve fitted to a steel's creep-rupture data."""

    data: CreepRuptureData

    @cached_property
    def coefficients(self) -> np.ndarray:
        """(a₀, a₁, a₂) of log10 σ[Pa] = a₀ + a₁·P + a₂·P² (least squares)."""
        p = self.parameter(self.data.temperatures_k, self.data.rupture_hours)
        return np.polynomial.polynomial.polyfit(p, np.log10(self.data.stresses_pa), 2)

    @property
    def stress_range_pa(self) -> tuple[float, float]:
        return float(self.data.stresses_pa.min()), float(self.data.stresses_pa.max())

    @property
    def max_temperature_k(self) -> float:
        return float(self.data.temperatures_k.max())

    def parameter(self, temperature_k: ArrayLike, hours: ArrayLike) -> np.ndarray:
        """P = T·(C + log10 t_r), K·(1 + log10 h)."""
        return np.asarray(temperature_k, float) * (self.data.larson_miller_constant
                                                   + np.log10(hours))

    def stress(self, parameter: ArrayLike) -> np.ndarray:
        """Rupture stress (Pa) of the master curve at P."""
        return 10.0 ** np.polynomial.polynomial.polyval(np.asarray(parameter, float),
                                                        self.coefficients)

    def parameter_at(self, stress_pa: ArrayLike) -> np.ndarray:
        """P on the master curve at stresses (Pa): the root of a₂P² + a₁P + a₀ − log10 σ = 0 on
        the curve's falling branch (P above the vertex −a₁/2a₂, where the data lie)."""
        a0, a1, a2 = self.coefficients
        disc = a1 * a1 - 4.0 * a2 * (a0 - np.log10(np.asarray(stress_pa, float)))
        return (-a1 - np.sqrt(disc)) / (2.0 * a2)

    def rupture_hours(self, stress_pa: ArrayLike, temperature_k: ArrayLike) -> np.ndarray:
        """Rupture time t_r (h) at tensile stresses (Pa) and temperatures (K); see the module
        docstring for the scope (below the creep threshold or at σ ≤ 0: ``inf``)."""
        s = np.asarray(stress_pa, dtype=float)
        t = np.asarray(temperature_k, dtype=float)
        bad = ~(np.isfinite(s) & np.isfinite(t))
        if np.any(bad):
            raise RotorAreaError(f"creep: stress (Pa) and temperature (K) must be finite, got "
                                 f"{float(s[bad].flat[0]) if s.ndim else float(s)!r}, "
                                 f"{float(t[bad].flat[0]) if t.ndim else float(t)!r}")
        if np.any(t > self.max_temperature_k):
            raise RotorAreaError(
                f"creep: temperature {np.max(t):.2f} K is above the rupture data "
                f"({CREEP_THRESHOLD:.2f}–{self.max_temperature_k:.2f} K, i.e. 371–"
                f"{self.max_temperature_k - 273.15:.0f} °C)")
        low, high = self.stress_range_pa
        creeping = (t >= CREEP_THRESHOLD) & (s > 0.0)
        if np.any(creeping & (s > high)):
            raise RotorAreaError(f"creep: stress {np.max(s[creeping]) / 1e6:.1f} MPa is above "
                                 f"the rupture data ({low / 1e6:.0f}–{high / 1e6:.0f} MPa)")
        p = self.parameter_at(np.clip(s, low, high))
        hours = 10.0 ** (p / t - self.data.larson_miller_constant)
        return np.where(creeping, hours, np.inf)


@dataclass(frozen=True)
class CreepResult:
    """Creep damage per interval of a history (Robinson's time fraction)."""

    interval_damage: np.ndarray
    """Damage of each interval between consecutive samples (length n − 1)."""

    @property
    def total_damage(self) -> float:
        """Σ Δt / t_r (dimensionless; 1 = creep rupture)."""
        return float(self.interval_damage.sum())

    def damage_per_window(self, edges: ArrayLike) -> np.ndarray:
        """Damage in each window [edges[i], edges[i+1]] of sample indices (per ramp, per day)."""
        bounds = np.asarray(edges, dtype=int)
        if (bounds.ndim != 1 or bounds.size < 2 or np.any(np.diff(bounds) <= 0)
                or bounds[0] < 0 or bounds[-1] > self.interval_damage.size):
            raise RotorAreaError(f"window edges must be ≥ 2 strictly increasing sample indices "
                                 f"in 0…{self.interval_damage.size}")
        cumulative = np.concatenate([[0.0], np.cumsum(self.interval_damage)])
        return np.diff(cumulative[bounds])


def creep_damage(stress: ArrayLike, temperature: ArrayLike, time_s: ArrayLike,
                 material: TabulatedSteel) -> CreepResult:
    """Larson–Miller time-fraction creep damage of a history: tensile equivalent stress (Pa),
    metal temperature (K) and sample times (s, strictly increasing)."""
    s = np.asarray(stress, dtype=float)
    t = np.asarray(temperature, dtype=float)
    time = np.asarray(time_s, dtype=float)
    if s.ndim != 1 or t.shape != s.shape or time.shape != s.shape or s.size < 2:
        raise RotorAreaError(f"creep: stress, temperature and time must be 1-D series of equal "
                             f"length ≥ 2, got shapes {s.shape}, {t.shape}, {time.shape}")
    if not np.all(np.isfinite(time)) or np.any(np.diff(time) <= 0.0):
        raise RotorAreaError("creep: sample times (s) must be finite and strictly increasing")
    curve = LarsonMillerCurve(material.creep)
    rate = 1.0 / (curve.rupture_hours(s, t) * SECONDS_PER_HOUR)
    return CreepResult(0.5 * (rate[1:] + rate[:-1]) * np.diff(time))
