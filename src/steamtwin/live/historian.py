"""The live twin's embedded historian: one DuckDB file per service (issue 21, item 7).

Kept as one module because it is one class, :class:`LiveHistorian`, over one connection whose
transactions the writes share, with the row types it takes.

Everything the live twin sees and says is kept in SI with the canonical names, one database
file per service, several units side by side:

* ``series`` (long: unit, time, source, signal, value, flag) — ``source`` is ``measured``
  (the cleaned DCS sample), ``twin`` (the model's output, ROM probe temperatures included)
  or ``residual`` (measured − twin); ``flag`` names what the data-quality gate found (NULL:
  good). Long rather than wide so that a unit's signals, a new probe or another twin output
  need no schema change;
* ``alarms`` (id, unit, kind, signal, start, end, evidence JSON, acknowledged_at/by);
* ``parameters`` (unit, time, name, value, reason, low, high) — every swap of the live
  parameters, with the filter's 95 % interval of each value it estimated;
* ``states`` (unit, time, state JSON) — the newest :data:`KEPT_STATES` state snapshots of
  each unit, to restart from;
* ``progress`` (unit, last_time) — the last committed sample;
* ``provisional`` (as ``series``) — the twin's first word on the samples the gate's look-ahead
  has not judged yet (:meth:`LiveHistorian.store_provisional`), each row deleted in the
  transaction that commits its sample's final row; the view ``latest_series`` is ``series``
  and ``provisional`` together, with a ``provisional`` column. A restarted service rewrites
  them; ``series``, ``progress`` and the rest never hold a provisional value.

Exactly once: :meth:`LiveHistorian.commit_block` writes a block's series rows, the unit's
progress and (optionally) its state snapshot in ONE transaction (DuckDB transactions are
ACID, durable at commit through its write-ahead log; DuckDB docs, "Transaction
Management"), so after a crash (even SIGKILL) the file holds whole blocks only, and
:meth:`resume_time` says where the stream must resume: no sample lost, none stored twice.
Times are stored as UTC ``TIMESTAMPTZ``.

Threads: the service stores provisional rows from its event loop and commits final blocks from
its final-work thread (:mod:`steamtwin.live.runner`); a ``DuckDBPyConnection`` is not
thread-safe (DuckDB Python docs, "use cursor() to create one per thread"), so every method that
uses the connection holds the historian's lock: one statement sequence at a time, as on one
thread, and no two transactions of this writer ever overlap.
"""

from __future__ import annotations

import functools
import json
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar, cast

import duckdb
import numpy as np
import pandas as pd
import pyarrow as pa

from steamtwin.live.config import MIN_MEMORY_LIMIT_MB

__all__ = ["SOURCES", "Alarm", "AlarmEnd", "BlockEvents", "LiveHistorian", "ProvisionalRows",
           "export_history"]

SOURCES = ("measured", "twin", "residual")
KEPT_STATES = 3
"""State snapshots kept per unit (a restart needs the newest; the rest are a margin)."""

_SCHEMA = (
    """CREATE TABLE IF NOT EXISTS series (unit VARCHAR NOT NULL, time TIMESTAMPTZ NOT NULL,
       source VARCHAR NOT NULL, signal VARCHAR NOT NULL, value DOUBLE, flag VARCHAR)""",
    """CREATE TABLE IF NOT EXISTS alarms (id BIGINT PRIMARY KEY, unit VARCHAR NOT NULL,
       kind VARCHAR NOT NULL, signal VARCHAR, start TIMESTAMPTZ NOT NULL, "end" TIMESTAMPTZ,
       evidence JSON, acknowledged_at TIMESTAMPTZ, acknowledged_by VARCHAR)""",
    """CREATE TABLE IF NOT EXISTS parameters (unit VARCHAR NOT NULL, time TIMESTAMPTZ NOT NULL,
       name VARCHAR NOT NULL, value DOUBLE NOT NULL, reason VARCHAR, low DOUBLE,
       high DOUBLE)""",
    # a database written before the interval columns existed gains them (NULL: not recorded)
    "ALTER TABLE parameters ADD COLUMN IF NOT EXISTS low DOUBLE",
    "ALTER TABLE parameters ADD COLUMN IF NOT EXISTS high DOUBLE",
    """CREATE TABLE IF NOT EXISTS states (unit VARCHAR NOT NULL, time TIMESTAMPTZ NOT NULL,
       state JSON NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS progress (unit VARCHAR PRIMARY KEY,
       last_time TIMESTAMPTZ NOT NULL)""",
    """CREATE TABLE IF NOT EXISTS provisional (unit VARCHAR NOT NULL,
       time TIMESTAMPTZ NOT NULL, source VARCHAR NOT NULL, signal VARCHAR NOT NULL,
       value DOUBLE, flag VARCHAR)""",
    """CREATE OR REPLACE VIEW latest_series AS
       SELECT *, false AS provisional FROM series
       UNION ALL SELECT *, true AS provisional FROM provisional""",
)


