"""The provisional path's array shortcuts (issue 21, latency, fourth pass) keep what the
pandas path gave: the gate's count of samples ready to judge, its one-array append (and a block
whose columns come in another order: its status bits follow their columns), and the model's
time steps from integer ticks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.live.gate import StreamGate
from steamtwin.model.fom import _time_steps


def _stream(n: int, start: int = 0) -> tuple[pd.DataFrame, pd.DataFrame]:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC", name="time") + \
        pd.Timedelta(seconds=start)
    k = np.arange(start, start + n, dtype=float)
    data = pd.DataFrame({"hp_exhaust_temperature": 600.0 + np.sin(k / 7.0),
                         "control_stage_pressure": 9.0e6 + 1.0e3 * np.cos(k / 5.0)}, index=index)
    bad = pd.DataFrame(False, index=index, columns=data.columns)
    bad.iloc[::17, 1] = True  # the source's status excludes some values
    return data, bad


@pytest.mark.parametrize("block", [3, 7, 60])
def test_ready_counts_what_release_judges_and_one_array_append_equals_concat(block):
    gate, reference = StreamGate({}, context_samples=120), StreamGate({}, context_samples=120)
    judged, total = [], 0
    for start in range(0, 250, block):
        data, bad = _stream(block, start)
        gate.add(data, bad)
        total += block
        # the same samples, columns in another order after the first block and the status
        # rows in another order (the reindexing path): the same verdicts
        reference.add(data if start == 0 else data[data.columns[::-1]], bad.iloc[::-1])
        ready = gate.ready()
        released = gate.release(min_samples=10)
        assert len(released.data) == (ready if ready >= 10 else 0)
        expected = reference.release(min_samples=10)
        pd.testing.assert_frame_equal(released.data, expected.data)
        pd.testing.assert_frame_equal(released.flags, expected.flags)
        judged.append(released.flags.to_numpy())
        assert gate.ready() == 0 or ready < 10
    flags = np.concatenate(judged)
    # every sample judged once, none twice: judged + still pending (the open clock bin and the
    # look-ahead) is what came in
    assert len(flags) + len(gate.pending()[0]) == total
    assert len(flags) >= total - gate.lookahead_samples - 60
    assert (flags[:, 1] != 0).sum() >= len(flags) // 17  # bad statuses


@pytest.mark.parametrize("unit", ["s", "ms", "us", "ns"])
def test_time_steps_from_ticks_equal_total_seconds(unit):
    seconds = np.array([0, 1, 3, 4, 10, 70], dtype=np.int64)
    index = pd.DatetimeIndex(pd.Timestamp("2026-03-01", tz="UTC")
                             + pd.to_timedelta(seconds, unit="s")).as_unit(unit)
    expected = np.diff((index - index[0]).total_seconds().to_numpy(dtype=float))
    steps = _time_steps(index)
    assert steps[0] == np.inf
    np.testing.assert_array_equal(steps[1:], expected)
    np.testing.assert_array_equal(steps[1:], np.diff(seconds).astype(float))
