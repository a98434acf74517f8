"""The recent past kept in memory (web.queries): a short raw range answered from it equals the
database's answer, for any range inside it, after new blocks are committed, with NaN values
and gate flags; a range reaching before it, or holding more than ``max_points`` samples, is
left to the database."""

from __future__ import annotations

import numpy as np
import pandas as pd
from web_fixtures import START, unit_block

from steamtwin.dcs.quality import Flag
from steamtwin.live.historian import LiveHistorian
from steamtwin.web.queries import HistorianReader, SeriesQuery

SECOND = pd.Timedelta(seconds=1)
LAST_S = 7199
"""The filled historian's last sample of unit1 (s after START)."""


def _queries(rng: np.random.Generator, last_s: int, n: int) -> list[SeriesQuery]:
    queries = []
    for k in range(n):
        source, signal = [("measured", "hp_exhaust_temperature"), ("twin", "blade_leading_edge"),
                          ("residual", "hp_exhaust_temperature"), ("twin", "nowhere")][k % 4]
        begin = last_s - rng.uniform(0.0, 300.0)
        end = min(float(last_s), begin + rng.uniform(0.0, 120.0))
        queries.append(SeriesQuery("unit1", source, signal, START + begin * SECOND,
                                   START + end * SECOND))
    return queries


def test_short_ranges_from_memory_equal_the_database(filled_db):
    rng = np.random.default_rng(1)
    with LiveHistorian(filled_db) as historian:
        kept = HistorianReader(historian.connection.cursor, size=2, recent_s=400.0)
        database = HistorianReader(historian.connection.cursor, size=1, recent_s=0.0)
        queried: list[str] = []
        scan = kept._rows
        kept._rows = lambda sql, arguments=(): queried.append(sql) or scan(sql, arguments)
        try:
            for step in range(3):
                if step:  # new blocks, with a missing value and flags, after the copy was made
                    frames, flags = unit_block(LAST_S + 1 + 20 * (step - 1), 20)
                    frames["measured"].iloc[3, 0] = np.nan
                    flags.iloc[5, 0] = str(int(Flag.SPIKE))
                    historian.commit_block("unit1", frames, flags)
                last_s = LAST_S + 20 * step
                for query in _queries(rng, last_s, 40):
                    assert kept.series(query, 500) == database.series(query, 500), query
            scans = [sql for sql in queried if "FROM series WHERE unit = ? AND source" in sql]
            assert len(scans) == 0  # every one answered from memory
            assert len([sql for sql in queried if "time > ?" in sql]) == 3  # one refresh a block
            old = SeriesQuery("unit1", "measured", "hp_exhaust_temperature",
                              START + (LAST_S - 500) * SECOND, START + LAST_S * SECOND)
            assert kept.series(old, 500) == database.series(old, 500)  # before it: database
            assert kept.series(old, 100)["downsampled"]  # more than max_points: database
            assert len([sql for sql in queried if "AND source" in sql]) >= 2
        finally:
            kept.close()
            database.close()
