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

Infeasible candidates
    When the simulator rejects a candidate (``ValueError``, e.g. the FOM's ``InputError`` for a
    flow coefficient too low to pass rated flow) or returns non-finite temperatures at valid
    samples, the evaluation scores :data:`PENALTY_RMSE` = 1000 K: finite, so the GA keeps
    ranking, and far above any feasible RMSE (temperature errors of a feasible model are tens of
    K at most), so penalised candidates always lose tournaments and never survive elitism.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem

from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters, ParameterPrior
from steamtwin.model.simulator import Simulator

__all__ = [
    "DEFAULT_SENSORS",
    "FITNESS_EPSILON",
    "MAX_INPUT_GAP_S",
    "MIN_WINDOW_SAMPLES",
    "PARAMETER_NAMES",
    "PENALTY_RMSE",
    "THERMOCOUPLE_BIAS",
    "CalibrationProblem",
    "Evaluation",
    "Objective",
    "PreparedWindow",
    "check_bounds",
    "checked_inputs",
    "fitness",
    "predict_window",
    "prepare_window",
    "squared_errors",
    "thermocouple_bias_spread",
    "window_rmse",
]

DEFAULT_SENSORS: tuple[str, ...] = (
    "control_stage_temperature",
    "hp_exhaust_temperature",
    "hp_inner_casing_temperature",
)
"""Measured temperatures (K) the method fits against."""

PARAMETER_NAMES: tuple[str, ...] = tuple(PARAMETER_BOUNDS)
"""Decision variables, in this order: the three :class:`ModelParameters` fields."""

PENALTY_RMSE = 1.0e3
"""Objective (K) of a candidate the simulator rejects (see the module docstring)."""

FITNESS_EPSILON = 1.0e-6
"""ε (K) in the method's fitness ``1 / (RMSE + ε)``."""

MAX_INPUT_GAP_S = 60.0
"""Longest input dropout (s) filled forward; longer ones are an error."""

MIN_WINDOW_SAMPLES = 60
"""Fewest usable rows a window may have. The RMSE of n samples of noise σ has a standard error
of about σ/√(2n) (the chi distribution's spread); 60 samples keep it under 10 % of σ."""


def fitness(rmse: float | np.ndarray) -> float | np.ndarray:
    """The method's fitness ``1 / (RMSE + ε)`` (1/K) of an RMSE in K."""
    value = 1.0 / (np.asarray(rmse, dtype=float) + FITNESS_EPSILON)
    return float(value) if value.ndim == 0 else value


def check_bounds(bounds: Mapping[str, tuple[float, float]] | None
                 ) -> dict[str, tuple[float, float]]:
    """Search bounds per parameter: ``bounds`` (partial allowed) within PARAMETER_BOUNDS."""
    result = dict(PARAMETER_BOUNDS)
    for name, pair in (bounds or {}).items():
        if name not in PARAMETER_BOUNDS:
            raise ValueError(f"bounds: unknown parameter {name!r}; known: {list(PARAMETER_NAMES)}")
        low, high = (float(v) for v in pair)
        phys_low, phys_high = PARAMETER_BOUNDS[name]
        if not phys_low <= low < high <= phys_high:
            raise ValueError(
                f"bounds[{name!r}] = ({low}, {high}) must satisfy {phys_low} ≤ low < high ≤ "
                f"{phys_high} (the physical bounds)"
            )
        result[name] = (low, high)
    return result


