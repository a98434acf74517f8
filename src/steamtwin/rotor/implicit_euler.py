"""Implicit-Euler transient of an :class:`AffineConduction`, properties at the mean temperature.

The full-order time integration the rotor ROM is trained on and compared with. Implicit
(backward) Euler on the semi-discrete system of :mod:`steamtwin.rotor.operators` (first order,
unconditionally stable; Hairer & Wanner, *Solving ODEs II*, 2nd ed., 1996, §IV.3):

    (M(T̄ⁿ)/Δt + K(T̄ⁿ) + Σ_g h_gⁿ⁺¹·H_g)·Tⁿ⁺¹ = M(T̄ⁿ)/Δt·Tⁿ + Σ_g h_gⁿ⁺¹·T_gⁿ⁺¹·b_g.

Temperature-dependent k(T) and ρc(T) enter through operators assembled at a few reference
temperatures and interpolated linearly in the heat-capacity-weighted mean temperature
T̄ = wᵀT, w = M₀·1 / (1ᵀ·M₀·1) (M₀ the mass at the first reference), lagged one step
(Picard linearisation; Zienkiewicz, Taylor & Zhu, 7th ed., 2013, §3.5). The reduced model
interpolates its projected operators the same way, so a ROM without truncation reproduces this
integrator to round-off. ``H_g`` and ``b_g`` are geometric (property-free) and are taken from the
first operator set. One reference temperature means frozen properties.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from steamtwin.cache import njit
from steamtwin.errors import RotorAreaError
from steamtwin.rotor.operators import AffineConduction

_STEADY_ITERATIONS = 50
_STEADY_TOLERANCE_K = 1e-10


@dataclass(frozen=True)
class SteamHistory:
    """Steam-side boundary conditions over a record at a fixed time step.

    Row k of ``htc`` (W/(m²·K)) and ``steam_temperature`` (K), one column per boundary group in
    the operators' group order, holds the conditions of the step that ends at (k + 1)·``dt``
    (s); implicit Euler evaluates them there.
    """

    htc: np.ndarray
    steam_temperature: np.ndarray
    dt: float

    def __post_init__(self) -> None:
        htc = np.ascontiguousarray(np.atleast_2d(np.asarray(self.htc, dtype=float)))
        steam = np.ascontiguousarray(np.atleast_2d(np.asarray(self.steam_temperature,
                                                              dtype=float)))
        if htc.ndim != 2 or htc.shape != steam.shape or htc.shape[0] == 0:
            raise RotorAreaError(f"steam history: htc {htc.shape} and steam_temperature "
                                 f"{steam.shape} must both be (steps ≥ 1, groups)")
        if not np.all(np.isfinite(htc)) or np.any(htc < 0.0):
            row = int(np.argwhere(~(np.isfinite(htc) & (htc >= 0.0)))[0, 0])
            raise RotorAreaError(f"steam history: htc must be finite and ≥ 0 W/(m²·K); row {row}"
                                 f" is {htc[row].tolist()}")
        if not np.all(np.isfinite(steam)) or np.any(steam <= 0.0):
            row = int(np.argwhere(~(np.isfinite(steam) & (steam > 0.0)))[0, 0])
            raise RotorAreaError(f"steam history: steam_temperature must be finite and > 0 K "
                                 f"(kelvin, not °C); row {row} is {steam[row].tolist()}")
        if not (np.isfinite(self.dt) and self.dt > 0.0):
            raise RotorAreaError(f"steam history: dt must be a positive number of seconds, "
                                 f"got {self.dt!r}")
        object.__setattr__(self, "htc", htc)
        object.__setattr__(self, "steam_temperature", steam)
        object.__setattr__(self, "dt", float(self.dt))

    @property
    def steps(self) -> int:
        """Number of time steps."""
        return self.htc.shape[0]


@dataclass(frozen=True)
class PropertyTable:
    """Conduction operators at ascending ``reference_temperatures`` (K), sharing H_g and b_g."""

    operators: tuple[AffineConduction, ...]
    reference_temperatures: np.ndarray

    @classmethod
    def build(cls, operators: AffineConduction | Sequence[AffineConduction],
              reference_temperatures: Sequence[float] | None = None) -> PropertyTable:
        """Validate one operator set (frozen properties) or several at reference temperatures."""
        if isinstance(operators, AffineConduction):
            operators = (operators,)
        operators = tuple(operators)
        if not operators:
            raise RotorAreaError("at least one AffineConduction is needed")
        if reference_temperatures is None:
            if len(operators) > 1:
                raise RotorAreaError(f"{len(operators)} operator sets need as many "
                                     "reference_temperatures (K)")
            reference_temperatures = [0.0]
        refs = np.asarray(reference_temperatures, dtype=float)
        if refs.shape != (len(operators),) or not np.all(np.isfinite(refs)) or (
                np.any(np.diff(refs) <= 0.0)):
            raise RotorAreaError(f"reference_temperatures {refs.tolist()} must be "
                                 f"{len(operators)} finite, strictly ascending values in K")
        first = operators[0]
        for ref, other in zip(refs, operators, strict=True):
            for name, matrix in [("mass", other.mass), ("stiffness", other.stiffness),
                                 *zip(other.groups, other.robin, strict=True)]:
                if abs(matrix - matrix.T).max() > 1e-12 * abs(matrix).max():
                    raise RotorAreaError(f"operators at {ref} K: {name} matrix is not "
                                         "symmetric (a Galerkin conduction matrix is)")
            if other.groups != first.groups or other.size != first.size:
                raise RotorAreaError(f"operators at {ref} K have groups {other.groups} and "
                                     f"{other.size} nodes; the first have {first.groups} and "
                                     f"{first.size}")
        return cls(operators, refs)

    @property
    def first(self) -> AffineConduction:
        """The operator set at the lowest reference temperature (its H_g, b_g are used)."""
        return self.operators[0]

    @property
    def mean_weights(self) -> np.ndarray:
        """w with T̄ = wᵀT the heat-capacity-weighted mean temperature (dimensionless, Σw = 1)."""
        capacity = self.first.mass @ np.ones(self.first.size)
        return capacity / capacity.sum()

    @cached_property
    def _pattern(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(indices, indptr, mass data (k, nnz), stiffness data (k, nnz), robin data (g, nnz))
        of every matrix on the union sparsity pattern, so a step combines plain arrays."""
        n = self.first.size
        matrices = ([op.mass for op in self.operators] + [op.stiffness for op in self.operators]
                    + list(self.first.robin))
        coo = [matrix.tocoo() for matrix in matrices]
        keys = np.unique(np.concatenate([m.row.astype(np.int64) * n + m.col for m in coo]))
        data = np.zeros((len(coo), keys.size))
        for row, m in zip(data, coo, strict=True):
            np.add.at(row, np.searchsorted(keys, m.row.astype(np.int64) * n + m.col), m.data)
        indptr = np.concatenate([[0], np.cumsum(np.bincount(keys // n, minlength=n))])
        k = len(self.operators)
        return keys % n, indptr, data[:k], data[k:2 * k], data[2 * k:]

    def system(self, mean_temperature: float, htc: np.ndarray,
               dt: float) -> tuple[sp.csc_matrix, sp.csr_matrix]:
        """(M/Δt + K + Σ h_g·H_g (W/K) in CSC, M (J/K)) with M and K interpolated at
        ``mean_temperature`` (K); ``dt`` = inf gives the steady operator. The matrices are
        symmetric (checked in :meth:`build`), so the CSR arrays serve as CSC."""
        indices, indptr, mass, stiffness, robin = self._pattern
        i, j, theta = bracket(mean_temperature, self.reference_temperatures)
        capacity = mass[i] if theta == 0.0 else (1.0 - theta) * mass[i] + theta * mass[j]
        conduction = (stiffness[i] if theta == 0.0
                      else (1.0 - theta) * stiffness[i] + theta * stiffness[j])
        shape = (self.first.size, self.first.size)
        return (sp.csc_matrix((capacity / dt + conduction + htc @ robin, indices, indptr),
                              shape=shape),
                sp.csr_matrix((capacity, indices, indptr), shape=shape))


@njit(cache=True, error_model="numpy")
def bracket(mean_temperature: float, references: np.ndarray) -> tuple[int, int, float]:
    """(i, j, θ) with the property at ``mean_temperature`` = (1−θ)·value[i] + θ·value[j]:
    linear between the bracketing references, constant beyond the first and last."""
    last = references.shape[0] - 1
    if last == 0 or mean_temperature <= references[0]:
        return 0, 0, 0.0
    if mean_temperature >= references[last]:
        return last, last, 0.0
    i = 0
    while references[i + 1] < mean_temperature:
        i += 1
    return i, i + 1, (mean_temperature - references[i]) / (references[i + 1] - references[i])


def steady_field(solve: Callable[[float], np.ndarray], mean: Callable[[np.ndarray], float],
                 start_mean_k: float) -> np.ndarray:
    """Fixed point T = solve(T̄(T)) of a steady state whose properties follow its mean
    temperature (Picard iteration from ``start_mean_k``, K); one solve for frozen properties."""
    field = solve(start_mean_k)
    for _ in range(_STEADY_ITERATIONS):
        previous = mean(field)
        field = solve(previous)
        if abs(mean(field) - previous) < _STEADY_TOLERANCE_K:
            return field
    raise RotorAreaError(f"the steady state's mean temperature did not settle within "
                         f"{_STEADY_ITERATIONS} iterations")


def steam_mean_temperature(htc: np.ndarray, steam_temperature: np.ndarray) -> float:
    """The htc-weighted mean steam temperature (K), the steady iteration's start."""
    if not np.sum(htc) > 0.0:
        raise RotorAreaError("a steady state needs a positive htc on at least one group "
                             f"(got {np.asarray(htc).tolist()} W/(m²·K))")
    return float(np.sum(htc * steam_temperature) / np.sum(htc))


def full_order_run(operators: AffineConduction | Sequence[AffineConduction],
                   history: SteamHistory, *,
                   reference_temperatures: Sequence[float] | None = None,
                   initial: np.ndarray | None = None) -> np.ndarray:
    """Nodal temperatures (K), shape (steps + 1, nodes): row 0 the ``initial`` field (default:
    the steady state at the history's first conditions), row k + 1 after step k."""
    table = PropertyTable.build(operators, reference_temperatures)
    first = table.first
    if history.htc.shape[1] != len(first.groups):
        raise RotorAreaError(f"steam history has {history.htc.shape[1]} groups, the operators "
                             f"{len(first.groups)} ({', '.join(first.groups)})")
    weights = table.mean_weights
    if initial is None:
        htc0, steam0 = history.htc[0], history.steam_temperature[0]

        def solve(mean_k: float) -> np.ndarray:
            return spla.spsolve(table.system(mean_k, htc0, np.inf)[0], first.load(htc0, steam0))

        field = steady_field(solve, weights.__matmul__, steam_mean_temperature(htc0, steam0))
    else:
        field = np.asarray(initial, dtype=float)
        if field.shape != (first.size,):
            raise RotorAreaError(f"initial field has shape {field.shape}, expected "
                                 f"({first.size},) nodal temperatures in K")
    fields = np.empty((history.steps + 1, first.size))
    fields[0] = field
    factored, factor = np.empty(0), None
    for k in range(history.steps):
        htc, steam = history.htc[k], history.steam_temperature[k]
        matrix, mass = table.system(float(weights @ field), htc, history.dt)
        if not np.array_equal(matrix.data, factored):  # a hold with frozen properties reuses it
            factored, factor = matrix.data, spla.splu(matrix, permc_spec="MMD_AT_PLUS_A")
        field = factor.solve(mass @ field / history.dt + first.load(htc, steam))
        fields[k + 1] = field
    return fields
