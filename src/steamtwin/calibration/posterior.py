"""Parameter uncertainty: the Laplace (Gauss–Newton) posterior at the MAP, a Gauss–Newton MAP
fit, and a random-walk Metropolis check.

(Over 500 lines for a reason: one method — the intervals of a calibration. Its parts share the
priors' normal coordinates, the standardised residuals' Jacobian and the residual time τ, and a
fifth of the module is this docstring, the method's statement with its sources.)

Coordinates
    Each parameter is handled in its prior's normal coordinate θ (x for a normal prior, ln x
    for a log-normal one), where the prior is N(m, s²); intervals are computed there and mapped
    back, so a log-normal parameter's interval is positive and asymmetric.

Laplace approximation (MacKay 2003, *Information Theory, Inference and Learning Algorithms*,
ch. 27; Bates & Watts 1988, §2.2 for the Gauss–Newton Hessian)
    With J = ∂r/∂θ of the standardised residuals r = √(ω w_s)·(T_sim − T_meas)/σ_s (central
    differences), the posterior precision at the MAP is ``H = J^T J / (τ·S²) + J_bᵀJ_b +
    diag(1/s²)`` and the covariance ``C = H⁻¹``; 95 % intervals are θ̂ ± 1.96 √C_ii mapped
    back to x. J_b is the Jacobian of the sensor-bias terms' prior rows b/β (the biases
    profiled out, :mod:`~steamtwin.calibration.objective`): a prior, so neither τ nor S
    scales it.

    * τ ≥ 1 is the residuals' integrated autocorrelation time (samples; Sokal's estimator as
      in :mod:`~steamtwin.calibration.identifiability`): the Gaussian likelihood counts every
      sample as independent, while lagged instruments and the model's own error make
      neighbouring residuals alike, so n samples carry the information of n/τ (the
      effective-sample-size correction; Sokal 1997).
    * S² = max(1, χ²/(n − p)) is the Birge ratio (Birge 1932, *Phys. Rev.* 40:207; the Particle
      Data Group's scale factor): when the model misses the data by more than the instruments'
      σ — a twin is never the plant — the spread of what it misses, not the instruments' σ,
      sets how well the data pin a parameter.

    Residuals that are white and of the stated σ give τ ≈ S ≈ 1 and the plain Laplace result.
    A parameter the data cannot see has a near-zero column of J: its interval is its prior's.

Tempered likelihood (:func:`likelihood_tempering`)
    The same κ = 1/(τ·S²) applied to the χ² the optimisers minimise makes the MAP the mode of
    the posterior whose width the intervals report (a "power likelihood", Grünwald & van
    Ommen 2017, *Bayesian Analysis* 12:1069, for misspecified models). Without it the
    instruments' σ and n independent samples let a parameter the data barely see (the
    heat-transfer coefficient on holds) follow thousands of samples' tiny preference to a bound
    while its interval spans the prior. The calibrators estimate κ once, at the priors'
    centres, before the search (``tempering="auto"``): residuals there are at least as large
    as at the MAP, so κ errs towards the prior.

Measured inputs (:data:`INPUT_UNCERTAINTIES`)
    The model runs on the DCS's measured boundary conditions, and each input instrument has a
    calibration error that stays put over the data (the plant's flow nozzle may read 1 % high
    for years). Such an error moves the MAP as a parameter would; the data cannot tell them
    apart. The MAP θ̂ is the minimiser of the objective the calibrators ran — κχ²/2 + Σz²/2
    with the tempering κ they fixed before the search (below) and the output sensors' biases
    profiled at that κ — so it is that estimator's response the input errors propagate
    through (GUM, JCGM 100:2008 §5.1: the measurement function is the estimator). By the
    implicit-function theorem on its stationarity condition (Gauss–Newton Hessian), the MAP
    moves by ``δθ = −H_κ⁻¹ J_κᵀ (∂r_κ/∂u) δu`` for an input error δu, with r_κ the
    objective's standardised residuals (κ-weighted, biases profiled), J_κ = ∂r_κ/∂θ and
    ``H_κ = J_κᵀJ_κ + diag(1/s²)``; an input error of standard uncertainty u_i adds
    ``g_i g_iᵀ`` with ``g_i = H_κ⁻¹ J_κᵀ (∂r_κ/∂u_i) u_i`` to the covariance (§5.1, the law
    of propagation of uncertainty; the input errors independent). Not the reported
    posterior's H = J^T J/(τS²) + …: where κ differs from 1/(τS²) (κ is estimated at the
    priors' centres) and a parameter leans on its prior or on a prior-held neighbour, that
    gain is not the MAP's. ∂r_κ/∂u_i comes from central differences of ±u_i on every
    window's input, for a thermocouple one offset over all windows as its calibration error
    is (an offset per window's mean temperature instead bends the load trend the friction
    coefficient is fitted to). The output thermocouples' own biases are integrated out as
    before, so an input error that only shifts a temperature's level is absorbed there.
    Checked on the virtual plant (seed 0, main-steam temperature ±1.24 K, recalibrated):
    the friction coefficient's ln moved by ∓0.064, this gain says 0.063; the reported
    posterior's weighting with an offset per window said 0.038 (docs/benchmarks.md). The
    intervals report the total ``C + Σ g_i g_iᵀ``; params.json keeps both parts.

Model discrepancy: the cluster-robust covariance (:func:`cluster_robust_covariance`)
    A twin is not its plant: its error at one load repeats in every sample there and varies
    smoothly across loads. The MAP then converges to a pseudo-true value that depends on how
    the loads are weighted (White 1982, *Econometrica* 50:1), and its scatter over what the
    plant could have done is set by how much each load band's residuals pull on it, not by
    the instruments' σ. A cluster-robust ("sandwich") covariance estimates that scatter from
    the bands themselves (Liang & Zeger 1986, *Biometrika* 73:13; as a posterior covariance
    under misspecification, Müller 2013, *Econometrica* 81:1805). With few clusters (a day
    has 5–7 bands) the plain sandwich (CR1) is biased low; its leave-one-cluster-out jackknife
    form (CV3) is not (if anything it errs wide), and takes Student's t with G − 1 degrees of
    freedom (MacKinnon, Nielsen & Webb 2023, *J. Econometrics* 232:272, §4–5; Cameron &
    Miller 2015, *J. Human Resources* 50:317, §VI). With the objective's own weighting κ
    (the tempered MAP minimises κ χ²/2 + Σ z²/2), the untempered standardised residuals r,
    J = ∂r/∂θ, and each cluster g (a load band; every ramp one band):
    ``A = κ JᵀJ + diag(1/s²)``, the MAP without band g one Newton step away,
    ``δ_g = κ (A − κ J_gᵀJ_g)⁻¹ J_gᵀ r_g``, and ``V = (G − 1)/G Σ_g δ_g δ_gᵀ``; the
    interval is ``θ̂ ± t_{G−1} √V_ii``. The δ_g are the per-band
    influence — which band pulls a parameter where. The bias terms' own rows stay in A (a
    prior on the biases, part of the estimator) but in no cluster; J is the profiled
    Jacobian (the biases refit), so a parameter that only moves a sensor's level has δ_g ≈ 0.
    For a correctly specified model with independent residuals and a weak prior, V ≈
    (JᵀJ)⁻¹ (the untempered Laplace covariance) within its sampling error (relative
    ≈ √(2/(G − 1))); where the bands disagree V grows with their disagreement. The reported
    interval per parameter is the wider of the Laplace interval and the robust one (each a
    lower bound on the uncertainty: the first from the residuals' size and correlation, the
    second from the bands' disagreement; ``method`` in :meth:`Posterior.table` says which
    made it), plus the inputs' term. Costs no model run beyond the Laplace posterior's.

MAP by Gauss–Newton (:func:`fit_map`)
    ``scipy.optimize.least_squares`` (trust-region reflective) on the stacked vector
    [r(θ); (θ − m)/s], whose half sum of squares is the negative log posterior: the cheap local
    path (tens of model runs) for a start near the optimum, for tests and for polishing.

MCMC check (:func:`metropolis`)
    Random-walk Metropolis (Metropolis et al. 1953) with Gaussian proposals of covariance
    (2.38²/d)·C (Gelman, Roberts & Gilks 1996, the optimal scale for a near-Gaussian target):
    where model runs are cheap (a small problem, a surrogate), its quantiles check the Laplace
    intervals.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, replace
from statistics import NormalDist

import numpy as np
import pandas as pd
from scipy.optimize import least_squares
from scipy.stats import t as student_t

from steamtwin.calibration.identifiability import integrated_time
from steamtwin.calibration.objective import Objective
from steamtwin.calibration.settings import PARAMETER_NAMES
from steamtwin.calibration.windowprep import (
    checked_inputs,
    predict_window,
    thermocouple_bias_spread,
)
from steamtwin.model.parameters import (
    PARAMETER_BOUNDS,
    PARAMETERS_SCHEMA_VERSION,
    ModelParameters,
    ParameterPrior,
)

__all__ = ["FLOW_MEASUREMENT_UNCERTAINTY", "INPUT_UNCERTAINTIES", "INTERVAL_PROBABILITY",
           "InputUncertainty", "Posterior", "cluster_robust_covariance", "fit_map",
           "input_covariance", "laplace_posterior", "likelihood_tempering", "metropolis",
           "window_clusters"]

INTERVAL_PROBABILITY = 0.95
"""Probability of the reported central posterior intervals."""

FLOW_MEASUREMENT_UNCERTAINTY = 0.015 / 1.96
"""Relative standard uncertainty of the main-steam flow measurement: a flow nozzle with its DP
transmitter, ±1.5 % of reading at 95 % (ISO 5167-3 nozzle discharge coefficient ±0.8-1.2 %
plus the transmitter; the virtual plant's instrument, :mod:`steamtwin.dcs.sensors`). The
measured flow is a model input, and by Stodola's cone law the control-stage pressure and the
expansion depend on m/φ: a flow reading biased by b is a flow coefficient biased by b, so the
data fix φ·(1 + b), not φ. The reported interval of the flow coefficient carries this constant
uncertainty beside the fit's own (measured on the virtual plant: its flow meter reads +1.06 %
high and both the joint calibration and the tracker sit +0.010…0.015 above the twin-equivalent
truth; docs/benchmarks.md). The tracker adds it to φ directly; the joint calibration propagates
it with the other inputs' (:data:`INPUT_UNCERTAINTIES`)."""



