"""Can the data identify each parameter? A local, linearised practical-identifiability check.

At the calibrated point the residuals r (simulated − measured, every valid sample of every
selected sensor: in K weighted by √w, or, where the windows carry each sensor's instrument
error σ as a joint calibration's do, as the objective weighs them, r·√(ω·w)/σ — instrument
errors, so that a pressure in Pa and a temperature in K add up) are differentiated by central
differences with respect to the parameters scaled to their bounds, u = (x − low)/(high − low):
J = ∂r/∂u. To first order, moving
parameter i by δ (a fraction of its range) while the others move to compensate as well as they
can raises the sum of squares by δ²/(J^T J)⁻¹_ii (the Schur complement of the Gauss–Newton
Hessian; Bates & Watts 1988, *Nonlinear Regression Analysis*, §2.2; the same curvature that
profile likelihoods measure, Raue et al. 2009, *Bioinformatics* 25:1923, taken locally).

The check asks whether a shift of :data:`TEST_SHIFT` (10 % of the range) raises the RMSE by
more than the RMSE's own sampling uncertainty, RMSE/√(2·n_eff) (the standard error of a root
mean square of n_eff independent errors). Samples one second apart are not independent — the
instruments' lags and the metal make the residuals autocorrelated — so n_eff = n/τ with τ the
integrated autocorrelation time of the residuals (Sokal's self-consistent window, c = 5; Sokal
1997, *Monte Carlo Methods in Statistical Mechanics*). A parameter that fails is reported as not
identifiable from these windows: its value is then whatever compensated the others best.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem, Objective
from steamtwin.calibration.settings import PARAMETER_NAMES
from steamtwin.calibration.windowprep import predict_window
from steamtwin.model.parameters import ModelParameters

__all__ = [
    "TEST_SHIFT",
    "IdentifiabilityWarning",
    "check_identifiability",
    "identifiability",
    "integrated_time",
    "residual_unit",
    "warn_unidentifiable",
]

TEST_SHIFT = 0.10
"""Parameter shift (fraction of its bound range) whose RMSE rise must be detectable."""

_STEP = 1e-3  # central-difference step, fraction of the bound range


class IdentifiabilityWarning(UserWarning):
    """A parameter cannot be identified from the calibration windows."""


def _residuals(objective: Objective, params: ModelParameters) -> list[np.ndarray]:
    """Weighted residuals per window (K, or instrument errors where the window has σ: module
    docstring): rows = samples, one column per sensor, NaN if unused."""
    result = []
    for window in objective.windows:
        predicted = predict_window(objective.simulator, window, params, objective.sensors)
        if window.sigma is None:
            result.append((predicted - window.measured) * np.sqrt(objective.weights))
        else:
            result.append((predicted - window.measured)
                          * np.sqrt(window.weight * objective.weights) / window.sigma)
    return result


def residual_unit(objective: Objective) -> str:
    """The unit :func:`identifiability`'s RMSE figures are in: "K", or "σ" (instrument errors)
    when the windows carry each sensor's σ."""
    return "K" if all(window.sigma is None for window in objective.windows) else "σ"


def integrated_time(series: np.ndarray, window_factor: float = 5.0) -> float:
    """Integrated autocorrelation time (samples) of a series, Sokal's automatic window."""
    x = np.asarray(series, dtype=float)
    x = x[np.isfinite(x)] - np.nanmean(x)
    n = x.size
    if n < 4 or not np.any(x):
        return 1.0
    spectrum = np.fft.rfft(x, 2 * n)
    correlation = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    correlation /= correlation[0]
    tau = 1.0
    for lag in range(1, n):
        tau += 2.0 * correlation[lag]
        if lag >= window_factor * tau:
            break
    return float(max(tau, 1.0))


