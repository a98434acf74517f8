"""CSV files of canonical signals in their wire units (MPa, °C, t/h, MW).

The simple exchange format of ``steamtwin simulate``: a ``time`` column (ISO 8601 timestamps, or
seconds) and one column per canonical signal, in the wire unit listed in
:data:`steamtwin.dcs.signals.SIGNALS`. Historian exports with plant tags and other units go
through tag maps instead.

Timestamps carry their UTC offset (``2026-03-01T10:00:00+08:00``, ``…Z``). One written without
it is refused unless the caller names the zone of the plant's clock (``time_zone``): read as UTC
it would shift the series by hours without a word. Errors name the file, the column and the data
row (1-based, the header not counted) with its line in the file (data row + 1).
"""

from __future__ import annotations

import re
from datetime import timedelta, timezone, tzinfo
from pathlib import Path
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

import numpy as np
import pandas as pd

from steamtwin.dcs.signals import SIGNALS
from steamtwin.errors import DataError
from steamtwin.units import convert

# An ISO 8601 time of day followed by its UTC offset: 'Z' or ±hh[[:]mm].
_WITH_OFFSET = re.compile(r"\d{2}:\d{2}(?::\d{2}(?:[.,]\d+)?)?\s*(?:[Zz]|[+-]\d{2}(?::?\d{2})?)$")
_FIXED_OFFSET = re.compile(r"([+-])(\d{2}):?(\d{2})")
_MAX_OFFSET = timedelta(hours=14)  # UTC−12 … UTC+14 are the offsets in civil use (IANA tz)


class CsvFormatError(DataError):
    """A canonical CSV file is malformed; the message names file, column and row."""


def parse_time_zone(name: str) -> tzinfo:
    """A zone from an IANA name (``Asia/Shanghai``, ``UTC``) or a fixed offset (``+08:00``).

    Raises ``ValueError`` saying what is expected.
    """
    fixed = _FIXED_OFFSET.fullmatch(name.strip())
    if fixed:
        sign, hours, minutes = fixed.groups()
        offset = timedelta(hours=int(hours), minutes=int(minutes))
        if offset > _MAX_OFFSET:
            raise ValueError(f"{name}: offsets lie within ±14:00")
        return timezone(-offset if sign == "-" else offset)
    try:
        return ZoneInfo(name.strip())
    except (ZoneInfoNotFoundError, ValueError):
        raise ValueError(f"{name!r}: not a time zone; give an IANA name such as "
                         "Asia/Shanghai or Europe/Berlin, UTC, or an offset such as +08:00"
                         ) from None


def read_canonical_csv(path: str | Path, required: tuple[str, ...] = (),
                       time_zone: tzinfo | None = None) -> pd.DataFrame:
    """Read a canonical CSV into SI units on a time index (UTC DatetimeIndex or seconds).

    ``time_zone``: the zone of timestamps written without a UTC offset (see
    :func:`parse_time_zone`); without it such timestamps are refused.
    """
    path = Path(path)
    try:
        frame = pd.read_csv(path, dtype={"time": str})
    except UnicodeDecodeError as error:
        raise CsvFormatError(f"{path}: not UTF-8 text (byte 0x{error.object[error.start]:02x} "
                             f"at offset {error.start}); save the CSV as UTF-8") from None
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as error:
        raise CsvFormatError(f"{path}: cannot read CSV: {error}") from None
    if "time" not in frame.columns:
        raise CsvFormatError(f"{path}: no 'time' column (ISO 8601 timestamps or seconds)")
    missing = [name for name in required if name not in frame.columns]
    if missing:
        raise CsvFormatError(
            f"{path}: missing column(s) {missing}; expected canonical names in wire units "
            + ", ".join(f"{name} [{SIGNALS[name].wire_unit}]" for name in missing)
        )
    frame.index = _time_index(frame.pop("time"), path, time_zone)
    for name in frame.columns:
        if name not in SIGNALS:
            continue
        values = pd.to_numeric(frame[name], errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & frame[name].notna().to_numpy())
        if bad.size:
            row = int(bad[0])
            raise CsvFormatError(
                f"{path}: column {name!r} data row {row + 1} (line {row + 2}): "
                f"{frame[name].iloc[row]!r} is not a number in {SIGNALS[name].wire_unit}"
            )
        signal = SIGNALS[name]
        frame[name] = convert(values.to_numpy(dtype=float), signal.wire_unit, signal.si_unit)
    return frame


def write_canonical_csv(frame: pd.DataFrame, path: str | Path) -> None:
    """Write SI canonical signals to CSV in wire units, with a ``time`` column."""
    out = pd.DataFrame({"time": _time_column(frame.index)})
    for name in frame.columns:
        signal = SIGNALS.get(name)
        values = frame[name].to_numpy(dtype=float)
        out[name] = convert(values, signal.si_unit, signal.wire_unit) if signal else values
    out.to_csv(path, index=False, float_format="%.6g")


def _time_column(index: pd.Index) -> list[str]:
    """Timestamps as ISO 8601, seconds at full precision (never rounded with the values)."""
    if isinstance(index, pd.DatetimeIndex):
        return [stamp.isoformat() for stamp in index]
    return [repr(float(seconds)) for seconds in index]


def _time_index(column: pd.Series, path: Path, zone: tzinfo | None) -> pd.Index:
    text = column.fillna("").astype(str).str.strip()
    numeric = pd.to_numeric(text, errors="coerce")
    if numeric.notna().all():
        return pd.Index(numeric.to_numpy(dtype=float), name="time")
    naive = (~text.str.contains(_WITH_OFFSET) & text.ne("")).to_numpy()
    times = pd.to_datetime(text.where(~naive), errors="coerce", utc=True, format="ISO8601")
    if naive.any():
        first = int(np.flatnonzero(naive)[0])
        if zone is None:
            raise CsvFormatError(
                f"{path}: column 'time' data row {first + 1} (line {first + 2}): "
                f"{column.iloc[first]!r} has no UTC offset ({int(naive.sum())} such rows); "
                "write the offset (e.g. 2026-03-01T10:00:00+08:00, or Z for UTC) or give the "
                "zone of the plant's clock (steamtwin simulate --time-zone, e.g. "
                "--time-zone Asia/Shanghai)")
        wall = pd.DatetimeIndex(pd.to_datetime(text[naive], errors="coerce", format="ISO8601"))
        local = wall.tz_localize(zone, ambiguous="NaT", nonexistent="NaT")
        lost = np.flatnonzero(local.isna() & wall.notna())
        if lost.size:
            bad = int(np.flatnonzero(naive)[lost[0]])
            raise CsvFormatError(
                f"{path}: column 'time' data row {bad + 1} (line {bad + 2}): "
                f"{column.iloc[bad]!r} is ambiguous or does not exist in {zone} (a "
                "daylight-saving change); write these timestamps with their UTC offset")
        times = times.copy()
        times[naive] = local.tz_convert("UTC")
    bad = np.flatnonzero(times.isna().to_numpy())
    if bad.size:
        row = int(bad[0])
        raise CsvFormatError(
            f"{path}: column 'time' data row {row + 1} (line {row + 2}): {column.iloc[row]!r} "
            "is neither an ISO 8601 timestamp nor seconds"
        )
    return pd.DatetimeIndex(times, name="time")
