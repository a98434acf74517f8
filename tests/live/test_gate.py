"""The streaming data-quality gate (issue 21, item 4): the batch gate's flags, block by block."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.dcs.plant import plant_tag_map, run_plant
from steamtwin.dcs.plant_model import PlantTruth
from steamtwin.dcs.quality import Flag, QualityOptions, clean
from steamtwin.dcs.sensors import FaultConfig
from steamtwin.live.gate import StreamGate, gate_options

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def faulty():
    """Half an hour with many dropouts, spikes and stuck runs, and the gate's options (the
    instruments' noise and resolution given, as a tag map can)."""
    truth = PlantTruth(faults=FaultConfig(dropout_rate_per_h=2, spike_rate_per_h=8,
                                          stuck_rate_per_h=2, stuck_median_s=120))
    run = run_plant("deep-peak-50", hours=0.3, random_state=3, truth=truth)
    measured = run.measured
    options = gate_options(plant_tag_map(), run.injected.sensors)
    batch = clean(measured, QualityOptions(nominal_step_s=1.0, out_of_range_error_fraction=1.0,
                                           **options))
    return measured, options, batch, run.injected.faults


def _stream(measured, options, sizes) -> tuple[pd.DataFrame, pd.DataFrame, list]:
    gate = StreamGate(options)
    outputs, start = [], 0
    for size in sizes:
        outputs.append(gate.push(measured.iloc[start:start + size]))
        start += size
    outputs.append(gate.flush())
    return (pd.concat([o.data for o in outputs]), pd.concat([o.flags for o in outputs]),
            [f for o in outputs for f in o.findings])


def _sizes(total: int, size: int) -> list[int]:
    return [size] * (total // size) + ([total % size] if total % size else [])


def _removed(flags: pd.DataFrame) -> np.ndarray:
    return (flags.to_numpy(dtype=np.uint16) & np.uint16(Flag.REMOVED)) != 0


def _caught(flags: pd.DataFrame, injected: pd.DataFrame, kind: str) -> float:
    """Share of the injected ``kind`` events with a rejected sample among their rows."""
    events = injected[injected["kind"] == kind]
    hits = [_removed(flags[[row.signal]].iloc[row.start_row:row.end_row + 1]).any()
            for row in events.itertuples()]
    return float(np.mean(hits))


def test_streamed_flags_agree_with_the_batch_gates(faulty):
    """Same detectors, same verdicts but where the spike detector's spread of departures —
    over the whole file in batch, over the window here — differs near a ramp."""
    measured, options, batch, injected = faulty
    assert {"spike", "stuck", "dropout"} <= set(injected["kind"])
    data, flags, findings = _stream(measured, options, _sizes(len(measured), 60))
    assert flags.index.equals(batch.flags.index) and list(flags.columns) == list(measured)
    agree = (_removed(flags) == _removed(batch.flags)).mean()
    assert agree >= 0.999
    for kind in ("spike", "stuck"):
        assert _caught(flags, injected, kind) >= _caught(batch.flags, injected, kind)
    missing = ~np.isfinite(measured.to_numpy())
    assert np.array_equal(missing & ~np.isfinite(data.to_numpy()), missing)  # never filled
    assert np.isnan(data.to_numpy()[_removed(flags)]).all()
    spikes = [f for f in findings if f.kind == "spike"]
    assert spikes and all(f.tag and f.first_time is not None and f.signal for f in spikes)
    assert sum(f.count for f in spikes) == int(
        ((flags.to_numpy() & np.uint16(Flag.SPIKE | Flag.REMOVED)) ==
         np.uint16(Flag.SPIKE | Flag.REMOVED)).sum())


@settings(max_examples=4, deadline=None)
@given(size=st.integers(45, 700))
def test_any_block_size_agrees_with_the_batch_gate(faulty, size):
    measured, options, batch, _ = faulty
    _, flags, _ = _stream(measured, options, _sizes(len(measured), size))
    assert (_removed(flags) == _removed(batch.flags)).mean() >= 0.999


def test_a_bad_status_is_flagged_and_order_is_enforced(faulty):
    measured, options, _, _ = faulty
    part = measured.iloc[:300]
    bad = pd.DataFrame(False, index=part.index, columns=part.columns)
    bad.iloc[100:105, 0] = True
    gate = StreamGate(options)
    out = gate.push(part, bad)
    rest = gate.flush()
    flags = pd.concat([out.flags, rest.flags])
    column = flags.iloc[:, 0].to_numpy()
    assert ((column[100:105] & np.uint16(Flag.BAD_QUALITY)) != 0).all()
    assert len(out.data) == 300 - gate.lookahead_samples  # the look-ahead waits
    assert np.isnan(pd.concat([out.data, rest.data]).iloc[100:105, 0]).all()
    with pytest.raises(ValueError, match="do not come after"):
        gate.push(part.iloc[:10])
    with pytest.raises(ValueError, match="context_samples"):
        StreamGate(options, context_samples=10)
