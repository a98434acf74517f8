"""Fixtures of the calibration tests: a short plant run and a small analytic simulator."""

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


@pytest.fixture
def linear_simulator() -> LinearSimulator:
    return LinearSimulator()


@pytest.fixture(scope="session")
def plant_run() -> PlantRun:
    return run_plant("deep-peak-50", hours=0.25, seed=1)


@pytest.fixture(scope="session")
def low_load_window(plant_run: PlantRun) -> pd.DataFrame:
    """The last 300 s of the 50 % hold (measured, with NaN dropouts of the casing sensor)."""
    return plant_run.measured.iloc[-300:]
