"""CSV files of canonical signals in their wire units (MPa, °C, t/h, MW).

The simple exchange format of ``steamtwin simulate``: a ``time`` column (ISO 8601 timestamps, or
seconds) and one column per canonical signal, in the wire unit listed in
:data:`steamtwin.dcs.signals.SIGNALS`. Historian exports with plant tags and other units go
through tag maps instead.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.signals import SIGNALS
from steamtwin.units import convert


class CsvFormatError(ValueError):
    """A canonical CSV file is malformed; the message names file, column and row."""


def read_canonical_csv(path: str | Path, required: tuple[str, ...] = ()) -> pd.DataFrame:
    """Read a canonical CSV into SI units on a time index (DatetimeIndex or seconds)."""
    path = Path(path)
    try:
        frame = pd.read_csv(path)
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
    frame.index = _time_index(frame.pop("time"), path)
    for name in frame.columns:
        if name not in SIGNALS:
            continue
        values = pd.to_numeric(frame[name], errors="coerce")
        bad = np.flatnonzero(values.isna().to_numpy() & frame[name].notna().to_numpy())
        if bad.size:
            row = int(bad[0])
            raise CsvFormatError(
                f"{path}: column {name!r} row {row + 2} (line in file): {frame[name].iloc[row]!r} "
                f"is not a number in {SIGNALS[name].wire_unit}"
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


def _time_index(column: pd.Series, path: Path) -> pd.Index:
    numeric = pd.to_numeric(column, errors="coerce")
    if numeric.notna().all():
        return pd.Index(numeric.to_numpy(dtype=float), name="time")
    times = pd.to_datetime(column, errors="coerce", utc=True, format="ISO8601")
    bad = np.flatnonzero(times.isna().to_numpy())
    if bad.size:
        row = int(bad[0])
        raise CsvFormatError(
            f"{path}: column 'time' row {row + 2} (line in file): {column.iloc[row]!r} is neither "
            "an ISO 8601 timestamp nor seconds"
        )
    return pd.DatetimeIndex(times, name="time")
