"""The detectors of the data-quality check: time order and duplicates, gaps, noise σ and
resolution, stuck runs, spikes (methods and sources in the package docstring)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.ndimage import median_filter
from scipy.special import ndtr

from steamtwin.dcs.quality.limits import (
    SECONDS_PER_DAY,
    SPIKE_MAX_SAMPLES,
    STUCK_CHANCE_RUNS_PER_DAY,
    TRIM_SHARE,
    TRIMMED_STD_FACTOR,
)
from steamtwin.dcs.quality.options import QualityOptions
from steamtwin.dcs.quality.report import time_label


@dataclass
class Column:
    values: np.ndarray
    nan: np.ndarray
    out_of_range: np.ndarray
    bad: np.ndarray
    spike: np.ndarray
    stuck: np.ndarray
    conflict: np.ndarray
    sigma: float = math.nan  # white-noise σ before quantisation, SI
    quantum: float = 0.0  # historian resolution, SI (0: none found)
    spike_scale: float = math.nan  # noise scale of the spike test, SI
    max_rate: float = 0.0  # SI per s
    stuck_runs: int = 0
    stuck_duration_s: float = 0.0
    constant: bool = False

@dataclass
class Analysis:
    n: int
    signals: tuple[str, ...]
    missing_required: list[str]
    non_numeric: list[str]
    is_datetime: bool
    rows: np.ndarray  # as-read position of each kept (sorted, unique) row
    times_ns: np.ndarray  # kept rows, int64 ns
    labels: pd.Index  # kept rows' index labels
    backwards: int
    first_backwards: int | None
    kept_late: np.ndarray
    kept_has_dup: np.ndarray
    n_dup_identical: int
    first_dup_identical: tuple[int | None, Any]
    n_dup_conflict: int
    first_dup_conflict: tuple[int | None, Any]
    conflict_signals: list[str]
    step_s: float
    gaps: np.ndarray  # kept-row positions i where step i → i+1 is a gap
    gap_steps_s: np.ndarray
    columns: dict[str, Column]
    raw_labels: pd.Index

def _times_ns(index: pd.Index, source: str) -> tuple[np.ndarray, bool]:
    if isinstance(index, pd.DatetimeIndex):
        if index.hasnans:
            row = int(np.flatnonzero(index.isna())[0])
            raise ValueError(f"{source or 'frame'}: row {row} has no timestamp (NaT)")
        return index.as_unit("ns").asi8, True
    if pd.api.types.is_numeric_dtype(index.dtype):
        seconds = np.asarray(index, dtype=float)
        if not np.isfinite(seconds).all():
            row = int(np.flatnonzero(~np.isfinite(seconds))[0])
            raise ValueError(f"{source or 'frame'}: row {row} has no valid time (s)")
        return np.round(seconds * 1e9).astype(np.int64), False
    raise TypeError(
        f"{source or 'frame'}: expected a DatetimeIndex (or time in s), got {type(index).__name__}"
    )

def analyse(frame: pd.DataFrame, options: QualityOptions) -> Analysis:
    n = len(frame)
    t_raw, is_datetime = _times_ns(frame.index, options.source)
    numeric = [c for c in frame.columns if pd.api.types.is_numeric_dtype(frame[c].dtype)]
    non_numeric = [str(c) for c in frame.columns if c not in numeric]
    missing = [name for name in options.required if name not in frame.columns]

    steps = np.diff(t_raw)
    backwards = int((steps < 0).sum())
    first_backwards = int(np.argmax(steps < 0)) + 1 if backwards else None
    late_raw = np.zeros(n, dtype=bool)
    if n > 1:
        late_raw[1:] = t_raw[1:] < np.maximum.accumulate(t_raw)[:-1]

    order = np.argsort(t_raw, kind="stable")
    ts = t_raw[order]
    dup = np.zeros(n, dtype=bool)
    dup[1:] = ts[1:] == ts[:-1]
    kept = ~dup
    rows = order[kept]
    group = np.cumsum(kept) - 1
    firsts = np.flatnonzero(kept)
    values = (
        frame[numeric].to_numpy(dtype=float)[order] if numeric else np.empty((n, 0), dtype=float)
    )
    dup_rows = np.flatnonzero(dup)
    first_of_dup = firsts[group[dup_rows]]
    a, b = values[dup_rows], values[first_of_dup]
    differ = ~((a == b) | (np.isnan(a) & np.isnan(b)))
    row_conflict = differ.any(axis=1)
    n_groups = len(firsts)
    conflict = np.zeros((n_groups, len(numeric)), dtype=bool)
    if dup_rows.size:
        np.logical_or.at(conflict, group[dup_rows], differ)
    has_dup = np.zeros(n_groups, dtype=bool)
    has_dup[group[dup_rows]] = True

    def first_of(mask: np.ndarray) -> tuple[int | None, Any]:
        if not mask.any():
            return None, None
        row = int(order[dup_rows[mask]].min())  # earliest duplicate row as read
        return row, time_label(frame.index[row], is_datetime)

    kept_values = values[kept]
    times = ts[kept]
    dts = np.diff(times) / 1e9
    if options.nominal_step_s is not None:
        step = float(options.nominal_step_s)
    else:
        step = float(np.median(dts)) if dts.size else math.nan
    gaps = np.flatnonzero(dts > options.gap_factor * step) if dts.size else np.zeros(0, int)

    columns: dict[str, Column] = {}
    where = options.source or "quality check"
    for name, mask in options.bad_quality.items():
        if name not in frame.columns:  # a non-numeric column is reported, not checked
            raise ValueError(f"{where}: bad_quality has a mask for {name!r}, which is not a "
                             "column of the data")
        if mask.size != n:
            raise ValueError(f"{where}: bad_quality[{name!r}] has {mask.size} entries, the data "
                             f"have {n} rows (one entry per row as read)")
    seconds = (times - times[0]) / 1e9 if times.size else np.zeros(0)
    step_s = step if math.isfinite(step) and step > 0 else 1.0
    for j, name in enumerate(numeric):
        key = str(name)
        x = np.ascontiguousarray(kept_values[:, j])
        nan = np.isnan(x)
        oor = np.zeros_like(nan)
        if name in options.ranges:
            lo, hi = options.ranges[name]
            with np.errstate(invalid="ignore"):
                oor = ~nan & ((x < lo) | (x > hi))
        bad = options.bad_quality[key][rows] if key in options.bad_quality else np.zeros_like(nan)
        col = Column(x, nan, oor, bad, np.zeros_like(nan), np.zeros_like(nan),
                      conflict[:, j].copy())
        _detect(col, seconds, step_s, options, key)
        if (~nan).sum() > 1 and np.nanmin(x) == np.nanmax(x):
            col.constant = True
            col.stuck[:] = False
            col.stuck_runs, col.stuck_duration_s = 0, 0.0
        columns[key] = col

    return Analysis(
        n=n, signals=tuple(str(c) for c in numeric), missing_required=missing,
        non_numeric=non_numeric, is_datetime=is_datetime, rows=rows, times_ns=times,
        labels=frame.index[rows], backwards=backwards, first_backwards=first_backwards,
        kept_late=late_raw[rows], kept_has_dup=has_dup,
        n_dup_identical=int((~row_conflict).sum()), first_dup_identical=first_of(~row_conflict),
        n_dup_conflict=int(row_conflict.sum()), first_dup_conflict=first_of(row_conflict),
        conflict_signals=[str(numeric[j]) for j in np.flatnonzero(differ.any(axis=0))],
        step_s=step, gaps=gaps, gap_steps_s=dts[gaps], columns=columns, raw_labels=frame.index,
    )

def estimate_noise_sigma(values: np.ndarray, resolution: float = 0.0) -> float:
    """White-noise σ of evenly sampled ``values`` (SI; NaN breaks the series), before quantisation.

    From the second differences ``(x[i−1] − 2·x[i] + x[i+1])/√6`` (variance σ² for white
    noise, a linear trend cancels) [Gasser, Sroka & Jennen-Steinmetz 1986, Biometrika 73(3)]:
    the standard deviation of their central 99 % / 0.9616 (truncated normal), robust to < 1 %
    of steps and spikes and, unlike a MAD, not collapsing on quantised data; then corrected
    for the quantisation noise ``resolution²/12`` (Sheppard 1898). NaN with fewer than 3
    triples of finite values.
    """
    x = np.asarray(values, dtype=float)
    if x.size < 3:
        return math.nan
    second = x[:-2] - 2.0 * x[1:-1] + x[2:]
    second = second[np.isfinite(second)]
    if second.size < 3:
        return math.nan
    total = _trimmed_std(second) / math.sqrt(6.0)
    return math.sqrt(max(total**2 - resolution**2 / 12.0, 0.0))

def estimate_resolution(values: np.ndarray) -> float:
    """Quantum (SI) of a historian signal: its values' grid step; 0 when no grid is found.

    Non-zero absolute differences of consecutive finite values (ignoring float noise below
    1e-9 of the largest magnitude) are tried against the smallest one divided by 1 … 8; the
    first candidate of which ≥ 99.9 % of the differences are whole multiples (within 1 %) is
    taken, refined as the median difference per step. Fewer than 10 non-zero differences:
    0 (no evidence of a grid).
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return 0.0
    tolerance = 1e-9 * float(np.max(np.abs(x))) + 1e-300
    steps = np.abs(np.diff(x))
    steps = steps[steps > tolerance]
    if steps.size < 10:
        return 0.0
    smallest = float(steps.min())
    for divisor in range(1, 9):
        candidate = smallest / divisor
        multiples = steps / candidate
        whole = np.round(multiples)
        if np.mean(np.abs(multiples - whole) <= 0.01) >= 0.999:
            return float(np.median(steps / whole))
    return 0.0

