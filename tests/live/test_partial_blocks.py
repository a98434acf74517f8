"""A partial residual block — the last, open bin of a finished stream, a gap — is judged with
the σ of its own mean (σ/√coverage), not a full block's (issue 21, "zero alarms on a clean
day": the one false alarm of clean seed 2 through the service was the replayed day's
one-sample last bin)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import plant_tag_map
from steamtwin.live.gate import StreamGate, gate_options
from steamtwin.live.historian import LiveHistorian
from steamtwin.live.residuals import ResidualMonitor, block_means
from steamtwin.live.service import LiveTwin
from steamtwin.live.sources import SourceBlock
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters

SIGMA = {"control_stage_temperature": 0.3, "hp_exhaust_temperature": 0.3,
         "hp_inner_casing_temperature": 0.3, "control_stage_pressure": 9.0e3}
SENSORS = tuple(SIGMA)
BLOCK_SIGMA = {s: v / np.sqrt(60.0) for s, v in SIGMA.items()}  # a 60-sample mean's


def test_a_one_sample_last_block_weighs_as_one_sample(tmp_path, reference_spec, model_plant):
    model = FullOrderModel(reference_spec)
    # 25 min + 1 sample from a minute boundary: the day's replay ends with a one-sample bin
    data = model_plant(reference_spec, np.full(1501, 0.5), np.full(1501, 0.99), SIGMA, seed=9)
    assert data.index[0].second == 0
    last = data.index[-1]
    # the last pressure reading 3 σ of one sample high: ordinary noise (1 sample in 370) ...
    data.loc[last, "control_stage_pressure"] += 3.0 * SIGMA["control_stage_pressure"]
    healthy = data.iloc[:900]
    residual = healthy[list(SENSORS)] - model.simulate(
        healthy, ModelParameters(flow_coefficient=0.99))[list(SENSORS)]
    fitted = ResidualMonitor(SENSORS, BLOCK_SIGMA).fit(block_means(residual, 60.0)[list(SENSORS)])
    twin = LiveTwin("unit1", model, ModelParameters(flow_coefficient=0.99),
                    StreamGate(gate_options(plant_tag_map())), LiveHistorian(tmp_path / "l.db"),
                    monitor=ResidualMonitor(SENSORS, BLOCK_SIGMA).set_state(fitted.get_state()),
                    monitored=SENSORS).start()
    for first in range(0, len(data), 300):
        frame = data.iloc[first:first + 300]
        twin.process(SourceBlock(frame, pd.DataFrame(False, index=frame.index,
                                                     columns=frame.columns)))
    twin.finish()
    stored = twin.historian.connection.execute(
        "SELECT value FROM series WHERE source = 'measured' AND signal = "
        "'control_stage_pressure' ORDER BY time DESC LIMIT 1").fetchone()[0]
    alarms = twin.historian.alarms("unit1")
    twin.close()
    assert stored == pytest.approx(data.loc[last, "control_stage_pressure"])  # judged, kept
    assert alarms.empty  # ... and no alarm from it
    # the same block judged as a full block's mean: 3·√60 ≈ 23 σ, a sensor fault at once
    block = dict(fitted.offset_)
    block["control_stage_pressure"] += 3.0 * SIGMA["control_stage_pressure"]
    as_full = ResidualMonitor(SENSORS, BLOCK_SIGMA).set_state(fitted.get_state())
    events = as_full.update(last + pd.Timedelta(seconds=60), block)
    assert [(e.kind, e.signal) for e in events] == [("sensor_fault", "control_stage_pressure")]
    as_partial = ResidualMonitor(SENSORS, BLOCK_SIGMA).set_state(fitted.get_state())
    share = {s: 1.0 / 60.0 for s in SENSORS}
    assert as_partial.update(last + pd.Timedelta(seconds=60), block, coverage=share) == []
    with pytest.raises(ValueError, match="coverage"):
        as_partial.update(last + pd.Timedelta(seconds=120), block, coverage={SENSORS[0]: -1.0})
