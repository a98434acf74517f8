"""A time-indexed frame as a JSON-ready document and back, exactly: the saved states of the
live twin's parts (open blocks, the tracker's step under way, the rewind buffer) hold a few
hundred samples each and must restore bit for bit (JSON floats round-trip exactly, RFC 8259 §6
with Python's shortest repr; NaN is written as null)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

__all__ = ["frame_from_json", "frame_to_json"]


def frame_to_json(frame: pd.DataFrame) -> dict[str, object]:
    """``frame`` (tz-aware DatetimeIndex, numeric columns) as index (ns since the epoch, UTC),
    its zone, columns and values (None for NaN)."""
    if frame.empty:
        return {"index": [], "tz": None, "columns": [str(c) for c in frame.columns], "values": []}
    index = frame.index
    return {"index": [int(t) for t in index.as_unit("ns").asi8],
            "tz": None if index.tz is None else str(index.tz),
            "columns": [str(c) for c in frame.columns],
            "values": [[None if not math.isfinite(v) else float(v) for v in row]
                       for row in frame.to_numpy(dtype=float)]}


def frame_from_json(document: Mapping[str, object]) -> pd.DataFrame:
    """:func:`frame_to_json`'s output as the frame it was (an empty frame if it had no rows)."""
    times = list(document.get("index", []))
    if not times:
        return pd.DataFrame()
    values = np.array([[np.nan if v is None else v for v in row] for row in document["values"]],
                      dtype=float).reshape(len(times), len(document["columns"]))
    index = pd.to_datetime(np.array(times, dtype=np.int64), unit="ns", utc=True)
    zone = document.get("tz")
    index = index.tz_convert(zone) if zone else index.tz_localize(None)
    return pd.DataFrame(values, index=index, columns=list(document["columns"]))
