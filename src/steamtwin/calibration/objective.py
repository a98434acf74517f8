"""The calibration objective: RMSE (K) between simulated and measured DCS temperatures.

Method (Wang et al.): the GA's fitness is ``1 / (RMSE + ε)``. Maximising it is equivalent to
minimising the RMSE, which is what :class:`CalibrationProblem` hands pymoo (``F = RMSE``); the
fitness is reported alongside (:func:`fitness`).

Objective
    ``RMSE = sqrt(Σ_s w_s Σ_i (T_sim − T_meas)² / Σ_s w_s n_s)`` over all windows and the selected
    sensors ``s`` (K), pooled: every valid sample counts once, so longer windows weigh more.
    Weights are relative (default 1 each). Measured NaN samples are excluded and counted.

Missing inputs (explicit choice)
    Rows before the first row with every input valid are dropped (counted as ``dropped_rows``).
    Later NaN inputs are filled forward from the last valid value when the dropout lasts at most
    ``max_input_gap_s`` (default 60 s, a few boiler-side time constants shorter than any input
    dynamics the HP temperatures follow) and counted (``filled_rows``); a longer dropout is a
    ``ValueError`` naming window, signal and time — split the window instead.

Posterior score (joint calibration with priors)
    With per-sample window weights ω (a :class:`~steamtwin.calibration.windowset.WindowSet`'s
    load-band weights; 1 for plain frames), the measurement error σ_s per sensor (K; default
    1 K) and priors per parameter, the Gaussian likelihood and the priors give the negative log
    posterior ``NLP = ½ (χ² + Σ_k z_k²)`` with ``χ² = Σ_w ω_w Σ_s w_s Σ_i (T_sim − T_meas)²/σ_s²``
    and ``z_k = (θ_k − m_k)/s_k`` in each prior's normal coordinate θ (x, or ln x for a
    log-normal prior; Gelman et al. 2013, *Bayesian Data Analysis*, §4.1). What the optimisers
    minimise is the *score* ``sqrt((χ² + Σ z²/κ) / Σ_w ω_w Σ_s w_s n_ws)``, a monotone function
    of the NLP with the likelihood tempered by κ ∈ (0, 1] (``Objective.tempering``; 1 = none),
    ``κχ² + Σz²``, so its minimum is the MAP, on the scale of the σ-normalised RMSE whatever
    κ. Without priors and with σ = 1 K the score is the RMSE above (K), the method's own
    objective. The RMSE itself is reported alongside.

Sensor biases (``sensor_bias``)
    A thermocouple's calibration error is constant over a day, not noise: IEC 60584-1 class 1
    allows ± max(1.5 K, 0.004·|t|) (t in °C). Counting it as independent noise would let the
    biases pose as parameter information (and give intervals far too narrow). Each sensor of
    each instrument set (``group``: one historian file) gets a constant bias b ~ N(0, β²),
    β = tolerance/√3 (a tolerance bound read as a uniform distribution, GUM JCGM 100:2008
    §4.3.7), integrated out analytically: per group and sensor, with precisions p = w_s ω/σ²,
    ``χ² = Σ p r² − (Σ p r)² / (Σ p + 1/β²)`` (the Gaussian integral over b; Kennedy &
    O'Hagan 2001, *J. R. Stat. Soc. B* 63:425, treat a model–data offset the same way). The
    calibration then learns from how the temperatures change across loads and time, not from
    their absolute level, which the thermocouples cannot vouch for.

    Tempering tempers the likelihood only (a power likelihood, Grünwald & van Ommen 2017;
    Bissiri, Holmes & Walker 2016, *J. R. Stat. Soc. B* 78:1103: the prior is not raised to
    κ). The bias prior b ~ N(0, β²) is a prior like the parameters', so what the optimisers
    minimise is ``κ Σ p (r − b)² + b²/β² + Σ z²`` with b profiled out:
    ``κχ² = κ Σ p r² − (κ Σ p r)² / (κ Σ p + 1/β²)``, i.e. the formula above with
    1/β² → 1/(κβ²) in the score's χ²-scale. Tempering χ² *after* the integral instead (the
    first version) weakened the offsets' class-1 prior by κ (≈ 1/4000 on the virtual plant's
    day): the offsets ran to 2.5× their tolerance/√3 to trade with the friction coefficient,
    whose prior kept its full weight (docs/benchmarks.md, "The offsets' class-1 prior").

Infeasible candidates
    When the simulator rejects a candidate (``ValueError``, e.g. the FOM's ``InputError`` for a
    flow coefficient too low to pass rated flow) or returns non-finite temperatures at valid
    samples, the evaluation scores :data:`PENALTY_RMSE` = 1000 K: finite, so the GA keeps
    ranking, and far above any feasible RMSE (temperature errors of a feasible model are tens of
    K at most), so penalised candidates always lose tournaments and never survive elitism.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import NamedTuple

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem

from steamtwin.cache import njit
from steamtwin.calibration.settings import PARAMETER_NAMES, ObjectiveSettings, check_bounds
from steamtwin.calibration.windowprep import (
    PreparedWindow,
    predict_window,
    prepare_window,
    squared_errors,
    with_bias_spread,
)
from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.parameters import ModelParameters, ParameterPrior
from steamtwin.model.simulator import Simulator

__all__ = [
    "FITNESS_EPSILON",
    "PENALTY_RMSE",
    "CalibrationProblem",
    "Evaluation",
    "Objective",
    "fitness",
    "window_rmse",
]

PENALTY_RMSE = 1.0e3
"""Objective (K) of a candidate the simulator rejects (see the module docstring)."""

FITNESS_EPSILON = 1.0e-6
"""ε (K) in the method's fitness ``1 / (RMSE + ε)``."""


