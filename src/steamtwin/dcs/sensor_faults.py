"""Sensor faults scheduled on purpose: what the live twin's alarms must tell from plant
degradation (issue 21, item 3).

The instrument models of :mod:`steamtwin.dcs.sensors` draw random faults (dropouts, spikes,
stuck runs) at low rates, so that normal data stay normal. A test of the twin's monitoring
needs faults it knows the start, size and signal of, the three faults a thermocouple or a
transmitter develops in service (Nicholas & White, *Traceable Temperatures*, 2nd ed., 2001,
ch. 6–7; IEC 60584-1 drift):

* ``drift``: the reading walks away at ``size`` per hour (K/h for a temperature, Pa/h for a
  pressure, SI per hour) from ``start`` to ``end`` (or the end of the data), then keeps the
  offset reached (inhomogeneity of an aged thermocouple does not heal);
* ``bias_step``: the reading jumps by ``size`` (SI) at ``start`` and stays off until ``end``
  (a knocked sensor, a junction or cold-junction fault);
* ``stuck``: the reading freezes at its last value before ``start`` until ``end`` (a failed
  transmitter, a frozen DCS point); ``size`` is not used.

Samples already missing (dropouts) stay missing. Faults apply after the instruments, in
order; each becomes one row of the run's fault record.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

__all__ = ["SENSOR_FAULT_KINDS", "SensorFault", "apply_sensor_faults", "parse_sensor_fault"]

SENSOR_FAULT_KINDS = ("drift", "bias_step", "stuck")


@dataclass(frozen=True)
class SensorFault:
    """A fault of ``signal`` (canonical name) of ``kind`` (:data:`SENSOR_FAULT_KINDS`) from
    ``start_s`` to ``end_s`` (s from the data's first sample; None: to the end); ``size``:
    SI per hour for a drift, SI for a bias step, unused for a stuck reading."""

    signal: str
    kind: str
    start_s: float
    size: float = 0.0
    end_s: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in SENSOR_FAULT_KINDS:
            raise ValueError(f"sensor fault kind {self.kind!r}: expected one of "
                             f"{', '.join(SENSOR_FAULT_KINDS)}")
        if not (math.isfinite(self.start_s) and self.start_s >= 0.0):
            raise ValueError(f"sensor fault of {self.signal}: start {self.start_s!r} s must be "
                             "finite and ≥ 0")
        if self.end_s is not None and not (math.isfinite(self.end_s)
                                           and self.end_s > self.start_s):
            raise ValueError(f"sensor fault of {self.signal}: end {self.end_s!r} s must be "
                             f"after its start ({self.start_s!r} s)")
        if not math.isfinite(self.size):
            raise ValueError(f"sensor fault of {self.signal}: size must be finite")


_TEXT = re.compile(r"^(?P<signal>[a-z_]+):(?P<kind>[a-z_]+)(?::(?P<size>[-+0-9.eE]+))?"
                   r"@(?P<start>[0-9.]+)h(?:-(?P<end>[0-9.]+)h)?$")


def parse_sensor_fault(text: str) -> SensorFault:
    """``SIGNAL:KIND[:SIZE]@STARTh[-ENDh]`` (hours from the first sample; SIZE in SI, per hour
    for a drift), e.g. ``hp_exhaust_temperature:drift:2@6h`` or
    ``control_stage_temperature:stuck@3h-4.5h``. ValueError naming the text otherwise."""
    match = _TEXT.match(text.strip())
    if match is None:
        raise ValueError(f"sensor fault {text!r}: expected SIGNAL:KIND[:SIZE]@STARTh[-ENDh], "
                         "e.g. hp_exhaust_temperature:drift:2@6h (2 K/h from hour 6)")
    kind = match["kind"]
    if kind != "stuck" and match["size"] is None:
        raise ValueError(f"sensor fault {text!r}: a {kind} needs a size (SI"
                         f"{' per hour' if kind == 'drift' else ''})")
    try:
        return SensorFault(signal=match["signal"], kind=kind,
                           start_s=3600.0 * float(match["start"]),
                           size=float(match["size"] or 0.0),
                           end_s=None if match["end"] is None else 3600.0 * float(match["end"]))
    except ValueError as error:
        raise ValueError(f"sensor fault {text!r}: {error}") from None


def apply_sensor_faults(measured: pd.DataFrame, faults: Sequence[SensorFault]
                        ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``measured`` (SI, time index) with ``faults`` applied, and one record row per fault:
    signal, kind, start, end (timestamps), start_row, end_row, n_samples, value (the held
    value of a stuck reading, else the largest offset, SI) and offset (``size``). ValueError
    for a signal the frame lacks or a fault that starts after the data end."""
    out = measured.copy()
    seconds = (measured.index - measured.index[0]).total_seconds().to_numpy(dtype=float)
    rows = []
    for fault in faults:
        if fault.signal not in out.columns:
            raise ValueError(f"sensor fault of {fault.signal!r}: the data have no such signal "
                             f"({', '.join(out.columns)})")
        end_s = seconds[-1] if fault.end_s is None else fault.end_s
        active = (seconds >= fault.start_s) & (seconds <= end_s)
        if not active.any():
            raise ValueError(f"sensor fault of {fault.signal}: starts at {fault.start_s:g} s, "
                             f"after the data's last sample ({seconds[-1]:g} s)")
        first, last = int(np.flatnonzero(active)[0]), int(np.flatnonzero(active)[-1])
        values = out[fault.signal].to_numpy(dtype=float, copy=True)
        missing = ~np.isfinite(values)
        if fault.kind == "stuck":
            before = values[:first][np.isfinite(values[:first])]
            held = before[-1] if before.size else values[first]
            values[active] = held
            value = held
        else:
            if fault.kind == "drift":
                offset = fault.size * (np.minimum(seconds, end_s) - fault.start_s) / 3600.0
                offset = np.where(seconds >= fault.start_s, offset, 0.0)
            else:  # bias step, only while active
                offset = np.where(active, fault.size, 0.0)
            values = values + offset
            value = float(np.max(np.abs(offset)) * np.sign(fault.size or 1.0))
        values[missing] = np.nan  # a dropout stays a dropout
        out[fault.signal] = values
        rows.append({"signal": fault.signal, "kind": fault.kind,
                     "start": measured.index[first], "end": measured.index[last],
                     "start_row": first, "end_row": last, "n_samples": last - first + 1,
                     "value": value, "offset": fault.size})
    return out, pd.DataFrame(rows, columns=["signal", "kind", "start", "end", "start_row",
                                            "end_row", "n_samples", "value", "offset"])
