"""Proper orthogonal decomposition of a snapshot matrix (rows = snapshots, columns = nodes).

The POD modes of mean-subtracted snapshots X − x̄ are its right singular vectors; the energy of
the first r modes is Σᵢ≤ᵣ σᵢ² / Σ σᵢ² (Holmes, Lumley & Berkooz, *Turbulence, Coherent
Structures, Dynamical Systems and Symmetry*, 1996, ch. 3). Three ways to the thin SVD:

* ``"thin"`` — LAPACK's economy SVD of the m × N matrix, O(m²·N);
* ``"snapshots"`` — Sirovich's method of snapshots (Q. Appl. Math. 45 (1987) 561): eigen-pairs
  of the m × m correlation matrix C = X·Xᵀ, modes Vᵀ·X/σ; cheapest when N ≫ m, accurate for the
  energetic modes kept (relative error ~ machine ε·σ₁²/σᵢ² in the smallest ones);
* ``"randomized"`` — Halko, Martinsson & Tropp, SIAM Rev. 53 (2011) 217, Alg. 4.4 + 5.1: a
  Gaussian sketch with oversampling 10 and two power iterations, for many snapshots.

Plain Euclidean inner product over the nodes (equal nodal weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SVD_METHODS = ("auto", "thin", "snapshots", "randomized")
RANDOMIZED_ABOVE = 1000  # snapshots; "auto" switches to the randomized SVD above this
OVERSAMPLING = 10
POWER_ITERATIONS = 2


@dataclass(frozen=True)
class PodBasis:
    """Mean (N,), singular values (k,), modes (k, N) with orthonormal rows, total energy."""

    mean: np.ndarray
    singular_values: np.ndarray
    modes: np.ndarray
    total_energy: float

    def modes_for_energy(self, energy: float) -> int:
        """Smallest r with Σᵢ≤ᵣ σᵢ² ≥ ``energy``·Σ σ² (at least 1)."""
        if self.total_energy <= 0.0:
            return 1
        cumulative = np.cumsum(self.singular_values**2) / self.total_energy
        r = int(np.searchsorted(cumulative, energy * (1.0 - 1e-12)) + 1)
        return min(max(r, 1), self.singular_values.size)


def pod(snapshots: np.ndarray, method: str = "auto", max_rank: int | None = None,
        random_state: int | np.random.Generator | None = 0) -> PodBasis:
    """POD of ``snapshots`` (m, N) after subtracting their mean.

    ``max_rank`` caps the modes kept (for ``"randomized"`` it sets the sketch: default
    min(m, 100)). ``random_state`` feeds the randomized sketch only.
    """
    if method not in SVD_METHODS:
        raise ValueError(f"method must be one of {SVD_METHODS}, got {method!r}")
    x = np.asarray(snapshots, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2:
        raise ValueError(f"snapshots must be a 2-D array of ≥ 2 rows, got shape {x.shape}")
    m, n = x.shape
    mean = x.mean(axis=0)
    centred = x - mean
    total = float(np.einsum("ij,ij->", centred, centred))
    if method == "auto":
        method = "randomized" if m > RANDOMIZED_ABOVE else ("snapshots" if n > 4 * m else "thin")
    if method == "thin":
        _, sigma, vt = np.linalg.svd(centred, full_matrices=False)
    elif method == "snapshots":
        correlation = centred @ centred.T
        eigenvalues, vectors = np.linalg.eigh(correlation)
        order = np.argsort(eigenvalues)[::-1]
        eigenvalues, vectors = eigenvalues[order], vectors[:, order]
        keep = eigenvalues > eigenvalues[0] * 1e-13 if eigenvalues[0] > 0 else eigenvalues > 0
        keep[0] = True
        sigma = np.sqrt(np.maximum(eigenvalues[keep], 0.0))
        vt = (vectors[:, keep].T @ centred) / np.where(sigma > 0, sigma, 1.0)[:, None]
    else:
        sigma, vt = _randomized_svd(centred, max_rank or min(m, 100), random_state)
    if max_rank is not None:
        sigma, vt = sigma[:max_rank], vt[:max_rank]
    return PodBasis(mean=mean, singular_values=sigma, modes=np.ascontiguousarray(vt),
                    total_energy=total)


def _randomized_svd(matrix: np.ndarray, rank: int, random_state: int | np.random.Generator | None
                    ) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(random_state)
    m, n = matrix.shape
    width = min(rank + OVERSAMPLING, m, n)
    sample = matrix.T @ rng.standard_normal((m, width))  # (N, width): range of the rows
    basis, _ = np.linalg.qr(sample)
    for _ in range(POWER_ITERATIONS):
        basis, _ = np.linalg.qr(matrix @ basis)
        basis, _ = np.linalg.qr(matrix.T @ basis)
    small = matrix @ basis  # (m, width)
    _, sigma, wt = np.linalg.svd(small, full_matrices=False)
    return sigma[:rank], (wt @ basis.T)[:rank]