def _trimmed_std(v: np.ndarray) -> float:
    """Std about the median of the central 99 % of ``v``, scaled to σ for a normal sample."""
    deviation = np.abs(v - np.median(v))
    central = deviation[deviation <= np.quantile(deviation, TRIM_SHARE)]
    return float(np.sqrt(np.mean(central**2)) / TRIMMED_STD_FACTOR)

def _detect(col: Column, seconds: np.ndarray, step_s: float, options: QualityOptions,
            name: str) -> None:
    """Noise, quantum, stuck runs and spikes of one column (sets the fields of ``col``)."""
    usable = ~col.nan & ~col.out_of_range & ~col.bad
    x = np.where(usable, col.values, np.nan)
    quantum = options.resolution_si.get(name)
    col.quantum = estimate_resolution(x) if quantum is None else quantum
    col.max_rate = options.rate_limits.get(name, 0.0)
    given = options.noise_si.get(name)
    sigma = given if given is not None else estimate_noise_sigma(x, col.quantum)
    stuck = _stuck(x, seconds, sigma, col.quantum, step_s, options.stuck_min_duration_s)
    if given is None and stuck.any():  # again without the stuck runs' zero differences
        sigma = estimate_noise_sigma(np.where(stuck, np.nan, x), col.quantum)
        stuck = _stuck(x, seconds, sigma, col.quantum, step_s, options.stuck_min_duration_s)
    col.sigma, col.stuck = sigma, stuck
    if stuck.any():
        starts, ends, _ = segments(np.r_[False, stuck[1:] & stuck[:-1]])
        runs = stuck[starts]
        col.stuck_runs = int(runs.sum())
        col.stuck_duration_s = float((seconds[ends] - seconds[starts])[runs].sum())
    col.spike, col.spike_scale = _spikes(x, seconds, usable & ~stuck, col, options)

