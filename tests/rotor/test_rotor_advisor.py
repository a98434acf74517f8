"""Ramp-rate advisor (rotor/advisor.py, rotor/allowable.py): the advised ramp checked through the
full FEM, the bisection boundary, the cap, the band curve, the cycle-based allowable and bad
input."""

from __future__ import annotations

import copy
import json
from dataclasses import replace

import numpy as np
import pytest

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.advisor import ROM_MARGIN, SOAK_STEP_S, NoFeasibleRampError, RampAdvisor
from steamtwin.rotor.allowable import cycle_limit, design_stress_range, user_limit
from steamtwin.rotor.fatigue import ASME_DESIGN_FACTORS, fatigue_damage
from steamtwin.rotor.model import RotorModel, RotorState
from steamtwin.rotor.steel import steel
from steamtwin.rotor.transient_rom import RomState
from steamtwin.spec import load_spec

STEP_S = 120.0
ALLOWABLE_PA = 80e6
FROM_LOAD, TO_LOAD, HOLD_S = 1.0, 0.8, 900.0


@pytest.fixture(scope="module")
def model():
    """A coarse rotor (≈ 260 nodes) trained on one 2 %/min ramp 100 → 75 % and back: ≈ 1 s."""
    return RotorModel(load_spec("reference"), mesh_size=0.08, groove_mesh_size=0.006,
                      fit_ramps=[(1.0, 0.75, 0.02)], training_hold_s=900.0,
                      training_step_s=STEP_S).fit()


@pytest.fixture(scope="module")
def advisor(model):
    return RampAdvisor(model, ALLOWABLE_PA, step_s=STEP_S).fit()


@pytest.fixture(scope="module")
def advice(advisor):
    """100 → 80 % of load: the constant-pressure part of the line, where the control-stage
    steam cools by ≈ 30 K, so the 80 MPa allowable binds at a fraction of a %/min."""
    return advisor.advise(None, FROM_LOAD, TO_LOAD, hold_after_s=HOLD_S)


def _fem_excess(model, advisor, advice, rate):
    """Largest excess (Pa) of the full FEM's groove and bore equivalent stress over the
    allowable windows, on the advisor's steam side of a ramp at ``rate``."""
    steam = advisor.steam_frame(FROM_LOAD, TO_LOAD, rate, HOLD_S)
    fem = model.simulate_steam(steam, full_order=True).frame
    return max(float(advice.limits[loc].excess(fem[f"{loc}_equivalent"].to_numpy()).max())
               for loc in ("groove", "bore"))


def test_advised_ramp_stays_within_the_allowable_in_the_full_fem(model, advisor, advice):
    assert advice.limited_by == "allowable" and advice.monotone
    assert 0.001 < advice.rate_per_min < 0.01  # a fraction of a %/min: the bound binds
    assert _fem_excess(model, advisor, advice, advice.rate_per_min) <= 0.0


def test_five_percent_faster_exceeds_the_allowable_in_the_full_fem(model, advisor, advice):
    assert _fem_excess(model, advisor, advice, 1.05 * advice.rate_per_min) > 0.0


def test_advised_rate_is_the_feasible_end_of_the_final_bracket(advisor, advice):
    trials = advice.evaluations.sort_values("rate_per_min")
    feasible = trials[trials["feasible"]]
    infeasible = trials[~trials["feasible"]]
    assert advice.rate_per_min == feasible["rate_per_min"].max()
    above = infeasible["rate_per_min"].min()
    assert above > advice.rate_per_min
    assert above - advice.rate_per_min <= advisor.rate_tolerance * advice.rate_per_min
    # the ROM peak sits just inside the window less the margin, at the groove (cooling: tension)
    groove = advice.limits["groove"]
    edge = groove.shrunk(ROM_MARGIN).upper_pa
    assert edge - 0.01 * (edge - max(groove.standing_pa)) < advice.peak_pa["groove"] <= edge
    # the life it costs: some fatigue, positive, far below one
    assert 0.0 < advice.fatigue_damage["groove"] < 1e-3


