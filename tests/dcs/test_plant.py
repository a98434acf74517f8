"""The virtual plant: historian round trip, truth kept apart, realism, reproducibility."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant import KKS_TAGS, SCENARIOS, PlantRun, load_demand, run_plant, write_plant
from steamtwin.dcs.plant_model import (
    PLANT_METAL_NODES,
    PlantModel,
    PlantTruth,
    generator_power,
    plant_spec,
)
from steamtwin.dcs.readers import read_historian
from steamtwin.dcs.sensors import FaultConfig, default_sensor_models
from steamtwin.dcs.tagmap import load_tag_map
from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import TurbineSpec

HOLD_HOURS = 0.2  # 12-min holds keep the suite fast


@pytest.fixture(scope="module")
def faulty_run() -> PlantRun:
    """A short run with many dropouts and spikes, so the round trip sees NaNs."""
    faults = FaultConfig(dropout_rate_per_h=20.0, spike_rate_per_h=20.0)
    return run_plant("deep-peak-50", hours=0.05, random_state=3, truth=PlantTruth(faults=faults))


@pytest.fixture(scope="module")
def hold_runs() -> dict[str, PlantRun]:
    return {name: run_plant(name, hours=HOLD_HOURS, random_state=7)
            for name in ("deep-peak-30", "deep-peak-50")}


@pytest.mark.parametrize("layout", ["wide", "long"])
@pytest.mark.parametrize("file_format", ["csv", "parquet"])
def test_historian_round_trip(faulty_run: PlantRun, tmp_path: Path, layout: str,
                              file_format: str) -> None:
    assert faulty_run.measured.isna().any().any()  # dropouts present
    paths = write_plant(faulty_run, tmp_path, layout=layout, file_format=file_format)
    data = read_historian(paths["historian"], load_tag_map(paths["tag_map"]))
    measured = faulty_run.measured
    assert list(data.signals.columns) == list(measured.columns)
    np.testing.assert_array_equal(data.signals.index.asi8,
                                  measured.index.as_unit("ns").asi8)
    for name in measured.columns:
        np.testing.assert_allclose(data.signals[name].to_numpy(), measured[name].to_numpy(),
                                   rtol=1e-12, atol=1e-9, equal_nan=True, err_msg=name)
    assert data.extras.empty


def test_truth_kept_apart(faulty_run: PlantRun, tmp_path: Path) -> None:
    paths = write_plant(faulty_run, tmp_path)
    assert {p.name for p in tmp_path.iterdir()} == {"historian.parquet", "tags.toml", "truth"}
    assert paths["truth"].parent == paths["true_signals"].parent == tmp_path / "truth"
    historian = pd.read_parquet(paths["historian"])
    assert set(historian.columns) == {"Timestamp", *KKS_TAGS.values()}
    tags = paths["tag_map"].read_text(encoding="utf-8")
    for secret in ("0.965", "flow_coefficient", "friction", "heat_transfer", "leak", "truth"):
        assert secret not in tags
    document = json.loads(paths["truth"].read_text(encoding="utf-8"))
    assert document["parameters"] == {"flow_coefficient": 0.965, "friction_coefficient": 1.3,
                                      "heat_transfer_coefficient": 1.4}
    assert len(document["injected_faults"]) == len(faulty_run.injected.faults) > 0
    assert document["plant_structure"]["casing_thermocouple_depth"] == 0.020
    assert len(document["tip_leakage_fractions"]) == 12
    assert any("tip leakage" in note for note in document["structure"])
    assert document["twin_equivalent_parameters"]["flow_coefficient"] == pytest.approx(
        faulty_run.truth.twin_equivalent.flow_coefficient)
    truth = pd.read_parquet(paths["true_signals"])
    assert {"hp_power", "stage_flow", "gland_leakage_fraction"} <= set(truth.columns)


def test_plant_structure_differs_from_twin(reference_spec: TurbineSpec) -> None:
    spec = plant_spec(reference_spec)
    assert [g.stages for g in spec.metal_groups] == [(s,) for s in range(13)]
    for attribute in ("casing_mass", "casing_area", "rotor_mass", "rotor_area"):
        total = sum(getattr(g, attribute) for g in spec.metal_groups)
        assert total == pytest.approx(sum(getattr(g, attribute)
                                          for g in reference_spec.metal_groups))
    capacity = PlantModel(spec).design_.kernel.metal.capacity
    assert capacity.shape == (26, PLANT_METAL_NODES)
    assert np.all(capacity[::2, 1:] == capacity[::2, :1])  # the twin's uniform walls, finer
    graded = PlantModel(spec, PlantTruth()).design_.kernel.metal.capacity
    assert graded.shape == capacity.shape
    assert np.all(np.diff(graded[0]) > 0.0)  # casing volumes grow from the bore
    np.testing.assert_allclose(graded.sum(axis=1), capacity.sum(axis=1), rtol=1e-12)


@pytest.mark.parametrize("scenario", ["deep-peak-30", "deep-peak-50"])
def test_hold_end_close_to_twin(hold_runs: dict[str, PlantRun], reference_model: FullOrderModel,
                                reference_spec: TurbineSpec, scenario: str) -> None:
    """Plant vs the twin (default parameters) fed the plant's boundary conditions at the hold's
    end (steady start: the twin's metal settled, the plant's 12 min into the hold).

    Bands: φ = 0.965 raises p1 by ≈ 1/φ (+3.6 %) and the 1.5 % gland leakage lowers it by
    ≈ 1.5 %, so p1 must sit above the twin's by less than 5 %. HP-exhaust temperature: the
    friction multiplier (profile loss 2.5 → 3.25 % of the drop), the tip leakage (0.6–0.8 % of
    each stage's work), the valve overlap and metal still releasing heat 12 min into the hold
    move it by a few K, < 10 K. Load: the leaked steam (1.5 %), φ, friction and tip leakage lower
    the HP power by a few %, so 0.95 < plant/twin < 1.01. The boiler schedule puts the 30 %
    hold at 520 °C main steam, the 50 % hold at the rated 538 °C.
    """
    run = hold_runs[scenario]
    load = float(run.true_inputs["load_demand"].iloc[-1])
    assert load == pytest.approx(SCENARIOS[scenario].segments[-1][0])
    inputs = run.true_inputs.iloc[[-1]][list(reference_model.input_signals)]
    assert inputs["main_steam_temperature"].iloc[0] - 273.15 == pytest.approx(
        {"deep-peak-30": 520.0, "deep-peak-50": 538.0}[scenario], abs=0.5)  # dip recovered
    twin = reference_model.simulate(inputs).iloc[0]
    plant = run.true_outputs.iloc[-1]
    assert 1.0 < plant["control_stage_pressure"] / twin["control_stage_pressure"] < 1.05
    assert abs(plant["hp_exhaust_temperature"] - twin["hp_exhaust_temperature"]) < 10.0
    twin_load = float(generator_power(twin["hp_power"], reference_spec))
    assert 0.95 < plant["load"] / twin_load < 1.01
    leakage = run.true_inputs["gland_leakage_fraction"]
    assert leakage.between(0.012, 0.018).all()


def test_measured_noise_matches_sensor_sigma(hold_runs: dict[str, PlantRun]) -> None:
    """Over the last 10 min of the hold, the scatter about a 61-s rolling mean is the σ."""
    measured = hold_runs["deep-peak-50"].measured.iloc[-600:]
    for name, model in default_sensor_models().items():
        series = measured[name]
        residual = (series - series.rolling(61, center=True, min_periods=31).mean()).dropna()
        deviation = residual - residual.median()
        sigma = 1.4826 * float(np.median(np.abs(deviation)))  # robust to spikes
        assert sigma == pytest.approx(model.noise_sigma, rel=0.2), name


def test_reproducible_with_seed() -> None:
    first = run_plant("deep-peak-30", hours=0.02, random_state=11)
    second = run_plant("deep-peak-30", hours=0.02, random_state=11)
    other = run_plant("deep-peak-30", hours=0.02, random_state=12)
    pd.testing.assert_frame_equal(first.measured, second.measured)
    pd.testing.assert_frame_equal(first.injected.sensors, second.injected.sensors)
    pd.testing.assert_frame_equal(first.true_outputs, other.true_outputs)
    assert not first.measured.equals(other.measured)


def test_day_profile() -> None:
    demand = load_demand(SCENARIOS["day"])
    assert demand.size == 24 * 3600 + 1
    assert demand.min() == pytest.approx(0.30) and demand.max() == pytest.approx(1.0)
    assert np.abs(np.diff(demand)).max() * 100.0 * 60.0 <= 5.0 + 1e-9
    valley = np.flatnonzero(np.isclose(demand, 0.30)) / 3600.0
    assert valley[0] < 12.0 < valley[-1]
    assert valley[-1] - valley[0] > 2.0
    short = load_demand(SCENARIOS["day"], hours=0.1)
    assert short.size < demand.size


def test_second_day_holds_other_loads() -> None:
    """'day-2' holds loads the 'day' never holds (for judging a twin calibrated on the 'day'),
    within the same 30–100 % range and the 5 %/min ramp limit."""
    demand = load_demand(SCENARIOS["day-2"])
    assert demand.size == 24 * 3600 + 1
    assert demand.min() == pytest.approx(0.35) and demand.max() == pytest.approx(1.0)
    assert np.abs(np.diff(demand)).max() * 100.0 * 60.0 <= 5.0 + 1e-9
    held = {round(100 * target) for target, _, hold in SCENARIOS["day-2"].segments if hold}
    day = {round(100 * target) for target, _, hold in SCENARIOS["day"].segments if hold}
    assert held - {100} and not (held - {100}) & day


def test_same_instruments_on_another_day() -> None:
    """``instruments`` keeps an earlier run's calibration errors and drift rates and draws the
    noise anew; without it, the seed decides everything as before."""
    first = run_plant("deep-peak-30", hours=0.02, random_state=11)
    again = run_plant("deep-peak-30", hours=0.02, random_state=12,
                      instruments=first.injected.sensors)
    other = run_plant("deep-peak-30", hours=0.02, random_state=12)
    columns = ["bias_fraction", "drift_rate"]
    pd.testing.assert_frame_equal(again.injected.sensors[columns],
                                  first.injected.sensors[columns])
    assert not (again.injected.sensors["bias_fraction"]
                == other.injected.sensors["bias_fraction"]).any()
    noise = (again.measured - other.measured).drop(columns="load", errors="ignore")
    bias = again.injected.sensors["bias"] - other.injected.sensors["bias"]
    # signals whose accuracy class is a constant offset here (of span; 1.5 K below 375 °C)
    for name in ("main_steam_pressure", "hp_exhaust_temperature"):  # same noise, other bias
        offset = noise[name].to_numpy()
        resolution = float(other.injected.sensors.loc[name, "resolution"])
        assert np.ptp(offset) <= 2 * resolution + 1e-9 * abs(offset).max()
        assert np.median(offset) == pytest.approx(bias[name], abs=0.05 * abs(bias[name])
                                                  + resolution)


def test_errors() -> None:
    with pytest.raises(KeyError, match="deep-peak-30, deep-peak-50, day"):
        run_plant("nope")
    with pytest.raises(ValueError, match="ramp_rate"):
        load_demand(SCENARIOS["deep-peak-30"], ramp_rate=8.0)
