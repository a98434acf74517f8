"""Time windows of DCS data: selection by time and search for steady-load periods.

Input: a frame of canonical signals in SI (load in W) on a sorted, unique time index (a
``DatetimeIndex``, or time in s), e.g. from :func:`steamtwin.dcs.quality.clean`; NaN allowed.

Steady criterion (:func:`find_steady_windows`)
    A span is steady when the signal stays within ± ``tolerance`` × ``rated_load_w`` of its
    median over the span. To be robust against noise and single bad samples, the test is made on
    the signal's centred rolling median over ``smoothing_s`` (default 60 s), not on raw samples.
    Candidates are found first with a rolling range: a sample is *locally steady* when
    max − min of the smoothed signal over a centred sub-window of ``sub_window_s`` (default
    600 s) is at most 2 × tolerance × rated, the band width — a necessary condition for any
    sample lying half a sub-window inside a steady span. Candidate regions (locally steady
    samples widened by half a sub-window) are then split: the longest run within the band
    around the region's median is taken, its median recomputed until the run is stable, and the
    rest of the region is searched again. Spans never cross a stretch without valid data, or a
    step of the index, longer than ``sub_window_s``; shorter NaN stretches are bridged and
    reported in ``nan_fraction``. Spans start and end on valid samples and do not overlap.

The one window-picking rule (:func:`find_windows`), for calibration and validation alike
    *Steady* windows: every steady span of at least ``min_steady_s``, at every load, cut to
    its last ``max_steady_s`` (the start of a hold still carries the ramp's transient). The
    steadiness test's sub-window is min(600 s, ``min_steady_s`` / 2), so that it fits in the
    shortest hold searched for. Validation takes the last ``hours`` of every hold of at least
    ``hours`` (``min_steady_s = max_steady_s``); calibration the last 2 h of every hold of at
    least 1 h. *Ramp* windows (``ramps=True``): every stretch between two steady spans (or
    before the first / after the last) in which the load moves by at least
    ``ramp_min_change`` of rated, widened by ``ramp_before_s`` before and ``ramp_after_s``
    after (the metal's settling: :mod:`steamtwin.calibration.windowset`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime
from numbers import Real
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["DataWindow", "SteadyWindow", "find_steady_windows", "find_windows", "name_windows",
           "parse_window", "select_window"]

_NS = 1_000_000_000
_MAX_SPLITS = 10_000  # bound on region splits (only reached on pathological data)


@dataclass(frozen=True)
class SteadyWindow:
    """A steady span ``[start, end)``; use :func:`select_window` with it to get its samples.

    ``end`` is the first time after the span (the next sample, at most one median step after the
    last one); ``duration_s = end − start`` in s; ``mean_load_fraction``: mean of the valid
    samples / rated value; ``n_samples``: rows in the span; ``nan_fraction``: share of the
    span's samples without a valid value, rows missing from the index (at the median step)
    counted as NaN.
    """

    start: pd.Timestamp | float
    end: pd.Timestamp | float
    mean_load_fraction: float
    duration_s: float
    n_samples: int
    nan_fraction: float


@dataclass(frozen=True)
class DataWindow:
    """One window of :func:`find_windows`: ``data`` (the rows, canonical SI signals), ``kind``
    ("steady", "ramp" or "given") and ``load_fraction`` (mean load / rated: the steady span's
    mean for a steady window, the rows' mean otherwise; NaN without load)."""

    data: pd.DataFrame
    kind: str
    load_fraction: float


def load_fraction(frame: pd.DataFrame, rated_load_w: float) -> float:
    """Mean of ``frame``'s ``load`` (W) / ``rated_load_w`` (W); NaN without valid load."""
    if "load" not in frame.columns or not frame["load"].notna().any():
        return float("nan")
    return float(frame["load"].mean()) / rated_load_w


def find_windows(data: pd.DataFrame, rated_load_w: float, *, min_steady_s: float = 3600.0,
                 max_steady_s: float = 7200.0, tolerance: float = 0.02, ramps: bool = True,
                 ramp_min_change: float = 0.05, ramp_before_s: float = 600.0,
                 ramp_after_s: float = 1800.0, source: str = "") -> list[DataWindow]:
    """Steady windows at every load (and ramp windows) of one history, in time order (the
    module docstring's rule). ``data``: canonical SI signals with ``load`` (W) on a sorted
    DatetimeIndex; ``rated_load_w`` (W); durations in s; ``tolerance`` and
    ``ramp_min_change`` fractions of rated. ValueError naming ``source`` when the data have
    no load signal."""
    if "load" not in data.columns:
        raise ValueError(f"{source or 'data'}: no 'load' signal, which the search for steady "
                         "and ramp windows needs; map the generator load in the tag map or "
                         "pass --window START/END")
    if not max_steady_s >= min_steady_s > 0:
        raise ValueError(f"need 0 < min_steady_s ≤ max_steady_s (got {min_steady_s}, "
                         f"{max_steady_s} s)")
    steady = sorted(find_steady_windows(data, duration_s=min_steady_s,
                                        rated_load_w=rated_load_w, tolerance=tolerance,
                                        sub_window_s=min(600.0, min_steady_s / 2.0)),
                    key=lambda w: pd.Timestamp(w.start))
    result = []
    for span in steady:
        start = max(pd.Timestamp(span.start),
                    pd.Timestamp(span.end) - pd.Timedelta(seconds=max_steady_s))
        result.append(DataWindow(select_window(data, start, span.end), "steady",
                                 span.mean_load_fraction))
    if ramps:
        edges = [data.index[0], *[t for s in steady for t in (pd.Timestamp(s.start),
                                                              pd.Timestamp(s.end))], None]
        for gap_start, gap_end in zip(edges[0::2], edges[1::2], strict=True):
            gap = data.loc[gap_start:gap_end] if gap_end is not None else data.loc[gap_start:]
            load = gap["load"].to_numpy(dtype=float)
            if gap.empty or not np.isfinite(load).any():
                continue
            if np.nanmax(load) - np.nanmin(load) < ramp_min_change * rated_load_w:
                continue
            start = max(gap.index[0] - pd.Timedelta(seconds=ramp_before_s), data.index[0])
            end = min(gap.index[-1] + pd.Timedelta(seconds=ramp_after_s), data.index[-1])
            frame = data.loc[start:end]
            result.append(DataWindow(frame, "ramp", load_fraction(frame, rated_load_w)))
    return sorted(result, key=lambda w: w.data.index[0])


def name_windows(frames: list[pd.DataFrame], rated_load_w: float) -> dict[str, pd.DataFrame]:
    """Windows named by mean load ("50 % load"), told apart by start time when two share a
    name, "window <n>" without load (as the validation report names them)."""
    names = []
    for i, frame in enumerate(frames):
        fraction = load_fraction(frame, rated_load_w)
        names.append(f"{100.0 * fraction:.0f} % load" if np.isfinite(fraction)
                     else f"window {i + 1}")
    named = {}
    for name, frame in zip(names, frames, strict=True):
        if names.count(name) > 1:
            name = f"{name}, {frame.index[0]:%Y-%m-%d %H:%M}"
        named[name] = frame
    return named


def parse_window(text: str, option: str = "--window") -> tuple[pd.Timestamp, pd.Timestamp]:
    """START/END (ISO 8601, each with its UTC offset) → two tz-aware timestamps.

    A time without an offset is refused: it could be any plant's local time, and reading it as
    UTC would shift the window by hours without a word. ``option`` names the source in errors.
    """
    start, sep, end = text.partition("/")
    if not sep or not start or not end:
        raise ValueError(f"{option} {text!r}: expected START/END (ISO 8601 times)")
    bounds = []
    for part in (start, end):
        try:
            stamp = pd.Timestamp(part)
        except ValueError as error:
            raise ValueError(f"{option} {text!r}: {error} (expected ISO 8601 times)") from None
        if stamp.tzinfo is None:
            raise ValueError(f"{option} {text!r}: {part!r} has no UTC offset; write e.g. "
                             f"'{stamp.isoformat()}+08:00' or '{stamp.isoformat()}Z'")
        bounds.append(stamp)
    if not bounds[0] < bounds[1]:
        raise ValueError(f"{option} {text!r}: START must be before END")
    return bounds[0], bounds[1]


def select_window(frame: pd.DataFrame, start: Any, end: Any) -> pd.DataFrame:
    """Rows of ``frame`` with ``start ≤ time < end`` (timestamps, or s for a numeric index).

    A naive timestamp is taken in the index's time zone. The data are taken to cover
    ``[first sample, last sample + one median step)``; a window reaching outside that, an empty or
    reversed window, or one holding no sample is an error.
    """
    times, is_datetime = _times_ns(frame.index)
    _check_sorted(times)
    if times.size == 0:
        raise ValueError("frame has no rows")
    lo, hi = _to_ns(start, frame.index, is_datetime), _to_ns(end, frame.index, is_datetime)
    if not lo < hi:
        raise ValueError(f"window start {start} must be before its end {end}")
    covered_end = int(times[-1]) + _median_step(times)
    if lo < times[0] or hi > covered_end:
        first, last = _label(int(times[0]), frame.index), _label(covered_end, frame.index)
        raise ValueError(
            f"window [{start}, {end}) reaches outside the data, which cover [{first}, {last})"
        )
    i, k = np.searchsorted(times, [lo, hi], side="left")
    if i == k:
        raise ValueError(f"window [{start}, {end}) holds no sample (it lies in a gap of the data)")
    return frame.iloc[i:k]


def find_steady_windows(
    frame: pd.DataFrame,
    *,
    duration_s: float = 7200.0,
    load_fraction: float | None = None,
    rated_load_w: float,
    tolerance: float = 0.02,
    signal: str = "load",
    sub_window_s: float = 600.0,
    smoothing_s: float = 60.0,
) -> list[SteadyWindow]:
    """Maximal steady spans of at least ``duration_s`` s, longest first (see module docstring).

    ``rated_load_w``: rated value of ``signal`` in its SI unit (W for ``load``). ``tolerance``:
    half band width as a fraction of rated (0.02 = ± 2 %). ``load_fraction``: when given, keep
    only spans whose median is within ± ``tolerance`` of this fraction of rated (e.g. 0.30).
    """
    _check_options(duration_s, load_fraction, rated_load_w, tolerance, sub_window_s, smoothing_s)
    if signal not in frame.columns:
        raise KeyError(f"signal {signal!r} is not a column of the frame")
    times, _ = _times_ns(frame.index)
    _check_sorted(times)
    if times.size < 2:
        return []
    x = frame[signal].to_numpy(dtype=float)
    step = _median_step(times)
    band = tolerance * rated_load_w
    sub_ns, duration_ns = round(sub_window_s * _NS), round(duration_s * _NS)

    clock = pd.DatetimeIndex(pd.to_datetime(times, unit="ns"))
    y = pd.Series(x, index=clock).rolling(pd.Timedelta(seconds=smoothing_s), center=True,
                                          min_periods=1).median().to_numpy()
    smooth = pd.Series(y, index=clock).rolling(pd.Timedelta(seconds=sub_window_s), center=True,
                                               min_periods=1)
    local_range = (smooth.max() - smooth.min()).to_numpy()
    steady = (local_range <= 2.0 * band).astype(float)
    widened = pd.Series(steady, index=clock).rolling(pd.Timedelta(seconds=sub_window_s),
                                                     center=True, min_periods=1).max().to_numpy()
    region = (widened > 0) & ~_long_no_data(times, x, sub_ns)

    # regions: runs of ``region`` not crossing a step of the index longer than sub_window_s
    long_step = np.diff(times) > sub_ns
    first = region & np.r_[True, ~region[:-1] | long_step]
    last = region & np.r_[~region[1:] | long_step, True]
    starts, ends = np.flatnonzero(first), np.flatnonzero(last) + 1

    def end_time(b: int) -> int:
        last = int(times[b - 1]) + step
        return min(last, int(times[b])) if b < times.size else last

    spans: list[tuple[int, int]] = []
    stack = [(int(s), int(e)) for s, e in zip(starts, ends, strict=True)]
    splits = 0
    while stack and splits < _MAX_SPLITS:
        lo, hi = stack.pop()
        splits += 1
        if hi <= lo or end_time(hi) - int(times[lo]) < duration_ns:
            continue
        run = _steady_run(y[lo:hi], x[lo:hi], times[lo:hi], band)
        if run is None:
            continue
        a, b = lo + run[0], lo + run[1]
        if end_time(b) - int(times[a]) >= duration_ns:
            spans.append((a, b))
        stack.extend([(lo, a), (b, hi)])

    windows = [_window(frame.index, times, x, a, b, end_time(b), step, rated_load_w)
               for a, b in spans]
    if load_fraction is not None:
        windows = [
            w for (a, b), w in zip(spans, windows, strict=True)
            if abs(float(np.nanmedian(y[a:b])) / rated_load_w - load_fraction) <= tolerance
        ]
    return sorted(windows, key=lambda w: (-w.duration_s, _sort_key(w.start)))


# --------------------------------------------------------------------------------------------
# helpers


def _steady_run(y: np.ndarray, x: np.ndarray, t: np.ndarray,
                band: float) -> tuple[int, int] | None:
    """[a, b) of the stable longest in-band run of a region (positions in the region)."""
    known = ~np.isnan(y)
    if not known.any():
        return None
    median = float(np.median(y[known]))
    previous: tuple[int, int] | None = None
    for _ in range(20):
        inside = ~known | (np.abs(y - median) <= band)  # short NaN stretches are bridged
        edges = np.diff(np.r_[0, inside.astype(np.int8), 0])
        run_starts, run_ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        if run_starts.size == 0:
            return None
        if previous is not None:
            middle = (previous[0] + previous[1]) // 2
            holds = (run_starts <= middle) & (middle < run_ends)
        else:
            holds = np.zeros(run_starts.size, dtype=bool)
        if holds.any():
            pick = int(np.argmax(holds))
        else:
            span_t = t[run_ends - 1] - t[run_starts]
            pick = int(np.argmax(span_t))
        a, b = int(run_starts[pick]), int(run_ends[pick])
        valid = np.flatnonzero(~np.isnan(x[a:b]) & known[a:b])
        if valid.size == 0:
            return None
        a, b = a + int(valid[0]), a + int(valid[-1]) + 1  # start and end on valid samples
        median = float(np.median(y[a:b][known[a:b]]))
        if (a, b) == previous:
            break
        previous = (a, b)
    if np.any(np.abs(y[a:b][known[a:b]] - median) > band):
        return None  # did not settle (pathological); the rest of the region is still searched
    return a, b


def _long_no_data(times: np.ndarray, x: np.ndarray, limit_ns: int) -> np.ndarray:
    """Samples in a NaN run whose valid neighbours are more than ``limit_ns`` apart."""
    valid = ~np.isnan(x)
    out = np.zeros(x.size, dtype=bool)
    tv = times[valid]
    if tv.size == 0:
        out[:] = True
        return out
    after = np.searchsorted(tv, times, side="left")  # first valid at or after
    t_next = np.where(after < tv.size, tv[np.minimum(after, tv.size - 1)], times[-1])
    t_prev = np.where(after > 0, tv[np.maximum(after - 1, 0)], times[0])
    out[~valid] = (t_next - t_prev)[~valid] > limit_ns
    return out


def _window(index: pd.Index, times: np.ndarray, x: np.ndarray, a: int, b: int, end: int,
            step: int, rated: float) -> SteadyWindow:
    duration = end - int(times[a])
    valid = int((~np.isnan(x[a:b])).sum())
    expected = max(b - a, round(duration / step))
    return SteadyWindow(
        start=_label(int(times[a]), index),
        end=_label(end, index),
        mean_load_fraction=float(np.nanmean(x[a:b])) / rated,
        duration_s=duration / _NS,
        n_samples=b - a,
        nan_fraction=1.0 - valid / expected,
    )


def _check_options(duration_s: float, load_fraction: float | None, rated: float,
                   tolerance: float, sub_window_s: float, smoothing_s: float) -> None:
    for name, value in (("duration_s", duration_s), ("rated_load_w", rated),
                        ("tolerance", tolerance), ("sub_window_s", sub_window_s),
                        ("smoothing_s", smoothing_s)):
        if not (isinstance(value, Real) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    if load_fraction is not None and not (
        isinstance(load_fraction, Real) and 0 <= load_fraction <= 1.5
    ):
        raise ValueError(f"load_fraction must be a fraction of rated (e.g. 0.3), got "
                         f"{load_fraction!r}")
    if sub_window_s >= duration_s:
        raise ValueError(f"sub_window_s ({sub_window_s:g} s) must be shorter than duration_s "
                         f"({duration_s:g} s)")


def _times_ns(index: pd.Index) -> tuple[np.ndarray, bool]:
    if isinstance(index, pd.DatetimeIndex):
        if index.hasnans:
            raise ValueError("time index has NaT; run quality.clean first")
        return index.as_unit("ns").asi8, True
    if pd.api.types.is_numeric_dtype(index.dtype) and not pd.api.types.is_bool_dtype(index.dtype):
        seconds = np.asarray(index, dtype=float)
        if not np.isfinite(seconds).all():
            raise ValueError("time index has non-finite times; run quality.clean first")
        return np.round(seconds * _NS).astype(np.int64), False
    raise TypeError(f"expected a DatetimeIndex (or time in s), got {type(index).__name__}")


def _check_sorted(times: np.ndarray) -> None:
    if (np.diff(times) <= 0).any():
        raise ValueError("time index is not sorted or has duplicate timestamps; "
                         "run quality.clean first")


def _median_step(times: np.ndarray) -> int:
    return int(np.median(np.diff(times))) if times.size > 1 else 1


def _to_ns(value: Any, index: pd.Index, is_datetime: bool) -> int:
    if not is_datetime:
        if isinstance(value, str | datetime | pd.Timestamp):
            raise TypeError(f"the index is time in s; give the window in s, got {value!r}")
        return round(float(value) * _NS)
    stamp = pd.Timestamp(value)
    tz = index.tz  # type: ignore[attr-defined]
    if stamp.tzinfo is None and tz is not None:
        stamp = stamp.tz_localize(tz)
    elif stamp.tzinfo is not None and tz is None:
        raise ValueError(f"{value!r} has a time zone but the index has none")
    return int(stamp.as_unit("ns").value)


def _label(t: int, index: pd.Index) -> pd.Timestamp | float:
    if isinstance(index, pd.DatetimeIndex):
        stamp = pd.Timestamp(t, unit="ns", tz="UTC")
        return stamp.tz_convert(index.tz) if index.tz is not None else stamp.tz_localize(None)
    return t / _NS


def _sort_key(value: pd.Timestamp | float) -> int | float:
    return value.value if isinstance(value, pd.Timestamp) else value
