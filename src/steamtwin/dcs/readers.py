"""Read plant historian exports (CSV or Parquet, wide or long) into canonical SI signals.

Kept as one module because it is one job, one reader (``_Reader``) whose wide/long and
CSV/Parquet paths share the same time parsing, unit conversion and counted notes.

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

CSV dialect: the tag map's ``historian.delimiter``, ``decimal`` and ``encoding`` when set;
otherwise sniffed, and recorded with their source ("tag map", "sniffed", "default") in
:attr:`HistorianData.dialect`:

- encoding: a byte-order mark (UTF-8, UTF-16) decides; else UTF-8 ("default") if the bytes are
  valid UTF-8; else GB18030 (a superset of GBK/GB2312) when every non-ASCII byte of the first MiB
  sits in a GB2312 pair (both bytes 0xA1–0xFE, the simplified-Chinese plant exports); else
  cp1252 (Western Windows exports); else GB18030 (GBK with rarer characters); else an error
  asking for ``historian.encoding``. The whole file must decode.
- delimiter: each of ``,`` ``;`` tab ``|`` splits the header and the first lines (64 KiB); the
  one whose header holds most names of the tag map wins, then the one splitting most lines into
  the header's field count. One column under every candidate → ``,`` ("default").
- decimal: ``,`` when the delimiter is not ``,`` and the first lines hold numbers like ``12,5``
  but none like ``12.5``; otherwise ``.`` ("default"). With decimal ``,`` a value holding a
  ``.`` is not a number (it may be a thousands separator).

Quality: a quality column (``historian.quality_column`` in the long layout,
``signals.<name>.quality_column`` in the wide one) is classified with the tag map's
:class:`~steamtwin.dcs.tagmap.QualityMapping`; :attr:`HistorianData.bad_quality` marks, per
signal, the samples whose class the mapping excludes. An unclassifiable value, or a sample with a
value but an empty quality, is an error.

Errors (:class:`HistorianFormatError`) name the file, column or tag, the row — ``line N`` (1-based
line in a CSV file, header = line 1, one record per line) or ``row index N`` (0-based, Parquet) —
and the expected unit or format; when the dialect looks wrong they say which tag-map key to set.
A file without data rows is an error.
"""

from __future__ import annotations

import codecs
import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import QUALITY_CLASSES, TagMap
from steamtwin.errors import DataError
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
    "missing_quality_column",  # configured quality columns absent from the file
    "quality_excluded",  # samples whose quality class the tag map excludes (bad_quality True)
)
DELIMITERS = (",", ";", "\t", "|")  # sniffed candidates, in order of preference on a tie
_SNIFF_CHARS = 1 << 16  # delimiter and decimal are sniffed from the first 64 KiB of text
_SNIFF_LINES = 50
_GB2312_SAMPLE = 1 << 20  # bytes tested for GB2312 pairs before GB18030 is chosen
# ASCII bytes or GB2312 pairs (lead 0xA1-0xF7, trail 0xA1-0xFE; GB 2312-80 EUC-CN code space).
_GB2312_TEXT = re.compile(rb"(?:[\x00-\x7f]|[\xa1-\xf7][\xa1-\xfe])*")
_COMMA_NUMBER = re.compile(r"[+-]?\d+,\d+(?:[eE][+-]?\d+)?")
_DOT_NUMBER = re.compile(r"[+-]?\d*\.\d+(?:[eE][+-]?\d+)?")


class HistorianFormatError(DataError):
    """A historian export is malformed; the message names file, column/tag, row and format."""


