"""The streaming gate's faster path gives the verdicts of the batch ``clean`` over its window,
bit for bit (issue 21: throughput without changing a flag), and its provisional verdicts."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from steamtwin.dcs.quality import Flag, QualityOptions, clean
from steamtwin.dcs.quality.detectors import row_nanmedian
from steamtwin.live.gate import StreamGate

GATE = {"context_samples": 90, "spike_window": 11, "stuck_min_duration_s": 8.0,
        "release_s": 10.0}


def _reference(frame: pd.DataFrame, bad: pd.DataFrame, options: dict):
    """The gate's definition: each clock bin of ``release_s`` judged by ``clean`` over the
    ``context_samples`` before it, the bin and the ``lookahead_samples`` after it (fewer at
    the ends) — a function of the stream alone, whatever the blocks."""
    lookahead = StreamGate(options, **GATE).lookahead_samples
    seconds = (frame.index - frame.index[0]).total_seconds().to_numpy()
    bins = np.floor(seconds / GATE["release_s"])
    edges = [0, *(np.flatnonzero(np.diff(bins)) + 1).tolist(), len(frame)]
    outputs = []
    for a, b in itertools.pairwise(edges):
        first, last = max(0, a - GATE["context_samples"]), min(len(frame), b + lookahead)
        values, flags_bad = frame.iloc[first:last], bad.iloc[first:last]
        cleaned = clean(values, QualityOptions(
            nominal_step_s=1.0, spike_window=GATE["spike_window"],
            stuck_min_duration_s=GATE["stuck_min_duration_s"],
            bad_quality={c: flags_bad[c].to_numpy(dtype=bool) for c in values.columns},
            out_of_range_error_fraction=1.0, **options))
        outputs.append((cleaned.data.iloc[a - first:b - first],
                        cleaned.flags.iloc[a - first:b - first]))
    return pd.concat([d for d, _ in outputs]), pd.concat([f for _, f in outputs])


@st.composite
def streams(draw):
    """Noisy quantised ramps with injected spikes, stuck runs, NaN, out-of-range values and
    bad statuses, cut into random blocks."""
    n = draw(st.integers(60, 260))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    x = np.column_stack([500.0 + 0.05 * t + rng.normal(0, 0.3, n),
                         np.round(2.0e6 + rng.normal(0, 2.0e3, n), -2),
                         80.0 + 3.0 * np.sin(t / 20.0) + rng.normal(0, 0.05, n)])
    for _ in range(draw(st.integers(0, 6))):  # spikes of 1–2 samples
        i, j = int(rng.integers(1, n - 3)), int(rng.integers(0, 3))
        x[i:i + int(rng.integers(1, 3)), j] += 40.0 * np.std(x[:, j]) + 10.0
    for _ in range(draw(st.integers(0, 2))):  # stuck runs
        i, j = int(rng.integers(0, n - 20)), int(rng.integers(0, 3))
        x[i:i + int(rng.integers(5, 20)), j] = x[i, j]
    x[rng.random(x.shape) < draw(st.sampled_from([0.0, 0.02]))] = np.nan
    x[rng.random(x.shape) < 0.005] = 1e9  # out of range
    index = pd.date_range("2026-01-01", periods=n, freq="1s", tz="UTC", name="time")
    frame = pd.DataFrame(x, index=index, columns=["a", "b", "c"])
    bad = pd.DataFrame(rng.random(x.shape) < 0.01, index=index, columns=frame.columns)
    sizes, total = [], 0
    while total < n:
        sizes.append(min(draw(st.integers(10, 80)), n - total))
        total += sizes[-1]
    noise = draw(st.sampled_from([{}, {"a": 0.3, "b": 2.0e3, "c": 0.05}]))
    options = {"ranges": {"a": (0.0, 2000.0), "b": (0.0, 1.0e8), "c": (0.0, 1000.0)},
               "noise_si": noise}
    return frame, bad, sizes, options


@settings(max_examples=8, deadline=None)
@given(streams())
def test_the_gate_equals_the_batch_clean_over_its_window(stream):
    frame, bad, sizes, options = stream
    gate, outputs, start = StreamGate(options, **GATE), [], 0
    for size in sizes:
        outputs.append(gate.push(frame.iloc[start:start + size], bad.iloc[start:start + size]))
        start += size
    outputs.append(gate.flush())
    data = pd.concat([o.data for o in outputs if len(o.data)])
    flags = pd.concat([o.flags for o in outputs if len(o.flags)])
    expected_data, expected_flags = _reference(frame, bad, options)
    assert np.array_equal(data.to_numpy(), expected_data.to_numpy(), equal_nan=True)
    assert np.array_equal(flags.to_numpy(dtype=np.uint16),
                          expected_flags.to_numpy(dtype=np.uint16))
    assert data.index.equals(frame.index)


@settings(max_examples=100, deadline=None)
@given(hnp.arrays(np.float64, hnp.array_shapes(min_dims=2, max_dims=2, max_side=9),
                  elements=st.floats(allow_nan=True, allow_infinity=True, width=64)))
def test_row_medians_are_numpys_bit_for_bit(rows):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN rows
        expected = np.nanmedian(rows, axis=1)
    assert np.array_equal(row_nanmedian(rows), expected, equal_nan=True)


def test_pending_samples_carry_the_verdicts_that_need_no_look_ahead():
    index = pd.date_range("2026-01-01", periods=40, freq="1s", tz="UTC", name="time")
    frame = pd.DataFrame({"a": np.linspace(500.0, 501.0, 40), "b": 2.0e6}, index=index)
    frame.iloc[35, 0] = 5000.0  # out of range
    frame.iloc[36, 1] = np.nan
    bad = pd.DataFrame(False, index=index, columns=frame.columns)
    bad.iloc[37, 1] = True
    gate = StreamGate({"ranges": {"a": (0.0, 2000.0)}}, **GATE)
    gate.add(frame, bad)
    ready = 20  # the 10-s bins whose look-ahead (16 samples) is in: 0–9 s and 10–19 s
    assert gate.release(min_samples=ready + 1).data.empty  # not enough judged yet: wait
    assert len(gate.release(min_samples=ready).data) == ready
    values, flags = gate.pending()
    assert values.index.equals(index[ready:])
    codes = flags.to_numpy(dtype=np.uint16)
    row = {t: i for i, t in enumerate(values.index)}
    assert codes[row[index[35]], 0] == Flag.OUT_OF_RANGE | Flag.REMOVED
    assert codes[row[index[36]], 1] == Flag.MISSING
    assert codes[row[index[37]], 1] == Flag.BAD_QUALITY | Flag.REMOVED
    assert np.isnan(values.iloc[row[index[35]], 0]) and np.isnan(values.iloc[row[index[37]], 1])
    good = codes == 0
    assert np.array_equal(values.to_numpy()[good], frame.loc[values.index].to_numpy()[good])
    gate.flush()
    assert gate.pending()[0].empty