def identifiability(objective: Objective, params: ModelParameters,
                    bounds: dict[str, tuple[float, float]]) -> pd.DataFrame:
    """One row per parameter: ``rmse_rise`` for a :data:`TEST_SHIFT` shift with the others
    compensating, ``detectable_rise`` (RMSE/√(2·n_eff)) — both in ``attrs["unit"]``
    (:func:`residual_unit`) —, ``identifiable``, ``std_error`` (linearised standard error in
    the parameter's own units, from the residual variance and n_eff) and the correlation with
    each other parameter (``corr:<name>``)."""
    centre = np.array([getattr(params, name) for name in PARAMETER_NAMES])
    width = np.array([bounds[name][1] - bounds[name][0] for name in PARAMETER_NAMES])
    base = _residuals(objective, params)
    valid = [np.isfinite(r) for r in base]
    r0 = np.concatenate([r[v] for r, v in zip(base, valid, strict=True)])
    jacobian = np.empty((r0.size, centre.size))
    low = np.array([bounds[name][0] for name in PARAMETER_NAMES])
    high = np.array([bounds[name][1] for name in PARAMETER_NAMES])
    for i in range(centre.size):
        sides = []
        for sign in (1.0, -1.0):
            x = centre.copy()
            x[i] = np.clip(x[i] + sign * _STEP * width[i], low[i], high[i])
            shifted = _residuals(objective, ModelParameters(*x))
            flat = np.concatenate([r[v] for r, v in zip(shifted, valid, strict=True)])
            sides.append((x[i], flat))
        (x_up, r_up), (x_down, r_down) = sides
        jacobian[:, i] = (r_up - r_down) / ((x_up - x_down) / width[i])
    n = r0.size
    rmse = float(np.sqrt(np.mean(r0**2)))
    tau = float(np.mean([integrated_time(r[:, j]) for r in base for j in range(r.shape[1])
                         if np.isfinite(r[:, j]).sum() > 3]))
    n_effective = max(n / tau, 1.0)
    detectable = rmse / np.sqrt(2.0 * n_effective)
    information = jacobian.T @ jacobian
    inverse = np.linalg.pinv(information)
    rows = []
    for i, name in enumerate(PARAMETER_NAMES):
        # a parameter with no effect has a zero column: pinv gives it no variance, no rise
        rise_sse = TEST_SHIFT**2 / inverse[i, i] if inverse[i, i] > 0 else 0.0
        rise = float(np.sqrt(rmse**2 + rise_sse / n) - rmse)
        variance = rmse**2 * inverse[i, i] * n / n_effective if inverse[i, i] > 0 else np.inf
        row: dict[str, object] = {
            "parameter": name, "value": float(centre[i]), "rmse_rise": rise,
            "detectable_rise": float(detectable), "identifiable": bool(rise > detectable),
            "std_error": float(np.sqrt(max(variance, 0.0)) * width[i]),
        }
        for j, other in enumerate(PARAMETER_NAMES):
            if j != i:
                denominator = np.sqrt(inverse[i, i] * inverse[j, j])
                row[f"corr:{other}"] = float(inverse[i, j] / denominator) if denominator > 0 \
                    else np.nan
        rows.append(row)
    table = pd.DataFrame(rows).set_index("parameter")
    table.attrs.update(rmse=rmse, unit=residual_unit(objective), samples=n,
                       autocorrelation_time_samples=tau, effective_samples=n_effective)
    return table


def warn_unidentifiable(table: pd.DataFrame) -> list[str]:
    """Issue an :class:`IdentifiabilityWarning` per parameter the data cannot identify; returns
    the messages."""
    messages = []
    unit = table.attrs.get("unit", "K")
    for name, row in table.iterrows():
        if row["identifiable"]:
            continue
        message = (
            f"{name} is not identifiable from these windows: moving it by "
            f"{TEST_SHIFT:.0%} of its range (the others compensating) changes the RMSE by "
            f"{row['rmse_rise']:.3f} {unit}, less than the RMSE's own uncertainty "
            f"{row['detectable_rise']:.3f} {unit}{' (instrument errors)' if unit == 'σ' else ''};"
            f" its value {row['value']:.3f} is whatever fitted "
            f"best, not a measurement. Add windows where it acts (the heat-transfer coefficient "
            f"needs load ramps; the friction coefficient several loads)."
        )
        warnings.warn(message, IdentifiabilityWarning, stacklevel=4)
        messages.append(message)
    return messages


def check_identifiability(problem: CalibrationProblem, params: ModelParameters, rmse: float
                          ) -> pd.DataFrame | None:
    """:func:`identifiability` at a calibration result, warning per unidentifiable parameter;
    None when the result itself was rejected (RMSE at the penalty)."""
    if rmse >= PENALTY_RMSE:
        return None
    table = identifiability(problem.objective, params, problem.parameter_bounds)
    warn_unidentifiable(table)
    return table
