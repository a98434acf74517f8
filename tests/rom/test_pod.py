"""POD: the three SVD routes agree; energy truncation; orthonormal modes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.rom.pod import pod


def low_rank(m: int, n: int, rank: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.standard_normal((n, rank)))
    sigma = 10.0 ** -np.arange(rank)
    coefficients = rng.standard_normal((m, rank)) * sigma
    return 500.0 + coefficients @ q.T, sigma


@pytest.mark.parametrize("method", ["thin", "snapshots", "randomized"])
def test_methods_agree_with_numpy_svd(method):
    data, _ = low_rank(40, 3000, 5)
    basis = pod(data, method=method, max_rank=5, random_state=1)
    centred = data - data.mean(axis=0)
    reference = np.linalg.svd(centred, compute_uv=False)[:5]
    np.testing.assert_allclose(basis.singular_values, reference, rtol=1e-6)
    np.testing.assert_allclose(basis.modes @ basis.modes.T, np.eye(5), atol=1e-8)
    # the modes span the data: projection error at round-off
    residual = centred - (centred @ basis.modes.T) @ basis.modes
    assert np.abs(residual).max() < 1e-8 * np.abs(centred).max()


@settings(max_examples=25, deadline=None)
@given(energy=st.floats(0.5, 0.999999))
def test_energy_truncation_is_the_smallest_sufficient_rank(energy):
    data, _ = low_rank(30, 200, 6, seed=2)
    basis = pod(data, method="thin")
    r = basis.modes_for_energy(energy)
    captured = np.cumsum(basis.singular_values**2) / basis.total_energy
    assert captured[r - 1] >= energy * (1 - 1e-12)
    assert r == 1 or captured[r - 2] < energy


def test_refuses_bad_input():
    with pytest.raises(ValueError, match="method"):
        pod(np.ones((3, 4)), method="qr")
    with pytest.raises(ValueError, match="2-D"):
        pod(np.ones(4))
