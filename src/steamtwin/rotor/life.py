"""Life consumed over a rotor run: fatigue and creep at a critical point, per ramp and per day.

:func:`rotor_life` takes a run frame of :class:`~steamtwin.rotor.model.RotorModel` (or the
full-order run's; columns ``<location>_equivalent`` in Pa and ``<location>_temperature`` in K)
and applies, at the chosen location:

* **fatigue**: rainflow (ASTM E1049-85 §5.4.4), Neuber, Manson–Coffin–Basquin with Morrow's
  mean-stress correction and the design-curve factors, Miner's sum —
  :func:`steamtwin.rotor.fatigue.fatigue_damage`, on the signed equivalent stress (model.py
  says why that scalar);
* **creep**: Robinson's time fraction with the Larson–Miller rupture time —
  :func:`steamtwin.rotor.creep.creep_damage`, on the tensile part of the same equivalent stress
  (compressive stress does no creep damage; the creep module's scope applies: none below 371 °C).

**Ramps** are found in the ``load`` signal (any unit) by a peak–valley filter with hysteresis
(the reversal filter that precedes rainflow counting; ASTM E1049-85 §3.2.5 "range-pair"
gating of small reversals): a reversal counts only once the load has moved back from the
running extreme by more than ``ramp_threshold``, so every ramp is a monotone change larger
than the threshold and noise or small load-following does not split it. A ramp starts where
the load last lay within ``ramp_tolerance`` of the extreme it leaves and ends where it first
comes within ``ramp_tolerance`` of the extreme it reaches.

**Attribution.** A fatigue cycle is charged to the window in which it closes (its later
reversal: a down-ramp's tensile swing and the next up-ramp's compressive one make one cycle,
closed on the way up); creep is charged per sample interval. Ramp windows run from a ramp's
start to the next ramp's start (the first from the record's start, the last to its end), and
day windows are calendar days of the index (UTC unless it carries a time zone), so both
partitions cover the record: per-ramp and per-day damages each sum to the totals.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import pandas as pd

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.creep import creep_damage
from steamtwin.rotor.fatigue import ASME_DESIGN_FACTORS, DesignFactors, fatigue_damage
from steamtwin.rotor.steel import TabulatedSteel

__all__ = ["DEFAULT_RAMP_THRESHOLD", "RotorLife", "detect_ramps", "rotor_life"]

DEFAULT_RAMP_THRESHOLD = 0.05
"""Smallest monotone load change counted as a ramp, fraction of the rated load (5 %: below it a
change is load-following, above it the rotor's thermal stress swings by tens of MPa)."""

DEFAULT_RAMP_TOLERANCE = 0.01
"""Band (fraction of the rated load) around a ramp's end levels that counts as the hold."""


def _seconds(index: pd.Index) -> np.ndarray:
    if isinstance(index, pd.DatetimeIndex):
        return np.asarray((index - index[0]).total_seconds(), dtype=float)
    return np.asarray(index, dtype=float)


def _reversals(load: np.ndarray, threshold: float) -> list[int]:
    """Sample indices of the load's extremes after hysteresis filtering (module docstring):
    consecutive extremes differ by more than ``threshold``."""
    high = low = 0
    direction = 0  # +1 rising, −1 falling, 0 not yet moved by the threshold
    extremes: list[int] = []
    extreme = 0
    for i in range(1, load.size):
        value = load[i]
        if direction == 0:
            high = i if value > load[high] else high
            low = i if value < load[low] else low
            if load[high] - load[low] > threshold:
                direction = 1 if high > low else -1
                extremes.append(low if direction == 1 else high)
                extreme = high if direction == 1 else low
        elif direction * (value - load[extreme]) > 0.0:
            extreme = i
        elif direction * (load[extreme] - value) > threshold:
            extremes.append(extreme)
            direction, extreme = -direction, i
    if direction != 0:
        extremes.append(extreme)
    return extremes


def detect_ramps(load: pd.Series, threshold: float, tolerance: float) -> pd.DataFrame:
    """Monotone load changes larger than ``threshold`` (the load's unit) in ``load``: columns
    ``start``, ``end`` (index labels), ``start_sample``, ``end_sample``, ``from_load``,
    ``to_load`` (the load's unit) and ``rate_per_min`` (load unit per minute)."""
    values = load.to_numpy(dtype=float)
    if not np.all(np.isfinite(values)):
        bad = int(np.flatnonzero(~np.isfinite(values))[0])
        raise RotorAreaError(f"load is not finite at row {bad} ({load.index[bad]})")
    if not (threshold > 0.0 and 0.0 <= tolerance < threshold):
        raise RotorAreaError(f"ramp threshold {threshold!r} must be > 0 and the tolerance "
                             f"{tolerance!r} in [0, threshold), in the load's unit")
    seconds = _seconds(load.index)
    rows = []
    points = _reversals(values, threshold)
    for first, last in pairwise(points):
        segment = values[first:last + 1]
        near_start = np.flatnonzero(np.abs(segment - values[first]) <= tolerance)
        near_end = np.flatnonzero(np.abs(segment - values[last]) <= tolerance)
        start, end = first + int(near_start[near_start < near_end[0]].max(initial=0)), (
            first + int(near_end[0]))
        duration = seconds[end] - seconds[start]
        rows.append({"start": load.index[start], "end": load.index[end],
                     "start_sample": start, "end_sample": end,
                     "from_load": float(values[first]), "to_load": float(values[last]),
                     "rate_per_min": (float(values[end] - values[start]) / duration * 60.0
                                      if duration > 0 else np.nan)})
    return pd.DataFrame(rows, columns=["start", "end", "start_sample", "end_sample",
                                       "from_load", "to_load", "rate_per_min"])


@dataclass(frozen=True)
class RotorLife:
    """Life consumed at one location over a run (damage dimensionless: 1 = crack initiation
    for fatigue, rupture for creep).

    ``cycles``: rainflow cycles (``range_pa``, ``mean_pa``, ``count``, ``start``/``end`` index
    labels, ``start_sample``/``end_sample``, ``temperature_k``, local Neuber values,
    ``cycles_to_failure``, ``damage``); ``per_ramp``: the ramps of :func:`detect_ramps` with
    ``fatigue_damage``, ``creep_damage``, ``damage`` and ``cumulative_damage`` of their windows
    (empty without a load signal); ``per_day``: the same per calendar day."""

    location: str
    cycles: pd.DataFrame
    fatigue_damage: float
    creep_damage: float
    per_ramp: pd.DataFrame
    per_day: pd.DataFrame
    design_factors: DesignFactors | None
    hours: float

    @property
    def total_damage(self) -> float:
        """Fatigue plus creep damage (linear damage summation, the usual rotor-life practice;
        ASME III Div. 5 HBB-T-1411 would use a bilinear interaction envelope instead)."""
        return self.fatigue_damage + self.creep_damage

    def summary(self) -> dict[str, object]:
        """Headline figures, JSON-ready."""
        return {"location": self.location, "hours": self.hours,
                "fatigue_damage": self.fatigue_damage, "creep_damage": self.creep_damage,
                "total_damage": self.total_damage, "cycles": float(self.cycles["count"].sum()),
                "largest_range_pa": float(self.cycles["range_pa"].to_numpy().max(initial=0.0)),
                "ramps": len(self.per_ramp),
                "design_factors": None if self.design_factors is None else {
                    "strain": self.design_factors.strain, "cycles": self.design_factors.cycles}}


def _windows(edges: np.ndarray, fatigue_closing: np.ndarray, fatigue: np.ndarray,
             creep_interval: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fatigue (cycles by closing sample) and creep (intervals i → i+1 by i) per window
    [edges[k], edges[k+1]); the last edge is the sample count."""
    which = np.searchsorted(edges, fatigue_closing, side="right") - 1
    by_fatigue = np.bincount(which, weights=fatigue, minlength=edges.size - 1)
    cumulative = np.concatenate([[0.0], np.cumsum(creep_interval)])
    creep_edges = np.minimum(edges, creep_interval.size)
    return by_fatigue, np.diff(cumulative[creep_edges])


def rotor_life(run_frame: pd.DataFrame, steel: TabulatedSteel, *,
               load: pd.Series | None = None,
               design_factors: DesignFactors | None = ASME_DESIGN_FACTORS,
               location: str = "groove", rated_load: float | None = None,
               ramp_threshold: float = DEFAULT_RAMP_THRESHOLD,
               ramp_tolerance: float = DEFAULT_RAMP_TOLERANCE,
               mean_stress_correction: str = "morrow") -> RotorLife:
    """Fatigue and creep damage at ``location`` over ``run_frame`` (module docstring).

    ``load``: the unit's load on the frame's index (any unit; fraction of rated when
    ``rated_load`` is not given) — ramps are counted where it changes monotonically by more
    than ``ramp_threshold`` × ``rated_load``; ``design_factors``: ``None`` for the mean curve.
    """
    columns = (f"{location}_equivalent", f"{location}_temperature")
    missing = [name for name in columns if name not in run_frame.columns]
    if missing:
        raise RotorAreaError(f"run frame lacks {missing} (has {list(run_frame.columns)}): "
                             "pass a RotorModel run's frame and a location it has")
    if len(run_frame) < 2:
        raise RotorAreaError("rotor life needs a run of at least 2 samples")
    frame = run_frame[list(columns)]
    gaps = frame.isna().any(axis=1).to_numpy()
    if gaps.any():
        row = int(np.flatnonzero(gaps)[0])
        raise RotorAreaError(f"run frame has no {location} stress/temperature at row {row} "
                             f"({run_frame.index[row]}); a full-order run with stress_every > 1 "
                             "must be thinned to its stress rows first")
    stress = frame[columns[0]].to_numpy(dtype=float)
    temperature = frame[columns[1]].to_numpy(dtype=float)
    seconds = _seconds(run_frame.index)
    fatigue = fatigue_damage(stress, temperature, steel, design=design_factors,
                             mean_stress_correction=mean_stress_correction)
    creep = creep_damage(np.maximum(stress, 0.0), temperature, seconds - seconds[0], steel)
    cycles = fatigue.cycles.rename(columns={"start": "start_sample", "end": "end_sample"})
    cycles.insert(3, "start", run_frame.index[cycles["start_sample"].to_numpy()])
    cycles.insert(4, "end", run_frame.index[cycles["end_sample"].to_numpy()])
    closing = cycles["end_sample"].to_numpy()
    damage = cycles["damage"].to_numpy()
    n = len(run_frame)

    def charged(table: pd.DataFrame, edges: np.ndarray) -> pd.DataFrame:
        by_fatigue, by_creep = _windows(np.append(edges, n), closing, damage,
                                        creep.interval_damage)
        total = by_fatigue + by_creep
        return table.assign(fatigue_damage=by_fatigue, creep_damage=by_creep, damage=total,
                            cumulative_damage=np.cumsum(total))

    per_ramp = pd.DataFrame(columns=["start", "end", "start_sample", "end_sample", "from_load",
                                     "to_load", "rate_per_min", "fatigue_damage",
                                     "creep_damage", "damage", "cumulative_damage"])
    if load is not None:
        if not load.index.equals(run_frame.index):
            raise RotorAreaError("load must be indexed like the run frame")
        rated = 1.0 if rated_load is None else float(rated_load)
        ramps = detect_ramps(load, ramp_threshold * rated, ramp_tolerance * rated)
        if len(ramps):
            edges = ramps["start_sample"].to_numpy().copy()
            edges[0] = 0
            per_ramp = charged(ramps, edges)
    index = run_frame.index
    if isinstance(index, pd.DatetimeIndex):
        days = (index.tz_convert("UTC") if index.tz is not None else index).floor("D")
    else:
        days = pd.Index(np.floor(seconds / 86400.0).astype(int))
    starts = np.flatnonzero(np.r_[True, days[1:] != days[:-1]])
    per_day = charged(pd.DataFrame({"day": days[starts], "start": index[starts],
                                    "samples": np.diff(np.append(starts, n))}), starts)
    return RotorLife(location=location, cycles=cycles, fatigue_damage=fatigue.total_damage,
                     creep_damage=creep.total_damage, per_ramp=per_ramp, per_day=per_day,
                     design_factors=design_factors,
                     hours=float(seconds[-1] - seconds[0]) / 3600.0)
