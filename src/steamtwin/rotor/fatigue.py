"""Low-cycle fatigue of the rotor from an elastic stress history at the critical point.

Steps (Dowling, *Mechanical Behavior of Materials*, 4th ed., 2013, ch. 14):

1. **Rainflow counting** per ASTM E1049-85 (2017) §5.4.4 with the maintained ``rainflow``
   package (3-point algorithm; half cycles from the residue), giving for each cycle its stress
   range, mean, count (0.5 or 1), and the start/end sample indices.
2. **Neuber's rule** (Neuber, J. Appl. Mech. 28 (1961) 544): the local elastic-plastic stress and
   strain satisfy σ·ε = σ_e²/E, with the cyclic Ramberg–Osgood curve ε = σ/E + (σ/K')^(1/n') for
   the largest-magnitude peak and Masing's doubled curve Δε = Δσ/E + 2(Δσ/2K')^(1/n') for the
   range (Dowling §14.5). The local mean stress is that peak minus (toward) half the range.
3. **Manson–Coffin–Basquin** with **Morrow's mean-stress correction** (Dowling eq. 14.23):
   ε_a = (σ'_f − σ_m)/E·(2N)^b + ε'_f·(2N)^c, solved for N by Brent's method in log10(2N).
   Morrow is the default: Dowling (Int. J. Fatigue 31 (2009) 1004) finds it accurate for steels,
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
from scipy.optimize import brentq

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
    frame = pd.DataFrame(rows, columns=["range_pa", "mean_pa", "count", "start", "end"])
    frame = frame.astype({"range_pa": float, "mean_pa": float, "count": float,
                          "start": int, "end": int})
    frame["temperature_k"] = np.maximum(t[frame["start"].to_numpy()], t[frame["end"].to_numpy()])
    return frame


def _neuber_solve(elastic: float, strain_of: Callable[[float], np.ndarray],
                  modulus: float) -> float:
    """σ ≥ 0 with σ·ε(σ) = elastic²/E (the elastic value is the upper bracket)."""
    if elastic <= 0.0:
        return 0.0
    target = elastic * elastic / modulus
    return brentq(lambda s: s * strain_of(s) - target, 0.0, elastic, xtol=1e-9 * elastic,
                  rtol=1e-13)


def neuber_range(elastic_range: float, curve: StrainLife) -> tuple[float, float]:
    """Local (stress range Pa, strain range) of an elastic stress range (Pa) by Neuber's rule on
    Masing's doubled cyclic curve."""
    stress = 2.0 * _neuber_solve(0.5 * abs(elastic_range), curve.strain_amplitude,
                                 curve.youngs_modulus)
    return stress, 2.0 * float(curve.strain_amplitude(0.5 * stress))


def neuber_peak(elastic_peak: float, curve: StrainLife) -> float:
    """Local stress (Pa, signed) at an elastic peak (Pa) by Neuber's rule on the cyclic curve."""
    return float(np.sign(elastic_peak)) * _neuber_solve(abs(elastic_peak),
                                                        curve.strain_amplitude,
                                                        curve.youngs_modulus)


def _mean_curve_life(strain_amplitude: float, mean_stress: float, curve: StrainLife,
                     correction: str) -> float:
    e = curve.youngs_modulus
    sf, b = curve.fatigue_strength_coefficient, curve.fatigue_strength_exponent
    ef, c = curve.fatigue_ductility_coefficient, curve.fatigue_ductility_exponent
    if correction == "swt":
        peak = mean_stress + float(_stress_amplitude_of(strain_amplitude, curve))
        if peak <= 0.0:
            return np.inf
        target = peak * strain_amplitude

        def residual(log_rev: float) -> float:
            rev = 10.0 ** log_rev
            return sf * sf / e * rev ** (2 * b) + sf * ef * rev ** (b + c) - target
    else:
        sm = mean_stress if correction == "morrow" else 0.0
        if sm >= sf:
            return 0.5
        target = strain_amplitude

        def residual(log_rev: float) -> float:
            rev = 10.0 ** log_rev
            return (sf - sm) / e * rev ** b + ef * rev ** c - target
    if residual(0.0) <= 0.0:
        return 0.5
    if residual(LOG_REVERSALS_MAX) >= 0.0:
        return np.inf
    return 0.5 * 10.0 ** brentq(residual, 0.0, LOG_REVERSALS_MAX, xtol=1e-12)


