"""The live twin's DuckDB historian (issue 21, item 7): blocks stored exactly once, a SIGKILL
loses no committed sample and stores none twice, alarms/parameters/states, export."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import duckdb
import numpy as np
import pandas as pd
import pytest

from steamtwin.live.historian import Alarm, LiveHistorian, export_history

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop


def _block(start: int, n: int = 60) -> dict[str, pd.DataFrame]:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC") + pd.Timedelta(
        seconds=start)
    k = np.arange(start, start + n, dtype=float)
    measured = pd.DataFrame({"hp_exhaust_temperature": 600.0 + 0.01 * k,
                             "control_stage_pressure": 9.0e6 + k}, index=index)
    twin = pd.DataFrame({"hp_exhaust_temperature": 600.2 + 0.01 * k,
                         "blade_leading_edge": 750.0 + 0.001 * k}, index=index)
    residual = measured[["hp_exhaust_temperature"]] - twin[["hp_exhaust_temperature"]]
    return {"measured": measured, "twin": twin, "residual": residual}


def test_blocks_round_trip_with_flags_and_refuse_overlap(tmp_path):
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:
        assert historian.resume_time("u1") is None
        first = _block(0)
        flags = pd.DataFrame(None, index=first["measured"].index,
                             columns=first["measured"].columns, dtype=object)
        flags.iloc[5, 0] = "spike"
        written = historian.commit_block("u1", first, flags, state={"metal": [1.0, 2.0]})
        assert written == 60 * 5
        historian.commit_block("u1", _block(60))
        assert historian.resume_time("u1") == first["measured"].index[0] + pd.Timedelta(
            seconds=119)
        with pytest.raises(ValueError, match="stored twice"):
            historian.commit_block("u1", _block(100))
        historian.commit_block("u2", _block(0))  # another unit, its own progress
        wide = historian.series("u1")
        assert len(wide) == 120
        assert np.allclose(wide["measured/control_stage_pressure"],
                           9.0e6 + np.arange(120.0))
        assert np.allclose(wide["residual/hp_exhaust_temperature"], -0.2)
        assert wide["flag/hp_exhaust_temperature"].iloc[5] == "spike"
        assert wide["flag/hp_exhaust_temperature"].drop(wide.index[5]).isna().all()
        state_time, state = historian.latest_state("u1")
        assert state == {"metal": [1.0, 2.0]} and state_time == first["measured"].index[-1]


def test_alarms_parameters_and_acknowledgement(tmp_path):
    start = pd.Timestamp("2026-03-01T12:00:00Z")
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:
        first = historian.raise_alarm(Alarm("u1", "sensor_fault", start,
                                            "hp_exhaust_temperature",
                                            evidence={"cusum": 5.2, "threshold": 5.0}))
        second = historian.raise_alarm(Alarm("u1", "degradation", start))
        historian.end_alarm(first, start + pd.Timedelta(minutes=5))
        historian.acknowledge(second, "operator", start + pd.Timedelta(minutes=1))
        with pytest.raises(KeyError, match="no alarm 99"):
            historian.acknowledge(99, "operator", start)
        historian.record_parameters("u1", start, {"flow_coefficient": 0.98}, "recalibration")
        historian.record_parameters("u1", start + pd.Timedelta(minutes=10),
                                    {"flow_coefficient": 0.97, "friction_coefficient": 1.1},
                                    "degradation:flow_coefficient",
                                    {"flow_coefficient": (0.955, 0.985)})
        alarms = historian.alarms("u1")
        parameters = historian.connection.execute("SELECT * FROM parameters").df()
    assert list(alarms["id"]) == [first, second] == [1, 2]
    assert alarms["evidence"].iloc[0] == {"cusum": 5.2, "threshold": 5.0}
    assert pd.Timestamp(alarms["end"].iloc[0]) == start + pd.Timedelta(minutes=5)
    assert pd.isna(alarms["end"].iloc[1]) and alarms["acknowledged_by"].iloc[1] == "operator"
    assert parameters["value"].tolist() == [0.98, 0.97, 1.1]
    # the 95 % interval where the value came from the filter, NULL where it did not
    assert parameters["low"].tolist()[1] == 0.955 and parameters["high"].tolist()[1] == 0.985
    assert parameters[["low", "high"]].iloc[[0, 2]].isna().all().all()


def test_a_database_from_before_the_parameter_intervals_gains_them(tmp_path):
    path = tmp_path / "old.duckdb"
    with duckdb.connect(str(path)) as old:  # the parameters table as it was first written
        old.execute("CREATE TABLE parameters (unit VARCHAR NOT NULL, time TIMESTAMPTZ NOT NULL, "
                    "name VARCHAR NOT NULL, value DOUBLE NOT NULL, reason VARCHAR)")
        old.execute("INSERT INTO parameters VALUES ('u1', '2026-03-01 12:00:00+00', "
                    "'flow_coefficient', 0.99, 'start')")
    start = pd.Timestamp("2026-03-01T13:00:00Z")
    with LiveHistorian(path) as historian:
        historian.record_parameters("u1", start, {"flow_coefficient": 0.98}, "schedule",
                                    {"flow_coefficient": (0.97, 0.99)})
        rows = historian.connection.execute(
            "SELECT value, low, high FROM parameters ORDER BY time").fetchall()
    assert rows == [(0.99, None, None), (0.98, 0.97, 0.99)]


_WRITER = textwrap.dedent("""
    import sys, time
    sys.path.insert(0, {tests!r})
    from test_historian import _block
    from steamtwin.live.historian import LiveHistorian
    with LiveHistorian({db!r}) as historian:
        resume = historian.resume_time("u1")
        start = 0 if resume is None else int((resume - _block(0)["measured"].index[0])
                                             .total_seconds()) + 1
        for k in range(start, {total}, 60):
            historian.commit_block("u1", _block(k), state={{"k": k}})
            print(k, flush=True)
            time.sleep({pause})