@dataclass(frozen=True)
class PreparedWindow:
    """One measured window ready for evaluation.

    ``inputs``: the simulator's input columns (SI) after dropping/filling; ``measured``:
    (n, n_sensors) measured temperatures (K), NaN where excluded; ``filled_rows``: rows with a
    forward-filled input; ``dropped_rows``: leading rows dropped; ``excluded``: NaN measured
    samples per sensor; ``checked``: the inputs as the simulator's ``check_inputs`` returned
    them, when it has that fast path (see :func:`predict_window`), else None; ``weight``: the
    weight ω of each of its samples (dimensionless); ``sigma``: measurement error σ per sensor
    (K), None for 1 K each; ``group``: its instrument set (windows of one file share the
    sensors' biases); ``bias_spread``: prior σ β of each sensor's bias (K; 0 or None: none).
    """

    inputs: pd.DataFrame
    measured: np.ndarray
    filled_rows: int
    dropped_rows: int
    excluded: tuple[int, ...]
    checked: object = None
    weight: float = 1.0
    sigma: np.ndarray | None = None
    group: int = 0
    bias_spread: np.ndarray | None = None


def _seconds(index: pd.Index) -> np.ndarray:
    if isinstance(index, pd.DatetimeIndex):
        return (index - index[0]).total_seconds().to_numpy(dtype=float)
    if isinstance(index, pd.TimedeltaIndex):
        return index.total_seconds().to_numpy(dtype=float)
    return np.asarray(index, dtype=float)


def prepare_window(window: pd.DataFrame, simulator: Simulator, sensors: Sequence[str],
                   max_input_gap_s: float = MAX_INPUT_GAP_S, name: str = "window",
                   min_samples: int = MIN_WINDOW_SAMPLES) -> PreparedWindow:
    """Select, check and gap-fill one window (see the module docstring for the NaN policy)."""
    if not isinstance(window, pd.DataFrame) or window.empty:
        raise ValueError(f"{name}: expected a non-empty DataFrame of canonical SI signals")
    needed = [*simulator.input_signals, *sensors]
    missing = [column for column in needed if column not in window.columns]
    if missing:
        raise ValueError(f"{name}: lacks column(s) {missing}")
    inputs = window[list(simulator.input_signals)].apply(pd.to_numeric, errors="coerce")
    complete = inputs.notna().all(axis=1).to_numpy()
    if not complete.any():
        raise ValueError(f"{name}: no row has every input {list(simulator.input_signals)}")
    first = int(np.argmax(complete))
    inputs = inputs.iloc[first:]
    if len(inputs) < min_samples:
        raise ValueError(
            f"{name}: {len(inputs)} usable rows ({window.index[first]} … {window.index[-1]}), "
            f"fewer than the {min_samples} a calibration window needs; take a longer window")
    seconds = _seconds(inputs.index)
    for column in inputs.columns:
        valid = inputs[column].notna().to_numpy()
        last_valid = pd.Series(np.where(valid, seconds, np.nan)).ffill().to_numpy()
        gap = seconds - last_valid
        too_long = np.flatnonzero(gap > max_input_gap_s)
        if too_long.size:
            row = int(too_long[0])
            raise ValueError(
                f"{name}: input {column!r} is missing for more than {max_input_gap_s:g} s at "
                f"{inputs.index[row]}; split the window around the dropout"
            )
    filled_rows = int((~inputs.notna().all(axis=1)).sum())
    inputs = inputs.ffill()
    measured = window[list(sensors)].iloc[first:].apply(pd.to_numeric, errors="coerce")
    values = measured.to_numpy(dtype=float, copy=True)
    values[~np.isfinite(values)] = np.nan
    excluded = tuple(int(n) for n in np.isnan(values).sum(axis=0))
    empty = [s for s, n in zip(sensors, excluded, strict=True) if n == len(values)]
    if empty:
        raise ValueError(f"{name}: sensor(s) {empty} have no valid measured sample")
    return PreparedWindow(inputs=inputs, measured=values, filled_rows=filled_rows,
                          dropped_rows=first, excluded=excluded,
                          checked=checked_inputs(simulator, inputs))


def checked_inputs(simulator: Simulator, inputs: pd.DataFrame) -> object:
    """The simulator's checked form of ``inputs`` (None without the fast path, or when it
    rejects them: every evaluation then reports the rejection through ``simulate``)."""
    check = getattr(simulator, "check_inputs", None)
    if check is None or not hasattr(simulator, "simulate_checked"):
        return None
    try:
        return check(inputs)
    except ValueError:
        return None


