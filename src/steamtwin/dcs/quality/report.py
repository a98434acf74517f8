"""What the data-quality check reports: per-sample :class:`Flag` codes, :class:`Finding` s,
the :class:`QualityReport` and the :class:`CleaningResult`, and how times and values are
written into them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntFlag
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.dcs.quality.limits import INDEX, Action, Severity


def time_label(label: Any, is_datetime: bool) -> Any:
    return pd.Timestamp(label) if is_datetime else float(label)

def time_text(value: Any) -> str:
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    return f"t = {value:g} s"

def json_time(value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    return float(value)

def json_value(value: Any) -> Any:
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    if isinstance(value, np.integer | bool | np.bool_):
        return value.item() if not isinstance(value, bool) else value
    if isinstance(value, float | np.floating):
        return None if not math.isfinite(float(value)) else float(value)
    if isinstance(value, list | tuple):
        return [json_value(v) for v in value]
    return value

class Flag(IntFlag):
    """Per-sample cleaning codes (bitmask); see the module docstring."""

    MISSING = 1
    SPIKE = 2
    OUT_OF_RANGE = 4
    STUCK = 8
    DUPLICATE = 16
    DUPLICATE_CONFLICT = 32
    OUT_OF_ORDER = 64
    REMOVED = 128
    BAD_QUALITY = 256

@dataclass(frozen=True)
class Finding:
    """One data-quality finding; ``first_row`` is the 0-based position in the frame as read."""

    kind: str
    severity: Severity
    signal: str | None
    tag: str | None
    count: int
    first_row: int | None
    first_time: pd.Timestamp | float | None
    message: str
    action: Action = "detected"
    details: tuple[tuple[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form (timestamps as ISO 8601, index times in s)."""
        return {
            "kind": self.kind,
            "severity": self.severity,
            "action": self.action,
            "signal": self.signal,
            "tag": self.tag,
            "count": int(self.count),
            "first_row": None if self.first_row is None else int(self.first_row),
            "first_time": json_time(self.first_time),
            "message": self.message,
            "details": {key: json_value(value) for key, value in self.details},
        }

@dataclass(frozen=True)
class QualityReport:
    """Findings of a quality check (and of a cleaning, with ``action`` repaired/rejected)."""

    findings: tuple[Finding, ...]
    source: str = ""
    n_rows: int = 0
    signals: tuple[str, ...] = ()

    @property
    def errors(self) -> tuple[Finding, ...]:
        """Findings of severity ``error``."""
        return tuple(f for f in self.findings if f.severity == "error")

    @property
    def warnings(self) -> tuple[Finding, ...]:
        """Findings of severity ``warning``."""
        return tuple(f for f in self.findings if f.severity == "warning")

    @property
    def ok(self) -> bool:
        """True when there is no error (warnings allowed)."""
        return not self.errors

    def counts(self, action: Action = "detected") -> pd.DataFrame:
        """Counts as a DataFrame: signal (``"(index)"`` for the time index) × kind."""
        rows: dict[tuple[str, str], int] = {}
        for f in self.findings:
            if f.action == action:
                key = (f.signal or INDEX, f.kind)
                rows[key] = rows.get(key, 0) + int(f.count)
        if not rows:
            return pd.DataFrame(dtype="int64")
        series = pd.Series(rows, dtype="int64")
        return series.unstack(fill_value=0).astype("int64")

    def to_dict(self) -> dict[str, Any]:
        """Machine-readable, JSON-serialisable form."""
        counts: dict[str, dict[str, dict[str, int]]] = {}
        for action in ("detected", "repaired", "rejected"):
            table = self.counts(action)  # type: ignore[arg-type]
            if not table.empty:
                counts[action] = {
                    str(signal): {str(k): int(v) for k, v in row.items() if v}
                    for signal, row in table.iterrows()
                }
        return {
            "source": self.source,
            "rows": int(self.n_rows),
            "signals": list(self.signals),
            "ok": self.ok,
            "errors": len(self.errors),
            "warnings": len(self.warnings),
            "counts": counts,
            "findings": [f.to_dict() for f in self.findings],
        }

    def to_text(self) -> str:
        """Printable aligned table, one line per finding, message last."""
        head = (
            f"Data quality{' of ' + self.source if self.source else ''}: {self.n_rows} rows, "
            f"{len(self.signals)} signals — {len(self.errors)} error(s), "
            f"{len(self.warnings)} warning(s)"
        )
        if not self.findings:
            return head + "\nno findings"
        columns = ("severity", "action", "kind", "signal", "tag", "count", "row", "message")
        table = [
            (
                f.severity, f.action, f.kind, f.signal or INDEX, f.tag or "", str(f.count),
                "" if f.first_row is None else str(f.first_row + 1), f.message,
            )
            for f in self.findings
        ]
        widths = [max(len(columns[i]), *(len(r[i]) for r in table)) for i in range(7)]
        right = {5, 6}

        def line(cells: tuple[str, ...]) -> str:
            padded = [
                cells[i].rjust(widths[i]) if i in right else cells[i].ljust(widths[i])
                for i in range(7)
            ]
            return "  ".join([*padded, cells[7]]).rstrip()

        return "\n".join([head, line(columns), *(line(r) for r in table)])

    def __str__(self) -> str:
        return self.to_text()

@dataclass(frozen=True)
class CleaningResult:
    """Cleaned data (time-sorted, unique index), per-sample :class:`Flag` codes and the report.

    ``rows`` gives, for each output row, its 0-based position in the frame as read.
    """

    data: pd.DataFrame
    flags: pd.DataFrame
    report: QualityReport
    rows: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