@dataclass(frozen=True)
class InputUncertainty:
    """Standard uncertainty of a measured input's calibration error: ``kind`` "relative"
    (``value`` a fraction of the reading), or "thermocouple" (IEC 60584-1 class 1 at the
    mean of the readings, read as a uniform bound: ``value`` unused — one offset for all of
    them, as a thermocouple's calibration error is over the narrow range a record spans);
    ``source`` says where it comes from."""

    kind: str
    value: float
    source: str

    def __post_init__(self) -> None:
        if self.kind not in ("relative", "thermocouple") or not (
                np.isfinite(self.value) and self.value >= 0.0):
            raise ValueError(f"InputUncertainty: kind must be 'relative' or 'thermocouple' and "
                             f"value a finite number ≥ 0 (got {self.kind!r}, {self.value!r})")

    def at(self, reading: np.ndarray) -> np.ndarray:
        """Standard uncertainty (SI) at each reading (SI)."""
        if self.kind == "relative":
            return self.value * np.abs(reading)
        return np.full_like(reading, thermocouple_bias_spread(float(np.nanmean(reading))))


INPUT_UNCERTAINTIES: dict[str, InputUncertainty] = {
    "main_steam_flow": InputUncertainty(
        "relative", FLOW_MEASUREMENT_UNCERTAINTY,
        "flow nozzle + DP transmitter, ±1.5 % of reading at 95 % (ISO 5167-3)"),
    "main_steam_temperature": InputUncertainty(
        "thermocouple", 0.0, "type K thermocouple, IEC 60584-1 class 1, uniform bound / √3"),
    "main_steam_pressure": InputUncertainty(
        "relative", 0.001 / np.sqrt(3.0),
        "smart pressure transmitter, ±0.1 % (IEC 60770-1 accuracy class 0.1, of a span taken "
        "as the reading), uniform bound / √3"),
    "hp_exhaust_pressure": InputUncertainty(
        "relative", 0.001 / np.sqrt(3.0),
        "smart pressure transmitter, ±0.1 % (IEC 60770-1 accuracy class 0.1, of a span taken "
        "as the reading), uniform bound / √3"),
}
"""The model inputs' calibration errors the intervals carry (module docstring), by signal."""

