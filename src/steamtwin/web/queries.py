"""Read-only SQL on the live twin's DuckDB historian for the HTTP service (issue 22, item 1).

The service and the web app share one process and one DuckDB database (DuckDB allows one
writing process; inside it, any number of connections to the same database instance, each
used by one thread at a time — DuckDB docs, "Concurrency" and the Python API's note that a
``DuckDBPyConnection`` is not thread-safe: "use cursor() to create one per thread").
:class:`HistorianReader` therefore holds a small pool of its own connections, made once in the
thread that builds it, and lends one to each query; DuckDB's MVCC gives every query a
consistent snapshot of what the writer has committed (DuckDB docs, "Transaction Management").

Long spans are downsampled in the database to at most ``max_points`` buckets of equal width
keeping each bucket's minimum and maximum (with their times), mean and count: the extrema-
preserving aggregation of M4 (Jugel, Jerzak, Hackenbroich & Markl, "M4: A Visualization-
Oriented Time Series Data Aggregation", PVLDB 7(10), 2014), so a spike or a dip of one sample
still shows in a chart of a day. NaN and NULL values (no twin value) are left out of every
aggregate (DuckDB orders NaN above every number, so a NaN would otherwise be each maximum).

The live feed reads the ``latest_series`` view where the historian has it: the final rows and
the provisional ones the service stores as each sample arrives, before the quality gate's
look-ahead has judged it (live/historian.py), so a new value shows within a second rather
than a minute; everything else reads the final ``series``.

The recent past of each unit's final series (the last ``recent_s``, default 10 min) is also
kept in memory (:class:`_Recent`): a short raw range inside it — the last minute every open
page polls — is answered from there instead of a scan of the newest row group (122 880 rows,
~2 ms of CPU, most of such a request's cost). Final rows never change once committed (the
writer refuses a block that does not start after the unit's last committed sample, and stores
the rows and that time in one transaction), so the copy is refreshed by appending the rows up to
the last committed time whenever that time moves, one query shared by every request.

The one write is :meth:`HistorianReader.acknowledge` (an alarm's acknowledgement, a row of the
``alarms`` table); nothing writes a file.
"""

from __future__ import annotations

import json
import queue
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime

import duckdb
import numpy as np
import pandas as pd

from steamtwin.dcs.quality import Flag

__all__ = ["HistorianReader", "SeriesQuery"]

Connect = Callable[[], duckdb.DuckDBPyConnection]


@dataclass(frozen=True)
class SeriesQuery:
    """One signal of one unit: ``source`` ("measured", "twin", "residual") in [start, end]
    (UTC)."""

    unit: str
    source: str
    signal: str
    start: pd.Timestamp
    end: pd.Timestamp


def _iso(value) -> str | None:
    """A stored time (aware datetime; the connections' zone is UTC) in ISO 8601."""
    if value is None or value is pd.NaT:
        return None
    if isinstance(value, datetime):
        return value.astimezone(UTC).isoformat()
    return pd.Timestamp(value).tz_convert("UTC").isoformat()


def _number(value) -> float | None:
    if value is None:
        return None
    number = float(value)
    return number if np.isfinite(number) else None


def _flag_names(text: str) -> list[str]:
    """Stored gate flag (the :class:`~steamtwin.dcs.quality.Flag` bits as text) → names."""
    try:
        bits = Flag(int(float(text)))
    except ValueError:
        return [text]
    return [flag.name for flag in Flag if flag in bits and flag.name]


@dataclass(frozen=True)
class _Recent:
    """One unit's final samples in (``first``, ``last``] (UTC ns), per (source, signal): the
    times (ns, sorted) and the answer's columns (ISO time, value or None, flag names)."""

    first: int
    last: int
    columns: dict[tuple[str, str], tuple[np.ndarray, list, list, list]]

    def covers(self, start: int, end: int) -> bool:
        return self.first < start and end <= self.last

    def extended(self, rows: list[tuple], last: int, keep_ns: int) -> _Recent:
        """With ``rows`` (source, signal, time, value, flag; ordered by time) up to ``last``,
        less what is older than ``last - keep_ns``."""
        first = last - keep_ns
        grouped: dict[tuple[str, str], list[tuple]] = {}
        for source, signal, stamp, value, flag in rows:
            grouped.setdefault((source, signal), []).append((stamp, value, flag))
        columns = {}
        for key in set(self.columns) | set(grouped):
            ns, iso, values, flags = self.columns.get(key, (np.empty(0, np.int64), [], [], []))
            new = grouped.get(key, [])
            ns = np.concatenate([ns, np.array([pd.Timestamp(t).value for t, _, _ in new],
                                              dtype=np.int64)])
            iso = iso + [_iso(t) for t, _, _ in new]
            values = values + [_number(v) for _, v, _ in new]
            flags = flags + [None if f is None else _flag_names(f) for _, _, f in new]
            cut = int(np.searchsorted(ns, first, side="right"))
            if cut < len(ns):
                columns[key] = (ns[cut:], iso[cut:], values[cut:], flags[cut:])
        return _Recent(max(first, self.first), last, columns)