def test_a_large_allowable_gives_the_rate_cap(model):
    capped = RampAdvisor(model, 1e9, step_s=STEP_S, max_rate=0.05).fit()
    advice = capped.advise(None, 0.8, 0.6, hold_after_s=0.0)
    assert (advice.rate_per_min, advice.limited_by) == (0.05, "max_rate")
    assert len(advice.evaluations) == 1


def test_band_curve_soaks_where_the_previous_band_left_no_feasible_rate(model, advisor):
    curve = advisor.curve(None, FROM_LOAD, TO_LOAD, band=0.1, hold_after_s=HOLD_S)
    table = curve.table
    assert table["from_load"].tolist() == pytest.approx([1.0, 0.9])
    assert table["to_load"].tolist() == pytest.approx([0.9, 0.8])
    first, second = curve.bands
    # band 1 ends at the fastest rate its hold allows, so band 2 cannot start at once: it soaks
    assert curve.soaks_s[0] == 0.0 and curve.soaks_s[1] > 0.0
    assert curve.soaks_s[1] % SOAK_STEP_S == 0.0
    with pytest.raises(NoFeasibleRampError):
        advisor.advise(first.end_state, 0.9, 0.8, hold_after_s=HOLD_S)
    for band in curve.bands:
        for location, limit in band.limits.items():
            stress = band.run[f"{location}_equivalent"].to_numpy()
            assert limit.shrunk(ROM_MARGIN).excess(stress).max() <= 0.0
    assert curve.duration_s == pytest.approx(first.ramp_s + second.ramp_s + curve.soaks_s[1])


def test_design_range_has_the_design_life_asked_for():
    crmov = steel("1CrMoV")
    ranges = []
    for cycles in (1e3, 1e4, 1e5):
        stress_range = design_stress_range(cycles, 50e6, 780.0, crmov, 1)
        series = np.array([50e6, 50e6 + stress_range, 50e6])
        damage = fatigue_damage(series, np.full(3, 780.0), crmov,
                                design=ASME_DESIGN_FACTORS).total_damage
        assert damage * cycles == pytest.approx(1.0, rel=1e-3)
        ranges.append(stress_range)
    assert ranges[0] > ranges[1] > ranges[2] > 0.0
    # Morrow: a tensile-going excursion from a tensile standing stress is allowed less range
    assert design_stress_range(1e4, 50e6, 780.0, crmov, 1) < design_stress_range(
        1e4, 50e6, 780.0, crmov, -1)
    window = cycle_limit("groove", 1e4, (40e6, 60e6), 780.0, crmov)
    assert window.upper_pa == pytest.approx(40e6 + design_stress_range(1e4, 40e6, 780.0, crmov, 1))
    # few cycles: the range is capped at the shakedown limit 3 S_m (taken as R_m at 507 °C)
    few = cycle_limit("groove", 1e3, (40e6, 60e6), 780.0, crmov)
    strength = float(crmov.tensile_strength(780.0))
    assert design_stress_range(1e3, 40e6, 780.0, crmov, 1) > strength
    assert (few.lower_pa, few.upper_pa) == pytest.approx((60e6 - strength, 40e6 + strength))


def test_cycle_allowable_in_the_advisor_is_wider_than_the_standing_stress(model):
    advisor = RampAdvisor(model, cycles=1e4, step_s=STEP_S).fit()
    advice = advisor.advise(None, 0.6, 0.4, hold_after_s=0.0)
    for limit in advice.limits.values():
        assert limit.lower_pa < min(limit.standing_pa) < max(limit.standing_pa) < limit.upper_pa
        assert "10000 cycles" in limit.basis


@pytest.mark.parametrize(("from_load", "to_load", "named"), [
    (1.0, 0.1, "to_load = 0.1"), (1.05, 0.5, "from_load = 1.05"),
    (0.5, float("nan"), "to_load = nan"), (0.5, 0.5, "nothing to ramp")])
