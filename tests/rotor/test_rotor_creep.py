"""Larson–Miller rupture time and Robinson's time fraction."""

import numpy as np
import pytest

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.creep import CREEP_THRESHOLD, LarsonMillerCurve, creep_damage
from steamtwin.rotor.steel import steel

MATERIAL = steel("1CrMoV")
CURVE = LarsonMillerCurve(MATERIAL.creep)


def test_master_curve_fits_the_rupture_points_and_falls_over_the_data():
    p = CURVE.parameter(MATERIAL.creep.temperatures_k, MATERIAL.creep.rupture_hours)
    np.testing.assert_allclose(CURVE.stress(p), MATERIAL.creep.stresses_pa, rtol=0.08)
    span = np.linspace(p.min(), p.max(), 50)
    assert np.all(np.diff(CURVE.stress(span)) < 0.0)


def test_rupture_time_is_the_larson_miller_definition_by_hand():
    parameter, kelvin = 19500.0, 800.0
    stress = float(CURVE.stress(parameter))
    assert CURVE.rupture_hours(stress, kelvin) == pytest.approx(10 ** (19500 / 800 - 20),
                                                                rel=1e-9)


def test_constant_hold_damage_is_duration_over_rupture_time():
    kelvin, stress, hours = 538.0 + 273.15, 180e6, 5000.0
    time = np.linspace(0.0, hours * 3600.0, 11)
    result = creep_damage(np.full(11, stress), np.full(11, kelvin), time, MATERIAL)
    assert result.total_damage == pytest.approx(hours / CURVE.rupture_hours(stress, kelvin))
    assert result.interval_damage.shape == (10,)


def test_no_creep_below_the_threshold_or_in_compression_and_low_stress_is_conservative():
    time = np.array([0.0, 3600.0])
    cold = creep_damage([200e6, 200e6], [CREEP_THRESHOLD - 1.0] * 2, time, MATERIAL)
    squeezed = creep_damage([-200e6, -200e6], [800.0, 800.0], time, MATERIAL)
    assert cold.total_damage == 0.0 and squeezed.total_damage == 0.0
    low, _ = CURVE.stress_range_pa
    assert CURVE.rupture_hours(0.5 * low, 800.0) == CURVE.rupture_hours(low, 800.0)


def test_bad_input_is_refused_with_the_data_range():
    time = np.array([0.0, 3600.0])
    with pytest.raises(RotorAreaError, match=r"above the rupture data .*371–550 °C"):
        creep_damage([100e6, 100e6], [850.0, 850.0], time, MATERIAL)
    with pytest.raises(RotorAreaError, match=r"above the rupture data \(120–350 MPa\)"):
        creep_damage([400e6, 100e6], [800.0, 800.0], time, MATERIAL)
    with pytest.raises(RotorAreaError, match="must be finite"):
        creep_damage([np.nan, 100e6], [800.0, 800.0], time, MATERIAL)
    with pytest.raises(RotorAreaError, match="strictly increasing"):
        creep_damage([100e6, 100e6], [800.0, 800.0], [0.0, 0.0], MATERIAL)


def test_damage_per_window_splits_the_history_additively():
    time = np.arange(0.0, 11.0) * 3600.0
    stress = np.linspace(150e6, 250e6, 11)
    result = creep_damage(stress, np.full(11, 800.0), time, MATERIAL)
    windows = result.damage_per_window([0, 3, 10])
    assert windows.sum() == pytest.approx(result.total_damage)
    assert windows[0] == pytest.approx(result.interval_damage[:3].sum())
    with pytest.raises(RotorAreaError, match="strictly increasing sample indices in 0…10"):
        result.damage_per_window([0, 12])