@dataclass(frozen=True)
class Alarm:
    """One alarm: ``kind`` (e.g. "sensor_fault", "degradation"), the ``signal`` it concerns
    (None: the unit), ``start``/``end`` (UTC; end None while active) and its ``evidence``
    (JSON-ready mapping: statistics, thresholds, the residuals that raised it)."""

    unit: str
    kind: str
    start: pd.Timestamp
    signal: str | None = None
    end: pd.Timestamp | None = None
    evidence: Mapping[str, object] | None = None


@dataclass(frozen=True)
class AlarmEnd:
    """The end at ``end`` (UTC) of the unit's open alarm of ``kind`` and ``signal``."""

    kind: str
    signal: str | None
    end: pd.Timestamp


@dataclass(frozen=True)
class ProvisionalRows:
    """One unit's provisional rows to store: ``frames`` (source → wide SI frame on a UTC
    index) and the measured samples' ``flags``, as :meth:`LiveHistorian.store_provisional`
    takes them."""

    unit: str
    frames: Mapping[str, pd.DataFrame]
    flags: pd.DataFrame | None = None


@dataclass(frozen=True)
class BlockEvents:
    """What a block did besides its samples: ``alarms`` started (:class:`Alarm`) and ended
    (:class:`AlarmEnd`), in the order they happened, and parameter swaps as
    (time, name → value, reason) or (time, name → value, reason, name → 95 % interval)."""

    alarms: tuple[Alarm | AlarmEnd, ...] = ()
    parameters: tuple[tuple, ...] = ()


def _utc(times: pd.DatetimeIndex | pd.Series) -> pd.DatetimeIndex:
    index = pd.DatetimeIndex(times)
    if index.tz is None:
        raise ValueError("times must be time-zone aware (UTC or a zone)")
    return index.tz_convert("UTC")


_Method = TypeVar("_Method", bound=Callable[..., object])


def _serialised(method: _Method) -> _Method:
    """Run ``method`` holding its historian's lock (see "Threads" in the module docstring)."""
    @functools.wraps(method)
    def locked(self: LiveHistorian, *args: object, **kwargs: object) -> object:
        with self._lock:
            return method(self, *args, **kwargs)
    return cast(_Method, locked)