def test_loads_outside_the_operating_line_are_refused(advisor, from_load, to_load, named):
    with pytest.raises(RotorAreaError, match=named):
        advisor.advise(None, from_load, to_load)


def test_an_allowable_below_the_standing_stress_is_refused(model):
    with pytest.raises(RotorAreaError, match="standing"):
        RampAdvisor(model, 10e6, step_s=STEP_S).fit().advise(None, 0.6, 0.4)
    with pytest.raises(RotorAreaError, match="standing"):
        user_limit("groove", 30e6, (-20e6, -35e6))
    with pytest.raises(RotorAreaError, match="positive"):
        user_limit("groove", -4e8, (0.0, 0.0))


def test_a_state_of_another_rotor_is_refused(model, advisor):
    state = model.initial_state(advisor.steam_frame(0.6, 0.4, 0.01, 0.0))
    wrong_size = RotorState(RomState(np.append(state.rom.coordinates, 0.0)), state.model)
    with pytest.raises(RotorAreaError, match="another rotor"):
        advisor.advise(wrong_size, 0.6, 0.4)
    hotter = RotorState(RomState(state.rom.coordinates * 1.5), state.model)  # metal far too hot
    with pytest.raises(RotorAreaError, match=r"temperature .* another rotor"):
        advisor.advise(hotter, 0.6, 0.4)


def test_a_same_size_state_of_another_rotor_model_is_refused_by_its_fingerprint(model,
                                                                                  advisor):
    # another fit of the same spec (another training rate): another basis, so another model
    other = RotorModel(model.spec, mesh_size=0.08, groove_mesh_size=0.006,
                       fit_ramps=[(1.0, 0.75, 0.04)], training_hold_s=900.0,
                       training_step_s=STEP_S).fit()
    assert other.fingerprint != model.fingerprint
    own = model.initial_state(advisor.steam_frame(0.6, 0.4, 0.01, 0.0))
    coordinates = np.resize(other.initial_state(advisor.steam_frame(0.6, 0.4, 0.01, 0.0))
                            .rom.coordinates, own.rom.coordinates.shape)
    foreign = RotorState(RomState(coordinates), other.fingerprint)  # same size as model's
    steam = advisor.steam_frame(0.6, 0.4, 0.01, 0.0)
    for use in (lambda: advisor.advise(foreign, 0.6, 0.4),
                lambda: model.simulate_steam(steam, foreign),
                lambda: model.step(foreign, steam.iloc[1], STEP_S),
                lambda: model.observe(foreign)):
        with pytest.raises(RotorAreaError, match=f"another rotor model.*{other.fingerprint}"):
            use()
    # the fingerprint survives JSON; a state without one (an older file) is refused clearly
    restored = RotorState.from_dict(json.loads(json.dumps(own.to_dict())))
    assert model.check_state(restored) == restored
    legacy = {key: value for key, value in own.to_dict().items() if key != "model"}
    with pytest.raises(RotorAreaError, match="no 'model' fingerprint"):
        RotorState.from_dict(legacy)
    # it covers the spec's [rotor] section: the same basis under a moved groove differs
    moved = copy.copy(model)
    moved.spec = replace(model.spec, rotor=replace(model.spec.rotor, groove_position=0.11))
    assert moved._fingerprint() != model.fingerprint


def test_bad_settings_are_refused(model):
    with pytest.raises(RotorAreaError, match="exactly one"):
        RampAdvisor(model, 4e8, cycles=1e4).fit()
    with pytest.raises(RotorAreaError, match="not fitted"):
        RampAdvisor(model, 4e8).advise(None, 0.6, 0.4)
    with pytest.raises(RotorAreaError, match="min_rate"):
        RampAdvisor(model, 4e8, max_rate=0.001).fit()
    with pytest.raises(RotorAreaError, match="cycle count"):
        design_stress_range(0.5, 0.0, 780.0, steel("1CrMoV"))
