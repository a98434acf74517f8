"""Design fit: part-load laws adjusted to a thermal kit (issue 17, item 4).

Heat balances here are made by models, so the answer is known: the reference model itself
(perturbed laws must be recovered), and the virtual plant (a different structure: gland
leakage, finer metal, hidden calibration parameters) as an independent target.
"""

from __future__ import annotations

import dataclasses
from importlib import resources

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.plant_model import PlantModel, PlantTruth, gland_leakage_fraction, plant_spec
from steamtwin.model.design_check import design_line
from steamtwin.model.design_fit import (
    ACCEPTANCE_BAND,
    FIT_PARAMETERS,
    RESIDUALS,
    DesignFit,
    DesignFitError,
    fit_design,
    fitted_spec_toml,
    given_value,
    outside_band,
    point_residuals,
)
from steamtwin.model.operating import operating_point
from steamtwin.spec import TurbineSpec, load_spec, parse_spec
from steamtwin.spec.heat_balance import HeatBalance, HeatBalancePoint, MachineDescription
from steamtwin.spec.turbine import PartLoad

pytestmark = pytest.mark.slow  # 16 s of the full suite (2026-11-27): not in the quick loop

LOADS = (1.0, 0.75, 0.6, 0.5, 0.4, 0.3)
MACHINE = MachineDescription(12, 314.159, 1.10, (0.25, 0.25, 0.25, 0.25), (1, 1, 2, 3),
                             ("GV1", "GV2", "GV3", "GV4"))
# A perturbed start, well inside the schema's ranges.
PERTURBED = PartLoad(reynolds_exponent=0.15, admission_loss_multiplier=1.6,
                     control_stage_velocity_ratio_factor=0.92, flow_capacity_multiplier=1.04)


def _point(load: float, inputs: dict[str, float], p1: float, t1: float | None,
           t_exhaust: float) -> HeatBalancePoint:
    return HeatBalancePoint(
        label=f"{load:.0%}", load_w=load * 600e6,
        main_steam_pressure_pa=inputs["main_steam_pressure"],
        main_steam_temperature_k=inputs["main_steam_temperature"],
        main_steam_flow_kg_s=inputs["main_steam_flow"], control_stage_pressure_pa=p1,
        control_stage_temperature_k=t1, hp_exhaust_pressure_pa=inputs["hp_exhaust_pressure"],
        hp_exhaust_temperature_k=t_exhaust, hp_isentropic_efficiency=0.85)


def _model_heat_balance(spec: TurbineSpec, loads=LOADS) -> HeatBalance:
    """The heat balance the model of ``spec`` itself computes along its sliding line."""
    line = design_line(spec, loads)
    points = tuple(
        _point(load, row.to_dict(), row["control_stage_pressure"],
               row["control_stage_temperature"], row["hp_exhaust_temperature"])
        for load, row in line.iterrows())
    return HeatBalance("model", MACHINE, points, "model-kit.toml")


def _plant_heat_balance() -> HeatBalance:
    """Steady states of the virtual plant (dcs.plant) at LOADS, measured flow, no noise."""
    spec = plant_spec(load_spec("reference"))
    truth = PlantTruth()
    model = PlantModel(spec)
    rated = model.simulate(model.design_inputs(), truth.parameters).iloc[0]
    rated_state = {"p1": float(rated["control_stage_pressure"]),
                   "t1": float(rated["control_stage_temperature"]),
                   "p_exhaust": spec.design.hp_exhaust_pressure,
                   "flow": spec.design.main_steam_flow}
    points = []
    for load in LOADS:
        inputs = {name: float(value) for name, value in operating_point(spec, load).items()}
        leakage = truth.gland_leakage_rated
        for _ in range(3):  # fixed point on the leakage, as run_plant does
            frame = pd.DataFrame({**inputs, "main_steam_flow": inputs["main_steam_flow"]
                                  * (1.0 - leakage)}, index=pd.to_datetime(["2000-01-01"]))
            state = model.simulate_detailed(frame, truth.parameters, stages=False).diagnostics
            p1 = float(state["control_stage_pressure"].iloc[0])
            t1 = float(state["control_stage_temperature"].iloc[0])
            leakage = float(gland_leakage_fraction(
                np.array([p1]), np.array([t1]), np.array([inputs["hp_exhaust_pressure"]]),
                np.array([inputs["main_steam_flow"]]), rated_state, truth.gland_leakage_rated)[0])
        points.append(_point(load, inputs, p1, t1,
                             float(state["hp_exhaust_temperature"].iloc[0])))
    return HeatBalance("virtual plant", MACHINE, tuple(points), "virtual-plant")


