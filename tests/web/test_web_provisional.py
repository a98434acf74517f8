"""The live feed shows a sample as soon as the service stores its provisional row (before the
quality gate's look-ahead has judged it), marked provisional until its final row replaces it."""

from __future__ import annotations

import pandas as pd
import pytest
from web_fixtures import START, unit_block

from steamtwin.live.historian import LiveHistorian
from steamtwin.web.queries import HistorianReader

SECOND = pd.Timedelta(seconds=1)


def test_provisional_rows_reach_the_feed_and_give_way_to_the_final_ones(tmp_path):
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:
        historian.commit_block("unit1", *unit_block(0, 60))
        early, early_flags = unit_block(60, 5)
        early["twin"]["hp_exhaust_temperature"] += 0.25  # the provisional chain's own value
        historian.store_provisional("unit1", early, early_flags)
        reader = HistorianReader(historian.connection.cursor, size=1)
        try:
            assert reader.last_times()["unit1"] == START + 59 * SECOND  # the final rows'
            assert reader.live_times()["unit1"] == START + 64 * SECOND
            samples = reader.samples_after("unit1", START + 59 * SECOND, 100)
            assert [sample["provisional"] for sample in samples] == [True] * 5
            assert samples[0]["values"]["twin/hp_exhaust_temperature"] == pytest.approx(
                early["twin"]["hp_exhaust_temperature"].iloc[0])

            final, final_flags = unit_block(60, 5)
            historian.commit_block("unit1", final, final_flags)
            samples = reader.samples_after("unit1", START + 59 * SECOND, 100)
            assert [sample["provisional"] for sample in samples] == [False] * 5
            assert samples[0]["values"]["twin/hp_exhaust_temperature"] == pytest.approx(
                final["twin"]["hp_exhaust_temperature"].iloc[0])
            assert reader.live_times()["unit1"] == START + 64 * SECOND
        finally:
            reader.close()


def test_before_the_first_final_block_the_signals_are_the_provisional_samples(tmp_path):
    """A service just started has only provisional rows (the gate's look-ahead): the pages
    still learn which signals the unit has, so they draw the live samples."""
    with LiveHistorian(tmp_path / "twin.duckdb") as historian:
        early, early_flags = unit_block(0, 5)
        historian.store_provisional("unit1", early, early_flags)
        reader = HistorianReader(historian.connection.cursor, size=1)
        try:
            expected = sorted((source, signal) for source, frame in early.items()
                              for signal in frame.columns)
            assert reader.last_times() == {}
            assert reader.signals("unit1") == expected
            historian.commit_block("unit1", *unit_block(0, 5))
            assert reader.signals("unit1") == expected  # now from the final rows
            assert reader.signals("unit2") == []
        finally:
            reader.close()
