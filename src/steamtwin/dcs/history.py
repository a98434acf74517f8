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
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from steamtwin.dcs.quality import Flag, QualityReport, clean
from steamtwin.dcs.readers import HistorianData, read_historian
from steamtwin.dcs.tagmap import TagMap, load_tag_map
from steamtwin.errors import DataError

__all__ = ["DataQualityError", "History", "load_history", "quality_options"]

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


def load_history(data: str | Path, tags: str | Path | TagMap, *,
                 required: Collection[str] = (), accept_errors: bool = False) -> History:
    """Read, check and clean a historian export (CSV or Parquet) through its tag map.

    ``required``: canonical signals the caller cannot do without; each must be mapped in the
    tag map and present in the file (a ``ValueError`` naming the signal, tag and files
    otherwise). Raises :class:`DataQualityError` on error-level findings unless
    ``accept_errors``; reader and tag-map errors propagate (both ``ValueError``).
    """
    tag_map = tags if isinstance(tags, TagMap) else load_tag_map(tags)
    required = tuple(required)
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
    result = clean(historian.signals, **quality_options(historian, required))
    if result.report.errors and not accept_errors:
        raise DataQualityError(result.report)
    return History(data=result.data, flags=result.flags, report=result.report,
                   historian=historian)


def quality_options(historian: HistorianData, required: Collection[str] = ()
                    ) -> dict[str, Any]:
    """Keyword arguments of :func:`~steamtwin.dcs.quality.check_quality` and
    :func:`~steamtwin.dcs.quality.clean` from everything the tag map and the export give: valid
    ranges, declared units, tags, noise, resolution, rate limits, the historian's quality marks.
    ``dcs check`` and the gate use the same, so what one reports is what the other excludes."""
    specs = [spec for spec in historian.tag_map.signals.values()
             if spec.signal in historian.signals.columns]

    def per_signal(attribute: str) -> dict[str, Any]:
        return {s.signal: getattr(s, attribute) for s in specs
                if getattr(s, attribute) is not None}

    return {
        "required": tuple(required),
        "ranges": per_signal("valid_range_si"),
        "declared_units": {s.signal: s.unit for s in specs},
        "tag_names": {s.signal: s.column for s in specs},
        "source": historian.source,
        "bad_quality": historian.bad_quality,
        "noise_si": per_signal("noise_si"),
        "resolution_si": per_signal("resolution_si"),
        "max_rate_si": per_signal("max_rate_si"),
    }
