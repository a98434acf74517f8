"""Rainflow, Neuber, Manson–Coffin–Basquin and Miner against hand calculations and invariants."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.fatigue import (
    ASME_DESIGN_FACTORS,
    cycles_to_failure,
    fatigue_damage,
    miner_damage,
    neuber_peak,
    neuber_range,
    rainflow_cycles,
)
from steamtwin.rotor.steel import StrainLife, steel

KELVIN_500 = 500.0 + 273.15
MATERIAL = steel("30CrMoNiV5-11")
CURVE = MATERIAL.strain_life(KELVIN_500)
E, SF, B = CURVE.youngs_modulus, CURVE.fatigue_strength_coefficient, CURVE.fatigue_strength_exponent
EF, CC = CURVE.fatigue_ductility_coefficient, CURVE.fatigue_ductility_exponent


def test_rainflow_reproduces_the_astm_e1049_example_table():
    # ASTM E1049-85 §5.4.4, Fig. 6 history; published counts: range 3: 0.5, 4: 1.5, 6: 0.5,
    # 8: 1.0, 9: 0.5.
    history = np.array([-2, 1, -3, 5, -1, 3, -4, 4, -2], dtype=float)
    temperature = np.linspace(700.0, 780.0, history.size)
    cycles = rainflow_cycles(history, temperature)
    counts = cycles.groupby("range_pa")["count"].sum().to_dict()
    assert counts == {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}
    full = cycles[cycles["count"] == 1.0].iloc[0]
    assert (full["start"], full["end"], full["mean_pa"]) == (4, 5, 1.0)
    assert full["temperature_k"] == pytest.approx(temperature[5])  # the hotter reversal


def test_a_two_sample_series_is_one_half_cycle():
    cycles = rainflow_cycles([0.0, 3e8], [700.0, 720.0])
    assert cycles[["range_pa", "mean_pa", "count", "start", "end", "temperature_k"]].to_numpy(
    ).tolist() == [[3e8, 1.5e8, 0.5, 0.0, 1.0, 720.0]]


def test_neuber_range_recovers_a_chosen_elastic_plastic_loop():
    d_sigma = 900e6  # local stress range beyond the cyclic yield
    d_eps = d_sigma / E + 2.0 * (d_sigma / (2.0 * CURVE.cyclic_strength_coefficient)) ** (
        1.0 / CURVE.cyclic_hardening_exponent)
    elastic_range = np.sqrt(E * d_sigma * d_eps)  # Neuber: Δσ_e² / E = Δσ·Δε
    got_sigma, got_eps = neuber_range(elastic_range, CURVE)
    assert got_sigma == pytest.approx(d_sigma, rel=1e-9)
    assert got_eps == pytest.approx(d_eps, rel=1e-9)
    assert d_eps > elastic_range / E  # plasticity adds strain beyond the elastic estimate
    assert neuber_peak(-elastic_range / 2, CURVE) == pytest.approx(-d_sigma / 2, rel=1e-9)


def test_neuber_is_elastic_for_small_stresses():
    stress, strain = neuber_range(20e6, CURVE)
    assert stress == pytest.approx(20e6, rel=1e-6) and strain == pytest.approx(20e6 / E, rel=1e-6)


@pytest.mark.parametrize("mean", [-150e6, 0.0, 200e6])
def test_morrow_life_inverts_the_closed_form_strain_life_curve(mean):
    reversals = 3.0e4
    strain_amplitude = (SF - mean) / E * reversals ** B + EF * reversals ** CC
    assert cycles_to_failure(strain_amplitude, mean, CURVE) == pytest.approx(reversals / 2,
                                                                             rel=1e-8)


def test_swt_life_inverts_the_closed_form_swt_curve():
    sigma_a = 400e6
    strain_amplitude = float(CURVE.strain_amplitude(sigma_a))
    reversals = 5.0e3
    sigma_max = (SF**2 / E * reversals ** (2 * B) + SF * EF * reversals ** (B + CC)) \
        / strain_amplitude
    life = cycles_to_failure(strain_amplitude, sigma_max - sigma_a, CURVE,
                             mean_stress_correction="swt")
    assert life == pytest.approx(reversals / 2, rel=1e-6)
    assert cycles_to_failure(strain_amplitude, -sigma_a - 1e6, CURVE,
                             mean_stress_correction="swt") == np.inf


def test_design_factors_take_the_lower_of_twice_the_strain_and_a_twentieth_of_the_life():
    for strain_amplitude in (2e-3, 6e-3):
        mean_life = cycles_to_failure(strain_amplitude, 0.0, CURVE)
        at_double = cycles_to_failure(2 * strain_amplitude, 0.0, CURVE)
        design = cycles_to_failure(strain_amplitude, 0.0, CURVE, design=ASME_DESIGN_FACTORS)
        assert design == pytest.approx(min(at_double, mean_life / 20.0))
        assert design < mean_life


def test_single_idealised_cycle_life_by_hand():
    # Choose the life, then build the elastic stress that gives it (closed-form steps):
    # σ_a = σ'_f (2N)^b, ε_a = σ_a/E + ε'_f (2N)^c, Neuber σ_e = √(E σ_a ε_a), mean zero.
    cycles = 1.0e4
    sigma_a = SF * (2 * cycles) ** B
    eps_a = sigma_a / E + EF * (2 * cycles) ** CC
    sigma_e = np.sqrt(E * sigma_a * eps_a)
    result = fatigue_damage([-sigma_e, sigma_e, -sigma_e], np.full(3, KELVIN_500), MATERIAL)
    assert result.cycles["count"].sum() == 1.0  # two half cycles of the same range
    np.testing.assert_allclose(result.cycles["cycles_to_failure"], cycles, rtol=1e-7)
    np.testing.assert_allclose(result.cycles["local_mean_pa"], 0.0, atol=1e-3 * sigma_a)
    assert result.total_damage == pytest.approx(1.0 / cycles, rel=1e-7)


def test_tensile_mean_shortens_and_compressive_mean_lengthens_the_life():
    swing = 700e6
    lives = [fatigue_damage([m - swing / 2, m + swing / 2, m - swing / 2], np.full(3, KELVIN_500),
                            MATERIAL).total_damage for m in (-300e6, 0.0, 300e6)]
    assert lives[0] < lives[1] < lives[2]


history_values = st.lists(st.integers(-400, 400), min_size=3, max_size=40)


@settings(max_examples=40, deadline=None)
@given(history_values, st.lists(st.integers(1, 38), max_size=4))
def test_damage_per_window_sums_to_the_total(values, cuts):
    stress = np.array(values, dtype=float) * 1e6
    result = fatigue_damage(stress, np.full(stress.size, KELVIN_500), MATERIAL)
    edges = sorted({0, stress.size, *[c for c in cuts if c < stress.size]})
    assert result.damage_per_window(edges).sum() == pytest.approx(result.total_damage,
                                                                  rel=1e-12, abs=1e-300)


@settings(max_examples=40, deadline=None)
@given(history_values, history_values)
def test_miner_sum_is_additive_over_blocks_that_start_and_end_at_the_overall_peak(a, b):
    peak = max(max(a), max(b)) + 1
    first = np.array([peak, *a, peak], dtype=float) * 1e6
    second = np.array([peak, *b, peak], dtype=float) * 1e6

    def damage(series):
        return fatigue_damage(series, np.full(series.size, KELVIN_500), MATERIAL).total_damage

    both = damage(np.concatenate([first, second]))
    assert both == pytest.approx(damage(first) + damage(second), rel=1e-9, abs=1e-300)


def test_bad_input_is_refused_with_a_clear_message():
    temperature = np.full(3, KELVIN_500)
    with pytest.raises(RotorAreaError, match=r"stress \(Pa\) is not finite at sample 1"):
        fatigue_damage([0.0, np.nan, 1e8], temperature, MATERIAL)
    with pytest.raises(RotorAreaError, match=r"tabulated for 273.15–823.15 K"):
        fatigue_damage([0.0, 3e8, 0.0], [KELVIN_500, 900.0, KELVIN_500], MATERIAL)
    with pytest.raises(RotorAreaError, match=r"cycle count -1.0 at class 0 must be finite and ≥ 0"):
        miner_damage([-1.0], [1e4])
    with pytest.raises(RotorAreaError, match="strain amplitude must be finite"):
        cycles_to_failure(-1e-3, 0.0, CURVE)
    with pytest.raises(RotorAreaError, match="mean_stress_correction"):
        cycles_to_failure(1e-3, 0.0, CURVE, mean_stress_correction="goodman")


def test_measured_strain_life_constants_replace_the_estimate():
    measured = StrainLife(youngs_modulus=170e9, fatigue_strength_coefficient=800e6,
                          fatigue_strength_exponent=-0.1, fatigue_ductility_coefficient=0.3,
                          fatigue_ductility_exponent=-0.6)
    cycles = 2.0e3
    sigma_a = 800e6 * (2 * cycles) ** -0.1
    eps_a = sigma_a / 170e9 + 0.3 * (2 * cycles) ** -0.6
    sigma_e = np.sqrt(170e9 * sigma_a * eps_a)
    result = fatigue_damage([-sigma_e, sigma_e, -sigma_e], np.full(3, KELVIN_500), MATERIAL,
                            strain_life=lambda temperature: measured)
    assert result.total_damage == pytest.approx(1.0 / cycles, rel=1e-7)
