"""The ROM's steady sensor values as the DCS reads them (issue 18, item 3: sensor models in
every mode): the thermocouple lag of the full-order model's readings and the calibration's
sensor offsets."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.model.measurement import lag
from steamtwin.model.sensor_setup import SensorSetup
from steamtwin.rom.reconstruction import read_through


def _table(values: dict[str, np.ndarray], step_s: float = 1.0) -> pd.DataFrame:
    n = len(next(iter(values.values())))
    index = pd.date_range("2026-03-01", periods=n, freq=pd.Timedelta(seconds=step_s), tz="UTC")
    return pd.DataFrame(values, index=index)


def test_a_step_is_read_as_the_first_order_response():
    """A 20 K step at t = 0 read by τ = 30 s: 20·(1 − e^(−t/τ)) after the step (the ramp of the
    first-order hold over the first second aside), pressures and probes untouched."""
    n = 600
    steam = np.full(n, 800.0)
    steam[1:] = 820.0
    table = _table({"hp_exhaust_temperature": steam, "control_stage_pressure": np.full(n, 9e6),
                    "blade_tip": steam.copy()})
    setup = SensorSetup({"hp_exhaust_temperature": 30.0}, {"hp_exhaust_temperature": "test"})
    read = read_through(table, setup)
    t = np.arange(n, dtype=float)
    # first-order hold: the input ramps from 800 to 820 over the first second
    exact = 820.0 - 20.0 * 30.0 * (math.exp(1.0 / 30.0) - 1.0) * np.exp(-t / 30.0)
    assert np.allclose(read["hp_exhaust_temperature"].to_numpy()[1:], exact[1:], atol=1e-9)
    assert read["hp_exhaust_temperature"].iloc[0] == 800.0
    assert read["control_stage_pressure"].equals(table["control_stage_pressure"])
    assert read["blade_tip"].equals(table["blade_tip"])


def test_offsets_are_added_and_a_gap_restarts_the_sensor():
    values = np.linspace(780.0, 800.0, 50)
    values[20:25] = np.nan
    table = _table({"control_stage_temperature": values})
    setup = SensorSetup({"control_stage_temperature": 20.0}, {"control_stage_temperature": "x"},
                        offsets={"control_stage_temperature": -1.25})
    read = read_through(table, setup)["control_stage_temperature"].to_numpy()
    steps = np.ones(50)
    assert np.isnan(read[20:25]).all()
    assert np.allclose(read[:20], lag(values[:20], steps[:20], 20.0) - 1.25)
    assert read[25] == pytest.approx(values[25] - 1.25)  # steady start after the gap
    assert np.allclose(read[25:], lag(values[25:], steps[25:], 20.0) - 1.25)


def test_unknown_sensors_and_unordered_times_are_refused():
    table = _table({"control_stage_temperature": np.full(5, 800.0)})
    with pytest.raises(ValueError, match="does not predict"):
        read_through(table, SensorSetup({}, {}, offsets={"hp_exhaust_temperature": 1.0}))
    backwards = table.iloc[::-1]
    with pytest.raises(ValueError, match="increasing"):
        read_through(backwards, SensorSetup({"control_stage_temperature": 5.0},
                                            {"control_stage_temperature": "x"}))
    # a time constant of a sensor the ROM does not carry is not this table's business
    same = read_through(table, SensorSetup({"hp_exhaust_temperature": 5.0},
                                           {"hp_exhaust_temperature": "x"}))
    assert same.equals(table)


@settings(max_examples=40, deadline=None)
@given(level=st.floats(300.0, 900.0), tau=st.floats(0.0, 600.0), step=st.floats(0.5, 60.0),
       n=st.integers(1, 200))
def test_a_steady_value_reads_as_itself(level, tau, step, n):
    """Limiting case: a constant temperature is read as itself for any τ and sample spacing."""
    table = _table({"hp_exhaust_temperature": np.full(n, level)}, step_s=step)
    read = read_through(table, SensorSetup({"hp_exhaust_temperature": tau},
                                           {"hp_exhaust_temperature": "x"}))
    assert np.allclose(read["hp_exhaust_temperature"], level, rtol=0, atol=1e-9 * level)