def test_default_part_load_leaves_the_reference_line_unchanged(sequential_spec):
    """Defaults are the model as it was: any other value moves the line, the defaults do not
    (figures of the line before [part_load] existed, rounded; the reference's valves as they
    were then, in sequence)."""
    reference_spec = sequential_spec
    line = design_line(reference_spec, (1.0, 0.5, 0.3))
    explicit = dataclasses.replace(reference_spec, part_load=PartLoad(0.0, 1.0, 1.0, 1.0))
    assert design_line(explicit, (1.0, 0.5, 0.3)).equals(line)
    np.testing.assert_allclose(line["control_stage_pressure"], [13.0215e6, 6.5643e6, 3.9933e6],
                               rtol=1e-4)
    np.testing.assert_allclose(line["hp_exhaust_temperature"], [599.850, 582.607, 585.969],
                               atol=2e-3)
    for name, value in (("reynolds_exponent", 0.2), ("admission_loss_multiplier", 2.0),
                        ("control_stage_velocity_ratio_factor", 0.9),
                        ("flow_capacity_multiplier", 1.05)):
        moved = dataclasses.replace(reference_spec, part_load=dataclasses.replace(
            PartLoad(), **{name: value}))
        difference = design_line(moved, (1.0, 0.5, 0.3)) - line
        assert (difference[["control_stage_pressure", "control_stage_temperature",
                            "hp_exhaust_temperature"]].abs().to_numpy().max() > 1e-3), name


def test_perturbed_laws_are_recovered_from_the_models_own_heat_balance(reference_spec):
    heat_balance = _model_heat_balance(reference_spec)
    start = dataclasses.replace(reference_spec, part_load=PERTURBED)
    before = point_residuals(start, heat_balance)
    assert before["control_stage_pressure_pct"].abs().max() > 3.0  # the start is far off
    fit = fit_design(start, heat_balance)
    assert fit.initial_part_load == PERTURBED
    for name in FIT_PARAMETERS:
        assert getattr(fit.part_load, name) == pytest.approx(getattr(PartLoad(), name),
                                                             abs=1e-3), name
    assert fit.residuals["control_stage_pressure_pct"].abs().max() < 0.1
    assert fit.residuals[["control_stage_temperature_k",
                          "hp_exhaust_temperature_k"]].abs().to_numpy().max() < 0.1
    assert fit.rank == 4 and not fit.unidentified
    np.testing.assert_allclose(fit.identified_share.sum(axis=0), 1.0)
    # the rated point says nothing about the Reynolds exponent (m = m_design there)
    assert fit.identified_share.loc["100%", "reynolds_exponent"] < 1e-6
    assert fit.identified_share.loc["30%", "reynolds_exponent"] > 0.2
    assert fit.evaluations <= 200  # measured 140 (its time is a benchmark's, not a test's)