def _cell_probability(offset: np.ndarray, sigma: float, quantum: float) -> np.ndarray:
    """Probability that a sample with noise σ, ``offset`` from a cell's centre, falls in it."""
    if not math.isfinite(sigma):
        return np.ones_like(offset)
    if quantum == 0.0:
        return np.full_like(offset, 0.0 if sigma > 0.0 else 1.0)
    if sigma == 0.0:
        return (offset < quantum / 2.0).astype(float)
    half = quantum / 2.0
    return ndtr((half - offset) / sigma) - ndtr((-half - offset) / sigma)

def _stuck(x: np.ndarray, seconds: np.ndarray, sigma: float, quantum: float, step_s: float,
           min_duration_s: float) -> np.ndarray:
    """Stuck mask: runs of equal values too improbable for noise σ and quantum (module doc)."""
    out = np.zeros(x.size, dtype=bool)
    if x.size < 2:
        return out
    same = np.zeros(x.size, dtype=bool)
    same[1:] = x[1:] == x[:-1]
    starts, ends, _ = segments(same)
    duration = seconds[ends] - seconds[starts]
    real = np.isfinite(x[starts])
    long = np.flatnonzero((ends > starts) & (duration >= min_duration_s) & real)
    limit = math.log(STUCK_CHANCE_RUNS_PER_DAY * step_s / SECONDS_PER_DAY)
    cells: list[np.ndarray] = []
    for s, e in zip(starts[long], ends[long], strict=True):
        slope = _slope_around(x, seconds, int(s), int(e))
        offset = abs(slope) * np.abs(seconds[s:e + 1] - 0.5 * (seconds[s] + seconds[e]))
        cells.append(_cell_probability(offset, sigma, quantum))
    # runs that white noise alone (without trend) cannot explain take no part in the persistence
    flat = float(_cell_probability(np.zeros(1), sigma, quantum)[0])
    impossible = np.array([_log_run(np.full(p.size, flat)) < limit for p in cells], dtype=bool)
    keep = real.copy()
    keep[long[impossible]] = False
    cap = max(round(min_duration_s / step_s), 2)
    observed = _persistence(np.minimum(ends - starts + 1, cap)[keep], cap)
    for run, p in zip(long, cells, strict=True):
        if _log_run(np.maximum(p, observed)) < limit:
            out[starts[run]:ends[run] + 1] = True
    return out

def _log_run(p: np.ndarray) -> float:
    """log of the product of the n − 1 smallest of ``p`` (the first sample of a run is free)."""
    with np.errstate(divide="ignore"):
        return float(np.sort(np.log(p))[:-1].sum())

