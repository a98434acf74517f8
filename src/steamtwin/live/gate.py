"""The live twin's data-quality gate: the batch checks, incrementally (issue 21, item 4).

The stream passes the same detectors as a historian file (:func:`steamtwin.dcs.quality.clean`:
valid range, spikes, stuck runs, the historian's/OPC UA status, unit plausibility), run over a
sliding window: ``context_samples`` already passed (the left context the detectors' noise and
trend estimates need) plus the new samples. A sample's verdict is final once
``lookahead_samples`` newer samples are in — the spike detector's half window (its rolling
median is centred) and the shortest stuck run (``stuck_min_duration_s`` at the nominal step),
whichever is longer, so a spike or a stuck run starting at a sample is recognised before that
sample leaves the gate. Samples are judged one clock bin of ``release_s`` (60 s) at a time, each
bin over its own window — the ``context_samples`` before it, the bin, the ``lookahead_samples``
after it — because the detectors' statistics (noise, spread of departures, run persistence)
are taken over the window: a window that followed the arriving blocks would make a verdict
depend on how the stream was cut, and a restart (which resumes with other cuts) would not
reproduce the uninterrupted run's flags (tested, :mod:`tests.live.test_restart_exactness`).
The price is that latency (60 s at 1 Hz, plus up to one bin, by default); the gain is that a
bad sample is flagged and stored, never fed to the model as good. The verdicts agree with the
batch gate's on ≥ 99.9 % of values (tested on half an hour with ~40 injected dropouts, spikes
and stuck runs, for any block size): what differs is the spike detector's spread of departures,
taken over the whole file in batch and over the window here, so near a ramp a few samples can
go one way or the other. Rejected values become NaN
with their :class:`~steamtwin.dcs.quality.Flag` bits; the findings of each passed block name
signal, tag and time. Nothing is dropped: every sample in comes out once, in time order.

Which detector needs how much look-ahead (the design of the provisional values, issue 21's
latency point): the valid range, the source's status and a missing value are judged per sample
and need none; unit plausibility is a verdict on a whole signal (the median of the window) and
needs none either; a spike is a departure from a *centred* rolling median that returns within
two samples — it needs the half window ahead for the batch gate's median (one neighbour would
tell a return, not the robust trend); a stuck run is one of at least ``stuck_min_duration_s`` of
equal values whose improbability is judged against the trend on up to 30 samples after the run
— it needs the run and that trend. So the final verdict waits the longer (60 s at 1 Hz), while
:meth:`StreamGate.pending` gives every waiting sample the verdicts that need no look-ahead at
once: the live twin stores a *provisional* value from them as soon as a sample arrives
(:mod:`steamtwin.live.service`), and a spike or stuck value can reach that provisional value
but never the final row nor the model state the final chain carries.

The detectors run over the window as :func:`steamtwin.dcs.quality.cleaning.clean_flags` (the
batch ``clean``'s masks without its messages, which the gate builds for its passed samples
only): the same verdicts, bit for bit, as ``clean`` over the same window (tested with random
streams, :mod:`tests.live.test_gate_equivalence`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.dcs.history import tag_map_quality_fields
from steamtwin.dcs.quality import Finding, Flag, QualityOptions
from steamtwin.dcs.quality.cleaning import clean_flags
from steamtwin.dcs.tagmap import TagMap

__all__ = ["GateOutput", "StreamGate", "gate_options"]


def gate_options(tag_map: TagMap, instruments: pd.DataFrame | None = None) -> dict[str, Any]:
    """:class:`~steamtwin.dcs.quality.QualityOptions` fields from ``tag_map`` (ranges,
    declared units, tags, noise, resolution, rate limits), as the batch gate takes them.
    ``instruments``: a table indexed by signal with ``noise_sigma`` and ``resolution`` (SI;
    e.g. the virtual plant's ``injected.sensors``), filling what the tag map does not state."""
    fields = tag_map_quality_fields(tag_map)
    if instruments is not None:
        for column, key in (("noise_sigma", "noise_si"), ("resolution", "resolution_si")):
            given = fields[key]
            for signal, value in instruments[column].items():
                if signal in tag_map.signals and signal not in given and float(value) > 0.0:
                    given[str(signal)] = float(value)
    return {**fields, "source": tag_map.source}


@dataclass
class GateOutput:
    """Samples whose verdict is final: ``data`` (SI, NaN where rejected or missing),
    ``flags`` (:class:`~steamtwin.dcs.quality.Flag` bits per value) and ``findings`` (the
    rejections among these samples, each naming signal, tag and first time)."""

    data: pd.DataFrame
    flags: pd.DataFrame
    findings: list[Finding] = field(default_factory=list)


class StreamGate:
    """Incremental gate over a stream of sample blocks (see the module docstring).

    ``options``: :class:`~steamtwin.dcs.quality.QualityOptions` fields (e.g.
    :func:`gate_options`); ``nominal_step_s``: the stream's sample step (s);
    ``context_samples``: passed samples kept as left context; ``release_s``: the clock bins
    (s, UTC-aligned) judged together, each over its own window.
    """

    def __init__(self, options: Mapping[str, Any], nominal_step_s: float = 1.0,
                 context_samples: int = 1800, spike_window: int = 61,
                 stuck_min_duration_s: float = 30.0, release_s: float = 60.0) -> None:
        if not (math.isfinite(nominal_step_s) and nominal_step_s > 0.0):
            raise ValueError(f"nominal_step_s must be positive (got {nominal_step_s!r})")
        if not (isinstance(release_s, int | float) and math.isfinite(release_s)
                and release_s > 0.0):
            raise ValueError(f"release_s must be a positive number of seconds (got "
                             f"{release_s!r})")
        if context_samples < spike_window:
            raise ValueError(f"context_samples ({context_samples}) must hold at least one "
                             f"spike window ({spike_window})")
        self.options = dict(options)
        self.nominal_step_s = nominal_step_s
        self.context_samples = context_samples
        self.spike_window = spike_window
        self.stuck_min_duration_s = stuck_min_duration_s
        self.release_s = float(release_s)
        self.lookahead_samples = max(spike_window // 2 + 1,
                                     math.ceil(2.0 * stuck_min_duration_s / nominal_step_s))
        self._values: pd.DataFrame | None = None  # context + pending, raw SI
        self._bad: np.ndarray | None = None  # True where the source's status excluded a value
        self._passed = 0  # rows of _values already passed (the context)

    def push(self, data: pd.DataFrame, bad: pd.DataFrame | None = None) -> GateOutput:
        """Take new samples (SI, time index after every earlier one; ``bad``: True where the
        source's status excluded the value) and return those now final (maybe none):
        :meth:`add` then :meth:`release`."""
        self.add(data, bad)
        return self.release()

    def add(self, data: pd.DataFrame, bad: pd.DataFrame | None = None) -> None:
        """Take new samples (as :meth:`push`) without judging any: they wait in
        :meth:`pending` until :meth:`release`."""
        if len(data) == 0:
            return
        if self._values is not None and not data.columns.equals(self._values.columns) and \
                set(data.columns) == set(self._values.columns):
            data = data[self._values.columns]  # the gate's order: its status bits are positional
        if bad is None:
            bad_values = np.zeros(data.shape, dtype=bool)
        elif bad.index.equals(data.index) and bad.columns.equals(data.columns):
            bad_values = bad.to_numpy(dtype=bool)  # a source's usual block: no reindex
        else:
            bad_values = bad.reindex(index=data.index, columns=data.columns,
                                     fill_value=False).to_numpy(dtype=bool)
        if self._values is not None and len(self._values) and not (
                data.index[0] > self._values.index[-1]):
            raise ValueError(f"samples from {data.index[0]} do not come after the gate's last "
                             f"({self._values.index[-1]}); the source must pass them in order")
        if self._values is None or self._bad is None:
            self._values, self._bad = data.copy(), bad_values
        elif data.columns.equals(self._values.columns):  # one array, not pandas' concat
            self._values = pd.DataFrame(
                np.concatenate([self._values.to_numpy(dtype=float), data.to_numpy(dtype=float)]),
                index=self._values.index.append(data.index), columns=self._values.columns)
            self._bad = np.concatenate([self._bad, bad_values])
        else:
            self._values = pd.concat([self._values, data])
            self._bad = np.concatenate([self._bad, bad_values])

    def release(self, min_samples: int = 1) -> GateOutput:
        """The samples whose look-ahead is in, judged — once at least ``min_samples`` of them
        are (fewer: none yet; a live service judges a minute at a time, not every second)."""
        if self._values is None:
            return self._empty(pd.Index([]))
        ends = self._group_ends()
        ready = ends[ends <= len(self._values) - self.lookahead_samples]
        stop = int(ready[-1]) if ready.size else self._passed
        if stop - self._passed < min_samples:
            return self._empty(self._values.columns)
        return self._release(stop)

    def ready(self) -> int:
        """How many samples :meth:`release` would judge now (their look-ahead is in): a
        caller that releases a minute at a time asks this every second instead of building an
        empty output."""
        if self._values is None:
            return 0
        ends = self._group_ends()  # whole clock bins whose look-ahead is in, as release takes
        done = ends[ends <= len(self._values) - self.lookahead_samples]
        return int(done[-1]) - self._passed if done.size else 0

    def flush(self) -> GateOutput:
        """Everything still pending (the end of a stream: no more look-ahead)."""
        if self._values is None:
            return self._empty(pd.Index([]))
        return self._release(len(self._values))

    def pending(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        """The samples still waiting for their look-ahead, with the verdict of the checks that
        need none (valid range, the source's status, missing values): their values (SI, NaN
        where rejected so far) and :class:`~steamtwin.dcs.quality.Flag` bits. Provisional — a
        spike or a stuck run among them is only recognised once the look-ahead is in."""
        if self._values is None or self._bad is None:
            empty = self._empty(pd.Index([]))
            return empty.data, empty.flags
        values = self._values.iloc[self._passed:]
        bad = self._bad[self._passed:]
        x = values.to_numpy(dtype=float)
        ranges = self.options.get("ranges", {})
        lo = np.array([ranges.get(name, (-np.inf, np.inf))[0] for name in values.columns])
        hi = np.array([ranges.get(name, (-np.inf, np.inf))[1] for name in values.columns])
        missing = np.isnan(x)
        with np.errstate(invalid="ignore"):
            out_of_range = ~missing & ((x < lo) | (x > hi))
        status = bad & ~missing
        flags = (missing * np.uint16(Flag.MISSING) | out_of_range * np.uint16(Flag.OUT_OF_RANGE)
                 | bad * np.uint16(Flag.BAD_QUALITY)).astype(np.uint16)
        removed = out_of_range | status
        flags[removed] |= np.uint16(Flag.REMOVED)
        return (pd.DataFrame(np.where(removed, np.nan, x), index=values.index,
                             columns=values.columns),
                pd.DataFrame(flags, index=values.index, columns=values.columns))

    def _group_ends(self) -> np.ndarray:
        """Positions in the buffer where each pending clock bin of ``release_s`` ends (the
        first sample of the next bin; the open last bin has none)."""
        assert self._values is not None
        step_ns = round(self.release_s * 1e9)
        index = self._values.index[self._passed:]
        bins = np.floor_divide(index.tz_convert("UTC").as_unit("ns").asi8, step_ns)
        return self._passed + np.flatnonzero(np.diff(bins)) + 1

    def _release(self, stop: int) -> GateOutput:
        """Judge the pending samples before buffer position ``stop`` (a bin's end or the
        buffer's end), one clock bin at a time, each over its own window: the
        ``context_samples`` before the bin, the bin, and the ``lookahead_samples`` after it
        (fewer only at the stream's end). The window depends on the stream alone, not on
        how it was cut into blocks or where a restart resumed, so neither changes a verdict."""
        assert self._values is not None and self._bad is not None
        if stop <= self._passed:
            return self._empty(self._values.columns)
        ends = self._group_ends()
        edges = [self._passed, *ends[ends < stop].tolist(), stop]
        parts = [self._judge(a, b) for a, b in itertools.pairwise(edges)]
        data = pd.concat([part[0] for part in parts])
        flags = pd.concat([part[1] for part in parts])
        findings = _findings(flags, self.options.get("tag_names", {}))
        keep = max(0, stop - self.context_samples)
        self._values = self._values.iloc[keep:]
        self._bad = self._bad[keep:]
        self._passed = stop - keep
        return GateOutput(data, flags, findings)

    def _judge(self, start: int, stop: int) -> tuple[pd.DataFrame, pd.DataFrame]:
        """Values (NaN where rejected) and flag bits of buffer rows ``start:stop``, judged by
        the batch detectors over the window around them (:meth:`_release`)."""
        assert self._values is not None and self._bad is not None
        first = max(0, start - self.context_samples)
        last = min(len(self._values), stop + self.lookahead_samples)
        window, bad = self._values.iloc[first:last], self._bad[first:last]
        rows, codes = clean_flags(window, QualityOptions(
            nominal_step_s=self.nominal_step_s, spike_window=self.spike_window,
            stuck_min_duration_s=self.stuck_min_duration_s,
            bad_quality={name: bad[:, j] for j, name in enumerate(window.columns)},
            out_of_range_error_fraction=1.0,  # a stream has no "file" to refuse
            **self.options))
        kept = window.iloc[rows[start - first:stop - first]]
        codes = codes[start - first:stop - first]
        values = np.where((codes & np.uint16(Flag.REMOVED)) != 0, np.nan,
                          kept.to_numpy(dtype=float))
        return (pd.DataFrame(values, index=kept.index, columns=kept.columns),
                pd.DataFrame(codes, index=kept.index, columns=kept.columns))

    def get_state(self) -> dict[str, Any]:
        """JSON-ready context (the passed samples the detectors look back on), exact; samples
        still waiting for their look-ahead are not kept: a restart receives them again."""
        if self._values is None or self._bad is None:
            return {"columns": [], "times": [], "values": [], "bad": []}
        context = self._values.iloc[:self._passed]
        return {"columns": [str(c) for c in context.columns],
                "times": [t.isoformat() for t in context.index],
                "values": [[None if not np.isfinite(v) else float(v) for v in row]
                           for row in context.to_numpy(dtype=float)],
                "bad": self._bad[:self._passed].tolist()}

    def set_state(self, state: Mapping[str, Any]) -> StreamGate:
        """Continue after the context :meth:`get_state` wrote."""
        if not state.get("times"):
            self._values = self._bad = None
            self._passed = 0
            return self
        index = pd.DatetimeIndex(pd.to_datetime(state["times"], utc=True), name="time")
        values = np.array([[np.nan if v is None else v for v in row] for row in state["values"]],
                          dtype=float)
        self._values = pd.DataFrame(values, index=index, columns=state["columns"])
        self._bad = np.array(state["bad"], dtype=bool).reshape(values.shape)
        self._passed = len(index)
        return self

    @staticmethod
    def _empty(columns: pd.Index) -> GateOutput:
        index = pd.DatetimeIndex([], tz="UTC", name="time")
        return GateOutput(pd.DataFrame(index=index, columns=columns, dtype=float),
                          pd.DataFrame(index=index, columns=columns, dtype=np.uint16))


_REJECTIONS = ((Flag.SPIKE, "spike", "spike(s) replaced by NaN"),
               (Flag.OUT_OF_RANGE, "out_of_range", "out-of-range value(s) replaced by NaN"),
               (Flag.STUCK, "stuck", "stuck value(s) replaced by NaN"),
               (Flag.BAD_QUALITY, "historian_quality",
                "value(s) with a bad status replaced by NaN"))


def _findings(flags: pd.DataFrame, tags: Mapping[str, str]) -> list[Finding]:
    """One finding per signal and kind of rejection among these rows: count, first time."""
    findings = []
    for signal in flags.columns:
        codes = flags[signal].to_numpy(dtype=np.uint16)
        removed = (codes & np.uint16(Flag.REMOVED)) != 0
        for bit, kind, what in _REJECTIONS:
            mask = removed & ((codes & np.uint16(bit)) != 0)
            if mask.any():
                first = int(np.flatnonzero(mask)[0])
                tag = tags.get(signal)
                findings.append(Finding(
                    kind, "warning", signal, tag, int(mask.sum()), None, flags.index[first],
                    f"{signal} ({tag}): {int(mask.sum())} {what}, the first at "
                    f"{flags.index[first]}", "rejected"))
    return findings