def test_fit_against_the_virtual_plant_reduces_the_residuals(reference_spec):
    """Measured with the reference's valve management (2026-11-27): before, control-stage p
    −1.90…−2.11 %, T −1.23…−3.94 K, exhaust T −1.39…+0.09 K; after, p within 0.09 %,
    control-stage T within 0.50 K, exhaust T within 1.39 K (the rated point's exhaust T is the
    spec's design figure, which the design step meets by construction and the fit cannot
    move); the squared residuals fall to 6 %."""
    heat_balance = _plant_heat_balance()
    fit = fit_design(reference_spec, heat_balance)
    before, after = fit.initial_residuals.abs(), fit.residuals.abs()
    assert before["control_stage_pressure_pct"].min() > 1.8
    assert before["control_stage_temperature_k"].max() > 3.5
    assert after["control_stage_pressure_pct"].max() < 0.15
    assert after["control_stage_temperature_k"].max() < 0.6
    assert after.drop(index="100%")["hp_exhaust_temperature_k"].max() < 0.7
    assert after.loc["100%", "hp_exhaust_temperature_k"] == pytest.approx(
        before.loc["100%", "hp_exhaust_temperature_k"], abs=1e-6)
    assert (after.to_numpy() ** 2).sum() < 0.2 * (before.to_numpy() ** 2).sum()
    pd.testing.assert_frame_equal(point_residuals(fit.fitted_spec(reference_spec),
                                                  heat_balance), fit.residuals)


def test_fitted_laws_are_written_into_a_copy_of_the_spec_text(reference_spec):
    text = (resources.files("steamtwin.spec") / "data" / "reference.toml").read_text(
        encoding="utf-8")
    once = fitted_spec_toml(text, PERTURBED)
    assert parse_spec(once, "fitted.toml").part_load == PERTURBED
    assert parse_spec(once, "fitted.toml") == dataclasses.replace(reference_spec,
                                                                  part_load=PERTURBED)
    # an existing [part_load] table, even followed by another table, is replaced
    twice = fitted_spec_toml(once + "\n[zzz_other]\n", PartLoad(reynolds_exponent=0.3))
    assert twice.count("[part_load]") == 1 and "[zzz_other]" in twice
    assert "reynolds_exponent = 0.3" in twice


def test_only_fitted_parameters_move(reference_spec):
    heat_balance = _model_heat_balance(reference_spec, loads=(1.0, 0.5))
    start = dataclasses.replace(reference_spec, part_load=dataclasses.replace(
        PartLoad(), admission_loss_multiplier=1.5))
    fit = fit_design(start, heat_balance, parameters=("flow_capacity_multiplier",))
    assert fit.part_load.admission_loss_multiplier == 1.5
    assert list(fit.sensitivity.columns) == ["flow_capacity_multiplier"]


def test_bad_input_is_a_clear_error(reference_spec):
    heat_balance = _model_heat_balance(reference_spec, loads=(1.0, 0.5, 0.3))
    with pytest.raises(DesignFitError, match=r"model-kit\.toml: 3 heat-balance point\(s\) cannot "
                                             r"identify 4 parameters"):
        fit_design(reference_spec, heat_balance)
    nan_point = dataclasses.replace(heat_balance.points[1], hp_exhaust_temperature_k=float("nan"))
    broken = dataclasses.replace(heat_balance, points=(heat_balance.points[0], nan_point))
    with pytest.raises(DesignFitError, match=r"points\[2\] \('50%'\): hp_exhaust_temperature_k = "
                                             r"nan is not a finite positive number"):
        fit_design(reference_spec, broken, parameters=("flow_capacity_multiplier",))
    with pytest.raises(DesignFitError, match=r"parameters: expected distinct names"):
        fit_design(reference_spec, heat_balance, parameters=("blade_count",))
    tiny = dataclasses.replace(heat_balance.points[2], label="5%",
                               main_steam_flow_kg_s=0.05 * heat_balance.points[0]
                               .main_steam_flow_kg_s)
    with pytest.raises(DesignFitError, match=r"points\[3\] \('5%'\): the model cannot run this "
                                             r"point: .*below 15% of rated flow"):
        point_residuals(reference_spec, dataclasses.replace(
            heat_balance, points=(*heat_balance.points[:2], tiny)))


# The shipped example kit (an independent 600 MW unit, six valves), derived and fitted.
KIT_TEXT = (resources.files("steamtwin.spec") / "data" / "example-600mw-heat-balance.toml"
            ).read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def kit():
    from steamtwin.spec.derive import derive_spec
    from steamtwin.spec.heat_balance import parse_heat_balance

    heat_balance = parse_heat_balance(KIT_TEXT, "kit.toml")
    return parse_spec(derive_spec(heat_balance).toml, "unit.toml"), heat_balance