_STEP = 1e-4  # central-difference step in θ (a fraction of a per cent of any parameter)


@dataclass(frozen=True)
class Posterior:
    """Laplace posterior at ``map`` (:class:`ModelParameters`): ``theta`` (MAP in the priors'
    normal coordinates), ``covariance`` (in θ), ``priors`` (PARAMETER_NAMES order),
    ``autocorrelation_time`` (samples, τ), ``samples`` (residuals used), ``scale_factor``
    (the Birge ratio S, ≥ 1), ``input_covariance`` (θ; what the measured inputs' calibration
    errors add, :func:`input_covariance`; None: not propagated), ``input_sources`` (signal
    → the uncertainty it carried), ``robust_covariance`` (θ; the cluster-robust covariance V,
    :func:`cluster_robust_covariance`; None: not computed), ``clusters`` (the labels of
    the clusters it was computed over) and ``cluster_shifts`` (θ; per cluster, the MAP
    without it minus the MAP, one Newton step)."""

    map: ModelParameters
    theta: np.ndarray
    covariance: np.ndarray
    priors: tuple[ParameterPrior, ...]
    autocorrelation_time: float
    samples: int
    scale_factor: float = 1.0
    input_covariance: np.ndarray | None = None
    input_sources: tuple[tuple[str, str], ...] = ()
    robust_covariance: np.ndarray | None = None
    clusters: tuple[str, ...] = ()
    cluster_shifts: np.ndarray | None = None

    def without_cluster(self) -> dict[str, dict[str, float]]:
        """Per cluster (load band): each parameter's MAP without that band's data (one Newton
        step; module docstring) — which band pulls a parameter where. Empty without it."""
        if self.cluster_shifts is None:
            return {}
        return {name: {parameter: float(prior.from_internal(self.theta[i] + shift[i]))
                       for i, (parameter, prior) in enumerate(zip(PARAMETER_NAMES, self.priors,
                                                                  strict=True))}
                for name, shift in zip(self.clusters, self.cluster_shifts, strict=True)}

    def robust_factor(self, probability: float = INTERVAL_PROBABILITY) -> float:
        """t_{G−1}/z at ``probability``: the robust variance is scaled by its square so that
        ``z·σ`` spans the Student-t interval of G clusters (module docstring); 1 without it."""
        if self.robust_covariance is None:
            return 1.0
        tail = 0.5 + probability / 2.0
        return float(student_t.ppf(tail, len(self.clusters) - 1) / NormalDist().inv_cdf(tail))

    def fit_covariance(self, probability: float = INTERVAL_PROBABILITY
                       ) -> tuple[np.ndarray, list[str]]:
        """The fit's covariance in θ the intervals use and, per parameter, the method that
        made its variance: "laplace", or "cluster-robust" where the t-scaled sandwich is
        wider (module docstring). The variances are the wider of the two; the correlations
        the Laplace covariance's."""
        laplace = np.diag(self.covariance)
        if self.robust_covariance is None:
            return self.covariance, ["laplace"] * len(laplace)
        robust = np.diag(self.robust_covariance) * self.robust_factor(probability) ** 2
        variance = np.maximum(laplace, robust)
        scale = np.sqrt(variance / laplace)
        methods = ["cluster-robust" if r > v else "laplace" for r, v in zip(robust, laplace,
                                                                            strict=True)]
        return self.covariance * np.outer(scale, scale), methods

    @property
    def total_covariance(self) -> np.ndarray:
        """Covariance in θ the 95 % intervals report: the fit's (:meth:`fit_covariance`)
        plus the inputs'."""
        fit, _ = self.fit_covariance()
        return fit if self.input_covariance is None else fit + self.input_covariance

    def table(self, probability: float = INTERVAL_PROBABILITY) -> pd.DataFrame:
        """One row per parameter: ``map``, ``low``/``high`` (central interval, clipped to the
        physical bounds), ``method`` (what made it: "laplace" or "cluster-robust"), the two
        candidates ``laplace_low``/``laplace_high`` and ``robust_low``/``robust_high`` (NaN
        without clusters; each with the inputs' term), ``std`` (θ units: absolute for normal,
        relative for log-normal), ``robust_std`` (√V_ii, θ units, before the t factor), the
        prior's ``prior_center`` and interval ``prior_low``/``prior_high``, ``shrinkage``
        (Laplace posterior σ / prior σ in θ: ≈ 1 = the data add nothing), ``input_std`` and
        the posterior correlations ``corr:<name>``."""
        z = NormalDist().inv_cdf(0.5 + probability / 2.0)
        fit, methods = self.fit_covariance(probability)
        inputs = np.zeros_like(fit) if self.input_covariance is None else self.input_covariance
        total = fit + inputs
        std = np.sqrt(np.diag(total))
        laplace_std = np.sqrt(np.diag(self.covariance + inputs))
        robust_std = np.full(len(std), np.nan) if self.robust_covariance is None else \
            np.sqrt(np.diag(self.robust_covariance))
        robust_total = np.sqrt(robust_std**2 * self.robust_factor(probability) ** 2
                               + np.diag(inputs))
        fit_std = np.sqrt(np.diag(self.covariance))
        correlation = total / np.outer(std, std)
        rows = []
        for i, (name, prior) in enumerate(zip(PARAMETER_NAMES, self.priors, strict=True)):
            low, high = PARAMETER_BOUNDS[name]
            prior_low, prior_high = prior.interval(probability)

            def bound(half: float, i: int = i, prior: ParameterPrior = prior,
                      low: float = low, high: float = high) -> tuple[float, float]:
                if not np.isfinite(half):
                    return float("nan"), float("nan")
                return (float(np.clip(prior.from_internal(self.theta[i] - half), low, high)),
                        float(np.clip(prior.from_internal(self.theta[i] + half), low, high)))

            interval = bound(z * std[i])
            laplace = bound(z * laplace_std[i])
            robust = bound(z * robust_total[i])
            row: dict[str, object] = {
                "parameter": name, "map": getattr(self.map, name),
                "low": interval[0], "high": interval[1], "method": methods[i],
                "laplace_low": laplace[0], "laplace_high": laplace[1],
                "robust_low": robust[0], "robust_high": robust[1],
                "std": float(std[i]), "robust_std": float(robust_std[i]),
                "distribution": prior.distribution,
                "prior_center": prior.center, "prior_low": prior_low, "prior_high": prior_high,
                "shrinkage": float(fit_std[i] / prior.spread),
                "input_std": float(np.sqrt(max(total[i, i] - fit[i, i], 0.0))),
            }
            for j, other in enumerate(PARAMETER_NAMES):
                if j != i:
                    row[f"corr:{other}"] = float(correlation[i, j])
            rows.append(row)
        return pd.DataFrame(rows).set_index("parameter")

    def to_dict(self, probability: float = INTERVAL_PROBABILITY) -> dict[str, object]:
        """The ``posterior`` section of a parameter file (schema version
        :data:`~steamtwin.model.parameters.PARAMETERS_SCHEMA_VERSION`): per parameter the
        reported interval and the ``method`` that made it, beside both candidates."""
        table = self.table(probability)

        def number(value: object) -> float | None:
            return None if not np.isfinite(float(value)) else float(value)

        robust = {} if self.robust_covariance is None else {
            "robust": {"method": "cluster-robust (leave-one-band-out jackknife, CV3), "
                                 "Student t with G − 1 degrees of freedom",
                       "clusters": list(self.clusters),
                       "t_over_z": self.robust_factor(probability),
                       "map_without_band": self.without_cluster()}}
        return {
            "schema_version": PARAMETERS_SCHEMA_VERSION,
            "method": "laplace" if self.robust_covariance is None
            else "wider of laplace and cluster-robust",
            "probability": probability, "autocorrelation_time_samples": self.autocorrelation_time,
            "scale_factor": self.scale_factor, "samples": self.samples, **robust,
            "input_uncertainties": dict(self.input_sources),
            "intervals": {name: {"map": float(row["map"]), "low": float(row["low"]),
                                 "high": float(row["high"]), "method": str(row["method"]),
                                 "laplace_low": float(row["laplace_low"]),
                                 "laplace_high": float(row["laplace_high"]),
                                 "robust_low": number(row["robust_low"]),
                                 "robust_high": number(row["robust_high"]),
                                 "std": float(row["std"]),
                                 "robust_std": number(row["robust_std"]),
                                 "input_std": float(row["input_std"]),
                                 "shrinkage": float(row["shrinkage"])}
                          for name, row in table.iterrows()},
            "correlation": {name: {other: float(row[f"corr:{other}"])
                                   for other in PARAMETER_NAMES if other != name}
                            for name, row in table.iterrows()},
        }


