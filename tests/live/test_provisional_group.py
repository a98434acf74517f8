"""Group commit of provisional rows (issue 21, latency): every unit's rows of a moment in one
transaction give the same database as one transaction per unit; the service's group gathers the
units that arrive within a few event-loop rounds and lets none settle before its rows are in."""

from __future__ import annotations

import asyncio

import numpy as np
import pandas as pd
import pytest

from steamtwin.live.historian import LiveHistorian, ProvisionalRows
from steamtwin.live.runner import GATHER_ROUNDS, ProvisionalGroup

QUERY = "SELECT unit, time, source, signal, value, flag FROM provisional ORDER BY ALL"


def _rows(unit: str, start: int, n: int = 3) -> ProvisionalRows:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC") + pd.Timedelta(
        seconds=start)
    k = np.arange(start, start + n, dtype=float) + (0.5 if unit == "u2" else 0.0)
    measured = pd.DataFrame({"hp_exhaust_temperature": 600.0 + k,
                             "control_stage_pressure": 9.0e6 + k}, index=index)
    measured.iloc[0, 1] = np.nan  # a missing value: stored as NULL
    twin = pd.DataFrame({"hp_exhaust_temperature": 600.2 + k}, index=index)
    flags = pd.DataFrame(None, index=index, columns=measured.columns, dtype=object)
    flags.iloc[-1, 0] = "range"
    return ProvisionalRows(unit, {"measured": measured, "twin": twin,
                                  "residual": measured[["hp_exhaust_temperature"]] - twin},
                           flags)


# (unit, first sample): later rows replace a unit's rows from their first time on
STEPS = [[("u1", 0), ("u2", 0)], [("u1", 2), ("u2", 3)], [("u2", 1)], [("u1", 1), ("u2", 5)]]


def test_one_transaction_for_all_units_stores_what_one_per_unit_does(tmp_path):
    with (LiveHistorian(tmp_path / "each.duckdb") as each,
          LiveHistorian(tmp_path / "group.duckdb") as group):
        for step in STEPS:
            for unit, start in step:
                entry = _rows(unit, start)
                each.store_provisional(entry.unit, entry.frames, entry.flags)
            group.store_provisional_many([_rows(unit, start) for unit, start in step])
            expected = each.connection.execute(QUERY).df()
            pd.testing.assert_frame_equal(group.connection.execute(QUERY).df(), expected)
        # u1: 0 s (step 1), 1–3 s (step 4); u2: 0 s, 1–3 s (step 3), 5–7 s: 4 values each;
        # NULL: each surviving entry's first pressure; "range": each surviving entry's last
        assert len(expected) == 11 * 4 and expected["value"].isna().sum() == 5
        assert (expected["flag"] == "range").sum() == 3

        group.commit_block("u1", {"measured": _rows("u1", 0).frames["measured"].iloc[:2]})
        before = group.connection.execute(QUERY).df()
        with pytest.raises(ValueError, match="not after the last committed sample"):
            group.store_provisional_many([_rows("u2", 9), _rows("u1", 1)])
        pd.testing.assert_frame_equal(group.connection.execute(QUERY).df(), before)  # none
        with pytest.raises(ValueError, match="twice"):
            group.store_provisional_many([_rows("u2", 9), _rows("u2", 12)])


class _Counting(LiveHistorian):
    def __init__(self, path) -> None:
        super().__init__(path)
        self.batches: list[list[str]] = []

    def store_provisional_many(self, batch):
        self.batches.append([entry.unit for entry in batch])
        return super().store_provisional_many(batch)


def test_the_group_gathers_units_arriving_within_its_rounds(tmp_path):
    async def scenario(historian: _Counting) -> list[int]:
        group = ProvisionalGroup(historian)
        seen: list[int] = []

        async def unit(name: str, hops: int, start: int) -> None:
            for _ in range(hops):  # the hops from the socket to the unit's rows
                await asyncio.sleep(0)
            await group.store(_rows(name, start))
            # committed before the unit goes on to settle
            seen.append(historian.connection.execute(
                "SELECT count(*) FROM provisional WHERE unit = ?", [name]).fetchall()[0][0])

        await asyncio.gather(unit("u1", 0, 0), unit("u2", GATHER_ROUNDS - 2, 0),
                             unit("u3", 3 * GATHER_ROUNDS, 0))
        await group.store(None)  # nothing to store: returns
        return seen

    with _Counting(tmp_path / "twin.duckdb") as historian:
        seen = asyncio.run(scenario(historian))
    assert historian.batches == [["u1", "u2"], ["u3"]]
    assert seen == [12, 12, 12]
