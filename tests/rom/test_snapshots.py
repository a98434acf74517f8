"""The snapshot plan (design of experiments) around the spec's operating line."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from steamtwin.model.operating import hp_exhaust_pressure, main_steam_temperature
from steamtwin.rom.snapshots import TEMPERATURE_VARIATION, design_conditions
from steamtwin.spec import TemperatureSchedule

KELVIN = 273.15


@pytest.fixture(scope="module")
def scheduled_spec(reference_spec):
    """The reference with a boiler that runs 520 °C main steam, 500 °C reheat at 30 % load."""
    schedule = TemperatureSchedule((0.3, 0.5, 1.0), (520.0 + KELVIN, 532.0 + KELVIN,
                                                     538.0 + KELVIN),
                                   (500.0 + KELVIN, 525.0 + KELVIN, 538.0 + KELVIN))
    return dataclasses.replace(reference_spec, temperature_schedule=schedule)


def test_the_30_percent_snapshots_centre_on_the_scheduled_temperature(scheduled_spec):
    """The 2³ corners of the 30 % box are 520 ± 10 °C, not the design 538 ± 10 °C."""
    plan = design_conditions(scheduled_spec, 32, layout="corners")
    low = plan[plan["load_level"] == 0.3]
    assert len(low) == 8
    assert sorted(set(low["main_steam_temperature"] - KELVIN)) == pytest.approx(
        [520.0 - TEMPERATURE_VARIATION, 520.0 + TEMPERATURE_VARIATION], abs=1e-9)


@pytest.mark.parametrize("layout", ["lhs", "bands"])
def test_every_snapshot_lies_in_the_band_around_its_scheduled_temperature(scheduled_spec,
                                                                           layout):
    plan = design_conditions(scheduled_spec, 32, layout=layout)
    # lhs: each level's box is centred at the level; bands: each row at its own load
    centre_load = plan["load_fraction"] if layout == "bands" else plan["load_level"]
    offset = plan["main_steam_temperature"] - main_steam_temperature(scheduled_spec,
                                                                     centre_load.to_numpy())
    assert np.all(np.abs(offset) <= TEMPERATURE_VARIATION + 1e-9)
    if layout == "lhs":  # the 30 % box is 520 ± 10 °C (the design's 538 °C lies outside it)
        low = plan[plan["load_level"] == 0.3]["main_steam_temperature"] - KELVIN
        assert low.min() >= 510.0 - 1e-9 and low.max() <= 530.0 + 1e-9
    # the HP-exhaust pressure of each condition follows the operating line's law
    expected = hp_exhaust_pressure(scheduled_spec, plan["main_steam_flow"].to_numpy(),
                                   plan["load_fraction"].to_numpy())
    assert np.array_equal(plan["hp_exhaust_pressure"].to_numpy(), expected)