class LiveHistorian:
    """The DuckDB file at ``path`` (created with its tables if missing); use as a context
    manager or call :meth:`close`.

    ``memory_limit_mb``: DuckDB's memory limit for this connection, MB (None: DuckDB's
    default, 80 % of the RAM). DuckDB's buffer manager keeps the blocks it has written
    cached until the limit presses (measured: its memory grows with the file, 31 MB after a
    day of one unit), so a service that runs for months bounds it (``steamtwin serve``:
    ``historian_memory_mb``, default 32); a query that needs more than the limit fails, so
    exports keep the default."""

    def __init__(self, path: str | Path, memory_limit_mb: float | None = None) -> None:
        self.path = Path(path)
        self.memory_limit_mb = memory_limit_mb
        self._connection: duckdb.DuckDBPyConnection | None = None
        self._last_times: dict[str, pd.Timestamp | None] = {}  # what progress holds
        self._provisional: dict[str, bool] = {}  # unit → it may have provisional rows
        # unit → the newest provisional row this writer stored: rows after it replace none
        self._provisional_end: dict[str, pd.Timestamp] = {}
        self._lock = threading.RLock()

    def __enter__(self) -> LiveHistorian:
        self.open()
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    @_serialised
    def open(self) -> None:
        """Open (or create) the database and its tables."""
        if self._connection is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            connection = duckdb.connect(str(self.path))
            connection.execute("SET TimeZone = 'UTC'")
            if self.memory_limit_mb is not None:  # DuckDB's own default: 80 % of the RAM
                limit = self.memory_limit_mb
                if (isinstance(limit, bool) or not isinstance(limit, int | float)
                        or not np.isfinite(limit) or limit < MIN_MEMORY_LIMIT_MB):
                    connection.close()
                    raise ValueError(f"memory_limit_mb must be a number ≥ "
                                     f"{MIN_MEMORY_LIMIT_MB:g} (MB; got {limit!r})")
                connection.execute(f"SET memory_limit = '{limit:.0f}MB'")
            for statement in _SCHEMA:
                connection.execute(statement)
            self._connection = connection

    @_serialised
    def close(self) -> None:
        """Close the database (idempotent)."""
        if self._connection is not None:
            self._connection.close()
            self._connection = None
        self._last_times.clear()
        self._provisional.clear()
        self._provisional_end.clear()

    @property
    def connection(self) -> duckdb.DuckDBPyConnection:
        """The open connection."""
        if self._connection is None:
            raise RuntimeError(f"{self.path}: the historian is not open")
        return self._connection

    @_serialised
    def resume_time(self, unit: str) -> pd.Timestamp | None:
        """The last committed sample's time of ``unit`` (UTC), None before the first. Read
        from the database once, then kept up to date by :meth:`commit_block` (DuckDB lets one
        process write a file, and this connection is its writer)."""
        if unit not in self._last_times:
            row = self.connection.execute(
                "SELECT last_time FROM progress WHERE unit = ?", [unit]).fetchone()
            self._last_times[unit] = (None if row is None
                                      else pd.Timestamp(row[0]).tz_convert("UTC"))
        return self._last_times[unit]

    @_serialised
    def commit_block(self, unit: str, frames: Mapping[str, pd.DataFrame],
                     flags: pd.DataFrame | None = None,
                     state: Mapping[str, object] | None = None,
                     events: BlockEvents | None = None) -> int:
        """Store one block of samples of ``unit`` atomically; return the rows written.

        ``frames``: source (one of :data:`SOURCES`) → wide frame (time index, canonical signal
        columns, SI). ``flags``: the gate's finding per measured sample and signal (same
        shape as ``frames["measured"]``, strings, NaN/None for good). ``state``: a model state
        snapshot (JSON-ready) stored at the block's last time. ``events``: the alarms the block
        starts and ends and the parameter swaps it makes, stored in the same transaction (a
        crash never leaves a state that knows an alarm the table lacks). Refuses a block that
        does not start after the unit's last committed sample (ValueError naming both times).
        """
        unknown = sorted(set(frames) - set(SOURCES))
        if unknown:
            raise ValueError(f"unknown series source(s) {unknown}; expected {SOURCES}")
        times = [_utc(frame.index) for frame in frames.values() if len(frame)]
        if not times:
            return 0
        first = min(index[0] for index in times)
        last = max(index[-1] for index in times)
        resume = self.resume_time(unit)
        if resume is not None and first <= resume:
            raise ValueError(f"unit {unit!r}: block starts at {first.isoformat()}, not after "
                             f"the last committed sample {resume.isoformat()} (a sample would "
                             "be stored twice)")
        rows = self._long(unit, frames, flags)
        connection = self.connection
        connection.execute("BEGIN TRANSACTION")
        try:
            self._insert_series(rows)
            self._set_progress(unit, last, known=resume is not None)
            if self._may_have_provisional(unit):  # superseded by the final rows
                connection.execute("DELETE FROM provisional WHERE unit = ? AND time <= ?",
                                   [unit, last.to_pydatetime()]).fetchall()
            if state is not None:
                connection.execute("INSERT INTO states VALUES (?, ?, ?)",
                                   [unit, last.to_pydatetime(), json.dumps(state)])
                connection.execute(  # a restart needs the newest; keep a few
                    "DELETE FROM states WHERE unit = ? AND time < (SELECT min(time) FROM "
                    "(SELECT time FROM states WHERE unit = ? ORDER BY time DESC LIMIT ?))",
                    [unit, unit, KEPT_STATES])
            if events is not None:
                self._store_events(unit, events)
            connection.execute("COMMIT")
        except Exception:
            connection.execute("ROLLBACK")
            self._last_times.pop(unit, None)  # read again from the database
            raise
        self._last_times[unit] = last
        return rows.num_rows

    def store_provisional(self, unit: str, frames: Mapping[str, pd.DataFrame],
                          flags: pd.DataFrame | None = None) -> int:
        """Store provisional rows of ``unit`` (``frames`` and ``flags`` as in
        :meth:`commit_block`): they replace the unit's provisional rows from their first time
        on, and :meth:`commit_block` deletes them when it stores their samples' final rows.
        Refuses rows at or before the last committed sample (ValueError); returns the rows
        written."""
        return self.store_provisional_many([ProvisionalRows(unit, frames, flags)])

    @_serialised
    def store_provisional_many(self, batch: Sequence[ProvisionalRows]) -> int:
        """:meth:`store_provisional` for several units at once (at most one entry per unit,
        else ValueError), in ONE transaction with one DELETE and one INSERT: the service
        stores every unit's provisional rows of a moment together (group commit: DeWitt et
        al., "Implementation techniques for main memory database systems", SIGMOD 1984;
        measured 7 → 2 ms of CPU per unit and sample for ten units, docs/benchmarks.md).
        Nothing is stored if any entry is refused; the DELETE runs only for the units whose
        rows start at or before the newest provisional row stored (a restarted chain), not
        for the usual next sample (1.5 ms of CPU saved per sample). Returns the rows
        written."""
        units = [entry.unit for entry in batch]
        if len(set(units)) < len(units):
            raise ValueError(f"provisional rows of one unit twice in one batch: {units}")
        tables, firsts, lasts = [], {}, {}
        for entry in batch:
            times = [_utc(frame.index) for frame in entry.frames.values() if len(frame)]
            if not times:
                continue
            first = min(index[0] for index in times)
            resume = self.resume_time(entry.unit)
            if resume is not None and first <= resume:
                raise ValueError(f"unit {entry.unit!r}: provisional rows from "
                                 f"{first.isoformat()}, not after the last committed sample "
                                 f"{resume.isoformat()}")
            tables.append(self._long(entry.unit, entry.frames, entry.flags))
            firsts[entry.unit] = first
            lasts[entry.unit] = max(index[-1] for index in times)
        if not tables:
            return 0
        rows = pa.concat_tables(tables)
        replaced = [unit for unit in firsts if self._may_have_provisional(unit)
                    and not firsts[unit] > self._provisional_end.get(unit, firsts[unit])]
        connection = self.connection
        connection.execute("BEGIN TRANSACTION")
        try:
            if replaced:
                connection.register("replaced_from", pa.table({
                    "unit": pa.array(replaced, type=pa.string()),
                    "first": pa.array([firsts[unit].to_pydatetime() for unit in replaced],
                                      type=pa.timestamp("us", tz="UTC"))}))
                try:
                    connection.execute(
                        "DELETE FROM provisional USING replaced_from WHERE provisional.unit = "
                        "replaced_from.unit AND provisional.time >= replaced_from.first"
                    ).fetchall()
                finally:
                    connection.unregister("replaced_from")
            self._insert_series(rows, "provisional")
            connection.execute("COMMIT")
        except Exception:
            connection.execute("ROLLBACK")
            raise
        for unit in firsts:
            self._provisional[unit] = True
            self._provisional_end[unit] = max(lasts[unit],
                                              self._provisional_end.get(unit, lasts[unit]))
        return rows.num_rows

    def _may_have_provisional(self, unit: str) -> bool:
        if unit not in self._provisional:  # once per connection; then this writer knows
            self._provisional[unit] = bool(self.connection.execute(  # fetchall: DuckDB keeps
                "SELECT count(*) FROM provisional WHERE unit = ?",  # a fetchone's result open
                [unit]).fetchall()[0][0])
        return self._provisional[unit]

    def _insert_series(self, rows: pa.Table, table: str = "series") -> None:
        """Append ``rows`` (the series columns in the table's order, Arrow) to ``table``: one
        bulk insert of a relation over the Arrow table, scanned without copying (DuckDB docs,
        "Data Ingestion": bulk insert from Arrow/pandas rather than row by row; a relation's
        ``insert_into`` spares the register/unregister round of a named view)."""
        self.connection.from_arrow(rows).insert_into(table)

    def _set_progress(self, unit: str, last: pd.Timestamp, known: bool) -> None:
        """The unit's last committed sample: an UPDATE of its row once it has one (cheaper in
        DuckDB than INSERT OR REPLACE, which deletes and re-inserts under the primary key)."""
        stamp = last.to_pydatetime()
        if known:
            self.connection.execute("UPDATE progress SET last_time = ? WHERE unit = ?",
                                    [stamp, unit])
        else:
            self.connection.execute("INSERT OR REPLACE INTO progress VALUES (?, ?)",
                                    [unit, stamp])

    def _store_events(self, unit: str, events: BlockEvents) -> None:
        for alarm in events.alarms:
            if isinstance(alarm, Alarm):
                self.raise_alarm(alarm)
                continue
            row = self.connection.execute(
                'SELECT max(id) FROM alarms WHERE unit = ? AND kind = ? AND signal IS NOT '
                'DISTINCT FROM ? AND "end" IS NULL', [unit, alarm.kind, alarm.signal]).fetchone()
            if row[0] is not None:
                self.end_alarm(int(row[0]), alarm.end)
        for time, values, reason, *intervals in events.parameters:
            self.record_parameters(unit, time, values, reason, *intervals)

    @staticmethod
    def _long(unit: str, frames: Mapping[str, pd.DataFrame], flags: pd.DataFrame | None
              ) -> pa.Table:
        """The series rows of the wide ``frames`` (source → frame; ``flags`` belong to the
        ``measured`` one), frame after frame, each time-major (one row per time and signal),
        as ONE Arrow table: unit, source and signal dictionary-encoded (no string per row),
        NaN values stored as NULL. One table per unit rather than per source: its fixed cost
        is most of a one-sample block's (docs/benchmarks.md, "Latency, fourth pass")."""
        where: dict[str, int] = {}  # signal → its code in the dictionary
        sources: list[str] = []
        times, source_codes, signal_codes, values, flag_values = [], [], [], [], []
        for source, frame in frames.items():
            if not len(frame):
                continue
            codes = np.array([where.setdefault(str(name), len(where))
                              for name in frame.columns.tolist()], dtype=np.int32)
            index = _utc(frame.index)
            block = frame.to_numpy(dtype=float).reshape(-1)
            flagged = np.full(block.shape, None, dtype=object)
            if flags is not None and source == "measured":
                aligned = (flags if flags.index.equals(frame.index)
                           and flags.columns.equals(frame.columns)
                           else flags.reindex(index=frame.index, columns=frame.columns))
                raw = aligned.to_numpy(dtype=object).reshape(-1)
                present = pd.notna(raw)
                flagged[present] = raw[present].astype(str)
            times.append(np.repeat(index.as_unit("us").asi8, codes.size))
            source_codes.append(np.full(block.size, len(sources), dtype=np.int32))
            signal_codes.append(np.tile(codes, len(index)))
            values.append(block)
            flag_values.append(flagged)
            sources.append(source)
        value = np.concatenate(values)
        return pa.table({
            "unit": pa.DictionaryArray.from_arrays(np.zeros(value.size, dtype=np.int32),
                                                   pa.array([unit])),
            "time": pa.array(np.concatenate(times), type=pa.timestamp("us", tz="UTC")),
            "source": pa.DictionaryArray.from_arrays(np.concatenate(source_codes),
                                                     pa.array(sources)),
            "signal": pa.DictionaryArray.from_arrays(np.concatenate(signal_codes),
                                                     pa.array(list(where), type=pa.string())),
            "value": pa.array(value, mask=np.isnan(value)),
            "flag": pa.array(np.concatenate(flag_values), type=pa.string()),
        })

    @_serialised
    def latest_state(self, unit: str) -> tuple[pd.Timestamp, dict] | None:
        """The newest state snapshot of ``unit`` and its time, None if there is none."""
        row = self.connection.execute(
            "SELECT time, state FROM states WHERE unit = ? ORDER BY time DESC LIMIT 1",
            [unit]).fetchone()
        if row is None:
            return None
        return pd.Timestamp(row[0]).tz_convert("UTC"), json.loads(row[1])

    @_serialised
    def record_parameters(self, unit: str, time: pd.Timestamp, values: Mapping[str, float],
                          reason: str,
                          intervals: Mapping[str, tuple[float, float]] | None = None) -> None:
        """One swap of the live parameters (name → value) and why it happened; ``intervals``:
        name → the estimate's 95 % interval (low, high), for the values that came from the
        filter (columns ``low``/``high``, NULL for the others)."""
        stamp = _utc(pd.DatetimeIndex([time]))[0].to_pydatetime()
        intervals = intervals or {}
        self.connection.executemany(
            "INSERT INTO parameters (unit, time, name, value, reason, low, high) "
            "VALUES (?, ?, ?, ?, ?, ?, ?)",
            [[unit, stamp, name, float(value), reason,
              *((float(b) for b in intervals[name]) if name in intervals else (None, None))]
             for name, value in values.items()])

    @_serialised
    def raise_alarm(self, alarm: Alarm) -> int:
        """Store ``alarm``; return its id."""
        connection = self.connection
        next_id = connection.execute("SELECT coalesce(max(id), 0) + 1 FROM alarms").fetchone()[0]
        connection.execute(
            "INSERT INTO alarms VALUES (?, ?, ?, ?, ?, ?, ?, NULL, NULL)",
            [next_id, alarm.unit, alarm.kind, alarm.signal,
             _utc(pd.DatetimeIndex([alarm.start]))[0].to_pydatetime(),
             None if alarm.end is None
             else _utc(pd.DatetimeIndex([alarm.end]))[0].to_pydatetime(),
             json.dumps(dict(alarm.evidence or {}))])
        return int(next_id)

    @_serialised
    def end_alarm(self, alarm_id: int, end: pd.Timestamp) -> None:
        """Mark alarm ``alarm_id`` as ended at ``end``."""
        self.connection.execute('UPDATE alarms SET "end" = ? WHERE id = ?',
                                [_utc(pd.DatetimeIndex([end]))[0].to_pydatetime(), alarm_id])

    @_serialised
    def acknowledge(self, alarm_id: int, by: str, at: pd.Timestamp) -> None:
        """Acknowledge alarm ``alarm_id`` (KeyError if there is no such alarm)."""
        found = self.connection.execute("SELECT count(*) FROM alarms WHERE id = ?",
                                        [alarm_id]).fetchone()[0]
        if not found:
            raise KeyError(f"no alarm {alarm_id} in {self.path}")
        self.connection.execute(
            "UPDATE alarms SET acknowledged_at = ?, acknowledged_by = ? WHERE id = ?",
            [_utc(pd.DatetimeIndex([at]))[0].to_pydatetime(), by, alarm_id])

    @_serialised
    def alarms(self, unit: str | None = None) -> pd.DataFrame:
        """Every alarm (of ``unit``), oldest first, evidence parsed."""
        query = "SELECT * FROM alarms" + (" WHERE unit = ?" if unit else "") + " ORDER BY id"
        frame = self.connection.execute(query, [unit] if unit else []).df()
        frame["evidence"] = [json.loads(text) if text else {} for text in frame["evidence"]]
        return frame

    @_serialised
    def series(self, unit: str, start: pd.Timestamp | None = None,
               end: pd.Timestamp | None = None, sources: tuple[str, ...] = SOURCES
               ) -> pd.DataFrame:
        """``unit``'s series in [start, end] as a wide frame: columns ``<source>/<signal>``
        (SI) and ``flag/<signal>`` where the gate flagged measured samples, UTC time index."""
        clauses, arguments = ["unit = ?"], [unit]
        if start is not None:
            clauses.append("time >= ?")
            arguments.append(_utc(pd.DatetimeIndex([start]))[0].to_pydatetime())
        if end is not None:
            clauses.append("time <= ?")
            arguments.append(_utc(pd.DatetimeIndex([end]))[0].to_pydatetime())
        marks = ", ".join("?" for _ in sources)
        long = self.connection.execute(
            f"SELECT time, source, signal, value, flag FROM series WHERE "
            f"{' AND '.join(clauses)} AND source IN ({marks}) ORDER BY time",
            [*arguments, *sources]).df()
        return _wide(long)


