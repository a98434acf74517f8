"""The fatigue scalar (rotor/stress_points.py ``equivalent_stress``/``equivalent_direction``):
continuous where the von Mises stress signed by the dominant principal jumped, exact for
proportional paths, tensile positive."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.stress_points import StressState, equivalent_direction, equivalent_stress

# a groove-root-like proportional path: σ_r = τ = 0, σ_θ = σ_z/2 plus a standing hoop stress
SHAPE = np.array([0.0, 0.5, 1.0, 0.0])
STANDING = np.array([0.0, 120e6, 0.0, 0.0])


def _path(amplitudes: np.ndarray) -> np.ndarray:
    return STANDING + np.outer(amplitudes, SHAPE)


def _signed_by_dominant_principal(state: StressState) -> np.ndarray:
    """The scalar used before: von Mises signed by the largest-magnitude principal."""
    principal = state.principal
    largest = np.take_along_axis(principal, np.argmax(np.abs(principal), axis=-1)[..., None],
                                 axis=-1)[..., 0]
    return np.where(largest < 0.0, -1.0, 1.0) * state.von_mises


def _state(components: np.ndarray) -> StressState:
    return StressState.from_components(np.asarray(components).T)


def test_a_proportional_path_gives_the_asme_range_between_any_two_instants():
    amplitudes = np.linspace(-400e6, 300e6, 41)
    path = _path(amplitudes)
    direction = equivalent_direction(path)
    values = equivalent_stress(_state(path), direction)
    # ASME VIII-2 §5.5.3.2: the range is the von Mises stress of the component differences
    i, j = np.triu_indices(amplitudes.size, 1)
    asme = _state(path[i] - path[j]).von_mises
    np.testing.assert_allclose(np.abs(values[i] - values[j]), asme, rtol=1e-12, atol=1e-3)
    # tensile (growing hydrostatic stress) positive
    assert np.all(np.diff(values) > 0.0)


def test_the_scalar_is_continuous_where_the_dominant_principal_changes_sign():
    # the standing hoop stress and a compressive axial swing make |σ_θ| = |σ_z| near
    # σ_z = −σ_θ: the old scalar jumps by 2·σ_vM between neighbouring samples
    amplitudes = np.linspace(-400e6, 300e6, 7001)  # 0.1 MPa steps
    path = _path(amplitudes)
    state = _state(path)
    step = _state(np.diff(path, axis=0)).von_mises  # von Mises of each sample-to-sample change
    old_jumps = np.abs(np.diff(_signed_by_dominant_principal(state)))
    assert old_jumps.max() > 100e6 > 1000 * step.max()
    new = equivalent_stress(state, equivalent_direction(path))
    assert np.all(np.abs(np.diff(new)) <= step * (1 + 1e-12))


@settings(max_examples=60, deadline=None)
@given(arrays(float, (2, 4), elements=st.floats(-800e6, 800e6)),
       arrays(float, (30, 4), elements=st.floats(-500e6, 500e6)))
def test_a_change_of_the_scalar_never_exceeds_the_von_mises_of_the_change(pair, path):
    if np.ptp(path[:, :3] - path[:, :3].mean(axis=1, keepdims=True)) + np.ptp(path[:, 3]) < 1.0:
        return  # a hydrostatic-only path has no deviatoric direction
    direction = equivalent_direction(path)
    values = equivalent_stress(_state(pair), direction)
    change = _state(pair[1] - pair[0]).von_mises
    assert abs(values[1] - values[0]) <= change * (1 + 1e-9) + 1e-3
    # a unit deviator: the scalar of N itself is vM(N) = 1 (Pa per Pa)
    assert float(equivalent_stress(_state(direction[None, :]), direction)[0]) == (
        pytest.approx(1.0))


def test_bad_paths_and_directions_are_refused():
    with pytest.raises(RotorAreaError, match="does not vary"):
        equivalent_direction(np.tile(STANDING, (5, 1)))
    with pytest.raises(RotorAreaError, match=r"samples ≥ 2, 4"):
        equivalent_direction(np.zeros((5, 3)))
    with pytest.raises(RotorAreaError, match="deviator"):
        equivalent_stress(_state(STANDING[None, :]), SHAPE)  # trace ≠ 0
