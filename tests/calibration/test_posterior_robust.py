"""The cluster-robust (leave-one-band-out jackknife) covariance on linear models whose
sampling distribution is known: a misspecified one, where every cluster carries its own
discrepancy (a random intercept and slope), and a correctly specified one, where it must agree
with the Laplace (Gauss–Newton) covariance within its sampling error."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import t as student_t

from steamtwin.calibration.posterior import cluster_robust_covariance

SLOPE = 2.0
SIGMA = 0.3


def _draw(random: np.random.Generator, *, discrepancy: float, clusters: int = 10,
          per_cluster: int = 40, shifted: bool = True):
    """y = 1 + 2x + ε (σ 0.3) plus, per cluster, a discrepancy a_g + b_g·x (a, b ~
    N(0, discrepancy²)) the fitted line cannot represent; OLS fit. Returns the slope, its
    cluster-robust variance, its Laplace variance (σ²(XᵀX)⁻¹ times the Birge ratio²) and G."""
    shift = random.uniform(-1.0, 1.0, (clusters, 1)) if shifted else 0.0
    x = random.uniform(0.0, 1.0, (clusters, per_cluster)) + shift
    y = 1.0 + SLOPE * x + SIGMA * random.standard_normal(x.shape)
    y += discrepancy * (random.standard_normal((clusters, 1))
                        + random.standard_normal((clusters, 1)) * x)
    design = np.column_stack([np.ones(x.size), x.ravel()])
    beta = np.linalg.lstsq(design, y.ravel(), rcond=None)[0]
    residuals = (design @ beta - y.ravel()) / SIGMA
    jacobian = design / SIGMA
    labels = np.repeat(np.arange(clusters), per_cluster)
    robust, names, _ = cluster_robust_covariance(jacobian, residuals, labels,
                                                     np.zeros((2, 2)))
    assert len(names) == clusters
    birge = max(1.0, residuals @ residuals / (residuals.size - 2))
    laplace = birge * np.linalg.inv(jacobian.T @ jacobian)
    return beta[1], robust[1, 1], laplace[1, 1], clusters


def _coverage(discrepancy: float, draws: int, shifted: bool = True):
    random = np.random.default_rng(11)
    robust = laplace = 0
    ratios = []
    for _ in range(draws):
        slope, v_robust, v_laplace, g = _draw(random, discrepancy=discrepancy, shifted=shifted)
        robust += abs(slope - SLOPE) <= student_t.ppf(0.975, g - 1) * np.sqrt(v_robust)
        laplace += abs(slope - SLOPE) <= 1.96 * np.sqrt(v_laplace)
        ratios.append(v_robust / v_laplace)
    return robust / draws, laplace / draws, np.array(ratios)


def test_robust_intervals_cover_a_misspecified_model_where_laplace_does_not():
    robust, laplace, ratios = _coverage(discrepancy=0.5, draws=300)
    # 95 % nominal; 300 draws give a binomial standard error of 1.3 %
    assert robust >= 0.91, robust
    assert laplace <= 0.5, laplace  # the Birge ratio cannot see that clusters repeat an error
    assert np.median(ratios) > 10.0


def test_robust_covariance_reduces_to_laplace_for_a_correct_model():
    robust, laplace, ratios = _coverage(discrepancy=0.0, draws=300, shifted=False)
    assert 0.92 <= robust <= 0.99 and 0.92 <= laplace <= 0.99, (robust, laplace)
    # the jackknife variance scatters by ≈ √(2/(G − 1)) ≈ 0.47 about the Laplace one
    assert 0.9 <= np.mean(ratios) <= 1.25, np.mean(ratios)
    assert 0.3 <= np.std(ratios) <= 0.7, np.std(ratios)


def test_each_shift_is_the_estimate_without_that_cluster():
    """For a linear model the one-step leave-one-cluster-out shift is exact, and with a prior
    it is the penalised refit's."""
    random = np.random.default_rng(3)
    design = np.column_stack([np.ones(60), random.uniform(0.0, 1.0, 60)])
    y = design @ [1.0, 2.0] + random.normal(0.0, 0.5, 60)
    labels = np.repeat(["a", "b", "c"], 20)
    prior = np.diag([0.5, 2.0])
    weight = 0.7

    def fit(keep: np.ndarray) -> np.ndarray:  # argmin weight·‖Xb − y‖²/2 + bᵀPb/2
        x = design[keep]
        return np.linalg.solve(weight * x.T @ x + prior, weight * x.T @ y[keep])

    everything = fit(np.ones(60, bool))
    shifts = np.array([fit(labels != name) - everything for name in ("a", "b", "c")])
    covariance, names, moved = cluster_robust_covariance(design, design @ everything - y,
                                                         labels, prior, weight=weight)
    assert names == ("a", "b", "c")
    np.testing.assert_allclose(moved, shifts, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(covariance, 2.0 / 3.0 * shifts.T @ shifts, rtol=1e-10)


def test_rows_without_a_cluster_count_in_the_bread_only_and_bad_input_is_named():
    design = np.column_stack([np.ones(6), np.arange(6.0)])
    residuals = np.array([0.1, -0.2, 0.3, -0.1, 0.2, 0.0])
    with_none, _, _ = cluster_robust_covariance(design, residuals, [0, 0, 1, 1, 2, None],
                                             np.zeros((2, 2)))
    assert np.isfinite(with_none).all()
    with pytest.raises(ValueError, match="at least 2 clusters"):
        cluster_robust_covariance(design, residuals, [0] * 6, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="5 labels, 6 residuals"):
        cluster_robust_covariance(design, residuals, [0, 1, 2, 0, 1], np.zeros((2, 2)))
