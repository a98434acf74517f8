"""The ROM's file-level steps (rom.workflow): wire units of the prediction table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.rom.reconstruction import (
    DISTANCE,
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
)
from steamtwin.rom.workflow import HistoryPrediction, build_rom_from_files, wire_unit


@pytest.mark.parametrize(("name", "si", "unit", "shown"), [
    ("control_stage_pressure", 12.5e6, "MPa", 12.5),
    ("hp_power", 177.3e6, "MW", 177.3),
    ("load", 600e6, "MW", 600.0),
    ("blade_leading_edge", 773.15, "degC", 500.0),
    ("hp_exhaust_temperature", 273.15, "degC", 0.0),
])
def test_wire_unit_converts_si_by_the_name(name, si, unit, shown):
    wire, convert = wire_unit(name)
    assert wire == unit
    assert convert(si) == pytest.approx(shown)


def test_in_wire_units_converts_values_and_keeps_the_flags():
    index = pd.date_range("2026-03-01", periods=2, freq="1s", tz="UTC")
    table = pd.DataFrame({"control_stage_pressure": [12e6, np.nan],
                          "blade_leading_edge": [800.0, np.nan],
                          FLAG_INVALID: [False, True], FLAG_OUT_OF_DOMAIN: [False, True],
                          FLAG_EXTRAPOLATED: [False, False], DISTANCE: [0.0, np.nan]},
                         index=index)
    result = HistoryPrediction(bundle=None, table=table, fields={}, excluded={}, warnings=[],
                               sensors_as_read=[])
    wire = result.in_wire_units()
    assert list(wire.columns) == ["control_stage_pressure [MPa]", "blade_leading_edge [degC]",
                                  FLAG_INVALID, FLAG_OUT_OF_DOMAIN, FLAG_EXTRAPOLATED, DISTANCE]
    assert wire.index.name == "time"
    assert wire.iloc[0, 0] == pytest.approx(12.0)
    assert wire.iloc[0, 1] == pytest.approx(800.0 - 273.15)
    assert wire[FLAG_INVALID].tolist() == [False, True]


def test_history_without_its_tag_map_is_refused_before_any_work():
    with pytest.raises(ValueError, match="go together"):
        build_rom_from_files("reference", history_file="historian.csv")
