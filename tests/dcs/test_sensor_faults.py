"""Sensor faults scheduled on purpose (issue 21, item 3): drift, bias step, stuck reading."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.dcs.plant import run_plant
from steamtwin.dcs.sensor_faults import SensorFault, apply_sensor_faults, parse_sensor_fault


def _frame(n: int = 7201) -> pd.DataFrame:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC")
    values = 600.0 + np.sin(np.arange(n) / 300.0)
    values[100:105] = np.nan
    return pd.DataFrame({"hp_exhaust_temperature": values,
                         "control_stage_pressure": np.full(n, 9.0e6)}, index=index)


def test_parse_reads_hours_and_refuses_bad_text():
    fault = parse_sensor_fault("hp_exhaust_temperature:drift:2@6h")
    assert fault == SensorFault("hp_exhaust_temperature", "drift", 21600.0, 2.0, None)
    stuck = parse_sensor_fault("control_stage_temperature:stuck@3h-4.5h")
    assert (stuck.kind, stuck.start_s, stuck.end_s) == ("stuck", 10800.0, 16200.0)
    with pytest.raises(ValueError, match="expected SIGNAL:KIND"):
        parse_sensor_fault("hp_exhaust_temperature drift 2")
    with pytest.raises(ValueError, match="needs a size"):
        parse_sensor_fault("hp_exhaust_temperature:bias_step@1h")
    with pytest.raises(ValueError, match="expected one of drift, bias_step, stuck"):
        parse_sensor_fault("hp_exhaust_temperature:melt:1@1h")
    with pytest.raises(ValueError, match="must be after its start"):
        parse_sensor_fault("hp_exhaust_temperature:stuck@2h-1h")


def test_drift_grows_at_its_rate_then_holds_and_dropouts_stay():
    frame = _frame()
    faulted, record = apply_sensor_faults(frame, [SensorFault(
        "hp_exhaust_temperature", "drift", start_s=600.0, size=2.0, end_s=4200.0)])
    offset = (faulted - frame)["hp_exhaust_temperature"].to_numpy()
    t = np.arange(len(frame), dtype=float)
    expected = np.clip((t - 600.0) * 2.0 / 3600.0, 0.0, 2.0)
    finite = np.isfinite(offset)
    assert np.allclose(offset[finite], expected[finite], atol=1e-9)
    assert np.isnan(faulted["hp_exhaust_temperature"].to_numpy()[100:105]).all()
    assert faulted["control_stage_pressure"].equals(frame["control_stage_pressure"])
    row = record.iloc[0]
    assert (row["kind"], row["start_row"], row["end_row"]) == ("drift", 600, 4200)
    assert row["value"] == pytest.approx(2.0)


def test_bias_step_and_stuck_reading():
    frame = _frame()
    faulted, record = apply_sensor_faults(frame, [
        SensorFault("hp_exhaust_temperature", "bias_step", start_s=1000.0, size=-1.5,
                    end_s=2000.0),
        SensorFault("control_stage_pressure", "stuck", start_s=3000.0)])
    offset = (faulted - frame)["hp_exhaust_temperature"].to_numpy()
    assert np.allclose(offset[1000:2001], -1.5) and np.allclose(offset[200:1000], 0.0)
    assert np.allclose(offset[2001:], 0.0)
    assert len(record) == 2 and list(record["kind"]) == ["bias_step", "stuck"]
    with pytest.raises(ValueError, match="no such signal"):
        apply_sensor_faults(frame, [SensorFault("load", "stuck", 0.0)])
    with pytest.raises(ValueError, match="after the data's last sample"):
        apply_sensor_faults(frame, [SensorFault("hp_exhaust_temperature", "stuck", 1e6)])


@settings(max_examples=30, deadline=None)
@given(start=st.integers(1, 7000), length=st.integers(1, 3000))
def test_a_stuck_reading_holds_the_last_good_value(start, length):
    frame = _frame()
    values = frame["hp_exhaust_temperature"].to_numpy()
    faulted, _ = apply_sensor_faults(frame, [SensorFault(
        "hp_exhaust_temperature", "stuck", float(start), end_s=float(start + length))])
    out = faulted["hp_exhaust_temperature"].to_numpy()
    before = values[:start][np.isfinite(values[:start])]
    stop = min(start + length, len(values) - 1)
    held = out[start:stop + 1]
    held = held[np.isfinite(held)]
    assert np.all(held == before[-1])
    assert np.array_equal(out[stop + 1:], values[stop + 1:], equal_nan=True)


def test_the_virtual_plant_records_scheduled_faults():
    fault = SensorFault("hp_exhaust_temperature", "drift", start_s=60.0, size=2.0)
    clean = run_plant("deep-peak-50", hours=0.02, random_state=4)
    faulted = run_plant("deep-peak-50", hours=0.02, random_state=4, sensor_faults=[fault])
    difference = (faulted.measured - clean.measured)["hp_exhaust_temperature"].dropna()
    t = (difference.index - clean.measured.index[0]).total_seconds().to_numpy()
    assert np.allclose(difference.to_numpy(), np.clip((t - 60.0) * 2.0 / 3600.0, 0, None),
                       atol=1e-9)
    drifts = faulted.injected.faults[faulted.injected.faults["kind"] == "drift"]
    assert len(drifts) == 1 and drifts.iloc[0]["signal"] == "hp_exhaust_temperature"


def test_plant_command_injects_and_records_the_fault(tmp_path):
    import json

    from typer.testing import CliRunner

    from steamtwin.cli.main import app

    runner = CliRunner()
    bad = runner.invoke(app, ["plant", "--scenario", "deep-peak-50", "--out", str(tmp_path / "x"),
                              "--sensor-fault", "hp_exhaust_temperature:drift@1h"])
    assert bad.exit_code == 2 and "--sensor-fault" in bad.output and "needs a size" in bad.output
    done = runner.invoke(app, ["plant", "--scenario", "deep-peak-50", "--hours", "0.02",
                               "--out", str(tmp_path / "p"), "--sensor-fault",
                               "hp_exhaust_temperature:bias_step:1.5@0.01h"])
    assert done.exit_code == 0, done.output
    truth = json.loads((tmp_path / "p" / "truth" / "truth.json").read_text(encoding="utf-8"))
    steps = [row for row in truth["injected_faults"] if row["kind"] == "bias_step"]
    assert len(steps) == 1
    assert steps[0]["signal"] == "hp_exhaust_temperature" and steps[0]["offset"] == 1.5
    assert steps[0]["start"].startswith("2026-03-01T00:00:36")