""")


def _writer(db, total: int, pause: float) -> subprocess.Popen:
    code = _WRITER.format(tests=os.path.dirname(__file__), db=str(db), total=total,
                          pause=pause)
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)


def test_a_sigkilled_writer_resumes_to_the_uninterrupted_database(tmp_path):
    total = 60 * 40
    reference = _writer(tmp_path / "reference.duckdb", total, 0.0)
    assert reference.wait(timeout=120) == 0
    killed = _writer(tmp_path / "killed.duckdb", total, 0.02)
    for _ in range(8):  # let a few blocks commit, then SIGKILL mid-stream
        killed.stdout.readline()
    killed.send_signal(signal.SIGKILL)
    killed.wait(timeout=30)
    time.sleep(0.2)
    with LiveHistorian(tmp_path / "killed.duckdb") as historian:
        rows, samples = historian.connection.execute(
            "SELECT count(*), count(DISTINCT time) FROM series").fetchone()
        assert rows == samples * 5 and samples % 60 == 0  # whole blocks only
        assert 0 < samples < total
    resumed = _writer(tmp_path / "killed.duckdb", total, 0.0)
    assert resumed.wait(timeout=120) == 0
    query = "SELECT unit, time, source, signal, value, flag FROM series ORDER BY ALL"
    with LiveHistorian(tmp_path / "reference.duckdb") as a, \
            LiveHistorian(tmp_path / "killed.duckdb") as b:
        pd.testing.assert_frame_equal(a.connection.execute(query).df(),
                                      b.connection.execute(query).df())
        assert a.resume_time("u1") == b.resume_time("u1")


def test_export_wide_and_long(tmp_path):
    db = tmp_path / "twin.duckdb"
    with LiveHistorian(db) as historian:
        historian.commit_block("u1", _block(0))
        historian.commit_block("u1", _block(60))
        historian.commit_block("u2", _block(0))
    start = pd.Timestamp("2026-03-01T00:00:30Z")
    end = pd.Timestamp("2026-03-01T00:01:29Z")
    assert export_history(db, tmp_path / "u1.parquet", unit="u1", start=start, end=end) == 60
    wide = pd.read_parquet(tmp_path / "u1.parquet")
    assert wide.index[0] == start and wide.index[-1] == end
    assert np.allclose(wide["twin/blade_leading_edge"], 750.0 + 0.001 * np.arange(30, 90))
    assert export_history(db, tmp_path / "all.csv", layout="long") == (120 + 60) * 5
    with pytest.raises(ValueError, match="name one"):
        export_history(db, tmp_path / "x.parquet")
    with pytest.raises(ValueError, match="no unit 'u9'"):
        export_history(db, tmp_path / "x.parquet", unit="u9")
    with pytest.raises(FileNotFoundError):
        export_history(tmp_path / "missing.duckdb", tmp_path / "x.parquet")


def test_history_export_command(tmp_path):
    from typer.testing import CliRunner

    from steamtwin.cli.main import app

    db = tmp_path / "twin.duckdb"
    with LiveHistorian(db) as historian:
        historian.commit_block("u1", _block(0))
    runner = CliRunner()
    out = tmp_path / "out.csv"
    done = runner.invoke(app, ["history", "export", "--db", str(db), "--out", str(out),
                               "--from", "2026-03-01T08:00:10+08:00"])
    assert done.exit_code == 0, done.output
    assert "wrote 50 rows" in done.output
    table = pd.read_csv(out, index_col="time")
    assert len(table) == 50 and "measured/hp_exhaust_temperature" in table.columns
    naive = runner.invoke(app, ["history", "export", "--db", str(db), "--out", str(out),
                                "--from", "2026-03-01T08:00:10"])
    assert naive.exit_code == 2 and "no time zone" in naive.output
    missing = runner.invoke(app, ["history", "export", "--db", str(tmp_path / "no.duckdb"),
                                  "--out", str(out)])
    assert missing.exit_code == 2 and "no such historian database" in missing.output


def test_the_memory_limit_bounds_duckdb_and_a_bad_one_is_refused(tmp_path):
    with LiveHistorian(tmp_path / "bounded.duckdb", memory_limit_mb=64) as historian:
        limit = historian.connection.execute("SELECT current_setting('memory_limit')").fetchone()
    assert limit == ("61.0 MiB",)  # 64 MB
    with LiveHistorian(tmp_path / "default.duckdb") as historian:  # DuckDB's own default
        default = historian.connection.execute("SELECT current_setting('memory_limit')").fetchone()
    assert default != limit
    for bad in (1, "64", float("nan"), True):
        with pytest.raises(ValueError, match="memory_limit_mb must be a number ≥ 16"):
            LiveHistorian(tmp_path / "bad.duckdb", memory_limit_mb=bad).open()