def _persistence(lengths: np.ndarray, cap: int, least_runs: int = 20) -> float:
    """Largest observed chance that a run of equal values goes on one more sample.

    ``lengths``: run lengths (samples) capped at ``cap`` (runs that reach it are censored).
    For m = 1, 2, 4, … < cap with at least ``least_runs`` runs reaching m, the geometric
    estimate Σ(c − m) / Σ(c − m + [c < cap]) over those runs; the largest is returned (0 with
    no data). Coloured noise or a slowly wandering level makes runs persist longer than white
    noise would; this floor keeps such legitimate runs from being called stuck.
    """
    best, m = 0.0, 1
    while m < cap:
        reach = lengths[lengths >= m]
        if reach.size < least_runs:
            break
        trials = float((reach - m).sum() + (reach < cap).sum())
        if trials > 0.0:
            best = max(best, float((reach - m).sum()) / trials)
        m *= 2
    return best

def _slope_around(x: np.ndarray, seconds: np.ndarray, start: int, end: int,
                  reach: int = 30, least: int = 10) -> float:
    """Local trend (SI/s) across a run: medians of ≤ ``reach`` finite samples either side."""
    before = slice(max(start - reach, 0), start)
    after = slice(end + 1, end + 1 + reach)
    xb, xa = x[before], x[after]
    fb, fa = np.isfinite(xb), np.isfinite(xa)
    if fb.sum() < least or fa.sum() < least:
        return 0.0
    tb, ta = float(np.median(seconds[before][fb])), float(np.median(seconds[after][fa]))
    return float((np.median(xa[fa]) - np.median(xb[fb])) / (ta - tb))

def _spikes(x: np.ndarray, seconds: np.ndarray, valid: np.ndarray, col: Column,
            options: QualityOptions) -> tuple[np.ndarray, float]:
    """Spike mask (module doc) and the noise scale used (SI)."""
    out = np.zeros(x.size, dtype=bool)
    index = np.flatnonzero(valid)
    if index.size < 3:
        return out, math.nan
    xv, tv = x[index], seconds[index]
    residual = xv - _rolling_median(xv, options.spike_window)
    noise = math.sqrt(col.sigma**2 + col.quantum**2 / 12.0) if math.isfinite(col.sigma) else 0.0
    scale = max(noise, _trimmed_std(residual))
    dt = np.diff(tv)
    longer_step = np.maximum(np.r_[dt[0], dt], np.r_[dt, dt[-1]])
    threshold = np.maximum(options.spike_n_sigmas * scale, col.max_rate * longer_step)
    candidate = (threshold > 0.0) & (np.abs(residual) > threshold)
    sign = np.sign(residual)
    joined = np.zeros(index.size, dtype=bool)
    joined[1:] = candidate[1:] & candidate[:-1] & (sign[1:] == sign[:-1])
    starts, ends, ids = segments(joined)
    last = index.size - 1
    returns = (candidate[starts] & (ends - starts + 1 <= SPIKE_MAX_SAMPLES)
               & (starts > 0) & (ends < last)
               & ~candidate[np.maximum(starts - 1, 0)] & ~candidate[np.minimum(ends + 1, last)])
    out[index] = returns[ids] & candidate
    return out, scale

def _rolling_median(x: np.ndarray, window: int) -> np.ndarray:
    """Centred rolling median over ``window`` samples, windows truncated at the ends."""
    trend = median_filter(x, size=window, mode="nearest")
    half = min(window // 2, x.size)
    edges = np.unique(np.r_[np.arange(half), np.arange(x.size - half, x.size)])
    padded = np.concatenate([np.full(window // 2, np.nan), x, np.full(window // 2, np.nan)])
    trend[edges] = row_nanmedian(padded[edges[:, None] + np.arange(window)])
    return trend

def row_nanmedian(rows: np.ndarray) -> np.ndarray:
    """``np.nanmedian(rows, axis=1)``, bit for bit, without its masked-array machinery (5× its
    cost on the short rows here): sort each row (NaN last), take the low and high middle of its
    finite count c (the same element when c is odd) and halve their sum — numpy's own
    definition (``numpy.ma.median``, which ``nanmedian`` uses on rows this short). A row
    without a finite value gives NaN."""
    ordered = np.sort(rows, axis=1)
    counts = np.count_nonzero(~np.isnan(rows), axis=1)
    high = counts // 2
    low = np.where(counts % 2 == 1, high, high - 1)
    picked = np.arange(rows.shape[0])
    with np.errstate(invalid="ignore", over="ignore"):  # inf − inf, huge + huge: as numpy
        return (ordered[picked, low] + ordered[picked, high]) / 2.0

def segments(mask_continue: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments of samples where ``mask_continue[i]`` says i continues i − 1's segment."""
    starts = np.flatnonzero(~mask_continue)
    ends = np.r_[starts[1:] - 1, mask_continue.size - 1]
    ids = np.cumsum(~mask_continue) - 1
    return starts, ends, ids
