"""What a calibration objective is made of: :class:`ObjectiveSettings`, one frozen dataclass.

Every calibrator — :class:`~steamtwin.calibration.calibrator.Calibrator` whatever its search,
:class:`~steamtwin.calibration.online.OnlineCalibrator` — and the pymoo problem
(:class:`~steamtwin.calibration.objective.CalibrationProblem`) take the objective's settings as
this one object: the fitted sensors and their weights, the search bounds, the priors, the
measurement errors σ, the sensors' bias terms, the likelihood tempering and the window policy
(longest input dropout filled, fewest samples). Each is checked once, in ``__post_init__``,
with a ``ValueError`` that names the argument, its unit and what was expected. What the
settings mean is the objective's method (:mod:`~steamtwin.calibration.objective`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    PARAMETER_BOUNDS,
    ParameterError,
    ParameterPrior,
    parse_prior,
    priors_from_dict,
)
from steamtwin.textfile import read_utf8_text

__all__ = [
    "DEFAULT_SENSORS",
    "MAX_INPUT_GAP_S",
    "MIN_WINDOW_SAMPLES",
    "PARAMETER_NAMES",
    "THERMOCOUPLE_BIAS",
    "ObjectiveSettings",
    "check_bounds",
    "check_random_state",
    "load_priors",
]

DEFAULT_SENSORS: tuple[str, ...] = (
    "control_stage_temperature",
    "hp_exhaust_temperature",
    "hp_inner_casing_temperature",
)
"""Measured temperatures (K) the method fits against."""

PARAMETER_NAMES: tuple[str, ...] = tuple(PARAMETER_BOUNDS)
"""Decision variables, in this order: the three :class:`ModelParameters` fields."""

MAX_INPUT_GAP_S = 60.0
"""Longest input dropout (s) filled forward; longer ones are an error."""

MIN_WINDOW_SAMPLES = 60
"""Fewest usable rows a window may have. The RMSE of n samples of noise σ has a standard error
of about σ/√(2n) (the chi distribution's spread); 60 samples keep it under 10 % of σ."""

THERMOCOUPLE_BIAS = "thermocouple"
"""``sensor_bias`` value: β from IEC 60584-1 class 1 for every temperature sensor
(:mod:`~steamtwin.calibration.objective`), and a pressure transmitter's
(:data:`~steamtwin.calibration.windowprep.TRANSMITTER_BIAS_FRACTION`) for a pressure."""


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


def check_random_state(random_state: object) -> int:
    """``random_state`` as an int; ValueError unless it is an integer ≥ 0."""
    if (isinstance(random_state, bool) or not isinstance(random_state, int | np.integer)
            or random_state < 0):
        raise ValueError(f"random_state must be an integer ≥ 0 (got {random_state!r})")
    return int(random_state)


def load_priors(path: str | Path | None = None, overrides: Sequence[str] = ()
                ) -> dict[str, ParameterPrior]:
    """The default priors (:data:`DEFAULT_PRIORS`), overridden by the ``priors`` section of
    the JSON file ``path`` (as a calibration's params.json carries it), then by each of
    ``overrides`` (``NAME=normal|lognormal:CENTER:SPREAD``,
    :func:`~steamtwin.model.parameters.parse_prior`); errors name the file or the text
    (:class:`~steamtwin.model.parameters.ParameterError`)."""
    result = dict(DEFAULT_PRIORS)
    if path is not None:
        document = json.loads(read_utf8_text(path, "priors file", "JSON", ParameterError))
        if not isinstance(document, dict) or "priors" not in document:
            raise ParameterError(f"{path}: expected a JSON object with a 'priors' section "
                                 "(as calibrate writes into params.json)")
        result = priors_from_dict(document["priors"], str(path), result)
    for text in overrides:
        name, value = parse_prior(text)
        result[name] = value
    return result


def _is_number(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float | np.integer
                                                      | np.floating)


@dataclass(frozen=True)
class ObjectiveSettings:
    """The calibration objective's settings (see :mod:`~steamtwin.calibration.objective`).

    ``sensors``: the measured signals fitted (canonical names; at least one temperature, K);
    ``weights``: relative weight per sensor (mapping sensor → weight, or one per sensor in
    order; default 1 each); ``bounds``: search bounds per parameter (partial allowed, within
    the physical :data:`~steamtwin.model.parameters.PARAMETER_BOUNDS`; dimensionless);
    ``priors``: name → :class:`ParameterPrior`, one per parameter (default
    :data:`DEFAULT_PRIORS`: the MAP; None: the method's plain RMSE, no intervals); ``sigma``:
    measurement error σ per sensor (K, Pa for a pressure) for windows that do not bring their
    own (default 1 each); ``sensor_bias``: None (no bias terms), :data:`THERMOCOUPLE_BIAS`
    (IEC 60584-1 class 1) or sensor → β (SI); ``tempering``: κ ∈ (0, 1] weighting the
    likelihood, or ``"auto"`` (1/(τ·S²) at the priors' centres; 1 without priors);
    ``max_input_gap_s``: the longest input dropout filled forward (s); ``min_samples``: the
    fewest usable rows of a window.
    """

    sensors: Sequence[str] = DEFAULT_SENSORS
    weights: Mapping[str, float] | Sequence[float] | None = None
    bounds: Mapping[str, tuple[float, float]] | None = None
    priors: Mapping[str, ParameterPrior] | None = field(
        default_factory=lambda: dict(DEFAULT_PRIORS))
    sigma: Mapping[str, float] | None = None
    sensor_bias: str | Mapping[str, float] | None = None
    tempering: float | str = "auto"
    max_input_gap_s: float = MAX_INPUT_GAP_S
    min_samples: int = MIN_WINDOW_SAMPLES

    def __post_init__(self) -> None:
        if isinstance(self.sensors, str):
            raise ValueError(f"sensors must be a list of signal names (got {self.sensors!r})")
        sensors = tuple(self.sensors)
        object.__setattr__(self, "sensors", sensors)
        if not sensors or len(set(sensors)) != len(sensors):
            raise ValueError("sensors must be a non-empty list of distinct signal names")
        self.sensor_weights()
        check_bounds(self.bounds)
        self.prior_tuple()
        if self.sigma is not None:
            values = [self.sigma[s] for s in self.sigma]
            if not all(_is_number(v) and math.isfinite(v) and v > 0 for v in values):
                raise ValueError(f"sigma: measurement errors σ must be finite numbers > 0 "
                                 f"(K, Pa for a pressure; got {dict(self.sigma)})")
        self._check_sensor_bias()
        tempering = self.tempering
        if tempering != "auto" and not (_is_number(tempering) and 0.0 < tempering <= 1.0):
            raise ValueError(f"tempering must be a number in (0, 1] or 'auto' "
                             f"(got {tempering!r})")
        gap = self.max_input_gap_s
        if not (_is_number(gap) and gap >= 0):
            raise ValueError(f"max_input_gap_s must be a number ≥ 0 s (got {gap!r})")
        count = self.min_samples
        if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
            raise ValueError(f"min_samples must be an integer ≥ 1 (got {count!r})")

    def _check_sensor_bias(self) -> None:
        bias = self.sensor_bias
        if bias is None:
            return
        if isinstance(bias, str):
            if bias != THERMOCOUPLE_BIAS:
                raise ValueError(f"sensor_bias must be None, {THERMOCOUPLE_BIAS!r} or a "
                                 f"mapping sensor → β in K (got {bias!r})")
            return
        unknown = sorted(set(bias) - set(self.sensors))
        values = [bias[name] for name in bias]
        if unknown or not all(_is_number(v) and math.isfinite(v) and v >= 0 for v in values):
            raise ValueError(f"sensor_bias: expected β ≥ 0 K for selected sensors "
                             f"{list(self.sensors)} (got {dict(bias)})")

    def sensor_weights(self) -> np.ndarray:
        """The relative weight of each sensor, in ``sensors`` order (dimensionless)."""
        sensors, weights = self.sensors, self.weights
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

    def prior_tuple(self) -> tuple[ParameterPrior, ...] | None:
        """The priors in :data:`PARAMETER_NAMES` order (None without priors)."""
        priors = self.priors
        if priors is None:
            return None
        unknown = sorted(set(priors) - set(PARAMETER_NAMES))
        missing = [n for n in PARAMETER_NAMES if n not in priors]
        if unknown or missing:
            raise ValueError(f"priors: give one per parameter {list(PARAMETER_NAMES)} "
                             f"(unknown {unknown}, missing {missing})")
        return tuple(priors[name] for name in PARAMETER_NAMES)

    def sensor_sigma(self, sigma: Mapping[str, float] | None, name: str) -> np.ndarray | None:
        """Per-sensor σ in ``sensors`` order from a window's own ``sigma`` or else these
        settings' (1 for a sensor not given; None if neither gives any); ``name`` (the
        window) is named in the error."""
        sigma = self.sigma if sigma is None else sigma
        if sigma is None:
            return None
        values = np.array([float(sigma.get(s, 1.0)) for s in self.sensors])
        if not (np.isfinite(values).all() and (values > 0).all()):
            raise ValueError(f"{name}: measurement errors σ must be finite numbers > 0 K "
                             f"(got {dict(zip(self.sensors, values.tolist(), strict=True))})")
        return values
