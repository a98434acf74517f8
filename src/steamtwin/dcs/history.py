"""One gate for every command that turns historian data into a result.

:func:`load_history` reads an export through its tag map, checks and cleans it with the quality
layer (:mod:`steamtwin.dcs.quality`) and returns the cleaned signals with the report. The rule is
the same for ``calibrate``, ``calibrate-online``, ``validate`` and ``rom predict`` (and for the
library's callers):

* every sample the quality layer marks bad — outside the tag map's valid range, a spike, part of
  a stuck run, marked Bad/Uncertain by the historian's quality column, or a signal whose level
  shows a unit mix-up — is flagged, replaced by NaN (never filled) and counted in the report, so
  it can reach no model input and no fit;
* an error-level finding (a required signal missing or all NaN, a unit mix-up, conflicting
  duplicate timestamps, too many out-of-range samples, ...) stops with
  :class:`DataQualityError` unless the caller accepts it explicitly (``accept_errors=True``,
  the CLI's ``--accept-quality-errors``); the bad samples stay excluded either way.

Several files of one historian (daily exports, say) load as one history: each is read and
checked on its own — its findings name its file and its own rows — and the cleaned parts are
joined in time order; files that overlap in time are refused. :meth:`History.windows` picks
windows by the one rule of :func:`steamtwin.dcs.windows.find_windows`.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.dcs.quality import Flag, QualityOptions, QualityReport, check_quality, clean
from steamtwin.dcs.readers import HistorianData, read_historian
from steamtwin.dcs.tagmap import TagMap, load_tag_map
from steamtwin.dcs.windows import (
    DataWindow,
    find_windows,
    load_fraction,
    parse_window,
    select_window,
)
from steamtwin.errors import DataError

__all__ = ["DEFAULT_TAG_MAP_NAME", "DataQualityError", "History", "check_history",
           "load_history", "quality_options", "tag_map_quality_fields"]

DEFAULT_TAG_MAP_NAME = "tags.toml"
"""The tag map :func:`load_history` looks for next to the data when none is given (the name
``steamtwin plant`` writes)."""

OVERRIDE_OPTION = "--accept-quality-errors"
"""The CLI option that lets a command go on past error-level findings."""


class DataQualityError(DataError):
    """The data have error-level quality findings and the caller did not accept them."""

    def __init__(self, report: QualityReport) -> None:
        self.report = report
        shown = report.errors[:5]
        lines = [f"  - {f.message}" for f in shown]
        more = len(report.errors) - len(shown)
        if more:
            lines.append(f"  … and {more} more")
        super().__init__(
            f"{report.source}: {len(report.errors)} data-quality error(s):\n"
            + "\n".join(lines)
            + f"\nFix the data or the tag map (see 'steamtwin dcs check'), or pass "
            f"{OVERRIDE_OPTION} to go on with the bad samples excluded."
        )


@dataclass(frozen=True)
class History:
    """Cleaned canonical signals (SI: Pa, K, kg/s, W) and what the gate did to them.

    ``data``: time-sorted, unique tz-aware index; every excluded sample is NaN. ``flags``: the
    per-sample :class:`~steamtwin.dcs.quality.Flag` codes. ``report``: detection and cleaning
    findings (``report.counts("rejected")`` counts the excluded samples per signal and reason).
    ``historian``: the export as read (source, dialect, reader notes).
    """

    data: pd.DataFrame
    flags: pd.DataFrame
    report: QualityReport
    historian: HistorianData

    @property
    def excluded(self) -> dict[str, int]:
        """Samples excluded per signal (all reasons together)."""
        return {str(name): int(((self.flags[name].to_numpy() & int(Flag.REMOVED)) != 0).sum())
                for name in self.flags.columns}

    @property
    def tag_map(self) -> TagMap:
        """The tag map the history was read through."""
        return self.historian.tag_map

    def windows(self, rated_load_w: float, *,
                given: Sequence[str | tuple[pd.Timestamp, pd.Timestamp]] = (),
                min_steady_s: float = 3600.0, max_steady_s: float = 7200.0,
                tolerance: float = 0.02, ramps: bool = True) -> list[DataWindow]:
        """Windows of the cleaned data, in time order.

        ``given``: START/END spans (ISO 8601 text with UTC offsets, or two tz-aware
        timestamps), each one window of kind "given"; without them, the one rule of
        :func:`~steamtwin.dcs.windows.find_windows`: the last ``max_steady_s`` (s) of every
        steady-load hold (± ``tolerance`` of ``rated_load_w``, W) of at least ``min_steady_s``
        (s), and with ``ramps`` the load ramps. ValueError naming the span or the file.
        """
        if not given:
            return find_windows(self.data, rated_load_w, min_steady_s=min_steady_s,
                                max_steady_s=max_steady_s, tolerance=tolerance, ramps=ramps,
                                source=self.historian.source)
        result = []
        for span in given:
            label = f"--window {span!r}" if isinstance(span, str) else f"window {span}"
            start, end = parse_window(span) if isinstance(span, str) else span
            try:
                frame = select_window(self.data, start, end)
            except ValueError as error:
                raise ValueError(f"{label}: {error}") from None
            result.append(DataWindow(frame, "given", load_fraction(frame, rated_load_w)))
        return result


def load_history(data: str | Path | Sequence[str | Path],
                 tag_map: str | Path | TagMap | None = None, *,
                 required: Collection[str] = (), accept_errors: bool = False) -> History:
    """Read, check and clean a historian export (CSV or Parquet, wide or long) through its tag
    map; a list of exports of one historian loads as one history (module docstring).

    ``tag_map``: the tag map (TOML path or :class:`~steamtwin.dcs.tagmap.TagMap`); None takes
    ``tags.toml`` next to the (first) export. ``required``: canonical signals the caller cannot
    do without; each must be mapped in the tag map and present in the file (a ``ValueError``
    naming the signal, tag and files otherwise). Raises :class:`DataQualityError` on
    error-level findings unless ``accept_errors``; reader and tag-map errors propagate (both
    ``ValueError``).
    """
    paths = [data] if isinstance(data, str | Path) else list(data)
    if not paths:
        raise ValueError("load_history: no historian file given")
    if tag_map is None:
        tag_map = Path(paths[0]).with_name(DEFAULT_TAG_MAP_NAME)
        if not tag_map.is_file():
            raise ValueError(f"{paths[0]}: no tag map given and no {DEFAULT_TAG_MAP_NAME} next "
                             "to it; pass the tag map (TOML) that maps the export's columns")
    tags = tag_map if isinstance(tag_map, TagMap) else load_tag_map(tag_map)
    parts = [_load_one(path, tags, tuple(required), accept_errors) for path in paths]
    return parts[0] if len(parts) == 1 else _joined(parts)


def check_history(data: str | Path, tag_map: str | Path | TagMap,
                  required: Collection[str] = ()) -> tuple[HistorianData, QualityReport]:
    """The export as read and its quality report, nothing cleaned (``steamtwin dcs check``):
    the same checks, with the same settings, as :func:`load_history` applies."""
    tags = tag_map if isinstance(tag_map, TagMap) else load_tag_map(tag_map)
    historian = read_historian(data, tags)
    return historian, check_quality(historian.signals, quality_options(historian, required))


def _load_one(data: str | Path, tag_map: TagMap, required: tuple[str, ...],
              accept_errors: bool) -> History:
    unmapped = [name for name in required if name not in tag_map.signals]
    if unmapped:
        raise ValueError(f"{tag_map.source}: signal(s) {unmapped} are needed but not mapped; "
                         "add [signals.<name>] with column and unit")
    historian = read_historian(data, tag_map)
    absent = {name: tag for name, tag in historian.missing_signals.items() if name in required}
    if absent:
        kind = "column" if tag_map.layout == "wide" else "tag"
        raise ValueError(f"{data}: no {kind} " + ", ".join(
            f"{tag!r} (signal {name}, mapped in {tag_map.source})" for name, tag in absent.items())
            + "; it is needed")
    result = clean(historian.signals, quality_options(historian, required))
    if result.report.errors and not accept_errors:
        raise DataQualityError(result.report)
    return History(data=result.data, flags=result.flags, report=result.report,
                   historian=historian)


def _joined(parts: list[History]) -> History:
    """One history of several files' cleaned parts, in time order; overlaps refused."""
    parts = sorted(parts, key=lambda part: part.data.index[0])
    for before, after in pairwise(parts):
        if after.data.index[0] <= before.data.index[-1]:
            raise ValueError(
                f"{before.historian.source} ({before.data.index[0]} … {before.data.index[-1]}) "
                f"and {after.historian.source} ({after.data.index[0]} … "
                f"{after.data.index[-1]}) overlap in time; give files of one historian that "
                "follow each other")
    first = parts[0].historian
    signals = list(dict.fromkeys(name for part in parts for name in part.data.columns))
    bad_quality = {name: np.concatenate([
        part.historian.bad_quality.get(name, np.zeros(len(part.data), dtype=bool))
        for part in parts]) for name in signals}
    notes: dict[str, int] = {}
    counts: dict[str, dict[str, int]] = {}
    for part in parts:
        for key, value in part.historian.notes.items():
            notes[key] = notes.get(key, 0) + value
        for name, classes in part.historian.quality_counts.items():
            for key, value in classes.items():
                counts.setdefault(name, {})[key] = counts.get(name, {}).get(key, 0) + value
    source = "; ".join(part.historian.source for part in parts)
    historian = replace(
        first, source=source, notes=notes, bad_quality=bad_quality, quality_counts=counts,
        signals=pd.concat([part.historian.signals for part in parts]),
        extras=pd.concat([part.historian.extras for part in parts]))
    report = QualityReport(
        findings=tuple(f for part in parts for f in part.report.findings), source=source,
        n_rows=sum(part.report.n_rows for part in parts),
        signals=tuple(dict.fromkeys(s for part in parts for s in part.report.signals)))
    return History(data=pd.concat([part.data for part in parts]),
                   flags=pd.concat([part.flags for part in parts]), report=report,
                   historian=historian)


