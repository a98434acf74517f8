"""The span model's robust solver (geometry/edge_span.py ``_robust_lm``) and the circle fit's
radius grid evaluated at once (geometry/edge_circle.py).

The span model's fit was scipy ``least_squares`` (trust-region reflective, LSMR steps), 22 s of
slender 80k's 39-s reconstruction with most fits stopping at their 60 evaluations; it is now a
banded Levenberg–Marquardt on the reweighted normal equations (2026-11-28). Here on a small
problem with a known optimum: a banded linear model whose data hold a few gross outliers, one
coefficient bounded short of its value.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import sparse
from scipy.interpolate import BSpline

from steamtwin.geometry import edge_span
from steamtwin.geometry.edge_circle import edge_distance_at, tangent_centre
from steamtwin.geometry.edge_span import _interleaved, _robust_lm, span_knots


def banded_problem(seed: int = 0) -> tuple:
    """Five cubic B-spline functions of z (the span model's layout: field-major
    coefficients), each sampled at 400 heights with noise 1e-3 of its scale and 2 % of the
    samples 50 scales off; the residuals in units of the noise. Returns (function, jacobian,
    true coefficients, count)."""
    rng = np.random.default_rng(seed)
    knots = span_knots((0.0, 20e-3))
    z = rng.uniform(0.0, 20e-3, 400)
    basis = BSpline.design_matrix(z, knots, 3).tocsr()
    count = basis.shape[1]
    truth = rng.normal(0.0, 1.0, 5 * count)
    design = sparse.block_diag([basis] * 5).tocsr()
    noise = 1e-3
    data = design @ truth + rng.normal(0.0, noise, design.shape[0])
    stray = rng.uniform(size=design.shape[0]) < 0.02
    data[stray] += 50.0 * noise * np.sign(rng.normal(size=stray.sum()))

    def function(x: np.ndarray) -> np.ndarray:
        return (design @ x - data) / noise

    def jacobian(_: np.ndarray) -> sparse.csr_matrix:
        return design / noise

    return function, jacobian, truth, count


def test_the_robust_fit_reaches_the_optimum_despite_outliers_and_holds_a_bound() -> None:
    """From zero the fit recovers every coefficient within 1e-2 (the noise and 2 % strays
    50 noise off; least squares without the soft-L1 loss is off by more), within few
    evaluations (converged, not stopped by the limit); a coefficient whose upper bound lies
    0.5 below its value ends at that bound, the others as before."""
    function, jacobian, truth, count = banded_problem()
    calls = []

    def counted(x: np.ndarray) -> np.ndarray:
        calls.append(1)
        return function(x)

    free = (np.full(truth.size, -np.inf), np.full(truth.size, np.inf))
    x = _robust_lm(counted, jacobian, np.zeros_like(truth), free, np.ones(truth.size),
                   _interleaved(count))
    assert np.abs(x - truth).max() < 1e-2
    assert len(calls) < edge_span.MAX_EVALUATIONS
    plain = np.linalg.lstsq(jacobian(x).toarray(), -function(np.zeros_like(truth)),
                            rcond=None)[0]
    assert np.abs(plain - truth).max() > np.abs(x - truth).max()
    bounded = count + 3
    upper = free[1].copy()
    upper[bounded] = truth[bounded] - 0.5
    x = _robust_lm(function, jacobian, np.zeros_like(truth), (free[0], upper),
                   np.ones(truth.size), _interleaved(count))
    assert x[bounded] == upper[bounded]
    far = np.abs(np.arange(truth.size) - bounded) > 8  # beyond the bounded one's reach
    assert np.abs(x - truth)[far].max() < 1e-2


def test_the_distance_of_a_grid_of_radii_is_that_of_each_radius() -> None:
    """``edge_distance_at`` with one centre and radius per grid row (the circle fit's grid,
    every radius at once) gives exactly each radius's own distances, sector and line."""
    rng = np.random.default_rng(3)
    half = math.radians(8.0)
    normals = np.array([[-math.sin(half), math.cos(half)], [-math.sin(half), -math.cos(half)]])
    xy = rng.uniform(-2e-3, 0.5e-3, (200, 2))
    offsets = np.tile([-0.2e-3, -0.2e-3], (200, 1)) + rng.normal(0.0, 1e-6, (200, 2))
    grid = np.linspace(0.01e-3, 0.6e-3, 7)
    centres = np.linalg.solve(normals, offsets.T[None] + grid[:, None, None]).transpose(0, 2, 1)
    together = edge_distance_at(xy, centres, grid[:, None], normals)
    for k, r in enumerate(grid):
        alone = edge_distance_at(xy, tangent_centre(normals, offsets, r), r, normals)
        for a, b in zip(alone, together, strict=True):
            assert np.array_equal(a, b[k])
