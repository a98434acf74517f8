"""The objective: hand-computed RMSE, NaN handling, weights, penalty, per-window breakdown."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from steamtwin.calibration.objective import (
    FITNESS_EPSILON,
    PENALTY_RMSE,
    CalibrationProblem,
    fitness,
    window_rmse,
)
from steamtwin.calibration.settings import ObjectiveSettings, check_bounds
from steamtwin.model.parameters import ModelParameters

PLAIN = ObjectiveSettings(priors=None, min_samples=1)  # the method's RMSE, tiny windows allowed
CASING = replace(PLAIN, sensors=["hp_inner_casing_temperature"])


def small_window(n: int = 6) -> pd.DataFrame:
    index = pd.date_range("2026-03-01", periods=n, freq="1s", tz="UTC")
    t0 = np.full(n, 800.0)
    return pd.DataFrame({
        "main_steam_pressure": 16.0e6, "main_steam_temperature": t0,
        "main_steam_flow": 400.0, "hp_exhaust_pressure": 3.5e6,
        "control_stage_temperature": [700.0, 701.0, np.nan, 699.0, 700.0, 702.0],
        "hp_exhaust_temperature": [611.0, 612.0, 609.0, np.nan, np.nan, 610.0],
        "hp_inner_casing_temperature": [655.0, 655.0, 656.0, 654.0, 655.0, 655.0],
    }, index=index)


def test_objective_equals_hand_computed_rmse(linear_simulator):
    window = small_window()
    params = ModelParameters(1.0, 1.0, 1.0)  # predictions 700, 610, 655 K
    weights = {"control_stage_temperature": 2.0, "hp_exhaust_temperature": 1.0,
               "hp_inner_casing_temperature": 0.5}
    problem = CalibrationProblem(linear_simulator, [window, window.iloc[:3]],
                                 replace(PLAIN, weights=weights))
    # squared errors of the valid samples, per sensor, both windows pooled
    cs = [*[0, 1, 1, 0, 4], *[0, 1]]        # NaN at row 2 excluded
    ex = [*[1, 4, 1, 0], *[1, 4, 1]]        # NaN at rows 3, 4 excluded
    ic = [*[0, 0, 1, 1, 0, 0], *[0, 0, 1]]
    expected = np.sqrt((2.0 * sum(cs) + sum(ex) + 0.5 * sum(ic))
                       / (2.0 * len(cs) + len(ex) + 0.5 * len(ic)))
    rmse = problem.rmse(params)
    assert rmse == pytest.approx(expected, rel=1e-12)
    out: dict = {}
    problem._evaluate(np.array([[1.0, 1.0, 1.0]]), out)
    assert out["F"][0, 0] == pytest.approx(expected, rel=1e-12)
    assert problem.windows[0].excluded == (1, 2, 0)
    assert problem.n_evaluations == 2
    assert fitness(rmse) == pytest.approx(1.0 / (expected + FITNESS_EPSILON))


def test_selected_sensor_only(linear_simulator):
    problem = CalibrationProblem(linear_simulator, [small_window()], CASING)
    assert problem.rmse(ModelParameters()) == pytest.approx(np.sqrt(2 / 6))


def test_input_dropouts_filled_forward_and_counted(linear_simulator):
    window = small_window()
    window.loc[window.index[0], "main_steam_flow"] = np.nan  # leading: dropped
    window.loc[window.index[3], "main_steam_temperature"] = np.nan  # short: filled
    problem = CalibrationProblem(linear_simulator, [window], PLAIN)
    prepared = problem.windows[0]
    assert prepared.dropped_rows == 1 and prepared.filled_rows == 1
    assert len(prepared.inputs) == 5 and not prepared.inputs.isna().any().any()
    long_gap = pd.concat([small_window()] * 40)
    long_gap.index = pd.date_range("2026-03-01", periods=len(long_gap), freq="1s", tz="UTC")
    long_gap.iloc[50:150, 1] = np.nan  # main_steam_temperature missing for 100 s
    with pytest.raises(ValueError, match="missing for more than 60 s"):
        CalibrationProblem(linear_simulator, [long_gap], ObjectiveSettings(priors=None))


def test_infeasible_parameters_give_the_penalty(linear_simulator):
    problem = CalibrationProblem(linear_simulator, [small_window()], PLAIN)
    assert problem.rmse(ModelParameters(flow_coefficient=0.9)) == PENALTY_RMSE
    assert problem.n_penalised == 1 and "valves" in problem.last_error


def test_fom_rejects_low_flow_coefficient_at_rated_flow(reference_model, plant_run):
    rated = plant_run.measured.iloc[:60]  # the run starts at rated load
    problem = CalibrationProblem(reference_model, [rated], ObjectiveSettings(priors=None))
    assert problem.rmse(ModelParameters(flow_coefficient=0.9)) == PENALTY_RMSE
    assert problem.rmse(ModelParameters()) < 10.0
    assert problem.n_penalised == 1


def test_bounds_checked():
    assert check_bounds({"flow_coefficient": (0.95, 1.05)})["flow_coefficient"] == (0.95, 1.05)
    with pytest.raises(ValueError, match="physical bounds"):
        check_bounds({"flow_coefficient": (0.8, 1.05)})
    with pytest.raises(ValueError, match="unknown parameter"):
        check_bounds({"flow": (0.95, 1.05)})


def test_window_rmse_breakdown(linear_simulator):
    window = small_window()
    table = window_rmse(linear_simulator, [window, window.iloc[:3]], settings=PLAIN)
    assert list(table["samples"]) == [6, 3]
    assert table.loc[1, "rmse:control_stage_temperature"] == pytest.approx(np.sqrt(1 / 2))
    assert table.loc[0, "excluded:hp_exhaust_temperature"] == 2
    rejected = window_rmse(linear_simulator, [window], ModelParameters(flow_coefficient=0.9),
                           PLAIN)
    assert np.isnan(rejected.loc[0, "rmse"]) and "valves" in rejected.loc[0, "error"]


def test_too_short_window_and_missing_sensor_are_named(linear_simulator):
    with pytest.raises(ValueError, match=r"window 0: 6 usable rows .* fewer than the 60"):
        CalibrationProblem(linear_simulator, [small_window()], ObjectiveSettings(priors=None))
    no_casing = small_window().drop(columns="hp_inner_casing_temperature")
    with pytest.raises(ValueError, match=r"window 0: lacks column\(s\) \['hp_inner_casing"):
        CalibrationProblem(linear_simulator, [no_casing], PLAIN)


class _SimulateOnly:
    """The FOM seen through the bare Simulator protocol (no checked-input fast path)."""

    def __init__(self, model) -> None:
        self.model = model
        self.input_signals = model.input_signals
        self.output_signals = model.output_signals

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        return self.model.simulate(inputs, params)


def test_fast_path_scores_as_the_protocol_does(reference_model, low_load_window):
    """The FOM's windows are checked once and run as arrays; the RMSE is the protocol's."""
    window = low_load_window.iloc[:300]
    fast = CalibrationProblem(reference_model, [window], PLAIN)
    plain = CalibrationProblem(_SimulateOnly(reference_model), [window],
                               PLAIN)
    assert fast.windows[0].checked is not None and plain.windows[0].checked is None
    params = ModelParameters(0.97, 1.3, 1.4)
    assert fast.rmse(params) == pytest.approx(plain.rmse(params), rel=1e-13)
    # inputs the model rejects keep being reported per evaluation, as through ``simulate``
    bad = window.copy()
    bad.iloc[5, bad.columns.get_loc("main_steam_flow")] = 10.0
    rejected = CalibrationProblem(reference_model, [bad], PLAIN)
    assert rejected.windows[0].checked is None
    evaluation = rejected.objective.evaluate([1.0, 1.0, 1.0])
    assert evaluation.rmse == PENALTY_RMSE and "main_steam_flow" in evaluation.error


def test_a_pressure_or_power_witness_counts_in_the_score_not_in_the_rmse(linear_simulator):
    """The RMSE (K) is over the temperatures; a witness in other units (here the power, W)
    enters the posterior score through its own σ, and a calibration needs a temperature."""
    window = small_window().assign(hp_power=1.0e8 + 3.0e5)  # 0.3 MW off
    sensors = ["hp_inner_casing_temperature", "hp_power"]
    sigma = {"hp_inner_casing_temperature": 1.0, "hp_power": 1.0e5}
    problem = CalibrationProblem(linear_simulator, [window],
                                 replace(PLAIN, sensors=sensors, sigma=sigma))
    alone = CalibrationProblem(linear_simulator, [window], CASING)
    params = ModelParameters()
    assert problem.rmse(params) == pytest.approx(alone.rmse(params), rel=1e-12)
    chi2 = 2.0 + 6 * 3.0**2  # casing: 2 K² at σ 1 K; power: six samples 3σ off
    assert problem.score(params) == pytest.approx(np.sqrt(chi2 / 12), rel=1e-12)
    with pytest.raises(ValueError, match="at least one temperature"):
        CalibrationProblem(linear_simulator, [window], replace(PLAIN, sensors=["hp_power"]))