def quality_options(historian: HistorianData, required: Collection[str] = ()
                    ) -> QualityOptions:
    """The options of :func:`~steamtwin.dcs.quality.check_quality` and
    :func:`~steamtwin.dcs.quality.clean` from everything the tag map and the export give: valid
    ranges, declared units, tags, noise, resolution, rate limits, the historian's quality marks.
    ``dcs check`` and the gate use the same, so what one reports is what the other excludes."""
    return QualityOptions(
        required=tuple(required), source=historian.source, bad_quality=historian.bad_quality,
        **tag_map_quality_fields(historian.tag_map, historian.signals.columns))


def tag_map_quality_fields(tag_map: TagMap, signals: Collection[str] | None = None
                           ) -> dict[str, dict[str, Any]]:
    """The :class:`~steamtwin.dcs.quality.QualityOptions` fields a tag map states for
    ``signals`` (default: all it maps): valid ranges, declared units, tags, noise, resolution
    and rate limits (SI), each signal → value, signals that state none left out."""
    specs = [spec for spec in tag_map.signals.values()
             if signals is None or spec.signal in signals]

    def per_signal(attribute: str) -> dict[str, Any]:
        return {s.signal: getattr(s, attribute) for s in specs
                if getattr(s, attribute) is not None}

    return {"ranges": per_signal("valid_range_si"),
            "declared_units": {s.signal: s.unit for s in specs},
            "tag_names": {s.signal: s.column for s in specs},
            "noise_si": per_signal("noise_si"), "resolution_si": per_signal("resolution_si"),
            "max_rate_si": per_signal("max_rate_si")}