@pytest.fixture(scope="module")
def kit_fit(kit):
    spec, heat_balance = kit
    return fit_design(spec, heat_balance)


def _kit_frame(point: HeatBalancePoint, flow_factor: float = 1.0) -> pd.DataFrame:
    return pd.DataFrame({"main_steam_pressure": [point.main_steam_pressure_pa],
                         "main_steam_temperature": [point.main_steam_temperature_k],
                         "main_steam_flow": [flow_factor * point.main_steam_flow_kg_s],
                         "hp_exhaust_pressure": [point.hp_exhaust_pressure_pa]}, index=[0.0])


def test_the_kits_vwo_point_runs_from_the_rough_start(kit):
    """VWO (1838 t/h, GV6 ~73 % open) has little valve reserve: from the rough start the first
    sweep probes a higher control-stage pressure than the converged one, where the valves fall
    short; over-capacity is decided on the converged pressures only. A flow the valves really
    cannot pass is still refused."""
    from steamtwin.model.fom import FullOrderModel, InputError

    spec, heat_balance = kit
    vwo = heat_balance.points[0]
    assert vwo.label == "VWO"
    model = FullOrderModel(spec)
    state = model.simulate_detailed(_kit_frame(vwo), stages=False).diagnostics.iloc[0]
    assert state["control_stage_pressure"] == pytest.approx(13.709e6, rel=2e-4)
    assert 0.85 < state["active_admission_arc"] < 0.88  # of 0.90: GV6 part open
    with pytest.raises(InputError, match="exceeds what the wide-open governing valves pass"):
        model.simulate(_kit_frame(vwo, 1.1))
    residuals = point_residuals(spec, heat_balance)
    assert residuals.loc["VWO", "control_stage_pressure_pct"] == pytest.approx(0.133, abs=0.02)


def test_a_design_point_on_a_valve_point_converges_after_a_tiny_change(kit):
    """The fit's first Jacobian step: GV1–5 exactly wide open at design, GV6 shut. The part-open
    group's throttle pressure is accepted within a flow tolerance whose window (~0.6 Pa) used to
    leave ~1e-3 J/kg of warm-start noise, above the steady start's 1e-5 J/kg, so the sweeps
    cycled across the valve point and the design step failed."""
    from steamtwin.model.fom import FullOrderModel

    spec, _ = kit
    # without the kit's overlap, the design point sits exactly on the valve point
    sequential = dataclasses.replace(spec, control_stage=dataclasses.replace(
        spec.control_stage, valve_overlap=0.0))
    nudged = dataclasses.replace(sequential, part_load=dataclasses.replace(
        spec.part_load, reynolds_exponent=5e-11, admission_loss_multiplier=1.00008))
    design = FullOrderModel(nudged).design_
    assert design.efficiency_scale == pytest.approx(1.0, abs=1e-3)


def test_a_small_control_stage_pressure_mismatch_is_resized_a_large_one_refused(reference_spec):
    from steamtwin.model.fom import DESIGN_PRESSURE_EXCESS, FullOrderModel
    from steamtwin.spec import SpecError

    def scaled(factor: float) -> TurbineSpec:
        return dataclasses.replace(reference_spec, stages=tuple(
            dataclasses.replace(stage, flow_capacity=factor * stage.flow_capacity)
            for stage in reference_spec.stages))

    model = FullOrderModel(scaled(0.97))  # the stages put the control stage 3 % higher
    point = model.simulate_detailed(model.design_inputs(), stages=False).diagnostics.iloc[0]
    assert point["control_stage_pressure"] / reference_spec.design.control_stage_pressure == (
        pytest.approx(1.030, abs=2e-3))
    # re-sized: GV1–3 (0.72 of the arc) pass the rated flow again, GV4 stays shut
    assert point["active_admission_arc"] == pytest.approx(0.72, abs=1.5e-3)
    assert DESIGN_PRESSURE_EXCESS == 0.05
    with pytest.raises(SpecError, match=r"valves open at design: main_steam_flow exceeds .* "
                                        r"14\.46. MPa, \+11\.0%, more than the 5%"):
        _ = FullOrderModel(scaled(0.9)).design_