def _priors(objective: Objective, priors: Mapping[str, ParameterPrior] | None
            ) -> tuple[ParameterPrior, ...]:
    if priors is not None:
        return tuple(priors[name] for name in PARAMETER_NAMES)
    if objective.priors is None:
        raise ValueError("a posterior needs priors: give them to the objective or here")
    return objective.priors


def _to_params(theta: np.ndarray, priors: tuple[ParameterPrior, ...]) -> ModelParameters:
    values = {}
    for name, prior, t in zip(PARAMETER_NAMES, priors, theta, strict=True):
        low, high = PARAMETER_BOUNDS[name]
        values[name] = float(np.clip(prior.from_internal(float(t)), low, high))
    return ModelParameters(**values)


def _theta_bounds(priors: tuple[ParameterPrior, ...]) -> tuple[np.ndarray, np.ndarray]:
    low = np.array([p.to_internal(PARAMETER_BOUNDS[n][0])
                    for n, p in zip(PARAMETER_NAMES, priors, strict=True)])
    high = np.array([p.to_internal(PARAMETER_BOUNDS[n][1])
                     for n, p in zip(PARAMETER_NAMES, priors, strict=True)])
    return low, high


def laplace_posterior(objective: Objective, params: ModelParameters,
                      priors: Mapping[str, ParameterPrior] | None = None, *,
                      inflate: bool = True,
                      inputs: Mapping[str, InputUncertainty] | None = None,
                      clusters: Sequence[Hashable] | None = None) -> Posterior:
    """Laplace posterior at ``params`` (the MAP; module docstring). ``priors`` default to the
    objective's; ``inflate=False`` takes τ = S = 1 (independent residuals of the stated
    σ); ``inputs``: the measured inputs' calibration errors to propagate (e.g.
    :data:`INPUT_UNCERTAINTIES`; those the model does not take are skipped); ``clusters``:
    one label per objective window (e.g. its load band, :func:`window_clusters`) for the
    cluster-robust sandwich beside the Laplace covariance (None, or fewer than two distinct
    labels: Laplace only). Costs 1 + 2·3 model runs per window, and 2 per propagated
    input."""
    prior_tuple = _priors(objective, priors)
    theta = np.array([p.to_internal(getattr(params, n))
                      for n, p in zip(PARAMETER_NAMES, prior_tuple, strict=True)])
    low, high = _theta_bounds(prior_tuple)
    parts = objective.residual_parts(params)
    base = objective.standardise(parts)
    kappa = objective.tempering  # undo the objective's tempering: τ and S give it anew
    data = objective.data_rows()  # the samples' rows; the bias priors' rows follow
    tau = _residual_time(objective, params) if inflate else 1.0
    freedom = objective.weighted_count() - theta.size
    scale = float(np.sqrt(max(1.0, base[:data] @ base[:data] / kappa / freedom))) \
        if inflate and freedom > 0 else 1.0
    # the posterior the intervals report: the likelihood weighted 1/(τ S²), the bias priors
    # at full weight, the biases profiled at that weight
    laplace = replace(objective, tempering=1.0 / (tau * scale**2))
    jacobian = np.empty((base.size, theta.size))  # of the objective's residuals (κ)
    weighted = np.empty((base.size, theta.size))  # of the reported posterior's
    for i in range(theta.size):
        up, down = theta.copy(), theta.copy()
        up[i], down[i] = min(theta[i] + _STEP, high[i]), max(theta[i] - _STEP, low[i])
        runs = [objective.residual_parts(_to_params(x, prior_tuple)) for x in (up, down)]
        for target, scored in ((jacobian, objective), (weighted, laplace)):
            target[:, i] = (scored.standardise(runs[0]) - scored.standardise(runs[1])) / (
                up[i] - down[i])
    prior_precision = np.diag([1.0 / p.spread**2 for p in prior_tuple])
    precision = weighted.T @ weighted + prior_precision
    covariance = np.linalg.inv(precision)
    posterior = Posterior(params, theta, covariance, prior_tuple, tau, int(base.size), scale)
    if clusters is not None:
        labels = _row_clusters(objective, clusters, base.size)
        if len(set(labels) - {None}) >= 2:
            robust, names, shifts = cluster_robust_covariance(
                jacobian / np.sqrt(kappa), base / np.sqrt(kappa), labels, prior_precision,
                weight=kappa)
            posterior = replace(posterior, robust_covariance=robust, clusters=names,
                                cluster_shifts=shifts)
    if not inputs:
        return posterior
    # the MAP's own response: the objective it minimised (κ, its biases profiled at κ), not
    # the reported posterior's weighting 1/(τ S²) (module docstring, "Measured inputs")
    gain = np.linalg.solve(jacobian.T @ jacobian + prior_precision, jacobian.T)
    used = {name: u for name, u in inputs.items()
            if name in objective.simulator.input_signals}
    covariance_in, rejected = input_covariance(objective, params, gain, used)
    return replace(posterior, input_covariance=covariance_in, input_sources=tuple(
        (name, f"not propagated: the model rejects the inputs with {name} moved by ±{u.source}"
         if name in rejected else u.source) for name, u in used.items()))


