"""Resampling of cleaned DCS data onto a uniform time grid, flagging every value it makes.

Rule: **nothing is invented silently.** Every output value says, in its flag, how it was made
(average, single sample, interpolation) or why it is empty, and :class:`ResampleResult` counts
them per signal. Input: a frame as returned by :func:`steamtwin.dcs.quality.clean` (canonical
signals in SI — Pa, K, kg/s, W — on a sorted, unique time index; NaN = rejected or missing).

Grid
    Grid times are whole multiples of the step counted from the Unix epoch (1970-01-01 UTC), so
    a 60 s grid falls on whole UTC minutes whatever the time zone of the index (a 1-day grid
    falls on UTC midnight). The output keeps the input's time zone. A numeric index (time in s)
    is aligned to multiples of the step from t = 0 s.

Methods
    ``"mean"``: each grid value is the average of the valid (non-NaN) samples in the bin
    ``[label, label + step)`` — **the label is the bin start**. The grid runs from the bin of the
    first sample to the bin of the last one. A bin without a valid sample stays NaN; a mean never
    bridges a gap, so ``max_gap_s`` does not act on it.
    ``"linear"``: each grid value is interpolated linearly in time between the nearest valid
    samples at or before and at or after it; a sample exactly on a grid time is copied. Grid
    points whose valid neighbours are more than ``max_gap_s`` apart (default 3 × step), or that
    lie before the first or after the last valid sample, stay NaN (no extrapolation). The grid
    runs over grid times within ``[first sample, last sample]``.

Flag codes (:class:`ResampleFlag`, bits above the :class:`~steamtwin.dcs.quality.Flag` bits)
    512 AVERAGED (mean of N ≥ 2 valid samples), 1024 SINGLE (one valid sample, copied unchanged),
    2048 INTERPOLATED (linear between two valid samples), 4096 GAP (left NaN: empty bin, or
    neighbours more than ``max_gap_s`` apart, or outside the valid data). Exactly one of them is
    set on every output value. When input ``flags`` are given, the low bits (1–256) are the OR of
    the input flags of the samples that made the value (those averaged, copied or interpolated
    between); for a GAP value in ``"mean"`` they are the OR of the flags of the (NaN) samples in
    the bin, which tell why it is empty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntFlag
from numbers import Real
from typing import Literal

import numpy as np
import pandas as pd

__all__ = ["COUNT_KINDS", "ResampleFlag", "ResampleResult", "resample"]

Method = Literal["mean", "linear"]


class ResampleFlag(IntFlag):
    """How a resampled value was made (bitmask); see the module docstring."""

    AVERAGED = 512
    SINGLE = 1024
    INTERPOLATED = 2048
    GAP = 4096


#: Columns of :attr:`ResampleResult.counts`, in order, and the flag each one counts.
COUNT_KINDS: dict[str, ResampleFlag] = {
    "averaged": ResampleFlag.AVERAGED,
    "single": ResampleFlag.SINGLE,
    "interpolated": ResampleFlag.INTERPOLATED,
    "gap": ResampleFlag.GAP,
}

_NS = 1_000_000_000


@dataclass(frozen=True)
class ResampleResult:
    """Resampled data (SI, on the grid), per-value flags (uint16) and counts.

    ``counts``: DataFrame signal × ``averaged | single | interpolated | gap`` with the number of
    grid values of each kind; each row sums to the grid length.
    """

    data: pd.DataFrame
    flags: pd.DataFrame
    counts: pd.DataFrame


def resample(
    frame: pd.DataFrame,
    step_s: float,
    *,
    method: Method = "mean",
    max_gap_s: float | None = None,
    flags: pd.DataFrame | None = None,
) -> ResampleResult:
    """Resample ``frame`` onto a grid of ``step_s`` seconds aligned to multiples of the step (UTC).

    ``method``: ``"mean"`` (bin average, label = bin start) or ``"linear"`` (interpolation in
    time). ``max_gap_s``: longest span in s between valid samples that ``"linear"`` may bridge
    (default 3 × ``step_s``). ``flags``: the per-sample :class:`~steamtwin.dcs.quality.Flag`
    codes of ``frame`` (e.g. ``CleaningResult.flags``), carried into the output flags.
    """
    step_ns, gap_ns = _check_arguments(step_s, method, max_gap_s)
    times, is_datetime = _times_ns(frame.index)
    _check_frame(frame, times)
    in_flags = _input_flags(frame, flags)
    values = frame.to_numpy(dtype=float) if frame.shape[1] else np.empty((len(frame), 0))

    if times.size == 0:
        grid = np.empty(0, dtype=np.int64)
    elif method == "mean":
        grid = np.arange(_floor(times[0], step_ns), times[-1] + 1, step_ns, dtype=np.int64)
    else:
        first = -_floor(-times[0], step_ns)  # ceil
        grid = np.arange(first, times[-1] + 1, step_ns, dtype=np.int64)

    out = np.full((grid.size, frame.shape[1]), np.nan)
    out_flags = np.zeros((grid.size, frame.shape[1]), dtype=np.uint16)
    for j in range(frame.shape[1]):
        if method == "mean":
            out[:, j], out_flags[:, j] = _mean(times, values[:, j], in_flags[:, j], grid, step_ns)
        else:
            out[:, j], out_flags[:, j] = _linear(times, values[:, j], in_flags[:, j], grid, gap_ns)

    index = _grid_index(grid, frame.index, is_datetime)
    data = pd.DataFrame(out, index=index, columns=frame.columns)
    flag_frame = pd.DataFrame(out_flags, index=index, columns=frame.columns)
    counts = pd.DataFrame(
        {kind: (out_flags & int(code) != 0).sum(axis=0) for kind, code in COUNT_KINDS.items()},
        index=frame.columns,
        dtype="int64",
    )
    return ResampleResult(data, flag_frame, counts)


# --------------------------------------------------------------------------------------------
# helpers


def _check_arguments(step_s: float, method: str, max_gap_s: float | None) -> tuple[int, int]:
    if not (isinstance(step_s, Real) and math.isfinite(step_s) and step_s > 0):
        raise ValueError(f"step_s must be a finite number of seconds > 0, got {step_s!r}")
    step_ns = round(step_s * _NS)
    if step_ns < 1:
        raise ValueError(f"step_s must be at least 1 ns, got {step_s!r} s")
    if method not in ("mean", "linear"):
        raise ValueError(f"method must be 'mean' or 'linear', got {method!r}")
    if max_gap_s is None:
        return step_ns, 3 * step_ns
    if not (isinstance(max_gap_s, Real) and max_gap_s > 0 and not math.isnan(max_gap_s)):
        raise ValueError(f"max_gap_s must be a number of seconds > 0 (or None), got {max_gap_s!r}")
    gap_ns = np.iinfo(np.int64).max if math.isinf(max_gap_s) else round(max_gap_s * _NS)
    return step_ns, gap_ns


def _times_ns(index: pd.Index) -> tuple[np.ndarray, bool]:
    if isinstance(index, pd.DatetimeIndex):
        if index.hasnans:
            row = int(np.flatnonzero(index.isna())[0])
            raise ValueError(f"row {row} has no timestamp (NaT); run quality.clean first")
        return index.as_unit("ns").asi8, True
    if pd.api.types.is_numeric_dtype(index.dtype) and not pd.api.types.is_bool_dtype(index.dtype):
        seconds = np.asarray(index, dtype=float)
        if not np.isfinite(seconds).all():
            row = int(np.flatnonzero(~np.isfinite(seconds))[0])
            raise ValueError(f"row {row} has no valid time (s); run quality.clean first")
        return np.round(seconds * _NS).astype(np.int64), False
    raise TypeError(f"expected a DatetimeIndex (or time in s), got {type(index).__name__}")


def _check_frame(frame: pd.DataFrame, times: np.ndarray) -> None:
    text = [str(c) for c in frame.columns if not pd.api.types.is_numeric_dtype(frame[c].dtype)]
    if text:
        raise TypeError(f"non-numeric column(s) {', '.join(text)}; resample numeric signals only")
    if frame.columns.has_duplicates:
        raise ValueError("duplicate column names; each signal must appear once")
    steps = np.diff(times)
    if (steps < 0).any():
        row = int(np.argmax(steps < 0)) + 1
        raise ValueError(
            f"time index is not sorted (row {row} goes back in time); run quality.clean first"
        )
    if (steps == 0).any():
        row = int(np.argmax(steps == 0)) + 1
        raise ValueError(
            f"time index has duplicate timestamps (row {row}); run quality.clean first"
        )


def _input_flags(frame: pd.DataFrame, flags: pd.DataFrame | None) -> np.ndarray:
    shape = (len(frame), frame.shape[1])
    if flags is None:
        return np.zeros(shape, dtype=np.uint16)
    if not flags.index.equals(frame.index):
        raise ValueError("flags must have the same index as frame (e.g. CleaningResult.flags)")
    missing = [str(c) for c in frame.columns if c not in flags.columns]
    if missing:
        raise ValueError(f"flags lack column(s) {', '.join(missing)} of frame")
    table = flags[list(frame.columns)]
    if not all(pd.api.types.is_integer_dtype(table[c].dtype) for c in table.columns):
        raise TypeError("flags must be integer bitmasks (quality.Flag codes)")
    array = table.to_numpy(dtype=np.int64) if shape[1] else np.zeros(shape, dtype=np.int64)
    if ((array < 0) | (array > 0x1FF)).any():
        raise ValueError("flags must hold quality.Flag codes (0–511); resample raw flags only")
    return array.astype(np.uint16)


def _floor(t: int | np.integer, step: int) -> int:
    return (int(t) // step) * step


def _mean(times: np.ndarray, x: np.ndarray, f: np.ndarray, grid: np.ndarray,
          step: int) -> tuple[np.ndarray, np.ndarray]:
    n = grid.size
    if n == 0:
        return np.empty(0), np.empty(0, dtype=np.uint16)
    bins = (times - grid[0]) // step
    valid = ~np.isnan(x)
    total = np.bincount(bins[valid], weights=x[valid], minlength=n)
    count = np.bincount(bins[valid], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        value = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    code = np.select(
        [count >= 2, count == 1], [int(ResampleFlag.AVERAGED), int(ResampleFlag.SINGLE)],
        default=int(ResampleFlag.GAP),
    ).astype(np.uint16)
    # carried flags: OR over the bin's valid samples, or over all its samples when it is empty
    starts = np.flatnonzero(np.r_[True, bins[1:] != bins[:-1]])
    occupied = bins[starts]
    or_valid = np.bitwise_or.reduceat(np.where(valid, f, 0).astype(np.uint16), starts)
    or_all = np.bitwise_or.reduceat(f, starts)
    carried = np.zeros(n, dtype=np.uint16)
    carried[occupied] = np.where(count[occupied] > 0, or_valid, or_all)
    return value, code | carried


def _linear(times: np.ndarray, x: np.ndarray, f: np.ndarray, grid: np.ndarray,
            max_gap: int) -> tuple[np.ndarray, np.ndarray]:
    n = grid.size
    value = np.full(n, np.nan)
    code = np.full(n, int(ResampleFlag.GAP), dtype=np.uint16)
    valid = ~np.isnan(x)
    tv, xv, fv = times[valid], x[valid], f[valid]
    if tv.size == 0 or n == 0:
        return value, code
    before = np.searchsorted(tv, grid, side="right") - 1  # last valid sample at or before
    has_before = before >= 0
    b = np.clip(before, 0, tv.size - 1)
    exact = has_before & (tv[b] == grid)
    a = np.clip(before + 1, 0, tv.size - 1)  # first valid sample after
    between = has_before & ~exact & (before + 1 < tv.size)
    between &= (tv[a] - tv[b]) <= max_gap
    value[exact] = xv[b[exact]]
    code[exact] = int(ResampleFlag.SINGLE) | fv[b[exact]]
    i, k = b[between], a[between]
    fraction = (grid[between] - tv[i]).astype(float) / (tv[k] - tv[i]).astype(float)
    value[between] = xv[i] + (xv[k] - xv[i]) * fraction
    code[between] = int(ResampleFlag.INTERPOLATED) | fv[i] | fv[k]
    return value, code


def _grid_index(grid: np.ndarray, index: pd.Index, is_datetime: bool) -> pd.Index:
    if is_datetime:
        utc = pd.DatetimeIndex(pd.to_datetime(grid, unit="ns", utc=True))
        tz = index.tz  # type: ignore[attr-defined]
        out = utc.tz_convert(tz) if tz is not None else utc.tz_localize(None)
        return out.rename(index.name)
    return pd.Index(grid / _NS, dtype=float, name=index.name)