def predict_window(simulator: Simulator, prepared: PreparedWindow, params: ModelParameters,
                   sensors: Sequence[str]) -> np.ndarray:
    """Predicted ``sensors`` (samples, sensors; K) on one window.

    A simulator may offer ``check_inputs(inputs)`` and ``simulate_checked(checked, params,
    signals)`` (as :class:`~steamtwin.model.fom.FullOrderModel` does): the window's inputs are
    then checked once, not at every one of a calibration's thousands of runs, and no DataFrame
    is built; otherwise ``simulate`` is called.
    """
    if prepared.checked is not None:
        return simulator.simulate_checked(prepared.checked, params, sensors)
    simulated = simulator.simulate(prepared.inputs, params)
    missing = [s for s in sensors if s not in simulated.columns]
    if missing:
        raise KeyError(f"the simulator does not predict {missing}")
    return simulated[list(sensors)].to_numpy(dtype=float)


def squared_errors(prepared: PreparedWindow, predicted: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Per-sensor sum of squared errors (K²) and valid-sample counts of ``predicted``
    (samples, sensors; K, as :func:`predict_window` returns); ValueError on NaN output."""
    valid = ~np.isnan(prepared.measured)
    if not np.isfinite(predicted[valid]).all():
        raise ValueError("the simulator returned non-finite temperatures")
    error = np.where(valid, predicted - np.where(valid, prepared.measured, 0.0), 0.0)
    return (error**2).sum(axis=0), valid.sum(axis=0)


def _weights(sensors: Sequence[str], weights: Mapping[str, float] | Sequence[float] | None
             ) -> np.ndarray:
    if weights is None:
        result = np.ones(len(sensors))
    elif isinstance(weights, Mapping):
        unknown = set(weights) - set(sensors)
        if unknown:
            raise ValueError(f"weights for unselected sensor(s) {sorted(unknown)}")
        result = np.array([float(weights.get(s, 1.0)) for s in sensors])
    else:
        result = np.asarray(weights, dtype=float)
        if result.shape != (len(sensors),):
            raise ValueError(f"expected {len(sensors)} weights, got {len(result)}")
    if not (np.isfinite(result).all() and (result >= 0).all() and result.sum() > 0):
        raise ValueError("weights must be finite, ≥ 0 and not all zero")
    return result


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

    def _residuals(self, params: ModelParameters) -> list[tuple[np.ndarray, np.ndarray]]:
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
        and 1/β² (+inf where a sensor has no bias term, so that B²/(A + 1/β²) vanishes)."""
        sums: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        for window, (residual, precision) in zip(self.windows, parts, strict=True):
            valid = ~np.isnan(residual)
            a = precision * valid.sum(axis=0)
            b = precision * np.where(valid, residual, 0.0).sum(axis=0)
            spread = np.zeros(len(self.sensors)) if window.bias_spread is None \
                else window.bias_spread
            inverse = np.full(len(self.sensors), np.inf)
            inverse[spread > 0] = 1.0 / spread[spread > 0] ** 2
            if window.group in sums:
                a0, b0, _ = sums[window.group]
                a, b = a + a0, b + b0
            sums[window.group] = (a, b, inverse)
        return sums

    def sensor_biases(self, params: ModelParameters) -> dict[int, np.ndarray]:
        """Per instrument group: each sensor's bias estimate (measured − model, K; its
        posterior mean given ``params``; 0 where a sensor has no bias term)."""
        sums = self._bias_sums(self._residuals(params))
        return {g: -b / (a + inverse) for g, (a, b, inverse) in sums.items()}

    def sensor_offsets(self, params: ModelParameters) -> dict[str, float]:
        """Each biased sensor's offset (measured − model, SI) pooled over every instrument
        group — the posterior mean of one constant bias per sensor given ``params``, as if all
        files came from the same instruments (one plant): what validate and predict add to
        the model's readings. Empty without bias terms."""
        sums = list(self._bias_sums(self._residuals(params)).values())
        a = sum(part[0] for part in sums)
        b = sum(part[1] for part in sums)
        inverse = np.mean([part[2] for part in sums], axis=0)
        return {name: float(-b[j] / (a[j] + inverse[j])) for j, name in enumerate(self.sensors)
                if np.isfinite(inverse[j])}

    def standardised_residuals(self, params: ModelParameters) -> np.ndarray:
        """Residuals whose sum of squares is χ² (module docstring): every valid sample's
        √(w_s ω)·(T_sim − T_meas − b)/σ_s with b the bias estimate of its sensor, then each bias
        term's b/β, flattened (dimensionless; order fixed by the windows); raises if the model
        rejects ``params``."""
        parts = self._residuals(params)
        sums = self._bias_sums(parts)
        bias = {g: b / (a + inverse) for g, (a, b, inverse) in sums.items()}
        flat = [((residual - bias[w.group]) * np.sqrt(precision))[~np.isnan(residual)]
                for w, (residual, precision) in zip(self.windows, parts, strict=True)]
        for group, (_, _, inverse) in sums.items():
            has = np.isfinite(inverse)
            flat.append(bias[group][has] * np.sqrt(inverse[has]))
        return np.concatenate(flat) * np.sqrt(self.tempering)

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
        """Score one decision vector; a rejected candidate scores :data:`PENALTY_RMSE`."""
        try:
            parts = self._residuals(self.parameters(x))
        except ValueError as error:
            reason = str(error) or type(error).__name__
            return Evaluation(PENALTY_RMSE, reason, PENALTY_RMSE)
        sse = count = counted = chi2 = 0.0
        kelvin = self.weights * self.temperature_mask  # the RMSE is over temperatures (K)
        for window, (residual, precision) in zip(self.windows, parts, strict=True):
            valid = ~np.isnan(residual)
            squares = (np.where(valid, residual, 0.0) ** 2).sum(axis=0)
            sse += window.weight * (kelvin * squares).sum()
            count += window.weight * (kelvin * valid.sum(axis=0)).sum()
            counted += window.weight * (self.weights * valid.sum(axis=0)).sum()
            chi2 += (precision * squares).sum()
        for a, b, inverse in self._bias_sums(parts).values():
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
    one instrument set per source file); ``sigma``: measurement error per sensor (K) for
    windows that do not bring their own (default 1 K); ``priors``: name →
    :class:`ParameterPrior` for every parameter, or None; ``sensor_bias``: None (no bias
    terms), :data:`THERMOCOUPLE_BIAS` or sensor → β (K) (module docstring).
    Variables ``x`` = (flow, friction, heat-transfer coefficient), dimensionless, within
    ``bounds`` (default :data:`PARAMETER_BOUNDS`). Each generation's candidates go to
    ``evaluator`` as one batch (see :mod:`steamtwin.calibration.evaluation`; ``None``
    evaluates in this process). ``n_evaluations`` and ``n_penalised`` count evaluations;
    ``last_error`` keeps the last rejection's reason.
    """

    def __init__(self, simulator: Simulator, windows: Sequence[pd.DataFrame], *,
                 bounds: Mapping[str, tuple[float, float]] | None = None,
                 sensors: Sequence[str] = DEFAULT_SENSORS,
                 weights: Mapping[str, float] | Sequence[float] | None = None,
                 max_input_gap_s: float = MAX_INPUT_GAP_S, evaluator: object = None,
                 min_samples: int = MIN_WINDOW_SAMPLES,
                 sigma: Mapping[str, float] | None = None,
                 priors: Mapping[str, ParameterPrior] | None = None,
                 sensor_bias: str | Mapping[str, float] | None = None) -> None:
        if isinstance(windows, pd.DataFrame) or len(windows) == 0:
            raise ValueError("windows must be a non-empty list of DataFrames")
        frames, names, sample_weights, sigmas, groups = _window_parts(windows)
        sensors = tuple(sensors)
        if not sensors or len(set(sensors)) != len(sensors):
            raise ValueError("sensors must be a non-empty list of distinct signal names")
        unknown = [s for s in sensors if s not in simulator.output_signals]
        if unknown:
            raise ValueError(f"sensor(s) {unknown} are not predicted by the simulator "
                             f"(it predicts {list(simulator.output_signals)})")
        if not any(s in SIGNALS and SIGNALS[s].si_unit == "K" for s in sensors):
            raise ValueError(f"sensors {list(sensors)}: give at least one temperature; a "
                             "pressure is a witness beside them, not the calibration's target")
        prepared = [
            replace(prepare_window(w, simulator, sensors, max_input_gap_s, name=name,
                                   min_samples=min_samples),
                    weight=weight, sigma=_sigma(sensors, own if own is not None else sigma,
                                                name), group=group)
            for w, name, weight, own, group in zip(frames, names, sample_weights, sigmas,
                                                   groups, strict=True)
        ]
        prepared = tuple(_with_bias_spread(prepared, sensors, sensor_bias))
        self.objective = Objective(simulator, prepared, sensors, _weights(sensors, weights),
                                   _priors(priors))
        self.parameter_bounds = check_bounds(bounds)
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
        self.n_evaluations += len(results)
        for result in results:
            if result.penalised:
                self.n_penalised += 1
                self.last_error = result.error
        return np.array([result.value for result in results])

    def evaluate_full(self, params: ModelParameters) -> Evaluation:
        """RMSE (K) and score of ``params``, counted as one evaluation."""
        x = np.array([getattr(params, name) for name in PARAMETER_NAMES])
        result = self.objective.evaluate(x)
        self.n_evaluations += 1
        if result.penalised:
            self.n_penalised += 1
            self.last_error = result.error
        return result

    def rmse(self, params: ModelParameters) -> float:
        """Weighted pooled RMSE (K) of ``params``; :data:`PENALTY_RMSE` if rejected."""
        return self.evaluate_full(params).rmse

    def score(self, params: ModelParameters) -> float:
        """Posterior score of ``params`` (what the optimisers minimise)."""
        return self.evaluate_full(params).value

    def _evaluate(self, x: np.ndarray, out: dict, *args: object, **kwargs: object) -> None:
        out["F"] = self.evaluate_candidates(x)[:, None]


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


THERMOCOUPLE_BIAS = "thermocouple"
"""``sensor_bias`` value: β from IEC 60584-1 class 1 for every temperature sensor (module
docstring), and a pressure transmitter's (:data:`TRANSMITTER_BIAS_FRACTION`) for a pressure."""