def cluster_robust_covariance(jacobian: np.ndarray, residuals: np.ndarray,
                              clusters: Sequence[Hashable | None],
                              prior_precision: np.ndarray, *, weight: float = 1.0
                              ) -> tuple[np.ndarray, tuple[str, ...], np.ndarray]:
    """Cluster-robust covariance (the leave-one-cluster-out jackknife, CV3; module
    docstring) of the estimate minimising ``weight``·Σ r²/2 + (θ − m)ᵀ P (θ − m)/2, from the
    Jacobian (rows, p) of the residuals (rows) at it, each row's cluster label (None: a row
    in A only, e.g. a bias term's) and the prior precision P (p, p; zeros for none):
    A = weight·JᵀJ + P, δ_g = weight·(A − weight·J_gᵀJ_g)⁻¹ J_gᵀ r_g (the estimate without
    cluster g, one Newton step) and V = (G − 1)/G Σ_g δ_g δ_gᵀ. Returns V (θ units²), the
    G cluster labels (as text, in first-seen order) and the shifts δ (G, p; θ units: the
    estimate without each cluster minus the estimate); ValueError for fewer than 2."""
    labels = list(clusters)
    if len(labels) != len(residuals) or jacobian.shape[0] != len(residuals):
        raise ValueError(f"cluster_robust_covariance: {len(labels)} labels, "
                         f"{len(residuals)} residuals and {jacobian.shape[0]} Jacobian rows "
                         "must agree")
    names = list(dict.fromkeys(label for label in labels if label is not None))
    if len(names) < 2:
        raise ValueError(f"cluster_robust_covariance: needs at least 2 clusters (got "
                         f"{len(names)})")
    index = {name: k for k, name in enumerate(names)}
    rows = np.array([index[label] if label is not None else -1 for label in labels])
    precision = weight * jacobian.T @ jacobian + prior_precision
    g = len(names)
    shifts = np.empty((g, jacobian.shape[1]))
    for k in range(g):
        part = jacobian[rows == k]
        # the estimate without cluster k, one Newton step from the full one (exact if linear)
        shifts[k] = weight * np.linalg.solve(precision - weight * part.T @ part,
                                             part.T @ residuals[rows == k])
    return (g - 1.0) / g * shifts.T @ shifts, tuple(str(name) for name in names), shifts


