"""Read plant historian exports (CSV or Parquet, wide or long) into canonical SI signals.

The reader translates columns/tags with a :class:`~steamtwin.dcs.tagmap.TagMap` and converts to the
SI units of :data:`~steamtwin.dcs.signals.SIGNALS` (Pa, K, kg/s, W). It never sorts, drops or
merges samples: rows stay in file order with duplicate and out-of-order timestamps kept (a quality
checker flags them), unmapped columns/tags are kept in ``extras``, and every decision the reader had
to take is counted in ``notes``. Valid ranges of the tag map are not applied here.

Time index: timezone-aware UTC ``DatetimeIndex`` (nanoseconds) named ``"time"``. Timestamps are
ISO 8601 text (``2026-03-01 10:00:00``, ``2026-03-01T10:00:00+08:00``, ``...Z``) or Parquet
timestamps; those without an offset are local time in ``historian.time_zone``.

Long layout: one output row per (timestamp, occurrence) key, where the occurrence counts repeated
rows of the same tag at the same timestamp — so repeated entries are kept in order, never merged.
If every tag's own rows are in time order the keys are merged in time order; otherwise the keys
appear in order of first appearance in the file (so the disorder stays visible).

Errors (:class:`HistorianFormatError`) name the file, column or tag, the row — ``line N`` (1-based
line in a CSV file, header = line 1, one record per line) or ``row index N`` (0-based, Parquet) —
and the expected unit or format.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap
from steamtwin.units import convert

_ISO_EXAMPLE = "ISO 8601, e.g. '2026-03-01 10:00:00' or '2026-03-01T10:00:00+08:00'"
_OFFSET = r"\d:\d{2}(?::\d{2}(?:[.,]\d+)?)?\s*(?:[Zz]|[+-]\d{2}(?::?\d{2})?)$"
NOTE_KEYS = (
    "missing_signal_columns",  # mapped signals whose column (wide) or tag (long) is absent
    "timestamps_localized",  # naive timestamps read as local time in historian.time_zone
    "blank_lines",  # empty CSV lines skipped (they hold no data)
    "duplicate_column_names",  # repeated unmapped CSV header names (pandas appends ".1", ...)
    "long_duplicate_entries",  # long rows repeating a tag at a timestamp (kept as extra rows)
    "long_tags_out_of_order",  # tags whose own long rows go back in time (index in file order)
    "missing_quality_column",  # historian.quality_column configured but absent from the file
)


class HistorianFormatError(ValueError):
    """A historian export is malformed; the message names file, column/tag, row and format."""


@dataclass(frozen=True)
class HistorianData:
    """Canonical signals in SI (Pa, K, kg/s, W) and everything else the export held.

    ``signals`` and ``extras`` share one UTC ``DatetimeIndex`` named ``"time"`` in file order.
    ``extras`` holds unmapped columns (wide) or unmapped tags (long), as read, plus
    ``quality:<tag>`` columns in the long layout. ``notes`` counts reader decisions (see
    :data:`NOTE_KEYS`).
    """

    signals: pd.DataFrame
    extras: pd.DataFrame
    tag_map: TagMap
    source: str
    notes: dict[str, int] = field(default_factory=dict)

    @property
    def missing_signals(self) -> dict[str, str]:
        """Mapped signals absent from the file: signal name → historian column or tag."""
        return {
            name: spec.column
            for name, spec in self.tag_map.signals.items()
            if name not in self.signals.columns
        }


def read_historian(path: str | Path, tag_map: TagMap) -> HistorianData:
    """Read a ``.csv`` or ``.parquet`` historian export into SI canonical signals.

    Raises :class:`HistorianFormatError` naming file, column/tag, row and expected format.
    """
    path = Path(path)
    reader = _Reader(path, tag_map)
    if tag_map.layout == "wide":
        signals, extras = reader.wide()
    else:
        signals, extras = reader.long()
    return HistorianData(
        signals=signals, extras=extras, tag_map=tag_map, source=str(path), notes=reader.notes
    )


def canonical_to_historian(signals_si: pd.DataFrame, tag_map: TagMap) -> pd.DataFrame:
    """Canonical SI signals → a wide historian frame: time column + mapped columns in tag units.

    The index (a ``DatetimeIndex``) becomes ``tag_map.time_column``, in ``historian.time_zone``
    when the index is timezone-aware and the map names one. Signals the map does not cover raise
    ``ValueError``; mapped signals absent from ``signals_si`` are left out.
    """
    unmapped = [name for name in signals_si.columns if name not in tag_map.signals]
    if unmapped:
        raise ValueError(
            f"signals {unmapped} are not mapped in {tag_map.source} "
            f"(mapped: {', '.join(tag_map.signals)})"
        )
    times = signals_si.index
    if isinstance(times, pd.DatetimeIndex) and times.tz is not None and tag_map.time_zone:
        times = times.tz_convert(tag_map.time_zone)
    out = {tag_map.time_column: np.asarray(times)
           if not isinstance(times, pd.DatetimeIndex) else times}
    for name, spec in tag_map.signals.items():
        if name in signals_si.columns:
            values = signals_si[name].to_numpy(dtype=float)
            out[spec.column] = convert(values, SIGNALS[name].si_unit, spec.unit)
    return pd.DataFrame(out)


class _Reader:
    """One read: the file, its tag map and the notes gathered on the way."""

    def __init__(self, path: Path, tag_map: TagMap) -> None:
        self.path, self.tag_map = path, tag_map
        self.notes = dict.fromkeys(NOTE_KEYS, 0)
        suffix = path.suffix.lower()
        if suffix not in (".csv", ".parquet"):
            raise HistorianFormatError(
                f"{path}: unsupported file type {path.suffix!r}; expected .csv or .parquet"
            )
        self.is_csv = suffix == ".csv"
        self.frame = self._read_csv() if self.is_csv else self._read_parquet()

    # --- files ----------------------------------------------------------------------------------

    def _read_csv(self) -> pd.DataFrame:
        text_columns = [self.tag_map.time_column]
        if self.tag_map.layout == "long":
            text_columns.append(self.tag_map.tag_column)
        try:
            header = self._csv_header()
            frame = pd.read_csv(
                self.path,
                encoding="utf-8-sig",
                skip_blank_lines=False,
                keep_default_na=False,
                na_values=[""],
                dtype=dict.fromkeys(text_columns, str),
                low_memory=False,
            )
        except (OSError, UnicodeDecodeError, pd.errors.ParserError,
                pd.errors.EmptyDataError) as error:
            raise HistorianFormatError(f"{self.path}: cannot read CSV: {error}") from None
        self._check_duplicate_names(header)
        blank = frame.isna().all(axis=1).to_numpy()
        if blank.any():
            self.notes["blank_lines"] = int(blank.sum())
            frame = frame.loc[~blank]  # keeps the row labels, so labels still give the line
        return frame

    def _csv_header(self) -> list[str]:
        with self.path.open(encoding="utf-8-sig", newline="") as handle:
            return next(csv.reader(handle), [])

    def _check_duplicate_names(self, header: list[str]) -> None:
        protected = {self.tag_map.time_column}
        if self.tag_map.layout == "wide":
            protected |= {spec.column for spec in self.tag_map.signals.values()}
        else:
            protected |= {self.tag_map.tag_column, self.tag_map.value_column,
                          self.tag_map.quality_column}
        seen: set[str] = set()
        for name in header:
            if name in seen:
                if name in protected:
                    raise HistorianFormatError(
                        f"{self.path}: column {name!r} appears more than once in the header "
                        "(line 1); it is mapped in the tag map, so the reader cannot choose one"
                    )
                self.notes["duplicate_column_names"] += 1
            seen.add(name)

    def _read_parquet(self) -> pd.DataFrame:
        try:
            frame = pd.read_parquet(self.path, engine="pyarrow")
        except Exception as error:  # pyarrow raises many types (ArrowInvalid, OSError, ...)
            raise HistorianFormatError(f"{self.path}: cannot read Parquet: {error}") from None
        return frame.reset_index(drop=True)

    def _where(self, label: int) -> str:
        """Row label (0-based data row in the file) → ``line N`` (CSV) or ``row index N``."""
        return f"line {label + 2}" if self.is_csv else f"row index {label}"

    def _require(self, column: str, key: str) -> pd.Series:
        if column not in self.frame.columns:
            raise HistorianFormatError(
                f"{self.path}: no column {column!r} (historian.{key} in {self.tag_map.source}); "
                f"columns are: {', '.join(map(str, self.frame.columns[:20]))}"
                + (" ..." if len(self.frame.columns) > 20 else "")
            )
        return self.frame[column]

    # --- time -----------------------------------------------------------------------------------

    def _times(self, column: pd.Series) -> pd.DatetimeIndex:
        """Timestamps (text or Parquet timestamps) → UTC nanoseconds, row by row as in the file."""
        name = self.tag_map.time_column
        missing = column.isna().to_numpy()
        if missing.any():
            self._raise_time(int(np.flatnonzero(missing)[0]), None, "")
        if isinstance(column.dtype, pd.DatetimeTZDtype):
            return pd.DatetimeIndex(column).tz_convert("UTC").as_unit("ns")
        rows = np.arange(len(column))
        if pd.api.types.is_datetime64_dtype(column.dtype):
            wall = pd.DatetimeIndex(column).as_unit("ns")
            return self._localize(wall, rows, rows, column)
        if not (pd.api.types.is_string_dtype(column.dtype) or column.dtype == object):
            raise HistorianFormatError(
                f"{self.path}: column {name!r} holds {column.dtype} values; expected timestamps "
                f"({_ISO_EXAMPLE})"
            )
        codes, uniques = pd.factorize(column)
        text = pd.Series(np.asarray(uniques, dtype=object)).astype(str).str.strip()
        parsed = pd.to_datetime(text, format="ISO8601", utc=True, errors="coerce")
        bad = np.flatnonzero(parsed.isna().to_numpy())
        if bad.size:
            row = int(np.flatnonzero(codes == bad[0])[0])
            self._raise_time(row, column.iloc[row], f"is not a timestamp (expected {_ISO_EXAMPLE})")
        stamps = pd.DatetimeIndex(parsed).as_unit("ns")
        naive = np.flatnonzero(~text.str.contains(_OFFSET, regex=True).to_numpy())
        if naive.size:
            local = self._localize(stamps[naive].tz_localize(None), naive, codes, column)
            values = stamps.asi8.copy()
            values[naive] = local.asi8
            stamps = pd.DatetimeIndex(values.view("M8[ns]")).tz_localize("UTC")
        return stamps[codes]

    def _localize(self, wall: pd.DatetimeIndex, ids: np.ndarray, codes: np.ndarray,
                  column: pd.Series) -> pd.DatetimeIndex:
        """Wall-clock times → UTC in the tag map's zone.

        ``wall[i]`` is the time of unique value ``ids[i]``; ``codes`` maps file rows to unique
        values, so errors can name the first file row concerned.
        """
        zone = self.tag_map.time_zone

        def fail(position: int, problem: str) -> None:
            row = int(np.flatnonzero(codes == ids[position])[0])
            self._raise_time(row, column.iloc[row], problem)

        if zone is None:
            fail(0, f"has no UTC offset and {self.tag_map.source} sets no historian.time_zone; "
                    "add time_zone (e.g. \"Asia/Shanghai\") to the tag map or export with offsets")
        local = wall.tz_localize(zone, ambiguous="NaT", nonexistent="NaT")
        bad = np.flatnonzero(local.isna())
        if bad.size:
            fail(int(bad[0]), f"is ambiguous or does not exist in time zone {zone!r} "
                              "(daylight-saving change); export with UTC offsets")
        counts = np.bincount(codes, minlength=int(ids.max()) + 1)
        self.notes["timestamps_localized"] += int(counts[ids].sum())
        return local.tz_convert("UTC")

    def _raise_time(self, row: int, value: object, problem: str) -> None:
        where = f"{self.path}: column {self.tag_map.time_column!r} {self._where(self._label(row))}"
        if value is None:
            raise HistorianFormatError(f"{where}: empty timestamp (expected {_ISO_EXAMPLE})")
        raise HistorianFormatError(f"{where}: {value!r} {problem}")

    def _label(self, position: int) -> int:
        return int(self.frame.index[position])

    # --- values ---------------------------------------------------------------------------------

    def _numbers(self, raw: pd.Series, what: str, unit: str, signal: str) -> np.ndarray:
        """A mapped column's values as floats; non-numeric text raises naming row and value."""
        if pd.api.types.is_bool_dtype(raw.dtype):
            raise HistorianFormatError(
                f"{self.path}: {what} holds true/false values; expected numbers in {unit} "
                f"(signal {signal})"
            )
        if pd.api.types.is_numeric_dtype(raw.dtype):
            return raw.to_numpy(dtype=float, na_value=np.nan)
        values = pd.to_numeric(raw, errors="coerce")
        bad = values.isna().to_numpy() & raw.notna().to_numpy()
        if bad.any():
            blank = raw[bad].astype(str).str.strip().eq("").to_numpy()
            bad[np.flatnonzero(bad)[blank]] = False
        if bad.any():
            position = int(np.flatnonzero(bad)[0])
            raise HistorianFormatError(
                f"{self.path}: {what} {self._where(int(raw.index[position]))}: "
                f"{raw.iloc[position]!r} is not a number in {unit} (signal {signal})"
            )
        return values.to_numpy(dtype=float, na_value=np.nan)

    def _to_si(self, name: str, values: np.ndarray) -> np.ndarray:
        return convert(values, self.tag_map.signals[name].unit, SIGNALS[name].si_unit)

    # --- layouts --------------------------------------------------------------------------------

    def wide(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        tag_map, frame = self.tag_map, self.frame
        index = self._times(self._require(tag_map.time_column, "time_column")).rename("time")
        signals = {}
        mapped = set()
        for name, spec in tag_map.signals.items():
            if spec.column not in frame.columns:
                self.notes["missing_signal_columns"] += 1
                continue
            mapped.add(spec.column)
            raw = frame[spec.column]
            values = self._numbers(raw, f"column {spec.column!r}", spec.unit, name)
            signals[name] = self._to_si(name, values)
        signals_frame = pd.DataFrame(signals, index=index, columns=list(signals))
        rest = [c for c in frame.columns if c != tag_map.time_column and c not in mapped]
        extras = frame[rest].set_axis(index, axis=0)
        return signals_frame, extras

    def long(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        tag_map, frame = self.tag_map, self.frame
        time_raw = self._require(tag_map.time_column, "time_column")
        tag_raw = self._require(tag_map.tag_column, "tag_column")
        value_raw = self._require(tag_map.value_column, "value_column")
        quality_raw = None
        if tag_map.quality_column is not None:
            if tag_map.quality_column in frame.columns:
                quality_raw = frame[tag_map.quality_column]
            else:
                self.notes["missing_quality_column"] = 1
        empty_tag = tag_raw.isna().to_numpy()
        if empty_tag.any():
            row = int(np.flatnonzero(empty_tag)[0])
            raise HistorianFormatError(
                f"{self.path}: column {tag_map.tag_column!r} {self._where(self._label(row))}:"
                " empty tag; every row of the long layout needs a tag"
            )
        tag_codes, tags = pd.factorize(tag_raw.astype(str), sort=False)
        tags = [str(tag) for tag in tags]
        times = self._times(time_raw).asi8
        rows, row_times, out_of_order, duplicates = _long_keys(tag_codes, times, len(tags))
        self.notes["long_duplicate_entries"] = duplicates
        self.notes["long_tags_out_of_order"] = out_of_order
        index = pd.DatetimeIndex(row_times.view("M8[ns]"), name="time").tz_localize("UTC")
        n_rows = len(row_times)
        by_tag = np.argsort(tag_codes, kind="stable")
        bounds = np.searchsorted(tag_codes[by_tag], np.arange(len(tags) + 1))
        tag_rows = {tag: by_tag[bounds[j]:bounds[j + 1]] for j, tag in enumerate(tags)}

        signals = {}
        mapped = set()
        for name, spec in tag_map.signals.items():
            if spec.column not in tag_rows:
                self.notes["missing_signal_columns"] += 1
                continue
            mapped.add(spec.column)
            picked = tag_rows[spec.column]
            values = self._numbers(
                value_raw.iloc[picked], f"tag {spec.column!r} (column {tag_map.value_column!r})",
                spec.unit, name,
            )
            column = np.full(n_rows, np.nan)
            column[rows[picked]] = self._to_si(name, values)
            signals[name] = column
        signals_frame = pd.DataFrame(signals, index=index, columns=list(signals))

        extras = {}
        for tag, picked in tag_rows.items():
            if tag not in mapped:
                extras[tag] = _scatter(value_raw, picked, rows[picked], n_rows)
        if quality_raw is not None:
            for tag, picked in tag_rows.items():
                extras[f"quality:{tag}"] = _scatter(quality_raw, picked, rows[picked], n_rows)
        extras_frame = pd.DataFrame(extras, index=index, columns=list(extras))
        return signals_frame, extras_frame


def _long_keys(
    tag_codes: np.ndarray, times: np.ndarray, n_tags: int
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Output row of every long row, the output rows' times, tags out of order, repeat count.

    A key is (timestamp, occurrence of this tag at this timestamp); each key is one output row.
    """
    by_tag = np.argsort(tag_codes, kind="stable")
    sorted_codes, sorted_times = tag_codes[by_tag], times[by_tag]
    same_tag = sorted_codes[1:] == sorted_codes[:-1]
    backwards = same_tag & (sorted_times[1:] < sorted_times[:-1])
    out_of_order = int(np.unique(sorted_codes[1:][backwards]).size)
    if out_of_order:  # sort by tag, then time, keeping file order among equals
        by_tag = np.lexsort((times, tag_codes))
        sorted_codes, sorted_times = tag_codes[by_tag], times[by_tag]
        same_tag = sorted_codes[1:] == sorted_codes[:-1]
    repeat = np.concatenate(([False], same_tag & (sorted_times[1:] == sorted_times[:-1])))
    occurrence = np.zeros(len(times), dtype=np.int64)
    duplicates = int(repeat.sum())
    if duplicates:
        run_start = np.maximum.accumulate(np.where(repeat, 0, np.arange(len(times))))
        occurrence[by_tag] = np.arange(len(times)) - run_start
    if duplicates:
        time_codes, _ = pd.factorize(times)
        keys = time_codes.astype(np.int64) * (int(occurrence.max()) + 1) + occurrence
    else:
        keys = times
    rows, unique_keys = pd.factorize(keys)  # first appearance in the file
    first = np.zeros(len(unique_keys), dtype=np.int64)
    first[rows[::-1]] = np.arange(len(rows))[::-1]
    row_times = times[first]
    if not out_of_order:  # merge the per-tag sequences in time order (occurrence breaks ties)
        key_occurrence = occurrence[first]
        order = np.lexsort((key_occurrence, row_times))
        if (order != np.arange(len(order))).any():
            rank = np.empty_like(order)
            rank[order] = np.arange(len(order))
            rows, row_times = rank[rows], row_times[order]
    return np.asarray(rows), row_times, out_of_order, duplicates


def _scatter(
    raw: pd.Series, picked: np.ndarray, rows: np.ndarray, n_rows: int
) -> pd.api.extensions.ExtensionArray:
    """Values of one long-layout tag placed on their output rows (NaN elsewhere), dtype as read."""
    values = raw.iloc[picked].set_axis(rows)
    return values.reindex(np.arange(n_rows)).array