def test_fit_on_the_derived_kit_meets_every_point_within_the_band(kit_fit):
    """Issue 17's acceptance on the independent kit: after derive + fit, every point from VWO to
    30 % within 0.5 % in control-stage pressure and 1.0 K in control-stage and HP-exhaust
    temperature (measured in docs/benchmarks.md, "Design fit"). The kit's valves (GV1–5 one
    opening group, throttled alike below THA; the rated point between valve points) are in
    the derived spec; the part-load laws take the rest: the pressure stages' Reynolds loss and
    the control stage's velocity-ratio optimum."""
    before, after = kit_fit.initial_residuals, kit_fit.residuals
    # before: the pressure stages too efficient at part load (the kit's fall 0.900 -> 0.865)
    assert before.loc["30 %", "hp_exhaust_temperature_k"] == pytest.approx(-7.7, abs=0.3)
    assert after["control_stage_pressure_pct"].abs().max() < 0.5
    assert after["control_stage_temperature_k"].abs().max() < 1.0
    assert after["hp_exhaust_temperature_k"].abs().max() < 1.0
    assert (after.to_numpy() ** 2).sum() < 0.05 * (before.to_numpy() ** 2).sum()
    assert 0.2 < kit_fit.part_load.reynolds_exponent < 0.4
    assert kit_fit.part_load.control_stage_velocity_ratio_factor > 1.1
    # the kit states no admission losses of its own: the fit takes them to their lower bound
    assert kit_fit.bound_reached("admission_loss_multiplier") == "lower"
    assert kit_fit.bound_reached("reynolds_exponent") is None


def test_outside_band_names_each_residual_beyond_the_acceptance_band():
    residuals = pd.DataFrame(
        {"control_stage_pressure_pct": [0.49, -0.51, np.nan],
         "control_stage_temperature_k": [np.nan, 0.2, 1.5],
         "hp_exhaust_temperature_k": [-1.01, 1.0, 0.0]},
        index=pd.Index(["THA", "50 %", "30 %"], name="point"))
    assert outside_band(residuals) == ["THA (hp_exhaust_temperature -1.01 K)",
                                       "50 % (control_stage_pressure -0.51 %)",
                                       "30 % (control_stage_temperature +1.50 K)"]
    assert outside_band(residuals.iloc[:0]) == []
    assert set(ACCEPTANCE_BAND) == set(RESIDUALS)


def test_given_value_is_the_kit_figure_behind_each_residual():
    point = _point(1.0, {"main_steam_pressure": 16.7e6, "main_steam_temperature": 811.15,
                         "main_steam_flow": 500.0, "hp_exhaust_pressure": 3.6e6},
                   p1=12.0e6, t1=None, t_exhaust=590.0)
    assert given_value(point, "control_stage_pressure_pct") == 12.0e6
    assert given_value(point, "control_stage_temperature_k") is None
    assert given_value(point, "hp_exhaust_temperature_k") == 590.0
    with pytest.raises(ValueError, match="expected one of"):
        given_value(point, "hp_power")


def test_spec_toml_writes_the_fitted_laws_into_the_spec_text():
    text = resources.files("steamtwin.spec").joinpath("data", "reference.toml").read_text(
        encoding="utf-8")
    empty = pd.DataFrame()
    fit = DesignFit(part_load=PERTURBED, initial_part_load=PartLoad(), parameters=(),
                    initial_residuals=empty, residuals=empty, sensitivity=empty,
                    identified_share=empty, singular_values=np.zeros(0), rank=0,
                    condition_number=1.0, unidentified=(), evaluations=0, wall_time_s=0.0,
                    message="")
    written = fit.spec_toml(text)
    assert written == fitted_spec_toml(text, PERTURBED)
    assert parse_spec(written).part_load == PERTURBED
