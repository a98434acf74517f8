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
    # a larger flow capacity at fixed boundary pressures changes the exhaust temperature
    # monotonically: the samples order the same way by ratio and by temperature
    order_ratio = np.argsort(result.throat_area_ratio)
    diffs = np.diff(result.hp_exhaust_temperature[order_ratio])
    assert np.all(diffs >= -1e-9) or np.all(diffs <= 1e-9)
