"""Fixtures of the calibration tests: a short plant run, a small analytic simulator and data."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import PlantRun, run_plant
from steamtwin.model.fom import InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS


class LinearSimulator:
    """Analytic stand-in: temperatures linear in the parameters; rejects flow < 0.95."""

    input_signals = INPUT_SIGNALS
    output_signals = ("control_stage_temperature", "hp_exhaust_temperature",
                      "hp_inner_casing_temperature", "hp_power")

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        if params.flow_coefficient < 0.95:
            raise InputError("main_steam_flow exceeds what the valves pass")
        t0 = inputs["main_steam_temperature"].to_numpy(dtype=float)
        return pd.DataFrame({
            "control_stage_temperature": t0 - 100.0 * params.flow_coefficient,
            "hp_exhaust_temperature": t0 - 200.0 + 10.0 * params.friction_coefficient,
            "hp_inner_casing_temperature": t0 - 150.0 + 5.0 * params.heat_transfer_coefficient,
            "hp_power": np.full(t0.size, 1.0e8),
        }, index=inputs.index)


@pytest.fixture(scope="session")
def linear_simulator() -> LinearSimulator:
    return LinearSimulator()


@pytest.fixture(scope="session")
def linear_window() -> pd.DataFrame:
    """Two minutes of 1-s data that :class:`LinearSimulator` fits at (1.02, 1.2, 0.8) ± 0.5 K."""
    n = 120
    random = np.random.default_rng(7)
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC")
    t0 = 810.0 + random.normal(0.0, 1.0, n)
    inputs = pd.DataFrame({"main_steam_pressure": 16.0e6, "main_steam_temperature": t0,
                           "main_steam_flow": 400.0, "hp_exhaust_pressure": 3.5e6}, index=index)
    truth = LinearSimulator().simulate(inputs, ModelParameters(1.02, 1.2, 0.8))
    measured = truth[list(LinearSimulator.output_signals[:3])] + random.normal(0.0, 0.5, (n, 3))
    return pd.concat([inputs, measured], axis=1)


@pytest.fixture(scope="session")
def plant_run() -> PlantRun:
    return run_plant("deep-peak-50", hours=0.25, random_state=1)


@pytest.fixture(scope="session")
def low_load_window(plant_run: PlantRun) -> pd.DataFrame:
    """The last 300 s of the 50 % hold (measured, with NaN dropouts of the casing sensor)."""
    return plant_run.measured.iloc[-300:]