def thermocouple_bias_spread(temperature_k: float) -> float:
    """β (K) of a class-1 thermocouple's bias at ``temperature_k`` (K): the IEC 60584-1
    class-1 tolerance max(1.5 K, 0.004·|t °C|) read as a uniform bound, divided by √3."""
    return max(1.5, 0.004 * abs(temperature_k - 273.15)) / np.sqrt(3.0)


#: β of a pressure transmitter's calibration error as a fraction of its reading: IEC 60770-1
#: accuracy class 0.1 (±0.1 %, of a span taken as the reading) read as a uniform bound, /√3.
TRANSMITTER_BIAS_FRACTION = 0.001 / np.sqrt(3.0)


def _bias_spread(name: str, mean_reading: float) -> float:
    """β of a sensor's bias under the :data:`THERMOCOUPLE_BIAS` rule: a thermocouple's
    (K), a pressure transmitter's (Pa), none for anything else."""
    unit = SIGNALS[name].si_unit if name in SIGNALS else ""
    if unit == "K":
        return thermocouple_bias_spread(mean_reading)
    if unit == "Pa":
        return TRANSMITTER_BIAS_FRACTION * abs(mean_reading)
    return 0.0


def _with_bias_spread(windows: list[PreparedWindow], sensors: tuple[str, ...],
                      sensor_bias: str | Mapping[str, float] | None) -> list[PreparedWindow]:
    """Set each window's β per sensor: None, the thermocouple rule (from the group's mean
    measured temperature of each temperature sensor) or a mapping sensor → β (K)."""
    if sensor_bias is None:
        return windows
    if isinstance(sensor_bias, str):
        if sensor_bias != THERMOCOUPLE_BIAS:
            raise ValueError(f"sensor_bias must be None, {THERMOCOUPLE_BIAS!r} or a mapping "
                             f"sensor → β in K (got {sensor_bias!r})")
        spread: dict[int, np.ndarray] = {}
        for group in {w.group for w in windows}:
            measured = np.vstack([w.measured for w in windows if w.group == group])
            spread[group] = np.array([
                _bias_spread(name, float(np.nanmean(measured[:, j])))
                for j, name in enumerate(sensors)])
        return [replace(w, bias_spread=spread[w.group]) for w in windows]
    unknown = sorted(set(sensor_bias) - set(sensors))
    values = np.array([float(sensor_bias.get(name, 0.0)) for name in sensors])
    if unknown or not (np.isfinite(values).all() and (values >= 0).all()):
        raise ValueError(f"sensor_bias: expected β ≥ 0 K for selected sensors {list(sensors)} "
                         f"(got {dict(sensor_bias)})")
    return [replace(w, bias_spread=values) for w in windows]