def _stress_amplitude_of(strain_amplitude: float, curve: StrainLife) -> float:
    """Inverse of the cyclic curve: σ_a with ε_a(σ_a) = the given strain amplitude."""
    upper = curve.youngs_modulus * strain_amplitude
    if upper <= 0.0:
        return 0.0
    return brentq(lambda s: float(curve.strain_amplitude(s)) - strain_amplitude, 0.0, upper,
                  xtol=1e-9 * upper)


def cycles_to_failure(strain_amplitude: float, mean_stress: float, curve: StrainLife, *,
                      mean_stress_correction: str = "morrow",
                      design: DesignFactors | None = None) -> float:
    """Cycles to crack initiation for a local strain amplitude and mean stress (Pa); ``inf``
    beyond 10²⁰ reversals, 0.5 when the first reversal already fails. ``design`` applies the
    design-curve factors (min of the life at factor × strain and life / factor)."""
    if mean_stress_correction not in MEAN_STRESS_CORRECTIONS:
        raise RotorAreaError(f"mean_stress_correction must be one of {MEAN_STRESS_CORRECTIONS}, "
                             f"got {mean_stress_correction!r}")
    if not (np.isfinite(strain_amplitude) and strain_amplitude >= 0.0
            and np.isfinite(mean_stress)):
        raise RotorAreaError(f"strain amplitude must be finite and ≥ 0 and mean stress (Pa) "
                             f"finite, got {strain_amplitude!r}, {mean_stress!r}")
    if strain_amplitude == 0.0:
        return np.inf
    life = _mean_curve_life(strain_amplitude, mean_stress, curve, mean_stress_correction)
    if design is None:
        return life
    factored = _mean_curve_life(design.strain * strain_amplitude, mean_stress, curve,
                                mean_stress_correction)
    return min(factored, life / design.cycles)


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
                   design: DesignFactors | None = None) -> FatigueResult:
    """Fatigue damage of an elastic stress series at the critical point (Pa, e.g. the signed
    von Mises or the largest principal stress at the groove) with its metal temperatures (K).

    Raises :class:`RotorAreaError` for NaN samples or temperatures outside the steel's
    strain-life data (0–550 °C for 30CrMoNiV5-11)."""
    cycles = rainflow_cycles(stress, temperature)
    local_range, strain_range, local_mean, life = [], [], [], []
    curves: dict[float, StrainLife] = {}
    for rng, mean, temp in cycles[["range_pa", "mean_pa", "temperature_k"]].itertuples(
            index=False):
        curve = curves.get(temp)
        if curve is None:
            curve = curves[temp] = material.strain_life(temp)
        d_sigma, d_eps = neuber_range(rng, curve)
        peak_elastic = mean + 0.5 * rng if abs(mean + 0.5 * rng) >= abs(mean - 0.5 * rng) \
            else mean - 0.5 * rng
        peak = neuber_peak(peak_elastic, curve)
        mean_local = peak - np.sign(peak_elastic) * 0.5 * d_sigma
        local_range.append(d_sigma)
        strain_range.append(d_eps)
        local_mean.append(mean_local)
        life.append(cycles_to_failure(0.5 * d_eps, mean_local, curve,
                                      mean_stress_correction=mean_stress_correction,
                                      design=design))
    cycles["local_range_pa"] = np.array(local_range, dtype=float)
    cycles["strain_range"] = np.array(strain_range, dtype=float)
    cycles["local_mean_pa"] = np.array(local_mean, dtype=float)
    cycles["cycles_to_failure"] = np.array(life, dtype=float)
    cycles["damage"] = miner_damage(cycles["count"], cycles["cycles_to_failure"])
    return FatigueResult(cycles)