class HistorianReader:
    """``size`` connections from ``connect`` (e.g. ``lambda: duckdb.connect(path)`` or the
    service historian's ``connection.cursor``), lent to one query at a time (see the module
    docstring); ``timeout_s``: how long a query waits for a free connection; ``recent_s``:
    the recent past kept in memory per unit (s; 0: none)."""

    def __init__(self, connect: Connect, size: int = 4, timeout_s: float = 10.0,
                 recent_s: float = 600.0) -> None:
        if size < 1:
            raise ValueError(f"size must be ≥ 1 connection (got {size})")
        self._pool: queue.Queue[duckdb.DuckDBPyConnection] = queue.Queue()
        self._all = []
        self.timeout_s = timeout_s
        self.recent_s = recent_s
        self._recent: dict[str, _Recent] = {}
        self._recent_lock = threading.Lock()
        self._last_times: tuple[float, dict[str, pd.Timestamp]] | None = None
        self._signals: dict[str, tuple[float, list[tuple[str, str]]]] = {}
        for _ in range(size):
            connection = connect()
            connection.execute("SET TimeZone = 'UTC'")
            self._all.append(connection)
            self._pool.put(connection)

    def close(self) -> None:
        """Close every connection of the pool."""
        for connection in self._all:
            connection.close()
        self._all.clear()

    @contextmanager
    def connection(self) -> Iterator[duckdb.DuckDBPyConnection]:
        """One connection of the pool, for one thread, returned afterwards."""
        connection = self._pool.get(timeout=self.timeout_s)
        try:
            yield connection
        finally:
            self._pool.put(connection)

    def _rows(self, sql: str, arguments: list | tuple = ()) -> list[tuple]:
        with self.connection() as connection:
            return connection.execute(sql, list(arguments)).fetchall()

    # -- units and signals ---------------------------------------------------------------
    def _has_provisional(self) -> bool:
        """Whether the historian has the provisional rows (older databases do not)."""
        return bool(self._rows("SELECT count(*) FROM information_schema.tables "
                               "WHERE table_name = 'latest_series'")[0][0])

    def live_times(self) -> dict[str, pd.Timestamp]:
        """Each unit's newest sample time (UTC), final or provisional."""
        last = dict(self.last_times())
        if self._has_provisional():
            for unit, stamp in self._rows("SELECT unit, max(time) FROM provisional "
                                          "GROUP BY unit"):
                last[unit] = max(last.get(unit, pd.Timestamp(stamp)),
                                 pd.Timestamp(stamp).tz_convert("UTC"))
        return last

    def last_times(self, max_age_s: float = 0.0) -> dict[str, pd.Timestamp]:
        """Each unit's last committed sample time (UTC); an answer at most ``max_age_s`` old
        may be reused (one query serves the requests of that moment)."""
        now = time.monotonic()
        cached = self._last_times
        if cached is not None and now - cached[0] <= max_age_s:
            return cached[1]
        last = {unit: pd.Timestamp(stamp).tz_convert("UTC")
                for unit, stamp in self._rows("SELECT unit, last_time FROM progress")}
        self._last_times = (now, last)
        return last

    def signals(self, unit: str, max_age_s: float = 0.0) -> list[tuple[str, str]]:
        """(source, signal) pairs stored for ``unit``'s last committed sample — or, before
        its first final block (a service just started: the gate's look-ahead), its newest
        provisional sample — sorted; an answer at most ``max_age_s`` old may be reused."""
        now = time.monotonic()
        cached = self._signals.get(unit)
        if cached is not None and now - cached[0] <= max_age_s:
            return cached[1]
        last, table = self.last_times(max_age_s).get(unit), "series"
        if last is None and self._has_provisional():
            last, table = self.live_times().get(unit), "provisional"
        pairs = [] if last is None else [(source, signal) for source, signal in self._rows(
            f"SELECT DISTINCT source, signal FROM {table} WHERE unit = ? AND time = ? "
            "ORDER BY source, signal", [unit, last.to_pydatetime()])]
        self._signals[unit] = (now, pairs)
        return pairs

    # -- series ---------------------------------------------------------------------------
    @staticmethod
    def _where(query: SeriesQuery) -> tuple[str, list]:
        return ("unit = ? AND source = ? AND signal = ? AND time >= ? AND time <= ?",
                [query.unit, query.source, query.signal, query.start.to_pydatetime(),
                 query.end.to_pydatetime()])

    def count(self, query: SeriesQuery) -> int:
        """Stored rows of the signal in the range."""
        where, arguments = self._where(query)
        return int(self._rows(f"SELECT count(*) FROM series WHERE {where}", arguments)[0][0])

    def raw(self, query: SeriesQuery) -> pd.DataFrame:
        """The stored samples: columns time (UTC), value (SI; NaN: none), flag (gate)."""
        where, arguments = self._where(query)
        with self.connection() as connection:
            frame = connection.execute(f"SELECT time, value, flag FROM series WHERE {where} "
                                       "ORDER BY time", arguments).df()
        frame["time"] = pd.to_datetime(frame["time"], utc=True)
        return frame

    def series(self, query: SeriesQuery, max_points: int) -> dict[str, object]:
        """The signal as JSON-ready columns: raw (time, value, flag) when it has at most
        ``max_points`` samples in the range, else ``max_points`` equal buckets with each
        bucket's min and max (and their times), mean and count (M4; module docstring)."""
        recent = self._recent_answer(query, max_points)
        if recent is not None:
            return recent
        where, arguments = self._where(query)
        rows = self._rows(f"SELECT time, value, flag FROM series WHERE {where} ORDER BY time "
                          "LIMIT ?", [*arguments, max_points + 1])
        if len(rows) <= max_points:
            return {"downsampled": False, "count": len(rows),
                    "time": [_iso(t) for t, _, _ in rows],
                    "value": [_number(v) for _, v, _ in rows],
                    "flag": [None if f is None else _flag_names(f) for _, _, f in rows]}
        total = self.count(query)
        start_us = int(query.start.value // 1000)
        span_us = int(query.end.value // 1000) - start_us
        width_us = max(1, -(-span_us // max_points))  # ceil; the end joins the last bucket
        rows = self._rows(
            "SELECT bucket, min(value), arg_min(time, value), max(value), arg_max(time, value), "
            "avg(value), count(value) FROM (SELECT time, value, least((epoch_us(time) - ?) // "
            f"?, ?) AS bucket FROM series WHERE {where} AND value IS NOT NULL AND NOT "
            "isnan(value)) GROUP BY bucket ORDER BY bucket",
            [start_us, width_us, max_points - 1, *arguments])
        starts = [query.start + pd.Timedelta(microseconds=int(b) * width_us) for b, *_ in rows]
        return {"downsampled": True, "count": total, "bucket_s": width_us / 1e6,
                "time": [t.isoformat() for t in starts],
                "min": [_number(r[1]) for r in rows], "min_time": [_iso(r[2]) for r in rows],
                "max": [_number(r[3]) for r in rows], "max_time": [_iso(r[4]) for r in rows],
                "mean": [_number(r[5]) for r in rows], "n": [int(r[6]) for r in rows]}

    def _recent_answer(self, query: SeriesQuery, max_points: int) -> dict[str, object] | None:
        """The raw answer from the unit's recent past in memory, None when the range is not
        inside it or holds more than ``max_points`` samples (module docstring)."""
        if self.recent_s <= 0.0:
            return None
        start, end = query.start.value, query.end.value
        recent = self._recent.get(query.unit)
        if recent is not None and start <= recent.first:
            return None  # begins before the recent past (which only moves on)
        if recent is None or not recent.covers(start, end):
            recent = self._refresh_recent(query.unit)
            if recent is None or not recent.covers(start, end):
                return None
        ns, iso, values, flags = recent.columns.get(
            (query.source, query.signal), (np.empty(0, np.int64), [], [], []))
        low = int(np.searchsorted(ns, start, side="left"))
        high = int(np.searchsorted(ns, end, side="right"))
        if high - low > max_points:
            return None
        return {"downsampled": False, "count": high - low, "time": iso[low:high],
                "value": values[low:high], "flag": flags[low:high]}

    def _refresh_recent(self, unit: str) -> _Recent | None:
        """Append the unit's rows committed since the copy was made (one request does it;
        the others wait for it and use its result)."""
        with self._recent_lock:
            last = self.last_times().get(unit)
            if last is None:
                return None
            recent = self._recent.get(unit)
            keep_ns = int(self.recent_s * 1e9)
            if recent is not None and recent.last >= last.value:
                return recent
            if recent is None or recent.last < last.value - keep_ns:
                recent = _Recent(last.value - keep_ns, last.value - keep_ns, {})
            rows = self._rows(
                "SELECT source, signal, time, value, flag FROM series WHERE unit = ? AND "
                "time > ? AND time <= ? ORDER BY time",
                [unit, pd.Timestamp(recent.last, tz="UTC").to_pydatetime(),
                 last.to_pydatetime()])
            recent = recent.extended(rows, last.value, keep_ns)
            self._recent[unit] = recent
            return recent

    def samples_after(self, unit: str, after: pd.Timestamp | None, limit: int = 600
                      ) -> list[dict[str, object]]:
        """``unit``'s samples stored after ``after`` (all sources; the newest ``limit`` when
        ``after`` is None or older), oldest first: {time, values: {source/signal: value},
        provisional: whether the gate has yet to judge it (its final row replaces it)}."""
        table = "latest_series" if self._has_provisional() else "series"
        flag = "provisional" if table == "latest_series" else "false"
        clause, arguments = "", [unit]
        if after is not None:
            clause, arguments = " AND time > ?", [unit, after.to_pydatetime()]
        rows = self._rows(
            f"SELECT time, source, signal, value, {flag} FROM {table} WHERE unit = ? AND time IN "
            f"(SELECT DISTINCT time FROM {table} WHERE unit = ?{clause} ORDER BY time DESC "
            "LIMIT ?) ORDER BY time, source, signal", [unit, *arguments, limit])
        samples: dict[pd.Timestamp, dict[str, float | None]] = {}
        provisional: dict[pd.Timestamp, bool] = {}
        for stamp, source, signal, value, early in rows:
            samples.setdefault(pd.Timestamp(stamp), {})[f"{source}/{signal}"] = _number(value)
            provisional[pd.Timestamp(stamp)] = bool(early)
        return [{"time": _iso(stamp), "values": values, "provisional": provisional[stamp]}
                for stamp, values in samples.items()]

    # -- alarms ---------------------------------------------------------------------------
    _ALARM_COLUMNS = ('id, unit, kind, signal, start, "end", evidence, acknowledged_at, '
                      "acknowledged_by")

    @staticmethod
    def _alarm(row: tuple, evidence: bool) -> dict[str, object]:
        alarm_id, unit, kind, signal, start, end, text, acked_at, acked_by = row
        alarm = {"id": int(alarm_id), "unit": unit, "kind": kind, "signal": signal,
                 "start": _iso(start), "end": _iso(end), "active": end is None,
                 "acknowledged_at": _iso(acked_at), "acknowledged_by": acked_by}
        if evidence:
            alarm["evidence"] = json.loads(text) if text else {}
        return alarm

    def alarms(self, unit: str | None = None, active: bool = False, limit: int = 1000
               ) -> list[dict[str, object]]:
        """Alarms (of ``unit``; only those without an end if ``active``), newest first."""
        clauses, arguments = [], []
        if unit is not None:
            clauses.append("unit = ?")
            arguments.append(unit)
        if active:
            clauses.append('"end" IS NULL')
        where = f" WHERE {' AND '.join(clauses)}" if clauses else ""
        rows = self._rows(f"SELECT {self._ALARM_COLUMNS} FROM alarms{where} ORDER BY id DESC "
                          "LIMIT ?", [*arguments, limit])
        return [self._alarm(row, evidence=False) for row in rows]

    def alarm(self, alarm_id: int) -> dict[str, object] | None:
        """One alarm with its evidence, None if there is no such alarm."""
        rows = self._rows(f"SELECT {self._ALARM_COLUMNS} FROM alarms WHERE id = ?", [alarm_id])
        return self._alarm(rows[0], evidence=True) if rows else None

    def alarm_marks(self) -> tuple[int, int]:
        """(largest alarm id, alarms ended): a cheap fingerprint of the alarm table's news."""
        row = self._rows('SELECT coalesce(max(id), 0), count("end") FROM alarms')[0]
        return int(row[0]), int(row[1])

    def acknowledge(self, alarm_id: int, by: str, at: pd.Timestamp) -> dict[str, object] | None:
        """Acknowledge alarm ``alarm_id`` as ``by`` at ``at`` unless it already is; the alarm
        afterwards (None: no such alarm). The first acknowledgement stands."""
        with self.connection() as connection:
            connection.execute(
                "UPDATE alarms SET acknowledged_at = ?, acknowledged_by = ? WHERE id = ? AND "
                "acknowledged_at IS NULL", [at.to_pydatetime(), by, alarm_id])
        return self.alarm(alarm_id)

    # -- parameters and data quality ------------------------------------------------------
    def parameters(self, unit: str, start: pd.Timestamp | None = None,
                   end: pd.Timestamp | None = None) -> list[dict[str, object]]:
        """Every swap of ``unit``'s live parameters in [start, end], oldest first, with the
        filter's 95 % interval (low, high; None when the value did not come from the filter)."""
        clauses, arguments = ["unit = ?"], [unit]
        for bound, operator in ((start, ">="), (end, "<=")):
            if bound is not None:
                clauses.append(f"time {operator} ?")
                arguments.append(bound.to_pydatetime())
        rows = self._rows(f"SELECT time, name, value, reason, low, high FROM parameters WHERE "
                          f"{' AND '.join(clauses)} ORDER BY time, name", arguments)
        return [{"time": _iso(t), "name": n, "value": _number(v), "reason": r,
                 "low": _number(lo), "high": _number(hi)} for t, n, v, r, lo, hi in rows]

    def current_parameters(self, unit: str) -> dict[str, dict[str, object]]:
        """Each parameter's latest value, its time, reason and 95 % interval (low, high; None
        when that value did not come from the filter)."""
        rows = self._rows("SELECT name, arg_max(value, time), max(time), arg_max(reason, time), "
                          "arg_max_null(low, time), arg_max_null(high, time) "
                          "FROM parameters WHERE unit = ? GROUP BY name ORDER BY name", [unit])
        return {n: {"value": _number(v), "time": _iso(t), "reason": r, "low": _number(lo),
                    "high": _number(hi)} for n, v, t, r, lo, hi in rows}

    def quality(self, unit: str, start: pd.Timestamp, end: pd.Timestamp) -> dict[str, object]:
        """The gate's verdicts on ``unit``'s measured samples in [start, end]: samples per
        signal and flagged samples per signal and flag (:class:`~steamtwin.dcs.quality.Flag`
        names; a sample can carry several)."""
        window = "unit = ? AND source = 'measured' AND time >= ? AND time <= ?"
        arguments = [unit, start.to_pydatetime(), end.to_pydatetime()]
        totals = self._rows(f"SELECT signal, count(*), count(flag) FROM series WHERE {window} "
                            "GROUP BY signal ORDER BY signal", arguments)
        kinds = self._rows(f"SELECT signal, flag, count(*) FROM series WHERE {window} AND flag "
                           "IS NOT NULL GROUP BY signal, flag", arguments)
        signals = {signal: {"samples": int(n), "flagged": int(flagged), "flags": {}}
                   for signal, n, flagged in totals}
        for signal, flag, n in kinds:
            for name in _flag_names(flag):
                counts = signals[signal]["flags"]
                counts[name] = counts.get(name, 0) + int(n)
        return {"unit": unit, "start": _iso(start), "end": _iso(end), "signals": signals,
                "flagged": sum(s["flagged"] for s in signals.values())}

    def sample_at(self, unit: str, at: pd.Timestamp, source: str = "measured"
                  ) -> tuple[pd.Timestamp, dict[str, float | None]] | None:
        """``unit``'s last stored sample at or before ``at`` (UTC): its time and the values
        of ``source`` by signal (SI; None: no value); None if nothing is stored by then."""
        rows = self._rows(
            "SELECT time, signal, value FROM series WHERE unit = ? AND source = ? AND time = "
            "(SELECT max(time) FROM series WHERE unit = ? AND source = ? AND time <= ?) "
            "ORDER BY signal", [unit, source, unit, source, at.to_pydatetime()])
        if not rows:
            return None
        return (pd.Timestamp(rows[0][0]).tz_convert("UTC"),
                {signal: _number(value) for _, signal, value in rows})