def _sigma(sensors: Sequence[str], sigma: Mapping[str, float] | None, name: str
           ) -> np.ndarray | None:
    """Per-sensor σ (K) in ``sensors`` order; 1 K for a sensor not given; None if none given."""
    if sigma is None:
        return None
    values = np.array([float(sigma.get(s, 1.0)) for s in sensors])
    if not (np.isfinite(values).all() and (values > 0).all()):
        raise ValueError(f"{name}: measurement errors σ must be finite numbers > 0 K "
                         f"(got {dict(zip(sensors, values.tolist(), strict=True))})")
    return values


def _priors(priors: Mapping[str, ParameterPrior] | None) -> tuple[ParameterPrior, ...] | None:
    if priors is None:
        return None
    unknown = sorted(set(priors) - set(PARAMETER_NAMES))
    missing = [n for n in PARAMETER_NAMES if n not in priors]
    if unknown or missing:
        raise ValueError(f"priors: give one per parameter {list(PARAMETER_NAMES)} "
                         f"(unknown {unknown}, missing {missing})")
    return tuple(priors[name] for name in PARAMETER_NAMES)


def window_rmse(simulator: Simulator, windows: Sequence[pd.DataFrame],
                params: ModelParameters | None = None, *,
                sensors: Sequence[str] = DEFAULT_SENSORS,
                weights: Mapping[str, float] | Sequence[float] | None = None,
                max_input_gap_s: float = MAX_INPUT_GAP_S,
                min_samples: int = MIN_WINDOW_SAMPLES) -> pd.DataFrame:
    """Per-window RMSE breakdown (K) for reports.

    One row per window: ``start``, ``end``, ``rmse`` (weighted, K; NaN if the simulator
    rejects the window, reason in ``error``), ``rmse:<sensor>`` (K), ``samples``,
    ``filled_rows``, ``dropped_rows`` and ``excluded:<sensor>`` (NaN measured samples).
    """
    params = params or ModelParameters()
    problem = CalibrationProblem(simulator, windows, sensors=sensors, weights=weights,
                                 max_input_gap_s=max_input_gap_s, min_samples=min_samples)
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