@dataclass(frozen=True)
class HistorianData:
    """Canonical signals in SI (Pa, K, kg/s, W) and everything else the export held.

    ``signals`` and ``extras`` share one UTC ``DatetimeIndex`` named ``"time"`` in file order.
    ``extras`` holds unmapped columns (wide) or unmapped tags (long), as read, plus
    ``quality:<tag>`` columns in the long layout. ``notes`` counts reader decisions (see
    :data:`NOTE_KEYS`). ``dialect`` says how a CSV was read: ``delimiter``, ``decimal`` and
    ``encoding`` (a Python codec name), each with a ``<key>_source`` of "tag map", "sniffed" or
    "default" (empty for Parquet). ``bad_quality`` holds, for every signal in ``signals``, a
    boolean mask over its rows: True where the sample's quality class is excluded by the tag map
    (all False without a quality column). ``quality_counts`` counts the samples per quality class
    ("good", "uncertain", "bad") of each signal that has a quality column.
    """

    signals: pd.DataFrame
    extras: pd.DataFrame
    tag_map: TagMap
    source: str
    notes: dict[str, int] = field(default_factory=dict)
    dialect: dict[str, str] = field(default_factory=dict)
    bad_quality: dict[str, np.ndarray] = field(default_factory=dict)
    quality_counts: dict[str, dict[str, int]] = field(default_factory=dict)

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

    The CSV dialect used is in ``dialect``; samples whose quality class the tag map excludes are
    True in ``bad_quality`` (the values are kept as read). Raises :class:`HistorianFormatError`
    naming file, column/tag, row and expected format.
    """
    path = Path(path)
    reader = _Reader(path, tag_map)
    if tag_map.layout == "wide":
        signals, extras = reader.wide()
    else:
        signals, extras = reader.long()
    reader.notes["quality_excluded"] = int(sum(mask.sum() for mask in reader.bad_quality.values()))
    return HistorianData(
        signals=signals, extras=extras, tag_map=tag_map, source=str(path), notes=reader.notes,
        dialect=reader.dialect, bad_quality=reader.bad_quality,
        quality_counts=reader.quality_counts,
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
        self.dialect: dict[str, str] = {}
        self.bad_quality: dict[str, np.ndarray] = {}
        self.quality_counts: dict[str, dict[str, int]] = {}
        suffix = path.suffix.lower()
        if suffix not in (".csv", ".parquet"):
            raise HistorianFormatError(
                f"{path}: unsupported file type {path.suffix!r}; expected .csv or .parquet"
            )
        self.is_csv = suffix == ".csv"
        self.frame = self._read_csv() if self.is_csv else self._read_parquet()
        if len(self.frame) == 0:
            holds = ("only its header (line 1)" if self.is_csv
                     else f"0 rows (columns: {self._column_list()})")
            raise HistorianFormatError(
                f"{path}: no data rows: the file holds {holds}; a historian export needs at "
                "least one sample"
            )

    # --- files ----------------------------------------------------------------------------------

    def _read_csv(self) -> pd.DataFrame:
        tag_map = self.tag_map
        try:
            data = self.path.read_bytes()
        except OSError as error:
            raise HistorianFormatError(f"{self.path}: cannot read CSV: {error}") from None
        text = self._decode(data)
        if not text.strip():
            raise HistorianFormatError(f"{self.path}: cannot read CSV: the file is empty "
                                       "(no header, no data rows)")
        sample = text[:_SNIFF_CHARS].splitlines()
        if len(text) > _SNIFF_CHARS:
            sample = sample[:-1]  # the last sampled line may be cut
        rows = [line for line in sample if line.strip()][:_SNIFF_LINES]
        delimiter = self._delimiter(rows)
        decimal = self._decimal(rows, delimiter)
        text_columns = [tag_map.time_column, *self._quality_columns()]
        if tag_map.layout == "long":
            text_columns.append(tag_map.tag_column)
        try:
            header = next(csv.reader(io.StringIO(text), delimiter=delimiter), [])
            frame = pd.read_csv(
                io.StringIO(text),
                sep=delimiter,
                decimal=decimal,
                skip_blank_lines=False,
                keep_default_na=False,
                na_values=[""],
                dtype=dict.fromkeys(text_columns, str),
                low_memory=False,
            )
        except (pd.errors.ParserError, pd.errors.EmptyDataError, csv.Error, ValueError,
                OverflowError) as error:
            raise HistorianFormatError(  # pandas' messages may end in a line break
                f"{self.path}: cannot read CSV: {' '.join(str(error).split())} "
                f"({self._dialect_text()})"
            ) from None
        if not isinstance(frame.index, pd.RangeIndex):  # pandas made the surplus an index
            width = len(frame.columns)
            raise HistorianFormatError(
                f"{self.path}: the first data line has {width + frame.index.nlevels} fields but "
                f"the header (line 1) has {width} ({self._dialect_text()})"
            )
        self._check_duplicate_names(header)
        blank = frame.isna().all(axis=1).to_numpy()
        if blank.any():
            self.notes["blank_lines"] = int(blank.sum())
            frame = frame.loc[~blank]  # keeps the row labels, so labels still give the line
        return frame

    def _decode(self, data: bytes) -> str:
        """The file's text; records ``encoding`` and its source in ``self.dialect``."""
        encoding = self.tag_map.encoding
        if encoding is not None:
            try:
                text = data.decode(encoding)
            except (UnicodeError, LookupError) as error:
                raise HistorianFormatError(
                    f"{self.path}: cannot decode the file as {encoding!r} (historian.encoding in "
                    f"{self.tag_map.source}): {error}; check the export's "
                    "encoding (e.g. \"utf-8\", \"gbk\", \"cp1252\") or remove the key to sniff it"
                ) from None
            source = "tag map"
        else:
            encoding, source, text = self._sniff_encoding(data)
        self.dialect.update(encoding=encoding, encoding_source=source)
        text = text.removeprefix("\ufeff")
        if "\x00" in text:
            line = text.count("\n", 0, text.index("\x00")) + 1
            raise HistorianFormatError(
                f"{self.path}: line {line} holds a NUL character: not CSV text in {encoding} "
                f"({source}); set historian.encoding in {self.tag_map.source} if the export uses "
                "another encoding (e.g. \"utf-16\")"
            )
        return text

    def _sniff_encoding(self, data: bytes) -> tuple[str, str, str]:
        """(codec, source, text) by the order of the module docstring."""
        for mark, name in ((codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"),
                           (codecs.BOM_UTF16_BE, "utf-16")):
            if data.startswith(mark):
                try:
                    return name, "sniffed", data.decode(name)
                except UnicodeDecodeError as error:
                    raise HistorianFormatError(
                        f"{self.path}: the file starts with a {name} byte-order mark but is not "
                        f"valid {name} at byte {error.start}; set historian.encoding in "
                        f"{self.tag_map.source}"
                    ) from None
        try:
            return "utf-8", "default", data.decode("utf-8")
        except UnicodeDecodeError as error:
            not_utf8 = error.start
        sample = data[:_GB2312_SAMPLE]
        candidates = ["cp1252", "gb18030"]
        if _GB2312_TEXT.match(sample).end() >= len(sample) - 1:  # a cut pair may end the sample
            candidates.insert(0, "gb18030")
        for name in candidates:
            try:
                return name, "sniffed", data.decode(name)
            except UnicodeDecodeError:
                continue
        raise HistorianFormatError(
            f"{self.path}: cannot tell the file's encoding: not UTF-8 (byte {not_utf8}), "
            f"GB18030 or cp1252; set historian.encoding in {self.tag_map.source} "
            "(e.g. \"utf-16\", \"shift_jis\")"
        )

    def _expected_names(self) -> set[str]:
        """Column names the tag map expects in the header (to tell delimiters apart)."""
        tag_map = self.tag_map
        names = {tag_map.time_column, *self._quality_columns()}
        if tag_map.layout == "long":
            names |= {tag_map.tag_column, tag_map.value_column}
        else:
            names |= {spec.column for spec in tag_map.signals.values()}
        return names

    def _quality_columns(self) -> list[str]:
        if self.tag_map.layout == "long":
            return [self.tag_map.quality_column] if self.tag_map.quality_column else []
        return [spec.quality_column for spec in self.tag_map.signals.values()
                if spec.quality_column is not None]

    def _delimiter(self, rows: list[str]) -> str:
        """The tag map's delimiter, else the sniffed one (module docstring); recorded."""
        if self.tag_map.delimiter is not None:
            self.dialect.update(delimiter=self.tag_map.delimiter, delimiter_source="tag map")
            return self.tag_map.delimiter
        expected = self._expected_names()
        best, best_score = None, (0, 0, 1)
        for candidate in DELIMITERS:
            if candidate == self.tag_map.decimal:
                continue
            split = list(csv.reader(rows, delimiter=candidate))
            width = len(split[0]) if split else 0
            known = len(expected.intersection(name.strip() for name in split[0])) if split else 0
            same = sum(len(fields) == width for fields in split)
            score = (known, same if width > 1 else 0, width)
            if score > best_score:
                best, best_score = candidate, score
        if best is None:
            default = ";" if self.tag_map.decimal == "," else ","
            self.dialect.update(delimiter=default, delimiter_source="default")
            return default
        self.dialect.update(delimiter=best, delimiter_source="sniffed")
        return best

    def _decimal(self, rows: list[str], delimiter: str) -> str:
        """The tag map's decimal separator, else the sniffed one (module docstring); recorded."""
        if self.tag_map.decimal is not None:
            self.dialect.update(decimal=self.tag_map.decimal, decimal_source="tag map")
            return self.tag_map.decimal
        decimal, source = ".", "default"
        if delimiter != ",":
            fields = [value.strip() for line in csv.reader(rows[1:], delimiter=delimiter)
                      for value in line]
            comma = any(_COMMA_NUMBER.fullmatch(value) for value in fields)
            dot = any(_DOT_NUMBER.fullmatch(value) for value in fields)
            if comma and not dot:
                decimal, source = ",", "sniffed"
        self.dialect.update(decimal=decimal, decimal_source=source)
        return decimal

    def _dialect_text(self) -> str:
        """How the CSV was read, for messages."""
        parts = [f"{key} {self.dialect[key]!r} ({self.dialect[key + '_source']})"
                 for key in ("delimiter", "decimal", "encoding") if key in self.dialect]
        return (f"read with {', '.join(parts)}; set historian.delimiter/decimal/encoding in "
                f"{self.tag_map.source} if these are wrong")

    def _check_duplicate_names(self, header: list[str]) -> None:
        protected = {self.tag_map.time_column, *self._quality_columns()}
        if self.tag_map.layout == "wide":
            protected |= {spec.column for spec in self.tag_map.signals.values()}
        else:
            protected |= {self.tag_map.tag_column, self.tag_map.value_column}
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

    def _column_list(self) -> str:
        columns = self.frame.columns
        return ", ".join(map(str, columns[:20])) + (" ..." if len(columns) > 20 else "")

    def _require(self, column: str, key: str) -> pd.Series:
        if column not in self.frame.columns:
            raise HistorianFormatError(
                f"{self.path}: no column {column!r} (historian.{key} in {self.tag_map.source}); "
                f"columns are: {self._column_list()}{self._header_hint()}"
            )
        return self.frame[column]

    def _header_hint(self) -> str:
        """Why a CSV header may not hold the expected names: delimiter or encoding."""
        if not self.is_csv:
            return ""
        header = "".join(map(str, self.frame.columns))
        dialect, source, hints = self.dialect, self.tag_map.source, []
        for char in DELIMITERS:
            if char != dialect["delimiter"] and char in header:
                hints.append(
                    f"the header holds {char!r} but was split at {dialect['delimiter']!r} "
                    f"({dialect['delimiter_source']}); if the file is {char!r}-separated, set "
                    f"historian.delimiter = {_toml_text(char)} in {source}"
                )
                break
        if not header.isascii() and dialect["encoding_source"] != "default":
            action = "check" if dialect["encoding_source"] == "tag map" else "set"
            hints.append(
                f"the file was decoded as {dialect['encoding']} ({dialect['encoding_source']}); "
                f"if the names look garbled, {action} historian.encoding (e.g. \"gbk\", "
                f"\"cp1252\") in {source}"
            )
        return "".join(f"; {hint}" for hint in hints)

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
        present = raw.notna().to_numpy()
        text = raw.astype(str).str.strip().where(present)
        if self.dialect.get("decimal") == ",":  # "12,5" → 12.5; a "." is not a decimal here
            text = text.where(~text.str.contains(".", regex=False, na=False), "")
            text = text.str.replace(",", ".", regex=False)
        values = pd.to_numeric(text.where(text != "", "not a number"), errors="coerce")
        bad = values.isna().to_numpy() & present & raw.astype(str).str.strip().ne("").to_numpy()
        if bad.any():
            position = int(np.flatnonzero(bad)[0])
            raise HistorianFormatError(
                f"{self.path}: {what} {self._where(int(raw.index[position]))}: "
                f"{raw.iloc[position]!r} is not a number in {unit} (signal {signal})"
                f"{self._decimal_hint(str(raw.iloc[position]).strip())}"
            )
        return values.to_numpy(dtype=float, na_value=np.nan)

    def _decimal_hint(self, value: str) -> str:
        """A hint when a value that failed to parse suggests the other decimal separator."""
        if not self.is_csv:
            return ""
        decimal, source = self.dialect["decimal"], self.dialect["decimal_source"]
        if decimal == "." and _COMMA_NUMBER.fullmatch(value):
            also = (" and another historian.delimiter" if self.dialect["delimiter"] == ","
                    else "")
            return (f"; it looks like a decimal comma: set historian.decimal = \",\"{also} in "
                    f"{self.tag_map.source}")
        if decimal == "," and _DOT_NUMBER.fullmatch(value):
            return (f"; the file is read with decimal ',' ({source}): if '.' is its decimal "
                    f"separator, set historian.decimal = \".\" in {self.tag_map.source}")
        return ""

    def _to_si(self, name: str, values: np.ndarray) -> np.ndarray:
        return convert(values, self.tag_map.signals[name].unit, SIGNALS[name].si_unit)

    def _quality(self, name: str, raw: pd.Series, values: np.ndarray, what: str) -> np.ndarray:
        """Quality classes of one signal's samples: True where excluded; counts recorded.

        ``raw`` holds the quality values of the samples, ``values`` the samples (NaN: none).
        """
        mapping = self.tag_map.quality
        try:
            codes, uniques = pd.factorize(raw, use_na_sentinel=True)
        except TypeError:  # unhashable cells (Parquet lists, ...)
            raise HistorianFormatError(
                f"{self.path}: {what} holds values that are not quality codes "
                "(expected text or integers)"
            ) from None
        classes = np.full(len(uniques) + 1, -1)  # the last entry serves NaN's code -1
        for position, value in enumerate(uniques):
            if isinstance(value, str) and not value.strip():
                continue
            found = mapping.classify(value)
            if found is None:
                row = int(np.flatnonzero(codes == position)[0])
                raise HistorianFormatError(
                    f"{self.path}: {what} {self._where(int(raw.index[row]))}: quality "
                    f"{raw.iloc[row]!r} (signal {name}) is not classified by "
                    f"{mapping.describe()}; list it under [historian.quality] good, uncertain "
                    f"or bad in {self.tag_map.source}"
                )
            classes[position] = QUALITY_CLASSES.index(found)
        row_classes = classes[codes]
        unknown = (row_classes < 0) & ~np.isnan(values)
        if unknown.any():
            row = int(np.flatnonzero(unknown)[0])
            raise HistorianFormatError(
                f"{self.path}: {what} {self._where(int(raw.index[row]))}: empty quality for a "
                f"sample of signal {name}; every sample needs a quality (good, uncertain or bad)"
            )
        self.quality_counts[name] = {
            cls: int((row_classes == k).sum()) for k, cls in enumerate(QUALITY_CLASSES)
        }
        excluded = [QUALITY_CLASSES.index(cls) for cls in mapping.exclude]
        return np.isin(row_classes, excluded)

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
            self.bad_quality[name] = np.zeros(len(values), dtype=bool)
            if spec.quality_column is None:
                continue
            if spec.quality_column not in frame.columns:
                self.notes["missing_quality_column"] += 1
                continue
            self.bad_quality[name] = self._quality(
                name, frame[spec.quality_column], values, f"column {spec.quality_column!r}"
            )
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
            self.bad_quality[name] = np.zeros(n_rows, dtype=bool)
            if quality_raw is not None:
                self.bad_quality[name][rows[picked]] = self._quality(
                    name, quality_raw.iloc[picked], values,
                    f"tag {spec.column!r} (column {tag_map.quality_column!r})",
                )
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


def _toml_text(char: str) -> str:
    """One character as a TOML string for messages (tab as ``"\\t"``)."""
    return '"\\t"' if char == "\t" else f'"{char}"'