def fitness(rmse: float | np.ndarray) -> float | np.ndarray:
    """The method's fitness ``1 / (RMSE + ε)`` (1/K) of an RMSE in K."""
    value = 1.0 / (np.asarray(rmse, dtype=float) + FITNESS_EPSILON)
    return float(value) if value.ndim == 0 else value



@dataclass(frozen=True)
class Evaluation:
    """One candidate's result: ``rmse`` (K; :data:`PENALTY_RMSE` if rejected), why, and the
    ``score`` the optimisers minimise (the posterior score; equal to ``rmse`` without priors
    and with σ = 1 K; None = ``rmse``)."""

    rmse: float
    error: str = ""
    score: float | None = None

    @property
    def value(self) -> float:
        """What the optimisers minimise: ``score``, or ``rmse`` when no score was set."""
        return self.rmse if self.score is None else self.score

    @property
    def penalised(self) -> bool:
        """True when the simulator rejected the candidate."""
        return bool(self.error)


@dataclass(frozen=True)
class Objective:
    """What scores a candidate: weighted pooled RMSE (K) of ``simulator`` over ``windows`` and
    the posterior score (module docstring) with ``priors`` (one per parameter, in
    PARAMETER_NAMES order; None = no prior term) and the likelihood tempered by
    ``tempering`` κ ∈ (0, 1] (χ² counts κ-fold; see
    :func:`~steamtwin.calibration.posterior.likelihood_tempering`).

    Picklable and self-contained: this is what evaluators send to their workers once.
    """

    simulator: Simulator
    windows: tuple[PreparedWindow, ...]
    sensors: tuple[str, ...]
    weights: np.ndarray
    priors: tuple[ParameterPrior, ...] | None = None
    tempering: float = 1.0

    def prior_terms(self, x: Sequence[float]) -> np.ndarray:
        """z_k = (θ_k − m_k)/s_k per parameter (empty without priors)."""
        if self.priors is None:
            return np.empty(0)
        return np.array([(prior.to_internal(float(v)) - prior.mean_internal) / prior.spread
                         for prior, v in zip(self.priors, x, strict=True)])

    def residual_parts(self, params: ModelParameters) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per window: residuals T_sim − T_meas (samples, sensors; K; NaN where not measured)
        and each sensor's precision w_s·ω/σ_s² (1/K²); raises if the model rejects ``params``."""
        parts = []
        for window in self.windows:
            predicted = predict_window(self.simulator, window, params, self.sensors)
            valid = ~np.isnan(window.measured)
            if not np.isfinite(predicted[valid]).all():
                raise ValueError("the simulator returned non-finite temperatures")
            sigma = np.ones(len(self.sensors)) if window.sigma is None else window.sigma
            parts.append((predicted - window.measured, window.weight * self.weights / sigma**2))
        return parts

    def _bias_sums(self, parts: list[tuple[np.ndarray, np.ndarray]]
                   ) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per instrument group and sensor: A = Σ p, B = Σ p·r over its windows' valid samples
        and 1/(κβ²) — the bias prior's precision on the untempered χ² scale, so that it keeps
        its full weight in κχ² (module docstring) — +inf where a sensor has no bias term, so
        that B²/(A + 1/(κβ²)) vanishes."""
        return self._group_sums([_residual_sums(residual, ~np.isnan(residual))
                                 for residual, _ in parts])

    def _group_sums(self, sums: list[tuple[np.ndarray, np.ndarray]]
                    ) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """:meth:`_bias_sums` from each window's per-sensor Σ r and Σ r²
        (:func:`_residual_sums`)."""
        grouped: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        for window, constants, (sum_r, _) in zip(self.windows, self._window_constants, sums,
                                                  strict=True):
            a = constants.precision * constants.counts
            b = constants.precision * sum_r
            if window.group in grouped:
                a0, b0, _ = grouped[window.group]
                a, b = a + a0, b + b0
            grouped[window.group] = (a, b, constants.bias_inverse)
        return grouped

    @cached_property
    def _window_constants(self) -> tuple[_WindowConstants, ...]:
        """What the score needs of each window besides the model run, computed once."""
        constants = []
        for window in self.windows:
            valid = ~np.isnan(window.measured)
            sigma = np.ones(len(self.sensors)) if window.sigma is None else window.sigma
            spread = np.zeros(len(self.sensors)) if window.bias_spread is None \
                else window.bias_spread
            inverse = np.full(len(self.sensors), np.inf)
            inverse[spread > 0] = 1.0 / (self.tempering * spread[spread > 0] ** 2)
            constants.append(_WindowConstants(
                counts=valid.sum(axis=0),
                precision=window.weight * self.weights / sigma**2, bias_inverse=inverse))
        return tuple(constants)

    def sensor_biases(self, params: ModelParameters) -> dict[int, np.ndarray]:
        """Per instrument group: each sensor's bias estimate (measured − model, K; its
        posterior mean given ``params``; 0 where a sensor has no bias term)."""
        sums = self._bias_sums(self.residual_parts(params))
        return {g: -b / (a + inverse) for g, (a, b, inverse) in sums.items()}

    def sensor_offsets(self, params: ModelParameters) -> dict[str, float]:
        """Each biased sensor's offset (measured − model, SI) pooled over every instrument
        group — the posterior mean of one constant bias per sensor given ``params``, as if all
        files came from the same instruments (one plant): what validate and predict add to
        the model's readings. Empty without bias terms."""
        sums = list(self._bias_sums(self.residual_parts(params)).values())
        a = sum(part[0] for part in sums)
        b = sum(part[1] for part in sums)
        inverse = np.mean([part[2] for part in sums], axis=0)
        return {name: float(-b[j] / (a[j] + inverse[j])) for j, name in enumerate(self.sensors)
                if np.isfinite(inverse[j])}

    def standardised_residuals(self, params: ModelParameters) -> np.ndarray:
        """Residuals whose sum of squares is κχ² (module docstring): every valid sample's
        √(κ w_s ω)·(T_sim − T_meas − b)/σ_s with b the bias estimate of its sensor (the
        :meth:`data_rows` first), then each bias term's b/β — its prior, untempered —,
        flattened (dimensionless; order fixed by the windows); raises if the model rejects
        ``params``."""
        return self.standardise(self.residual_parts(params))

    def standardise(self, parts: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
        """:meth:`standardised_residuals` of the per-window residuals ``parts`` (from
        :meth:`residual_parts`) under this objective's tempering: no model run, so one run's
        residuals can be standardised for several κ."""
        sums = self._bias_sums(parts)
        bias = {g: b / (a + inverse) for g, (a, b, inverse) in sums.items()}
        flat = [((residual - bias[w.group]) * np.sqrt(precision * self.tempering))[
            ~np.isnan(residual)] for w, (residual, precision) in zip(self.windows, parts,
                                                                   strict=True)]
        for group, (_, _, inverse) in sums.items():
            has = np.isfinite(inverse)
            flat.append(bias[group][has] * np.sqrt(inverse[has] * self.tempering))
        return np.concatenate(flat)

    def data_rows(self) -> int:
        """How many of :meth:`standardised_residuals` are samples (the first ones; the rest
        are the bias terms' prior rows)."""
        return int(sum((~np.isnan(w.measured)).sum() for w in self.windows))

    def weighted_count(self) -> float:
        """Σ_w ω_w Σ_s w_s n_ws: the number of samples the objective counts."""
        return float(sum(w.weight * (self.weights * (~np.isnan(w.measured)).sum(axis=0)).sum()
                         for w in self.windows))

    def parameters(self, x: Sequence[float]) -> ModelParameters:
        """The :class:`ModelParameters` of a decision vector (order: PARAMETER_NAMES)."""
        return ModelParameters(**{n: float(v) for n, v in zip(PARAMETER_NAMES, x, strict=True)})

    def squared_errors(self, params: ModelParameters) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per window: per-sensor sum of squared errors (K²) and counts; raises if rejected."""
        return [squared_errors(w, predict_window(self.simulator, w, params, self.sensors))
                for w in self.windows]

    def evaluate(self, x: Sequence[float]) -> Evaluation:
        """Score one decision vector; a rejected candidate scores :data:`PENALTY_RMSE`.

        The GA's and the surrogate's path: per window only each sensor's Σ r and Σ r² of the
        residuals r are formed (no residual arrays kept), the same sums and score as
        :meth:`evaluate_with_residuals` gives."""
        try:
            params = self.parameters(x)
            sums = []
            for window in self.windows:
                predicted = predict_window(self.simulator, window, params, self.sensors)
                window_sums = _window_sums(predicted, window.measured)
                if not (np.isfinite(window_sums[0]).all() and np.isfinite(window_sums[1]).all()):
                    raise ValueError("the simulator returned non-finite temperatures")
                sums.append(window_sums)
        except ValueError as error:
            return _penalty(error)
        return self._evaluation(x, sums)

    def evaluate_with_residuals(self, x: Sequence[float]) -> tuple[Evaluation, np.ndarray | None]:
        """One model run of ``x``: its :class:`Evaluation` (as :meth:`evaluate`) and the
        residual vector ``[standardised_residuals; prior_terms]`` (dimensionless), whose sum of
        squares is ``κχ² + Σz²`` — the score's square times κ·:meth:`weighted_count`, so a
        least-squares method on it minimises the score; None when the model rejects ``x``."""
        try:
            parts = self.residual_parts(self.parameters(x))
        except ValueError as error:
            return _penalty(error), None
        sums = [_residual_sums(residual, ~np.isnan(residual)) for residual, _ in parts]
        return (self._evaluation(x, sums),
                np.concatenate([self.standardise(parts), self.prior_terms(x)]))

    def _evaluation(self, x: Sequence[float], sums: list[tuple[np.ndarray, np.ndarray]]
                    ) -> Evaluation:
        """RMSE and score of ``x`` from each window's per-sensor Σ r and Σ r² (K, K²;
        :func:`_residual_sums`)."""
        sse = count = counted = chi2 = 0.0
        kelvin = self.weights * self.temperature_mask  # the RMSE is over temperatures (K)
        for window, constants, (_, squares) in zip(self.windows, self._window_constants, sums,
                                                    strict=True):
            sse += window.weight * (kelvin * squares).sum()
            count += window.weight * (kelvin * constants.counts).sum()
            counted += window.weight * (self.weights * constants.counts).sum()
            chi2 += (constants.precision * squares).sum()
        for a, b, inverse in self._group_sums(sums).values():
            chi2 -= float((b**2 / (a + inverse)).sum())  # the marginalised biases
        rmse = float(np.sqrt(sse / count))
        # (χ² + Σz²/κ)/n: the minimum of κχ² + Σz², on the scale of χ²/n whatever κ is
        score = float(np.sqrt((max(chi2, 0.0)
                               + (self.prior_terms(x) ** 2).sum() / self.tempering) / counted))
        return Evaluation(rmse, score=score)

    @property
    def temperature_mask(self) -> np.ndarray:
        """1 for each temperature sensor (K), 0 for a pressure or other witness: the RMSE (K)
        is over the temperatures; every sensor counts in the score through its own σ."""
        return np.array([1.0 if s in SIGNALS and SIGNALS[s].si_unit == "K" else 0.0
                         for s in self.sensors])

    def evaluate_many(self, rows: np.ndarray) -> list[Evaluation]:
        """Score each row of ``rows`` (n, 3) in order."""
        return [self.evaluate(row) for row in np.atleast_2d(rows)]


class CalibrationProblem(Problem):
    """Single-objective pymoo problem: minimise the posterior score over measured windows (the
    weighted RMSE in K without ``priors`` and ``sigma``; module docstring).

    ``windows``: DataFrames (weight 1 each, one instrument set) or a
    :class:`~steamtwin.calibration.windowset.WindowSet` (its load-band weights, per-window σ,
    one instrument set per source file); ``settings``: the objective's
    :class:`~steamtwin.calibration.settings.ObjectiveSettings` (sensors, weights, bounds,
    priors, σ for windows that do not bring their own, sensor biases, window policy; its
    ``tempering`` is the calibrator's to apply, see
    :func:`~steamtwin.calibration.calibrator.apply_tempering`). Variables ``x`` = (flow,
    friction, heat-transfer coefficient), dimensionless, within the settings' bounds. Each
    generation's candidates go to ``evaluator`` as one batch (see
    :mod:`steamtwin.calibration.evaluation`; ``None`` evaluates in this process).
    ``n_evaluations`` and ``n_penalised`` count evaluations; ``last_error`` keeps the last
    rejection's reason.
    """

    def __init__(self, simulator: Simulator, windows: Sequence[pd.DataFrame],
                 settings: ObjectiveSettings, *, evaluator: object = None) -> None:
        if not isinstance(settings, ObjectiveSettings):
            raise TypeError(f"settings must be an ObjectiveSettings "
                            f"(got {type(settings).__name__})")
        if isinstance(windows, pd.DataFrame) or len(windows) == 0:
            raise ValueError("windows must be a non-empty list of DataFrames")
        frames, names, sample_weights, sigmas, groups = _window_parts(windows)
        sensors = tuple(settings.sensors)
        unknown = [s for s in sensors if s not in simulator.output_signals]
        if unknown:
            raise ValueError(f"sensor(s) {unknown} are not predicted by the simulator "
                             f"(it predicts {list(simulator.output_signals)})")
        if not any(s in SIGNALS and SIGNALS[s].si_unit == "K" for s in sensors):
            raise ValueError(f"sensors {list(sensors)}: give at least one temperature; a "
                             "pressure is a witness beside them, not the calibration's target")
        prepared = [
            replace(prepare_window(w, simulator, sensors, settings.max_input_gap_s, name=name,
                                   min_samples=settings.min_samples),
                    weight=weight, sigma=settings.sensor_sigma(own, name), group=group)
            for w, name, weight, own, group in zip(frames, names, sample_weights, sigmas,
                                                   groups, strict=True)
        ]
        prepared = tuple(with_bias_spread(prepared, sensors, settings.sensor_bias))
        self.settings = settings
        self.objective = Objective(simulator, prepared, sensors, settings.sensor_weights(),
                                   settings.prior_tuple())
        self.parameter_bounds = check_bounds(settings.bounds)
        self.evaluator = evaluator
        self.n_evaluations = 0
        self.n_penalised = 0
        self.last_error: str | None = None
        low = np.array([self.parameter_bounds[n][0] for n in PARAMETER_NAMES])
        high = np.array([self.parameter_bounds[n][1] for n in PARAMETER_NAMES])
        super().__init__(n_var=len(PARAMETER_NAMES), n_obj=1, xl=low, xu=high)

    @property
    def simulator(self) -> Simulator:
        """The model being calibrated."""
        return self.objective.simulator

    @property
    def sensors(self) -> tuple[str, ...]:
        """Measured signals in the objective."""
        return self.objective.sensors

    @property
    def weights(self) -> np.ndarray:
        """Relative weight of each sensor."""
        return self.objective.weights

    @property
    def windows(self) -> tuple[PreparedWindow, ...]:
        """The prepared windows."""
        return self.objective.windows

    def parameters(self, x: Sequence[float]) -> ModelParameters:
        """The :class:`ModelParameters` of a decision vector."""
        return self.objective.parameters(x)

    def evaluate_candidates(self, candidates: np.ndarray) -> np.ndarray:
        """Score of each row of ``candidates`` (n, 3), counted, via the evaluator (the RMSE in
        K without priors and σ)."""
        rows = np.atleast_2d(np.asarray(candidates, dtype=float))
        if self.evaluator is None:
            results = self.objective.evaluate_many(rows)
        else:
            results = self.evaluator.evaluate(rows)
        for result in results:
            self._count(result)
        return np.array([result.value for result in results])

    def evaluate_full(self, params: ModelParameters) -> Evaluation:
        """RMSE (K) and score of ``params``, counted as one evaluation."""
        x = np.array([getattr(params, name) for name in PARAMETER_NAMES])
        result = self.objective.evaluate(x)
        self._count(result)
        return result

    def evaluate_with_residuals(self, x: Sequence[float]
                                ) -> tuple[Evaluation, np.ndarray | None]:
        """:meth:`Objective.evaluate_with_residuals` of the decision vector ``x``, counted as
        one evaluation."""
        result, residuals = self.objective.evaluate_with_residuals(x)
        self._count(result)
        return result, residuals

    def _count(self, result: Evaluation) -> None:
        self.n_evaluations += 1
        if result.penalised:
            self.n_penalised += 1
            self.last_error = result.error

    def rmse(self, params: ModelParameters) -> float:
        """Weighted pooled RMSE (K) of ``params``; :data:`PENALTY_RMSE` if rejected."""
        return self.evaluate_full(params).rmse

    def score(self, params: ModelParameters) -> float:
        """Posterior score of ``params`` (what the optimisers minimise)."""
        return self.evaluate_full(params).value

    def _evaluate(self, x: np.ndarray, out: dict, *args: object, **kwargs: object) -> None:
        out["F"] = self.evaluate_candidates(x)[:, None]


class _WindowConstants(NamedTuple):
    """What scoring a window needs besides the model run: its valid samples' count per
    sensor, each sensor's precision w_s·ω/σ_s² (1/K²) and its bias prior's 1/(κβ²) (+inf: no
    bias term)."""

    counts: np.ndarray
    precision: np.ndarray
    bias_inverse: np.ndarray


def _residual_sums(residual: np.ndarray, valid: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Per sensor Σ r and Σ r² over the ``valid`` samples of ``residual`` (samples,
    sensors)."""
    filled = np.where(valid, residual, 0.0)
    return filled.sum(axis=0), (filled**2).sum(axis=0)


