"""What the DCS reads of a simulated temperature: the first-order lag of its thermocouple.

A thermocouple in a thick-walled high-pressure thermowell follows the steam with a time constant
τ = m·c/(h·A) of tens of seconds (lumped model; ASME PTC 19.3 TW-2016 wells); one peened into
casing metal follows the metal within seconds. Comparing a model's instantaneous steam
temperature with such a reading adds the model's response to every flicker of its (noisy,
measured) inputs that the well filters away in the plant. :func:`lag` gives the reading
τ·dy/dt + y = x, exact for inputs linear between samples (first-order hold), from a steady
start — the same discretisation as the virtual plant's instruments
(:func:`steamtwin.dcs.sensors.first_order_lag`), here for any sample spacing.

:data:`TYPICAL_TIME_CONSTANTS_S` are typical values (s) for the reference unit's instruments
(reasoning in :func:`steamtwin.dcs.sensors.default_sensor_models`); a plant's own come from its
thermowell data sheets.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from steamtwin.cache import njit

__all__ = ["TYPICAL_TIME_CONSTANTS_S", "check_time_constants", "lag", "lag_outputs"]

TYPICAL_TIME_CONSTANTS_S: dict[str, float] = {
    "control_stage_temperature": 20.0,  # thermowell in dense, fast steam
    "hp_exhaust_temperature": 30.0,  # thermowell in thinner exhaust steam (lower h)
    "hp_inner_casing_temperature": 5.0,  # sheathed TC in a drilled hole (contact resistance)
}


def check_time_constants(time_constants: Mapping[str, float] | None,
                         outputs: tuple[str, ...]) -> dict[str, float]:
    """Validated ``{output: τ in s}``; names must be among ``outputs``, τ finite and ≥ 0."""
    checked: dict[str, float] = {}
    for name, value in (time_constants or {}).items():
        if name not in outputs:
            raise ValueError(f"sensor time constant for {name!r}: not an output of the model "
                             f"({list(outputs)})")
        tau = float(value)
        if not math.isfinite(tau) or tau < 0.0:
            raise ValueError(f"sensor time constant for {name!r} = {value!r}: expected a finite "
                             "number of seconds ≥ 0")
        checked[name] = tau
    return checked


@njit(cache=True)
def _lag(x, steps, tau, resume, y_before, x_before):
    y = np.empty_like(x)
    step = math.nan  # the step the weights below belong to: DCS data repeat one step
    a = one_minus_a = b0 = 0.0
    for k in range(x.size):
        if k == 0 and not resume:
            y[0] = x[0]
            continue
        if steps[k] != step:
            step = steps[k]
            ratio = step / tau
            a = math.exp(-ratio)
            one_minus_a = -math.expm1(-ratio)
            b0 = 1.0 - one_minus_a / ratio  # weight of x[k] under the first-order hold
        y_last, x_last = (y_before, x_before) if k == 0 else (y[k - 1], x[k - 1])
        y[k] = a * y_last + (one_minus_a - b0) * x_last + b0 * x[k]
    return y


def lag(values: np.ndarray, steps: np.ndarray, time_constant_s: float,
        before: tuple[float, float] | None = None) -> np.ndarray:
    """Reading (unit of ``values``) of a first-order sensor of τ = ``time_constant_s`` s.

    ``steps[k]`` is the time (s) from sample k − 1 to k. Without ``before`` the sensor starts
    steady at ``values[0]`` (``steps[0]`` is ignored); with ``before`` = (last reading, last
    value) of an earlier series, it continues that series (``steps[0]``: the time since its
    last sample), exactly as one call over both would.
    """
    x = np.ascontiguousarray(values, dtype=float)
    if time_constant_s == 0.0 or x.size == 0:
        return x.copy()
    y_before, x_before = before if before is not None else (0.0, 0.0)
    return _lag(x, np.ascontiguousarray(steps, dtype=float), float(time_constant_s),
                before is not None, float(y_before), float(x_before))


def lag_outputs(outputs: pd.DataFrame, steps: np.ndarray,
                time_constants: Mapping[str, float]) -> pd.DataFrame:
    """``outputs`` with each column named in ``time_constants`` replaced by its reading."""
    lagged = outputs.copy()
    for name, tau in time_constants.items():
        lagged[name] = lag(outputs[name].to_numpy(dtype=float), steps, tau)
    return lagged