def _wide(long: pd.DataFrame) -> pd.DataFrame:
    """Long series rows → one row per time, ``<source>/<signal>`` and ``flag/<signal>``."""
    if long.empty:
        return pd.DataFrame(index=pd.DatetimeIndex([], tz="UTC", name="time"))
    long = long.assign(time=pd.to_datetime(long["time"], utc=True))
    values = long.pivot_table(index="time", columns=["source", "signal"], values="value",
                              aggfunc="first", dropna=False)
    values.columns = [f"{source}/{signal}" for source, signal in values.columns]
    flagged = long.dropna(subset=["flag"])
    if not flagged.empty:
        flags = flagged.pivot_table(index="time", columns="signal", values="flag",
                                    aggfunc="first")
        flags.columns = [f"flag/{signal}" for signal in flags.columns]
        values = values.join(flags)
    values.index.name = "time"
    return values.sort_index()


def export_history(db: str | Path, out: str | Path, *, unit: str | None = None,
                   start: pd.Timestamp | None = None, end: pd.Timestamp | None = None,
                   layout: str = "wide") -> int:
    """Write ``db``'s series (of ``unit``; all units when None and the layout is long) in
    [start, end] to ``out`` (.parquet or .csv); return the rows written. ``layout`` "wide"
    (one row per time: ``<source>/<signal>`` columns, one unit) or "long"."""
    path = Path(db)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such historian database")
    out = Path(out)
    if out.suffix not in (".parquet", ".csv"):
        raise ValueError(f"{out}: expected a .parquet or .csv file")
    if layout not in ("wide", "long"):
        raise ValueError(f"layout must be 'wide' or 'long' (got {layout!r})")
    with LiveHistorian(path) as historian:
        units = [row[0] for row in historian.connection.execute(
            "SELECT DISTINCT unit FROM series ORDER BY unit").fetchall()]
        if unit is not None and unit not in units:
            raise ValueError(f"{path}: no unit {unit!r} (units: {', '.join(units) or 'none'})")
        if layout == "wide":
            if unit is None:
                if len(units) != 1:
                    raise ValueError(f"{path} holds units {units}: name one (--unit) for the "
                                     "wide layout")
                unit = units[0]
            frame = historian.series(unit, start, end)
        else:
            clauses, arguments = [], []
            if unit is not None:
                clauses.append("unit = ?")
                arguments.append(unit)
            for bound, operator in ((start, ">="), (end, "<=")):
                if bound is not None:
                    clauses.append(f"time {operator} ?")
                    arguments.append(_utc(pd.DatetimeIndex([bound]))[0].to_pydatetime())
            where = f" WHERE {' AND '.join(clauses)}" if clauses else ""
            frame = historian.connection.execute(
                f"SELECT * FROM series{where} ORDER BY unit, time, source, signal",
                arguments).df()
    if out.suffix == ".parquet":
        frame.to_parquet(out)
    else:
        frame.to_csv(out)
    return len(frame)