def _window_sums(predicted: np.ndarray, measured: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_residual_sums` of r = predicted − measured over the samples measured, to the
    bits of NumPy's sums: a C-ordered prediction (the FOM's) in one compiled pass in NumPy's
    order for it, any other (a DataFrame's columns) by NumPy, whose order there differs."""
    if predicted.dtype == np.float64 and predicted.flags.c_contiguous:
        return _prediction_sums(predicted, measured)
    return _residual_sums(predicted - measured, ~np.isnan(measured))


@njit(cache=True)
def _prediction_sums(predicted: np.ndarray, measured: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_residual_sums` of r = predicted − measured (C-ordered, samples × sensors) over
    the samples measured (not NaN), in one pass, sample by sample: the order NumPy sums a
    C-ordered array over its first axis in, so to the same bits."""
    sum_r = np.zeros(measured.shape[1])
    sum_r2 = np.zeros(measured.shape[1])
    for k in range(measured.shape[0]):
        for j in range(measured.shape[1]):
            if not math.isnan(measured[k, j]):
                r = predicted[k, j] - measured[k, j]
                sum_r[j] += r
                sum_r2[j] += r * r
    return sum_r, sum_r2


def _penalty(error: ValueError) -> Evaluation:
    """The penalised :class:`Evaluation` of a candidate the simulator rejected."""
    reason = str(error) or type(error).__name__
    return Evaluation(PENALTY_RMSE, reason, PENALTY_RMSE)


def _window_parts(windows: object) -> tuple[list[pd.DataFrame], list[str], list[float],
                                             list[Mapping[str, float] | None], list[int]]:
    """Frames, names, per-sample weights, own σ and instrument group (one per source file) of
    plain frames (one group) or a WindowSet."""
    if hasattr(windows, "sample_weights"):
        weights = list(windows.sample_weights())
        sources = list(dict.fromkeys(w.source for w in windows))
        return ([w.data for w in windows], [w.name for w in windows], weights,
                [w.sigma for w in windows], [sources.index(w.source) for w in windows])
    frames = list(windows)
    return (frames, [f"window {i}" for i in range(len(frames))], [1.0] * len(frames),
            [None] * len(frames), [0] * len(frames))



def window_rmse(simulator: Simulator, windows: Sequence[pd.DataFrame],
                params: ModelParameters | None = None,
                settings: ObjectiveSettings | None = None) -> pd.DataFrame:
    """Per-window RMSE breakdown (K) for reports, over ``settings``' sensors, weights and
    window policy (default :class:`ObjectiveSettings`; priors and σ play no part here).

    One row per window: ``start``, ``end``, ``rmse`` (weighted, K; NaN if the simulator
    rejects the window, reason in ``error``), ``rmse:<sensor>`` (K), ``samples``,
    ``filled_rows``, ``dropped_rows`` and ``excluded:<sensor>`` (NaN measured samples).
    """
    params = params or ModelParameters()
    problem = CalibrationProblem(simulator, windows, settings or ObjectiveSettings())
    rows = []
    for prepared in problem.windows:
        row: dict[str, object] = {
            "start": prepared.inputs.index[0], "end": prepared.inputs.index[-1],
            "samples": len(prepared.inputs), "filled_rows": prepared.filled_rows,
            "dropped_rows": prepared.dropped_rows, "error": "",
        }
        try:
            sse, count = squared_errors(
                prepared, predict_window(simulator, prepared, params, problem.sensors))
        except ValueError as error:
            sse, count = np.full(len(problem.sensors), np.nan), np.ones(len(problem.sensors))
            row["error"] = str(error)
        w = problem.weights
        row["rmse"] = float(np.sqrt((w * sse).sum() / (w * count).sum()))
        for s, e, n, x in zip(problem.sensors, sse, count, prepared.excluded, strict=True):
            row[f"rmse:{s}"] = float(np.sqrt(e / n))
            row[f"excluded:{s}"] = x
        rows.append(row)
    return pd.DataFrame(rows)