def window_clusters(windows: object) -> list[str] | None:
    """Cluster label of each calibration window: its load band for a
    :class:`~steamtwin.calibration.windowset.WindowSet` (every ramp one band; the bands are
    what the model's error repeats over, module docstring), None for plain frames."""
    bands = getattr(windows, "bands", None)
    return list(bands()) if callable(bands) else None


def _row_clusters(objective: Objective, clusters: Sequence[Hashable], rows: int
                  ) -> list[Hashable | None]:
    """Each standardised residual's cluster: its window's label, None for the bias terms."""
    labels = list(clusters)
    if len(labels) != len(objective.windows):
        raise ValueError(f"clusters: expected one label per window ({len(objective.windows)}), "
                         f"got {len(labels)}")
    per_row: list[Hashable | None] = []
    for window, label in zip(objective.windows, labels, strict=True):
        per_row += [label] * int((~np.isnan(window.measured)).sum())
    return per_row + [None] * (rows - len(per_row))


def input_covariance(objective: Objective, params: ModelParameters, gain: np.ndarray,
                     inputs: Mapping[str, InputUncertainty]) -> tuple[np.ndarray, list[str]]:
    """Σ_i g_i g_iᵀ (θ units): the covariance the inputs' calibration errors add (module
    docstring), with ``gain`` = H_κ⁻¹J_κᵀ of ``objective``'s standardised residuals at
    ``params`` (the objective the MAP minimised, with its own κ) and g_i the MAP's shift
    for each input moved by its standard uncertainty (central differences; one side where
    the model rejects the other); and the inputs the model rejects moved either way (not
    propagated: the caller says so)."""
    total = np.zeros((gain.shape[0], gain.shape[0]))
    rejected: list[str] = []
    for name, uncertainty in inputs.items():
        # the readings of every window at once: a thermocouple's error is one offset over the
        # whole record (InputUncertainty.at), not one per window's mean temperature
        readings = [window.inputs[name].to_numpy(dtype=float) for window in objective.windows]
        offsets = np.split(uncertainty.at(np.concatenate(readings)),
                           np.cumsum([len(r) for r in readings])[:-1])
        shifted = []
        for sign in (1.0, -1.0):
            try:
                moved = replace(objective, windows=tuple(
                    _moved_input(objective, window, name, sign * offset)
                    for window, offset in zip(objective.windows, offsets, strict=True)))
                shifted.append((sign, moved.standardised_residuals(params)))
            except ValueError:
                continue
        if not shifted:
            rejected.append(name)
            continue
        if len(shifted) == 2:
            difference = (shifted[0][1] - shifted[1][1]) / 2.0
        else:
            sign, residuals = shifted[0]
            difference = sign * (residuals - objective.standardised_residuals(params))
        g = gain @ difference
        total += np.outer(g, g)
    return total, rejected


