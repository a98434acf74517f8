"""The plant's sensors as the twin models them, one setup for every mode.

calibrate, calibrate-online, validate and predict all compare the model with what the DCS
reads, so all of them must read the model through the same sensors: a first-order time constant
per temperature (:mod:`steamtwin.model.measurement`) and the depth of the casing's metal
thermocouple. :func:`sensor_setup` decides both once, from

1. the tag map (``time_constant``, ``depth``; the plant's data sheets or a step test),
2. else, for a time constant, an estimate from the data's own ramps
   (:func:`estimate_time_constant`),
3. else the typical value (:data:`~steamtwin.model.measurement.TYPICAL_TIME_CONSTANTS_S`;
   for the depth, the spec's ``metal.casing_thermocouple_depth``),

and says which source each came from. :meth:`SensorSetup.model` builds the full-order model
that reads like that.

Estimating τ from ramps: for a first-order sensor the reading lags the steam by τ during a ramp
of rate r, an offset of r·τ, while a steady offset (bias, model error) stays the same at every
rate. The model's instantaneous temperature x is lagged by candidate τ and compared with the
reading y after removing each window's mean offset; the least-squares τ is the estimate and its
95 % interval is the profile-likelihood range Δcost ≤ 3.84·σ² (χ²₁, Wilks 1938), with σ² the
residual variance and the number of samples divided by the residuals' integrated
autocorrelation time (Sokal 1997; :func:`steamtwin.calibration.identifiability.integrated_time`)
because model-error residuals are far from white. An interval reaching either end of the search
range means the data (no ramp, or a ramp too slow for the noise) cannot tell τ: the typical
value is kept and the setup says so.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import brentq, minimize_scalar

from steamtwin.calibration.identifiability import integrated_time
from steamtwin.dcs.tagmap import MAX_TIME_CONSTANT_S, METAL_THERMOCOUPLE, TagMap
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.measurement import TYPICAL_TIME_CONSTANTS_S, lag
from steamtwin.model.parameters import ModelParameters, sensor_offset_unit
from steamtwin.spec import TurbineSpec

__all__ = ["SensorSetup", "TimeConstantEstimate", "estimate_time_constant", "sensor_setup"]

#: Search range of an estimated time constant, s: from a bare sheathed thermocouple to the
#: heaviest thermowell the tag map accepts.
TIME_CONSTANT_SEARCH_S = (0.5, MAX_TIME_CONSTANT_S)
#: χ²₁ quantile of a 95 % profile-likelihood interval.
CHI2_95 = 3.841
_GRID = np.geomspace(*TIME_CONSTANT_SEARCH_S, 41)


@dataclass(frozen=True)
class TimeConstantEstimate:
    """A time constant estimated from ramps: ``value`` and its 95 % interval (s); ``identified``
    False when the interval reaches an end of :data:`TIME_CONSTANT_SEARCH_S`."""

    value: float
    low: float
    high: float
    identified: bool
    samples: int


@dataclass(frozen=True)
class SensorSetup:
    """How the twin reads its temperatures: ``time_constants`` (output → τ, s), each one's
    ``sources`` entry (text), the casing thermocouple's depth (m; None: the spec's) and
    ``offsets`` (output → measured − model, K or Pa: a calibration's estimate of each sensor's
    calibration error, for validate and predict; never for a calibration, which estimates
    them)."""

    time_constants: dict[str, float]
    sources: dict[str, str]
    casing_thermocouple_depth: float | None = None
    depth_source: str = "the spec's metal.casing_thermocouple_depth"
    offsets: dict[str, float] = dataclasses.field(default_factory=dict)

    def spec_for(self, spec: TurbineSpec) -> TurbineSpec:
        """``spec`` with the casing thermocouple at this setup's depth (m)."""
        if self.casing_thermocouple_depth is None:
            return spec
        return dataclasses.replace(spec, casing_thermocouple_depth=self.casing_thermocouple_depth)

    def model(self, spec: TurbineSpec) -> FullOrderModel:
        """The full-order model of ``spec`` read through these sensors."""
        return FullOrderModel(self.spec_for(spec), sensor_time_constants=self.time_constants,
                              sensor_offsets=self.offsets or None)

    def describe(self) -> list[str]:
        """One line per sensor: its τ or depth and where it comes from."""
        lines = [f"{name}: τ = {tau:g} s ({self.sources[name]})"
                 for name, tau in self.time_constants.items()]
        if self.casing_thermocouple_depth is not None:
            lines.append(f"{METAL_THERMOCOUPLE}: depth {self.casing_thermocouple_depth * 1e3:g} mm"
                         f" ({self.depth_source})")
        lines += [f"{name}: offset {_offset_text(name, value)} (the calibration's estimate of "
                  "its bias)" for name, value in self.offsets.items()]
        return lines


