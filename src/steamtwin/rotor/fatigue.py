"""Low-cycle fatigue of the rotor from an elastic stress history at the critical point.

Steps (Dowling, *Mechanical Behavior of Materials*, 4th ed., 2013, ch. 14):

1. **Rainflow counting** per ASTM E1049-85 (2017) §5.4.4 with the maintained ``rainflow``
   package (3-point algorithm; half cycles from the residue), giving for each cycle its stress
   range, mean, count (0.5 or 1), and the start/end sample indices.
2. **Neuber's rule** (Neuber, J. Appl. Mech. 28 (1961) 544): the local elastic-plastic stress and
   strain satisfy σ·ε = σ_e²/E, with the cyclic Ramberg–Osgood curve ε = σ/E + (σ/K')^(1/n') for
   the largest-magnitude peak and Masing's doubled curve Δε = Δσ/E + 2(Δσ/2K')^(1/n') for the
   range (Dowling §14.5). The local mean stress is that peak minus (toward) half the range.
3. **Manson–Coffin–Basquin** with **Morrow's mean-stress correction** (Dowling ch. 14):
   ε_a = (σ'_f − σ_m)/E·(2N)^b + ε'_f·(2N)^c, solved for N by Newton's method in log10(2N).
   Morrow is the default: Dowling (Fatigue Fract. Eng. Mater. Struct. 32 (2009) 1004) finds it
   reasonable for steels,
   and unlike Smith–Watson–Topper (σ_max·ε_a = σ'_f²/E·(2N)^2b + σ'_f·ε'_f·(2N)^(b+c), offered
   as ``"swt"``) it gives a finite life to the compressive-mean cycles a rotor surface sees on
   heating. ``"none"`` drops the mean stress.
4. Optional **design-curve factors**: the life is the lower of the mean-curve life at twice the
   strain amplitude and the mean-curve life divided by 20 (ASME BPVC III, Mandatory Appendix I
   basis of the design fatigue curves; Langer, J. Basic Eng. 84 (1962) 389).
5. **Miner's rule** (Miner, J. Appl. Mech. 12 (1945) A159): D = Σ count/N.

The cycle's temperature is the higher of the temperatures at its two reversal points (strength
falls with temperature, so this is the conservative choice); the strain-life constants come
from the steel at that temperature (:meth:`TabulatedSteel.strain_life`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
import rainflow
from numpy.typing import ArrayLike

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.steel import StrainLife, TabulatedSteel

__all__ = ["ASME_DESIGN_FACTORS", "DesignFactors", "FatigueResult", "cycles_to_failure",
           "fatigue_damage", "miner_damage", "neuber_peak", "neuber_range", "rainflow_cycles"]

MEAN_STRESS_CORRECTIONS = ("morrow", "swt", "none")
LOG_REVERSALS_MAX = 20.0
"""log10(2N) beyond which a cycle does no damage (10²⁰ reversals: far past any rotor's life)."""


@dataclass(frozen=True)
class DesignFactors:
    """Design-curve factors: on the strain amplitude and on the cycles to failure."""

    strain: float = 2.0
    cycles: float = 20.0

    def __post_init__(self) -> None:
        if not (self.strain >= 1.0 and self.cycles >= 1.0):
            raise RotorAreaError(f"design factors must be ≥ 1, got strain {self.strain!r}, "
                                 f"cycles {self.cycles!r}")


ASME_DESIGN_FACTORS = DesignFactors(2.0, 20.0)
"""The factors behind the ASME BPVC III design fatigue curves (2 on strain, 20 on cycles)."""


def _checked_series(stress: ArrayLike, temperature: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    s = np.asarray(stress, dtype=float)
    t = np.asarray(temperature, dtype=float)
    if s.ndim != 1 or t.shape != s.shape:
        raise RotorAreaError(f"stress (Pa) and temperature (K) must be 1-D series of equal "
                             f"length, got shapes {s.shape} and {t.shape}")
    for label, values in (("stress (Pa)", s), ("temperature (K)", t)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise RotorAreaError(f"{label} is not finite at sample {bad[0]}: "
                                 f"{float(values[bad[0]])!r}")
    return s, t


def rainflow_cycles(stress: ArrayLike, temperature: ArrayLike) -> pd.DataFrame:
    """Rainflow cycles (ASTM E1049-85 §5.4.4) of a stress series (Pa) with its temperatures (K).

    Columns: ``range_pa``, ``mean_pa``, ``count`` (0.5 or 1), ``start``, ``end`` (sample
    indices of the two reversals), ``temperature_k`` (the higher of the two)."""
    s, t = _checked_series(stress, temperature)
    rows = list(rainflow.extract_cycles(s))
    if s.size == 2 and s[0] != s[1]:  # rainflow 3.2 drops the last point of a 2-sample series
        rows = [(abs(s[1] - s[0]), 0.5 * (s[0] + s[1]), 0.5, 0, 1)]
    frame = pd.DataFrame(rows, columns=["range_pa", "mean_pa", "count", "start", "end"])
    frame = frame.astype({"range_pa": float, "mean_pa": float, "count": float,
                          "start": int, "end": int})
    frame["temperature_k"] = np.maximum(t[frame["start"].to_numpy()], t[frame["end"].to_numpy()])
    return frame


NEWTON_TOLERANCE = 1e-13
"""Relative step at which the monotone Newton iterations below stop."""
NEWTON_ITERATIONS = 200


def _monotone_newton(residual: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                     start: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Newton's method, elementwise, for residuals that are convex and monotone on the side
    of the root the start lies on, so the iterates approach the root monotonically without
    overshoot (Ortega & Rheinboldt, *Iterative Solution of Nonlinear Equations*, 1970, §13.3)."""
    x = np.array(start, dtype=float)
    todo = np.array(active, dtype=bool)
    for _ in range(NEWTON_ITERATIONS):
        if not todo.any():
            break
        value, slope = residual(x)
        step = np.where(todo, value / np.where(slope == 0.0, np.inf, slope), 0.0)
        x = x - step
        todo &= np.abs(step) > NEWTON_TOLERANCE * np.maximum(np.abs(x), 1.0)
    return x


def _neuber_solve(elastic: ArrayLike, curve: StrainLife) -> np.ndarray:
    """σ ≥ 0 with σ·ε(σ) = σ_e²/E on the cyclic curve, elementwise. The residual
    g(σ) = σ²/E + σ·(σ/K')^(1/n') − σ_e²/E is convex and increasing for σ > 0 and g(σ_e) ≥ 0, so
    Newton from σ_e converges from above."""
    e = np.asarray(curve.youngs_modulus, dtype=float)
    k, inv_n = curve.cyclic_strength_coefficient, 1.0 / curve.cyclic_hardening_exponent
    sigma_e = np.abs(np.asarray(elastic, dtype=float))

    def residual(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        plastic = (s / k) ** inv_n
        return (s * s / e + s * plastic - sigma_e * sigma_e / e,
                2.0 * s / e + (1.0 + inv_n) * plastic)

    return _monotone_newton(residual, sigma_e, sigma_e > 0.0)


def neuber_range(elastic_range: ArrayLike, curve: StrainLife) -> tuple[np.ndarray, np.ndarray]:
    """Local (stress range Pa, strain range) of elastic stress ranges (Pa) by Neuber's rule on
    Masing's doubled cyclic curve."""
    half = _neuber_solve(0.5 * np.abs(np.asarray(elastic_range, dtype=float)), curve)
    return 2.0 * half, 2.0 * curve.strain_amplitude(half)


def neuber_peak(elastic_peak: ArrayLike, curve: StrainLife) -> np.ndarray:
    """Local stress (Pa, signed) at elastic peaks (Pa) by Neuber's rule on the cyclic curve."""
    peak = np.asarray(elastic_peak, dtype=float)
    return np.sign(peak) * _neuber_solve(peak, curve)


def _stress_amplitude_of(strain_amplitude: np.ndarray, curve: StrainLife) -> np.ndarray:
    """Inverse of the cyclic curve, σ_a with ε_a(σ_a) = the strain amplitude: the residual is
    convex increasing and E·ε_a bounds the root from above."""
    e = curve.youngs_modulus
    k, inv_n = curve.cyclic_strength_coefficient, 1.0 / curve.cyclic_hardening_exponent

    def residual(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        plastic = (s / k) ** inv_n
        return s / e + plastic - strain_amplitude, 1.0 / e + inv_n * plastic / np.maximum(s, 1e-30)

    return _monotone_newton(residual, e * strain_amplitude, strain_amplitude > 0.0)


def _mean_curve_life(strain_amplitude: np.ndarray, mean_stress: np.ndarray,
                     stress_amplitude: np.ndarray, curve: StrainLife,
                     correction: str) -> np.ndarray:
    """Cycles N solving the strain-life equation elementwise; in x = log10(2N) the residual
    (a sum of decaying exponentials minus the target) is convex and decreasing, so Newton from
    x = 0 converges from below. 0.5 if the first reversal fails, inf past 10²⁰ reversals."""
    e = curve.youngs_modulus
    sf, b = curve.fatigue_strength_coefficient, curve.fatigue_strength_exponent
    ef, c = curve.fatigue_ductility_coefficient, curve.fatigue_ductility_exponent
    ln10 = np.log(10.0)
    if correction == "swt":
        peak = mean_stress + stress_amplitude
        first, e1 = sf * sf / e, 2.0 * b
        second, e2 = sf * ef, b + c
        target = np.maximum(peak, 0.0) * strain_amplitude
        possible = peak > 0.0
    else:
        sm = mean_stress if correction == "morrow" else np.zeros_like(mean_stress)
        first, e1 = (sf - sm) / e, b
        second, e2 = ef, c
        target = strain_amplitude
        possible = sm < sf
    first = first * np.ones_like(target)

    def residual(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a, d = first * 10.0 ** (e1 * x), second * 10.0 ** (e2 * x)
        return a + d - target, ln10 * (e1 * a + e2 * d)

    at_start = residual(np.zeros_like(target))[0]
    at_end = residual(np.full_like(target, LOG_REVERSALS_MAX))[0]
    solve = possible & (at_start > 0.0) & (at_end < 0.0)
    x = _monotone_newton(residual, np.zeros_like(target), solve)
    life = np.where(at_start <= 0.0, 0.5, np.where(at_end >= 0.0, np.inf, 0.5 * 10.0 ** x))
    # Impossible cases: SWT with σ_max ≤ 0 never cracks; Morrow with σ_m ≥ σ'_f fails at once.
    return np.where(possible, life, np.inf if correction == "swt" else 0.5)


def _lives(strain_amplitude: np.ndarray, mean_stress: np.ndarray, stress_amplitude: np.ndarray,
           curve: StrainLife, correction: str, design: DesignFactors | None) -> np.ndarray:
    life = _mean_curve_life(strain_amplitude, mean_stress, stress_amplitude, curve, correction)
    if design is not None:
        factored_strain = design.strain * strain_amplitude
        factored = _mean_curve_life(factored_strain, mean_stress,
                                    _stress_amplitude_of(factored_strain, curve), curve,
                                    correction)
        life = np.minimum(factored, life / design.cycles)
    return np.where(strain_amplitude > 0.0, life, np.inf)


def cycles_to_failure(strain_amplitude: float, mean_stress: float, curve: StrainLife, *,
                      mean_stress_correction: str = "morrow",
                      design: DesignFactors | None = None) -> float:
    """Cycles to crack initiation for a local strain amplitude and mean stress (Pa); ``inf``
    beyond 10²⁰ reversals, 0.5 when the first reversal already fails. ``design`` applies the
    design-curve factors (min of the life at factor × strain and life / factor)."""
    _check_correction(mean_stress_correction)
    if not (np.isfinite(strain_amplitude) and strain_amplitude >= 0.0
            and np.isfinite(mean_stress)):
        raise RotorAreaError(f"strain amplitude must be finite and ≥ 0 and mean stress (Pa) "
                             f"finite, got {strain_amplitude!r}, {mean_stress!r}")
    amplitude = np.array([strain_amplitude], dtype=float)
    return float(_lives(amplitude, np.array([mean_stress], dtype=float),
                        _stress_amplitude_of(amplitude, curve), curve, mean_stress_correction,
                        design)[0])


def _check_correction(correction: str) -> None:
    if correction not in MEAN_STRESS_CORRECTIONS:
        raise RotorAreaError(f"mean_stress_correction must be one of {MEAN_STRESS_CORRECTIONS}, "
                             f"got {correction!r}")


def miner_damage(counts: ArrayLike, cycles_to_failure: ArrayLike) -> np.ndarray:
    """Miner's damage per cycle class, count / N (dimensionless). Counts must be ≥ 0 and lives
    > 0 (``inf`` for no damage)."""
    n = np.asarray(counts, dtype=float)
    life = np.asarray(cycles_to_failure, dtype=float)
    if n.shape != life.shape:
        raise RotorAreaError(f"Miner's sum: {n.shape} counts but {life.shape} lives")
    bad = np.flatnonzero(~np.isfinite(n) | (n < 0.0))
    if bad.size:
        raise RotorAreaError(f"Miner's sum: cycle count {float(n[bad[0]])!r} at class "
                             f"{bad[0]} must be finite and ≥ 0")
    bad = np.flatnonzero(np.isnan(life) | (life <= 0.0))
    if bad.size:
        raise RotorAreaError(f"Miner's sum: cycles to failure {float(life[bad[0]])!r} at class "
                             f"{bad[0]} must be > 0")
    return n / life


@dataclass(frozen=True)
class FatigueResult:
    """Rainflow cycles with their local strain, mean stress, life and damage (Miner)."""

    cycles: pd.DataFrame
    """Columns of :func:`rainflow_cycles` plus ``local_range_pa``, ``strain_range``,
    ``local_mean_pa``, ``cycles_to_failure``, ``damage`` (= count / cycles_to_failure)."""

    @property
    def total_damage(self) -> float:
        """Miner's sum over all cycles (dimensionless; 1 = crack initiation)."""
        return float(self.cycles["damage"].sum())

    def damage_per_window(self, edges: ArrayLike) -> np.ndarray:
        """Damage of the cycles that close (``end`` index) in each window [edges[i], edges[i+1])
        of sample indices: life per ramp or per day is this grouping."""
        bounds = np.asarray(edges, dtype=int)
        if bounds.ndim != 1 or bounds.size < 2 or np.any(np.diff(bounds) <= 0):
            raise RotorAreaError("window edges must be ≥ 2 strictly increasing sample indices")
        which = np.searchsorted(bounds, self.cycles["end"].to_numpy(), side="right") - 1
        inside = (which >= 0) & (which < bounds.size - 1)
        return np.bincount(which[inside], weights=self.cycles["damage"].to_numpy()[inside],
                           minlength=bounds.size - 1)


def fatigue_damage(stress: ArrayLike, temperature: ArrayLike, material: TabulatedSteel, *,
                   mean_stress_correction: str = "morrow",
                   design: DesignFactors | None = None,
                   strain_life: Callable[[ArrayLike], StrainLife] | None = None) -> FatigueResult:
    """Fatigue damage of an elastic stress series at the critical point (Pa, e.g. the signed
    von Mises or the largest principal stress at the groove) with its metal temperatures (K).

    ``strain_life`` replaces the steel's estimated constants (``material.strain_life``) with
    measured ones: a function of the temperatures (K, array) returning a :class:`StrainLife`
    with array fields. Raises :class:`RotorAreaError` for NaN samples or temperatures outside
    the strain-life data (0–550 °C for 30CrMoNiV5-11)."""
    _check_correction(mean_stress_correction)
    cycles = rainflow_cycles(stress, temperature)
    curve = (strain_life or material.strain_life)(cycles["temperature_k"].to_numpy())
    ranges, means = cycles["range_pa"].to_numpy(), cycles["mean_pa"].to_numpy()
    d_sigma, d_eps = neuber_range(ranges, curve)
    upper, lower = means + 0.5 * ranges, means - 0.5 * ranges
    peak_elastic = np.where(np.abs(upper) >= np.abs(lower), upper, lower)
    local_mean = neuber_peak(peak_elastic, curve) - np.sign(peak_elastic) * 0.5 * d_sigma
    cycles["local_range_pa"] = d_sigma
    cycles["strain_range"] = d_eps
    cycles["local_mean_pa"] = local_mean
    cycles["cycles_to_failure"] = _lives(0.5 * d_eps, local_mean, 0.5 * d_sigma, curve,
                                         mean_stress_correction, design)
    cycles["damage"] = miner_damage(cycles["count"], cycles["cycles_to_failure"])
    return FatigueResult(cycles)