def _moved_input(objective: Objective, window, name: str, offset: np.ndarray):
    """``window`` with input ``name`` moved by ``offset`` (SI, per sample), checked anew."""
    inputs = window.inputs.copy()
    inputs[name] = inputs[name].to_numpy(dtype=float) + offset
    return replace(window, inputs=inputs,
                   checked=checked_inputs(objective.simulator, inputs))


def _residual_time(objective: Objective, params: ModelParameters) -> float:
    """Mean integrated autocorrelation time (samples) of the per-window, per-sensor residuals."""
    times = []
    for window in objective.windows:
        residual = predict_window(objective.simulator, window, params, objective.sensors) \
            - window.measured
        times.extend(integrated_time(residual[:, j]) for j in range(residual.shape[1])
                     if np.isfinite(residual[:, j]).sum() > 3)
    return float(np.mean(times)) if times else 1.0


def likelihood_tempering(objective: Objective, params: ModelParameters) -> float:
    """κ = 1/(τ·S²) ∈ (0, 1] at ``params`` (module docstring): how much of its naive weight
    the likelihood deserves given the residuals' autocorrelation time τ and Birge ratio S."""
    residuals = objective.standardised_residuals(params)[:objective.data_rows()]
    freedom = max(objective.weighted_count() - len(PARAMETER_NAMES), 1.0)
    ratio = max(1.0, residuals @ residuals / objective.tempering / freedom)
    return float(1.0 / (_residual_time(objective, params) * ratio))


