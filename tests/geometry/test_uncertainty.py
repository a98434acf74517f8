"""Scan-uncertainty propagation: exactness without noise, each row through its own stage, and
the control-stage rotor reported without a temperature."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.geometry.fidelity import section_pitch
from steamtwin.geometry.pritchard import GeometryError
from steamtwin.geometry.profile import make_blade
from steamtwin.geometry.uncertainty import (
    CONTROL_STAGE_ROTOR,
    as_built_model,
    exact_sections,
    propagated_stage,
    rebuilt_throat,
    scan_uncertainty,
)

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop


def _exhaust(model) -> float:
    return float(model.simulate(model.design_inputs())["hp_exhaust_temperature"].iloc[0])


def test_rebuilt_section_without_noise_keeps_the_design_throat(hp1_blade) -> None:
    radii, points, _ = exact_sections(hp1_blade, 1)
    assert radii[0] == pytest.approx(hp1_blade.design.mean_radius)
    throat = rebuilt_throat(points[0], section_pitch(hp1_blade), 0.0)
    assert throat == pytest.approx(hp1_blade.profile.params.throat, abs=2e-6)


def test_rows_map_to_their_own_stage() -> None:
    assert propagated_stage("hp1") is None
    assert [propagated_stage(f"hp{k}") for k in range(2, 14)] == list(range(1, 13))
    with pytest.raises(GeometryError, match="'ip3' is not in the HP model"):
        propagated_stage("ip3")


def test_nominal_ratio_is_the_unmodified_model(reference_model) -> None:
    for stage in (1, 12):
        assert _exhaust(as_built_model(reference_model, stage, 1.0)) == _exhaust(
            reference_model)


def test_a_ratio_moves_only_its_own_stage(reference_model) -> None:
    design = reference_model.design_.kernel.stage_capacity
    built = as_built_model(reference_model, 12, 1.01)
    capacity = built.design_.kernel.stage_capacity
    assert capacity[11] == pytest.approx(1.01 * design[11], rel=1e-12)
    np.testing.assert_array_equal(capacity[:11], design[:11])
    assert built.spec.stages[11].flow_capacity == pytest.approx(
        1.01 * reference_model.spec.stages[11].flow_capacity, rel=1e-12)
    assert built.spec.stages[:11] == reference_model.spec.stages[:11]
    # the design step of the unmodified spec is kept: the change shows at the design point
    assert built.design_.efficiency_scale == reference_model.design_.efficiency_scale
    shift_last = _exhaust(built) - _exhaust(reference_model)
    shift_first = _exhaust(as_built_model(reference_model, 1, 1.01)) - _exhaust(reference_model)
    # a larger capacity lowers the upstream pressures: more drop in the control stage, hotter
    # exhaust; the first stage moves it more than the last (measured +0.096 / +0.023 K per %)
    assert 0.0 < shift_last < shift_first < 0.5
    with pytest.raises(GeometryError, match="pressure stage 13 is not in turbine"):
        as_built_model(reference_model, 13, 1.0)


def test_control_stage_rotor_is_not_propagated(hp1_blade, reference_model) -> None:
    result = scan_uncertainty(hp1_blade, reference_model, samples=3, sections=2, random_state=1)
    # ±0.05 mm on a 12.6 mm throat: the area moves by well under 1 %
    assert np.all(np.abs(result.throat_area_ratio - 1.0) < 0.01)
    assert result.stage is None and result.propagation == CONTROL_STAGE_ROTOR
    assert result.hp_exhaust_temperature is None
    assert result.temperature_spread is None and result.max_deviation is None
    document = result.as_dict()
    assert document["hp_exhaust_temperature_max_deviation_K"] is None
    assert document["samples"] == 3 and document["stage"] is None


def test_pressure_row_goes_through_its_stage_alone(reference_spec, reference_model) -> None:
    blade = make_blade(reference_spec, "hp13")
    result = scan_uncertainty(blade, reference_model, samples=4, sections=2, random_state=1)
    assert result.stage == 12 and "stages[12].flow_capacity" in result.propagation
    assert result.nominal_hp_exhaust_temperature == pytest.approx(326.7 + 273.15, abs=0.05)
    for ratio, temperature in zip(result.throat_area_ratio, result.hp_exhaust_temperature,
                                  strict=True):
        assert temperature == _exhaust(as_built_model(reference_model, 12, float(ratio)))
    deviation = result.hp_exhaust_temperature - result.nominal_hp_exhaust_temperature
    assert result.max_deviation == pytest.approx(np.abs(deviation).max(), abs=1e-12)
    assert 0.0 < result.max_deviation < 0.3
    assert result.as_dict()["hp_exhaust_temperature_max_deviation_K"] == result.max_deviation
    # a larger flow capacity at fixed boundary pressures changes the exhaust temperature
    # monotonically: the samples order the same way by ratio and by temperature
    order_ratio = np.argsort(result.throat_area_ratio)
    diffs = np.diff(result.hp_exhaust_temperature[order_ratio])
    assert np.all(diffs >= -1e-9) or np.all(diffs <= 1e-9)
