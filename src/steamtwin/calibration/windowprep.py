"""Measured windows made ready for the objective, and the model's predictions on them.

:func:`prepare_window` selects a window's inputs and measured sensors, drops the rows before
the first complete input, fills short input dropouts forward (at most ``max_input_gap_s``; the
policy is the objective's, :mod:`~steamtwin.calibration.objective`) and checks the inputs once
with the simulator's fast path; :func:`predict_window` and :func:`squared_errors` compare the
model with the measurements on it. :func:`with_bias_spread` gives each window the prior spread
β of its sensors' constant biases (IEC 60584-1 class 1 thermocouples, IEC 60770-1 transmitters).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from steamtwin.calibration.settings import MAX_INPUT_GAP_S, MIN_WINDOW_SAMPLES, THERMOCOUPLE_BIAS
from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator

__all__ = [
    "TRANSMITTER_BIAS_FRACTION",
    "PreparedWindow",
    "checked_inputs",
    "predict_window",
    "prepare_window",
    "squared_errors",
    "thermocouple_bias_spread",
    "with_bias_spread",
]


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


def with_bias_spread(windows: list[PreparedWindow], sensors: tuple[str, ...],
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