def fit_map(objective: Objective, start: ModelParameters | None = None,
            priors: Mapping[str, ParameterPrior] | None = None) -> ModelParameters:
    """MAP by Gauss–Newton/trust region from ``start`` (default the priors' centres) within
    the physical bounds (module docstring); raises ValueError if the model rejects a step."""
    prior_tuple = _priors(objective, priors)
    start = start or ModelParameters(**{n: p.center for n, p in
                                        zip(PARAMETER_NAMES, prior_tuple, strict=True)})
    theta0 = np.array([p.to_internal(getattr(start, n))
                       for n, p in zip(PARAMETER_NAMES, prior_tuple, strict=True)])
    means = np.array([p.mean_internal for p in prior_tuple])
    spreads = np.array([p.spread for p in prior_tuple])

    def residuals(theta: np.ndarray) -> np.ndarray:
        data = objective.standardised_residuals(_to_params(theta, prior_tuple))
        return np.concatenate([data, (theta - means) / spreads])

    low, high = _theta_bounds(prior_tuple)
    result = least_squares(residuals, np.clip(theta0, low, high), bounds=(low, high),
                           method="trf", diff_step=_STEP, x_scale=spreads)
    return _to_params(result.x, prior_tuple)


def metropolis(log_posterior: Callable[[np.ndarray], float], start: np.ndarray,
               covariance: np.ndarray, n_steps: int, *, random_state: int = 0) -> np.ndarray:
    """Random-walk Metropolis chain (n_steps, d) from ``start`` with proposal covariance
    (2.38²/d)·``covariance`` (module docstring); ``log_posterior`` returns −inf outside the
    support."""
    random = np.random.default_rng(random_state)
    d = len(start)
    factor = np.linalg.cholesky(2.38**2 / d * np.asarray(covariance, dtype=float))
    chain = np.empty((n_steps, d))
    current, current_lp = np.asarray(start, dtype=float), log_posterior(start)
    for step in range(n_steps):
        proposal = current + factor @ random.standard_normal(d)
        proposal_lp = log_posterior(proposal)
        if np.log(random.random()) < proposal_lp - current_lp:
            current, current_lp = proposal, proposal_lp
        chain[step] = current
    return chain
