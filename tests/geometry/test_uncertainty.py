"""Scan-uncertainty propagation: exactness without noise, and a bounded spread with it."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.fidelity import section_pitch
from steamtwin.geometry.uncertainty import _sections, rebuilt_throat, scan_uncertainty


def test_rebuilt_section_without_noise_keeps_the_design_throat(hp1_blade) -> None:
    radii, points, _ = _sections(hp1_blade, 1)
    assert radii[0] == pytest.approx(hp1_blade.design.mean_radius)
    throat = rebuilt_throat(points[0], section_pitch(hp1_blade), 0.0)
    assert throat == pytest.approx(hp1_blade.profile.params.throat, abs=2e-6)


def test_scan_errors_give_a_small_flow_and_temperature_spread(hp1_blade,
                                                              reference_model) -> None:
    result = scan_uncertainty(hp1_blade, reference_model, samples=4, sections=2, rng=1)
    # ±0.05 mm on a 12.6 mm throat: the area moves by well under 1 %
    assert np.all(np.abs(result.throat_area_ratio - 1.0) < 0.01)
    assert result.nominal_hp_exhaust_temperature == pytest.approx(326.7 + 273.15, abs=0.05)
    assert 0.0 < result.temperature_spread < 2.0
    deviation = result.hp_exhaust_temperature - result.nominal_hp_exhaust_temperature
    assert result.max_deviation == pytest.approx(np.abs(deviation).max(), abs=1e-12)
    # at least half the spread; at most the spread when the exact blade lies inside the samples
    assert result.max_deviation >= 0.5 * result.temperature_spread - 1e-12
    if deviation.min() <= 0.0 <= deviation.max():
        assert result.max_deviation <= result.temperature_spread + 1e-12
    assert result.as_dict()["hp_exhaust_temperature_max_deviation_K"] == result.max_deviation
    # a larger flow capacity at fixed boundary pressures changes the exhaust temperature
    # monotonically: the samples order the same way by ratio and by temperature
    order_ratio = np.argsort(result.throat_area_ratio)
    diffs = np.diff(result.hp_exhaust_temperature[order_ratio])
    assert np.all(diffs >= -1e-9) or np.all(diffs <= 1e-9)
