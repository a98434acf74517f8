"""rotor_life (rotor/life.py): a hand calculation of one idealised cycle, ramp detection, and the
per-ramp and per-day partitions summing to the totals."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

from steamtwin.errors import RotorAreaError
from steamtwin.model.operating import ramp_profile
from steamtwin.rotor.life import detect_ramps, rotor_life
from steamtwin.rotor.steel import steel

STEEL = steel("30CrMoNiV5-11")


def _frame(stress, temperature, index) -> pd.DataFrame:
    return pd.DataFrame({"groove_equivalent": stress, "groove_temperature": temperature},
                        index=index)


def _hand_life(mean_pa: float, amplitude_pa: float, temperature_k: float) -> float:
    """Cycles to failure of one elastic cycle σ_m ± σ_a at T, written out step by step:
    Uniform Material Law constants (Bäumel & Seeger 1990) from R_m(T), E(T); Neuber on the
    doubled (Masing) and the monotonic cyclic curve; Morrow's Manson–Coffin–Basquin; the ASME
    design factors (2 on strain, 20 on cycles) — root finding by bisection, not Newton."""
    e = float(STEEL.youngs_modulus(temperature_k))
    rm = float(STEEL.tensile_strength(temperature_k))
    psi = 1.0 if rm / e <= 0.003 else 1.375 - 125.0 * rm / e
    sf, b, ef, c = 1.5 * rm, -0.087, 0.59 * psi, -0.58
    n_prime = b / c
    k_prime = sf / ef ** n_prime

    def strain(stress):  # cyclic Ramberg–Osgood
        return stress / e + (stress / k_prime) ** (1.0 / n_prime)

    local_amplitude = brentq(lambda s: s * strain(s) - amplitude_pa ** 2 / e, 0.0, amplitude_pa)
    peak = mean_pa + amplitude_pa
    local_peak = brentq(lambda s: s * strain(s) - peak ** 2 / e, 0.0, peak)
    local_mean = local_peak - local_amplitude
    strain_amplitude = strain(local_amplitude)

    def life(eps_a):
        return 0.5 * 10.0 ** brentq(lambda x: (sf - local_mean) / e * 10 ** (b * x)
                                    + ef * 10 ** (c * x) - eps_a, 0.0, 20.0)

    return min(life(2.0 * strain_amplitude), life(strain_amplitude) / 20.0)


def test_one_idealised_cycle_matches_the_hand_calculation():
    # σ = 100 ± 300 MPa at 300 °C (below the creep threshold): one full cycle as two halves
    index = pd.date_range("2026-01-01", periods=3, freq="10min")
    frame = _frame([-200e6, 400e6, -200e6], 573.15, index)
    life = rotor_life(frame, STEEL)
    expected = _hand_life(100e6, 300e6, 573.15)
    assert life.cycles["count"].sum() == pytest.approx(1.0)
    assert life.fatigue_damage == pytest.approx(1.0 / expected, rel=1e-6)
    assert life.creep_damage == 0.0
    assert life.summary()["total_damage"] == pytest.approx(1.0 / expected, rel=1e-6)


def test_creep_of_a_hot_hold_is_its_time_fraction():
    index = pd.date_range("2026-01-01", periods=2, freq="10h")
    hold = rotor_life(_frame([200e6, 200e6], 793.15, index), STEEL, design_factors=None)
    from steamtwin.rotor.creep import LarsonMillerCurve
    rupture_h = float(LarsonMillerCurve(STEEL.creep).rupture_hours(200e6, 793.15))
    assert hold.fatigue_damage == 0.0
    assert hold.creep_damage == pytest.approx(10.0 / rupture_h, rel=1e-9)


def _day_of_ramps() -> tuple[pd.DataFrame, pd.Series]:
    """Two days at 60-s samples, each 100 → 30 → 100 % at 3 %/min with noise, and a surface
    stress following the load's rate (cooling tensile, heating compressive)."""
    one = np.concatenate([ramp_profile(1.0, 0.3, 0.03, 7200, 36000, 60.0),
                          ramp_profile(0.3, 1.0, 0.03, 0, 86400, 60.0)[1:]])[:1440]
    load = np.concatenate([one, one])
    index = pd.date_range("2026-03-01", periods=load.size, freq="60s")
    noisy = load + np.random.default_rng(1).normal(0.0, 0.003, load.size)
    rate = -np.gradient(pd.Series(load).ewm(span=20).mean().to_numpy())
    stress = 150e6 + 3e9 * rate
    temperature = 700.0 + 60.0 * load
    return _frame(stress, temperature, index), pd.Series(noisy, index=index)


def test_ramps_are_the_monotone_load_changes_above_the_threshold():
    _, load = _day_of_ramps()
    ramps = detect_ramps(load, 0.05, 0.01)
    assert len(ramps) == 4
    np.testing.assert_allclose(ramps["from_load"].iloc[:2], [1.0, 0.3], atol=0.015)
    np.testing.assert_allclose(ramps["rate_per_min"], [-0.03, 0.03, -0.03, 0.03], rtol=0.1)
    assert (ramps["end"] - ramps["start"]).dt.total_seconds().between(1200, 1700).all()
    # a 3 % step is load-following, not a ramp
    assert detect_ramps(pd.Series(np.r_[np.ones(50), np.full(50, 0.97)]), 0.05, 0.01).empty


def test_per_ramp_and_per_day_damage_sum_to_the_totals():
    frame, load = _day_of_ramps()
    life = rotor_life(frame, STEEL, load=load)
    total = life.fatigue_damage + life.creep_damage
    assert total > 0.0 and life.creep_damage > 0.0
    assert len(life.per_ramp) == 4 and len(life.per_day) == 2
    for table in (life.per_ramp, life.per_day):
        assert table["damage"].sum() == pytest.approx(total, rel=1e-12)
        assert table["fatigue_damage"].sum() == pytest.approx(life.fatigue_damage, rel=1e-12)
        assert table["cumulative_damage"].iloc[-1] == pytest.approx(total, rel=1e-12)
    # a cycle is charged where it closes: the first day's up-ramp closes its cool-down cycle;
    # the second day closes that day's and the one spanning midnight (rainflow's pairing)
    big = life.cycles["range_pa"] > 1e8
    assert big.sum() == 3
    np.testing.assert_allclose(life.per_day["fatigue_damage"].iloc[1],
                               2.0 * life.per_day["fatigue_damage"].iloc[0], rtol=1e-3)


def test_bad_run_frames_are_refused():
    frame, load = _day_of_ramps()
    with pytest.raises(RotorAreaError, match="lacks"):
        rotor_life(frame, STEEL, location="bore")
    with pytest.raises(RotorAreaError, match="row 3"):
        rotor_life(frame.assign(groove_equivalent=frame["groove_equivalent"].where(
            np.arange(len(frame)) != 3)), STEEL)
    with pytest.raises(RotorAreaError, match="indexed like"):
        rotor_life(frame, STEEL, load=load.iloc[1:])