def sensor_setup(spec: TurbineSpec, tag_map: TagMap | None = None,
                 windows: Sequence[pd.DataFrame] = (),
                 params: ModelParameters | None = None) -> SensorSetup:
    """The sensors of the model's temperature outputs: tag map, else estimated from the ramps
    of ``windows`` (canonical SI frames holding the model's inputs and the measured outputs;
    none: no estimate), else typical (see the module docstring). ``params``: the model
    parameters the estimate simulates with (default: the empirical ones)."""
    signals = tag_map.signals if tag_map is not None else {}
    depth_spec = signals.get(METAL_THERMOCOUPLE)
    depth = depth_spec.depth_m if depth_spec is not None else None
    setup_depth = SensorSetup({}, {}, depth, "tag map depth" if depth is not None
                              else SensorSetup.depth_source)
    outputs = setup_depth.model(spec).output_signals
    temperatures = [name for name in outputs if name in TYPICAL_TIME_CONSTANTS_S]
    constants: dict[str, float] = {}
    sources: dict[str, str] = {}
    to_estimate = []
    for name in temperatures:
        given = signals[name].time_constant_s if name in signals else None
        if given is not None:
            constants[name], sources[name] = given, "tag map"
        else:
            to_estimate.append(name)
    usable = [window for window in windows if len(window) > 1]
    if to_estimate and usable:
        simulated = _instantaneous(setup_depth.model(spec), usable, params)
        for name in to_estimate:
            pairs = [(window[name].to_numpy(float), run[name].to_numpy(float), _steps(window))
                     for window, run in zip(usable, simulated, strict=True)
                     if name in window.columns]
            estimate = estimate_time_constant(pairs) if pairs else None
            if estimate is not None and estimate.identified:
                constants[name] = estimate.value
                sources[name] = (f"estimated from the data's ramps, 95 % interval "
                                 f"{estimate.low:.3g}–{estimate.high:.3g} s")
            else:
                why = "no measured samples" if estimate is None else (
                    f"not identified by the data (95 % interval {estimate.low:.3g}–"
                    f"{estimate.high:.3g} s)")
                constants[name] = TYPICAL_TIME_CONSTANTS_S[name]
                sources[name] = f"typical value, {why}"
    for name in to_estimate:
        if name not in constants:
            constants[name] = TYPICAL_TIME_CONSTANTS_S[name]
            sources[name] = "typical value (no data to estimate it from)"
    ordered = {name: constants[name] for name in temperatures}
    return SensorSetup(ordered, {name: sources[name] for name in temperatures}, depth,
                       setup_depth.depth_source)


def estimate_time_constant(pairs: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]]
                           ) -> TimeConstantEstimate:
    """τ (s) of a first-order sensor from (measured reading, model's instantaneous value,
    sample steps in s) per window; each window's mean offset is removed (see the module
    docstring). Samples with a NaN reading or value are left out."""
    cleaned = []
    for measured, simulated, steps in pairs:
        valid = np.isfinite(measured) & np.isfinite(simulated)
        cleaned.append((measured, simulated, steps, valid))
    samples = int(sum(valid.sum() for *_, valid in cleaned))

    def residuals(tau: float) -> list[np.ndarray]:
        out = []
        for measured, simulated, steps, valid in cleaned:
            filled = pd.Series(simulated).ffill().bfill().to_numpy()
            reading = lag(filled, steps, tau)[valid]
            difference = measured[valid] - reading
            out.append(difference - difference.mean() if difference.size else difference)
        return out

    def cost(tau: float) -> float:
        return float(sum(np.sum(r**2) for r in residuals(tau)))

    costs = np.array([cost(tau) for tau in _GRID])
    best = int(np.argmin(costs))
    low_end, high_end = _GRID[max(best - 1, 0)], _GRID[min(best + 1, _GRID.size - 1)]
    refined = minimize_scalar(cost, bounds=(low_end, high_end), method="bounded",
                              options={"xatol": 1e-3})
    tau = float(refined.x) if refined.fun <= costs[best] else float(_GRID[best])
    minimum = min(float(refined.fun), float(costs[best]))
    pooled = np.concatenate(residuals(tau)) if samples else np.zeros(0)
    effective = samples / max(integrated_time(pooled), 1.0) if pooled.size > 2 else 0.0
    degrees = max(effective - len(cleaned) - 1.0, 1.0)
    variance = minimum / samples if samples else math.inf
    # cost differences scale with the raw sample count; the interval with the effective one
    threshold = CHI2_95 * variance * samples / degrees if samples else math.inf
    # (a floor far above round-off keeps data that do not move at all from "crossing" it)
    level = minimum + max(threshold, 1e-9 * (float(costs.max()) + 1.0))
    if not math.isfinite(level):
        return TimeConstantEstimate(tau, *TIME_CONSTANT_SEARCH_S, False, samples)
    # each end: the crossing of the level between τ and the nearest grid point beyond it
    below = [g for g in _GRID[::-1] if g < tau and cost(g) > level]
    above = [g for g in _GRID if g > tau and cost(g) > level]
    low = (float(brentq(lambda g: cost(g) - level, below[0], tau)) if below
           else TIME_CONSTANT_SEARCH_S[0])
    high = (float(brentq(lambda g: cost(g) - level, tau, above[0])) if above
            else TIME_CONSTANT_SEARCH_S[1])
    return TimeConstantEstimate(tau, low, high, bool(below and above), samples)


def _steps(window: pd.DataFrame) -> np.ndarray:
    """Seconds from each sample to the next (first entry unused)."""
    index = window.index
    if isinstance(index, pd.DatetimeIndex):
        seconds = (index - index[0]).total_seconds().to_numpy(float)
    else:
        seconds = np.asarray(index, dtype=float)
    return np.diff(seconds, prepend=seconds[0])


def _instantaneous(model: FullOrderModel, windows: Sequence[pd.DataFrame],
                   params: ModelParameters | None) -> list[pd.DataFrame]:
    """The model's unlagged outputs on each window's inputs."""
    runs = []
    for window in windows:
        inputs = window[[name for name in model.input_signals]]
        runs.append(model.simulate(inputs, params))
    return runs


def _offset_text(name: str, value: float) -> str:
    """An offset in its signal's unit: K, or kPa for a pressure (SI Pa inside)."""
    if sensor_offset_unit(name) == "Pa":
        return f"{value / 1e3:+.2f} kPa"
    return f"{value:+.2f} K"
