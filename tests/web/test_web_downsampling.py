"""Downsampling of long spans (issue 22, item 1): equal buckets that keep each bucket's
extrema (M4, Jugel et al. 2014) — checked against pandas on the raw samples for ranges,
bucket counts and data (NaN gaps included) drawn by hypothesis."""

from __future__ import annotations

import duckdb
import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from steamtwin.live.historian import LiveHistorian
from steamtwin.web.queries import HistorianReader, SeriesQuery

START = pd.Timestamp("2026-03-01T00:00:00Z")
N = 5000


@pytest.fixture(scope="module")
def reader(tmp_path_factory):
    """5 000 1-s samples of a noisy temperature with spikes, dips and NaN gaps."""
    path = tmp_path_factory.mktemp("down") / "twin.duckdb"
    rng = np.random.default_rng(3)
    values = 600.0 + np.cumsum(rng.normal(0.0, 0.2, N))
    values[rng.choice(N, 40, replace=False)] += rng.choice([-50.0, 80.0], 40)
    values[1000:1100] = np.nan  # no twin value for a while
    index = START + pd.to_timedelta(np.arange(N), unit="s")
    with LiveHistorian(path) as historian:
        historian.commit_block("u", {"twin": pd.DataFrame({"t": values}, index=index)})
    reader = HistorianReader(lambda: duckdb.connect(str(path)), size=1)
    yield reader, pd.Series(values, index=index)
    reader.close()


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(first=st.integers(0, N - 1), length=st.integers(0, N), points=st.integers(10, 300))
def test_every_bucket_keeps_the_extrema_of_its_samples(reader, first, length, points):
    reader, raw = reader
    start = START + pd.Timedelta(seconds=first) - pd.Timedelta(milliseconds=500)
    end = start + pd.Timedelta(seconds=length)
    answer = reader.series(SeriesQuery("u", "twin", "t", start, end), points)
    window = raw[(raw.index >= start) & (raw.index <= end)]
    assert answer["count"] == len(window)
    if len(window) <= points:
        assert not answer["downsampled"] and len(answer["time"]) == len(window)
        assert np.array_equal(np.array(answer["value"], dtype=float), window.to_numpy(),
                              equal_nan=True)
        return
    assert answer["downsampled"] and len(answer["time"]) <= points
    finite = window.dropna()
    assert sum(answer["n"]) == len(finite)  # every finite sample in exactly one bucket
    if finite.empty:
        return
    begins = pd.DatetimeIndex(pd.to_datetime(answer["time"], format="ISO8601"))
    assert begins.is_monotonic_increasing and begins[0] >= start
    width = pd.Timedelta(seconds=answer["bucket_s"])
    assert width * points >= end - start  # the buckets cover the range
    bucket = np.searchsorted(begins, finite.index, side="right") - 1
    assert (bucket >= 0).all()
    inside = (finite.index < begins[bucket] + width) | (bucket == len(begins) - 1)
    assert inside.all()  # a sample lies in the bucket it is counted in
    groups = finite.groupby(bucket)
    assert np.array_equal(groups.min().to_numpy(), answer["min"])
    assert np.array_equal(groups.max().to_numpy(), answer["max"])
    assert np.array_equal(groups.size().to_numpy(), answer["n"])
    assert np.allclose(groups.mean().to_numpy(), answer["mean"], rtol=1e-12)
    assert list(pd.to_datetime(answer["max_time"], format="ISO8601")) == list(groups.idxmax())
    assert max(answer["max"]) == finite.max() and min(answer["min"]) == finite.min()
