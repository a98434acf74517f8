"""Transient reduced-order model of the rotor conduction: POD–Galerkin on an AffineConduction.

(About 530 lines: the compiled kernel, the estimator and its file format share the reduced
arrays' layout, so they stay in one module; the full-order integrator is its own.)

**Why POD–Galerkin, not balanced truncation.** The rotor system
M·dT/dt + (K + Σ_g h_g(t)·H_g)·T = Σ_g h_g·T_g·b_g is *bilinear*: the heat-transfer
coefficients multiply the state. Balanced truncation (Moore, IEEE TAC 26 (1981) 17) balances
the Gramians of one linear time-invariant system, so it would hold for one frozen h only (or
need bilinear Gramians, costly and without the error bound). A Galerkin projection on a
snapshot basis keeps the affine h-dependence exactly, operator by operator (Rozza, Huynh &
Patera, Arch. Comput. Methods Eng. 15 (2008) 229), and the basis sees the h-range of real ramps.

**Basis.** Proper orthogonal decomposition (Holmes, Lumley & Berkooz, *Turbulence, Coherent
Structures, Dynamical Systems and Symmetry*, 1996, ch. 3) of implicit-Euler full-order runs on
training ramps (:func:`full_order_run`), in the thermal-energy inner product ⟨u, v⟩ = uᵀM₀v. The
uniform field 1 is always the first mode and the snapshots' uniform part is removed before the
POD, so the ROM keeps the FEM's exact invariants: the global energy balance and "uniform steam
→ uniform metal" (the P1 functions sum to one: K·1 = 0, H_g·1 = b_g). The POD runs as a
Euclidean thin SVD followed by an M₀-weighted SVD in its range, which keeps the small singular
values accurate (no Gram matrix that would square their condition number). Truncation keeps the
fewest modes carrying a fraction ``energy`` of the snapshots' M₀-energy, then, with
``tolerance`` (K), the fewest of those whose ROM reproduces the training runs within it at the
temperature nodes (all nodes if none) — an error-based choice, cheap since ROM runs take µs
per step.

**Reduced system.** With the M₀-orthonormal basis V (n × r): M_r,k = VᵀM_kV and K_r,k = VᵀK_kV at
each reference temperature k, H_g^r = VᵀH_gV, b_g^r = Vᵀb_g, precomputed once; each step
interpolates M_r, K_r in the mean temperature (as :mod:`steamtwin.rotor.implicit_euler`; one
common basis, so the reduced operators interpolate consistently — the condition Amsallem &
Farhat, AIAA J. 46 (2008) 1803, meet by congruence transforms), forms the r × r SPD matrix
M_r/Δt + K_r + Σ h_g·H_g^r and solves it by Cholesky (Golub & Van Loan, *Matrix Computations*,
4th ed., 2013, §4.2): about r³/6 flops, so no factorisation needs caching even when h varies
every step. Outputs are linear maps of the reduced coordinates: temperatures at chosen nodes
(rows of V) and y = S·T + s₀ for a user's linear output operator S (e.g. stresses in Pa at the
critical points from the thermo-elastic solver). A ROM with every mode reproduces the
full-order integrator to round-off (the Galerkin solution is unique and the FEM's lies in the
span). The batch loop and the streaming step run the same compiled kernel, so they agree bit
for bit.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from steamtwin.cache import njit
from steamtwin.errors import RotorAreaError
from steamtwin.progress import ProgressCallback
from steamtwin.rotor.implicit_euler import (
    PropertyTable,
    SteamHistory,
    bracket,
    full_order_run,
    steady_field,
    steam_mean_temperature,
)
from steamtwin.rotor.operators import AffineConduction

__all__ = ["ConductionRom", "RomRun", "RomState", "SteamHistory", "full_order_run"]

FORMAT = "steamtwin-rotor-conduction-rom"
FORMAT_VERSION = 1
_RANK_TOLERANCE = 1e-13
"""Relative singular value below which a snapshot direction counts as numerically absent."""


@dataclass(frozen=True)
class RomState:
    """The ROM's carried state: reduced coordinates (K·√(J/K), the field's components in the
    M₀-orthonormal basis) and the time ``time_s`` (s) since the start."""

    coordinates: np.ndarray
    time_s: float = 0.0

    def to_dict(self) -> dict[str, object]:
        """A JSON-ready dict; floats round-trip exactly through ``json``."""
        return {"coordinates": [float(c) for c in self.coordinates], "time_s": float(self.time_s)}

    @classmethod
    def from_dict(cls, data: dict[str, object]) -> RomState:
        """The state :meth:`to_dict` wrote, bit for bit."""
        try:
            coordinates = np.array(data["coordinates"], dtype=float)
            time_s = float(data["time_s"])  # type: ignore[arg-type]
        except (KeyError, TypeError, ValueError) as error:
            raise RotorAreaError(f"ROM state: expected {{'coordinates': [floats], 'time_s': "
                                 f"float}}, got {error!r}") from None
        return cls(coordinates, time_s)


@dataclass(frozen=True)
class RomRun:
    """A batch run: ``temperature`` (K) at the temperature nodes and ``output`` (the output
    operator's unit, e.g. Pa), one row per step (after it); ``final`` state to continue from."""

    temperature: np.ndarray
    output: np.ndarray
    final: RomState


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _cholesky_solve(matrix: np.ndarray, rhs: np.ndarray) -> None:
    """Solve matrix·x = rhs for SPD ``matrix`` in place (x into ``rhs``; lower triangle of
    ``matrix`` overwritten by its Cholesky factor; Golub & Van Loan §4.2.5)."""
    n = rhs.shape[0]
    for j in range(n):
        diagonal = matrix[j, j]
        for k in range(j):
            diagonal -= matrix[j, k] * matrix[j, k]
        diagonal = np.sqrt(diagonal)
        matrix[j, j] = diagonal
        for i in range(j + 1, n):
            value = matrix[i, j]
            for k in range(j):
                value -= matrix[i, k] * matrix[j, k]
            matrix[i, j] = value / diagonal
    for i in range(n):
        value = rhs[i]
        for k in range(i):
            value -= matrix[i, k] * rhs[k]
        rhs[i] = value / matrix[i, i]
    for i in range(n - 1, -1, -1):
        value = rhs[i]
        for k in range(i + 1, n):
            value -= matrix[k, i] * rhs[k]
        rhs[i] = value / matrix[i, i]


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _observe(coordinates: np.ndarray, outputs: np.ndarray, offset: np.ndarray,
             references: np.ndarray, mean_weights: np.ndarray, out: np.ndarray,
             row: int) -> None:
    """out[row] = outputs·coordinates + offset, both interpolated in the mean temperature of
    ``coordinates`` like the conduction operators."""
    mean = 0.0
    for p in range(coordinates.shape[0]):
        mean += mean_weights[p] * coordinates[p]
    i, j, theta = bracket(mean, references)
    for o in range(outputs.shape[1]):
        low, high = offset[i, o], offset[j, o]
        for p in range(coordinates.shape[0]):
            low += outputs[i, o, p] * coordinates[p]
            high += outputs[j, o, p] * coordinates[p]
        out[row, o] = (1.0 - theta) * low + theta * high


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _advance(coordinates: np.ndarray, htc: np.ndarray, steam_temperature: np.ndarray, dt: float,
             references: np.ndarray, mass: np.ndarray, stiffness: np.ndarray,
             robin: np.ndarray, load: np.ndarray, mean_weights: np.ndarray,
             outputs: np.ndarray, offset: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Implicit-Euler steps of the reduced system (module docstring); outputs into ``out``."""
    r = coordinates.shape[0]
    groups = robin.shape[0]
    state = coordinates.copy()
    matrix = np.empty((r, r))
    rhs = np.empty(r)
    for step in range(htc.shape[0]):
        mean = 0.0
        for p in range(r):
            mean += mean_weights[p] * state[p]
        i, j, theta = bracket(mean, references)
        for p in range(r):
            value_rhs = 0.0
            for q in range(r):
                capacity = ((1.0 - theta) * mass[i, p, q] + theta * mass[j, p, q]) / dt
                value_rhs += capacity * state[q]
                value = capacity + (1.0 - theta) * stiffness[i, p, q] + theta * stiffness[j, p, q]
                for g in range(groups):
                    value += htc[step, g] * robin[g, p, q]
                matrix[p, q] = value
            for g in range(groups):
                value_rhs += htc[step, g] * steam_temperature[step, g] * load[g, p]
            rhs[p] = value_rhs
        _cholesky_solve(matrix, rhs)
        for p in range(r):
            state[p] = rhs[p]
        _observe(state, outputs, offset, references, mean_weights, out, step)
    return state


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def _checked_step(coordinates: np.ndarray, htc: np.ndarray, steam_temperature: np.ndarray,
                  dt: float, references: np.ndarray, mass: np.ndarray, stiffness: np.ndarray,
                  robin: np.ndarray, load: np.ndarray,
                  mean_weights: np.ndarray) -> np.ndarray:
    """One :func:`_advance` step after the checks of :class:`SteamHistory` (finite, htc ≥ 0,
    T > 0 K, dt > 0 s); an empty array if they fail. One compiled call keeps the streaming step
    within its µs budget (each argument a Python call passes costs a fraction of one)."""
    for g in range(htc.shape[0]):
        if not (np.isfinite(htc[g]) and htc[g] >= 0.0 and np.isfinite(steam_temperature[g])
                and steam_temperature[g] > 0.0):
            return np.empty(0)
    if not (np.isfinite(dt) and dt > 0.0):
        return np.empty(0)
    return _advance(coordinates, htc.reshape(1, -1), steam_temperature.reshape(1, -1), dt,
                    references, mass, stiffness, robin, load, mean_weights,
                    np.empty((1, 0, coordinates.shape[0])), np.empty((1, 0)), np.empty((1, 0)))


def _m_orthonormal(basis: np.ndarray, mass: sp.spmatrix) -> np.ndarray:
    """The same span, orthonormal in uᵀ·mass·v (Cholesky QR; first column kept in direction)."""
    factor = la.cholesky(basis.T @ (mass @ basis), lower=True)
    return la.solve_triangular(factor, basis.T, lower=True).T


def _pod(snapshots: np.ndarray, mass: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    """Basis [uniform, POD modes …] (n × (1 + q)), M-orthonormal, and the M-singular values."""
    n = snapshots.shape[0]
    uniform = np.ones(n) / np.sqrt(np.ones(n) @ (mass @ np.ones(n)))
    varying = snapshots - np.outer(uniform, uniform @ (mass @ snapshots))
    directions, values, _ = la.svd(varying, full_matrices=False)
    directions = directions[:, values > values[0] * _RANK_TOLERANCE] if values[0] > 0 else (
        directions[:, :0])
    factor = la.cholesky(directions.T @ (mass @ directions), lower=True)
    left, singular, _ = la.svd(factor.T @ (directions.T @ varying), full_matrices=False)
    modes = directions @ la.solve_triangular(factor.T, left, lower=False)
    return _m_orthonormal(np.column_stack([uniform, modes]), mass), singular


def _output_map(operator: np.ndarray | sp.spmatrix | None, offset: np.ndarray | None,
                n: int, references: int) -> tuple[np.ndarray, np.ndarray]:
    """The output operator S (references × outputs × n, dense) and offset s₀ (references ×
    outputs), validated; one S (outputs × n) serves every reference temperature."""
    if operator is None:
        if offset is not None:
            raise RotorAreaError("output_offset given without an output_operator")
        return np.zeros((references, 0, n)), np.zeros((references, 0))
    matrix = operator.toarray() if sp.issparse(operator) else np.asarray(operator, dtype=float)
    if matrix.ndim == 2:
        matrix = np.broadcast_to(matrix, (references, *matrix.shape))
    if matrix.ndim != 3 or matrix.shape[0] != references or matrix.shape[2] != n or not np.all(
            np.isfinite(matrix)):
        raise RotorAreaError(f"output_operator has shape {np.shape(operator)}; expected finite "
                             f"(outputs, {n}) or ({references}, outputs, {n}) — one per "
                             "reference temperature — mapping nodal temperatures (K) to outputs")
    shape = matrix.shape[:2]
    shift = np.zeros(shape) if offset is None else np.asarray(offset, dtype=float)
    if shift.shape not in (shape, shape[1:]) or not np.all(np.isfinite(shift)):
        raise RotorAreaError(f"output_offset has shape {shift.shape}, expected finite "
                             f"({shape[1]},) or {shape} like the output_operator")
    return matrix, np.broadcast_to(shift, shape)


_ARRAYS = ("modes_", "projector_", "reference_temperatures_", "reduced_mass_",
           "reduced_stiffness_", "reduced_robin_", "reduced_load_", "mean_weights_",
           "temperature_nodes_", "output_matrix_", "output_offset_", "singular_values_")


class ConductionRom:
    """POD–Galerkin ROM of an :class:`AffineConduction` transient (module docstring).

    ``energy``: fraction of the snapshots' non-uniform M₀-energy the POD modes keep (1.0: all);
    ``max_modes``: cap on the modes (the uniform one included); ``tolerance``: if set, the
    fewest modes whose training runs stay within it (K) at the temperature nodes (if none does,
    all the energy criterion's, and ``training_error_`` says by how much it was missed);
    ``max_snapshots``: evenly spaced columns the POD reads at most (its thin SVD costs
    nodes × snapshots²; 1-s snapshots of a rotor are nearly collinear), ``None`` for all — a ROM
    with every mode then reproduces its training runs to round-off.
    """

    def __init__(self, energy: float = 1.0 - 1e-9, max_modes: int | None = None,
                 tolerance: float | None = None, max_snapshots: int | None = 2000) -> None:
        self.energy = energy
        self.max_modes = max_modes
        self.tolerance = tolerance
        self.max_snapshots = max_snapshots

    # --- fit -------------------------------------------------------------------------------
    def fit(self, operators: AffineConduction | Sequence[AffineConduction],
            training: Sequence[SteamHistory], *,
            reference_temperatures: Sequence[float] | None = None,
            temperature_nodes: Sequence[int] = (),
            output_operator: np.ndarray | sp.spmatrix | None = None,
            output_offset: np.ndarray | None = None,
            snapshots: Sequence[np.ndarray] = (),
            progress: ProgressCallback | None = None) -> ConductionRom:
        """Run the full order on each ``training`` history, build the basis and the reduced
        operators. ``operators`` at ascending ``reference_temperatures`` (K) make properties
        follow the mean temperature. ``output_operator`` (outputs × nodes) with
        ``output_offset`` gives y = S·T + s₀. Extra ``snapshots`` (nodes × m, K, e.g. from a FEM
        with local properties) join the training runs'. Returns ``self``."""
        if not 0.0 < self.energy <= 1.0:
            raise RotorAreaError(f"energy must lie in (0, 1], got {self.energy!r}")
        if self.max_modes is not None and self.max_modes < 1:
            raise RotorAreaError(f"max_modes must be ≥ 1, got {self.max_modes!r}")
        if self.max_snapshots is not None and self.max_snapshots < 2:
            raise RotorAreaError(f"max_snapshots must be ≥ 2 or None, got {self.max_snapshots!r}")
        if self.tolerance is not None and not self.tolerance > 0.0:
            raise RotorAreaError(f"tolerance must be a positive number of kelvin, "
                                 f"got {self.tolerance!r}")
        table = PropertyTable.build(operators, reference_temperatures)
        n = table.first.size
        nodes = np.asarray(temperature_nodes, dtype=np.int64).reshape(-1)
        if np.any((nodes < 0) | (nodes >= n)):
            raise RotorAreaError(f"temperature_nodes must be node indices in [0, {n}), got "
                                 f"{nodes[(nodes < 0) | (nodes >= n)].tolist()}")
        stress, stress_offset = _output_map(output_operator, output_offset, n,
                                            len(table.operators))
        if not training and not snapshots:
            raise RotorAreaError("fit needs at least one training history or snapshot block")
        runs = []
        for index, history in enumerate(training):
            if progress is not None:
                progress(0.9 * index / len(training), f"full-order training run {index + 1}")
            runs.append(full_order_run(table.operators, history,
                                       reference_temperatures=table.reference_temperatures))
        extra = [np.asarray(block, dtype=float) for block in snapshots]
        for index, block in enumerate(extra):
            if block.ndim != 2 or block.shape[0] != n or not np.all(np.isfinite(block)):
                raise RotorAreaError(f"snapshots[{index}] has shape {block.shape}; expected "
                                     f"finite ({n}, columns) nodal temperatures in K")
        columns = np.hstack([run.T for run in runs] + extra)
        if self.max_snapshots is not None and columns.shape[1] > self.max_snapshots:
            columns = columns[:, np.linspace(0, columns.shape[1] - 1, self.max_snapshots).round()
                              .astype(np.int64)]
        basis, singular = _pod(columns, table.first.mass)
        self.singular_values_ = singular
        self._project(table, basis, nodes, stress, stress_offset)
        energy_rank = self._energy_rank(singular)
        self.training_error_ = np.inf
        checks = [(history, run[1:, nodes] if nodes.size else run[1:])
                  for history, run in zip(training, runs, strict=True)]
        ranks = range(1, energy_rank + 1) if self.tolerance is not None else [energy_rank]
        for rank in ranks:
            self._set_rank(rank)
            error = max((self._training_error(history, reference, nodes)
                         for history, reference in checks), default=np.nan)
            self.training_error_ = error
            if self.tolerance is None or error <= self.tolerance:
                break
        if progress is not None:
            progress(1.0, f"{self.n_modes_} modes, training error {self.training_error_:.3g} K")
        return self

    def _energy_rank(self, singular: np.ndarray) -> int:
        energy = np.cumsum(singular ** 2)
        kept = singular.size if self.energy >= 1.0 or not energy.size else min(
            int(np.searchsorted(energy / energy[-1], self.energy)) + 1, singular.size)
        rank = 1 + kept
        return rank if self.max_modes is None else min(rank, self.max_modes)

    def _project(self, table: PropertyTable, basis: np.ndarray, nodes: np.ndarray,
                 stress: np.ndarray, stress_offset: np.ndarray) -> None:
        first = table.first
        self.groups_ = first.groups
        self.reference_temperatures_ = table.reference_temperatures
        self.modes_ = basis
        self.projector_ = np.asarray(first.mass @ basis)
        self.reduced_mass_ = np.stack([basis.T @ (op.mass @ basis) for op in table.operators])
        self.reduced_stiffness_ = np.stack([basis.T @ (op.stiffness @ basis)
                                            for op in table.operators])
        self.reduced_robin_ = np.stack([basis.T @ (h @ basis) for h in first.robin])
        self.reduced_load_ = np.stack([basis.T @ b for b in first.robin_load])
        self.mean_weights_ = table.mean_weights @ basis
        self.temperature_nodes_ = nodes
        references = len(table.operators)
        self.output_matrix_ = np.stack([np.vstack([basis[nodes], matrix @ basis])
                                        for matrix in stress])
        self.output_offset_ = np.hstack([np.zeros((references, nodes.size)), stress_offset])

    def _training_error(self, history: SteamHistory, reference: np.ndarray,
                        nodes: np.ndarray) -> float:
        rows = self.modes_[nodes] if nodes.size else self.modes_
        out = np.empty((history.steps, rows.shape[0]))
        start = self.initial_state(history.htc[0], history.steam_temperature[0])
        rows = rows[:, :self.n_modes_]
        references = self.reference_temperatures_.size  # the kernel reads one block per reference
        self._kernel(start.coordinates, history,
                     np.ascontiguousarray(np.broadcast_to(rows, (references, *rows.shape))),
                     np.zeros((references, rows.shape[0])), out)
        return float(np.max(np.abs(out - reference)))

    # --- online ----------------------------------------------------------------------------
    def _check_fitted(self) -> None:
        if not hasattr(self, "_online"):
            raise RotorAreaError("this ConductionRom is not fitted: call fit(...) or "
                                 "ConductionRom.load(path) first")

    def _set_rank(self, rank: int) -> None:
        """Keep the first ``rank`` modes; cache the contiguous arrays the kernel reads."""
        self.n_modes_ = rank
        self._online = (self.reduced_mass_[:, :rank, :rank].copy(),
                        self.reduced_stiffness_[:, :rank, :rank].copy(),
                        self.reduced_robin_[:, :rank, :rank].copy(),
                        self.reduced_load_[:, :rank].copy(), self.mean_weights_[:rank].copy())
        self._outputs = np.ascontiguousarray(self.output_matrix_[:, :, :rank])

    def _kernel(self, start: np.ndarray, history: SteamHistory, outputs: np.ndarray,
                offset: np.ndarray, out: np.ndarray) -> np.ndarray:
        return _advance(start, history.htc, history.steam_temperature, history.dt,
                        self.reference_temperatures_, *self._online, outputs, offset, out)

    def initial_state(self, htc: np.ndarray, steam_temperature: np.ndarray) -> RomState:
        """The reduced steady state under ``htc`` (W/(m²·K)) and ``steam_temperature`` (K)."""
        self._check_fitted()
        history = self._history(htc, steam_temperature, 1.0)
        htc0, steam0 = history.htc[0], history.steam_temperature[0]
        _, stiffness, robin, load, weights = self._online

        def solve(mean_k: float) -> np.ndarray:
            i, j, theta = bracket(mean_k, self.reference_temperatures_)
            matrix = (1 - theta) * stiffness[i] + theta * stiffness[j] + np.tensordot(htc0, robin,
                                                                                       1)
            return la.solve(matrix, (htc0 * steam0) @ load, assume_a="pos")

        return RomState(steady_field(solve, weights.__matmul__,
                                     steam_mean_temperature(htc0, steam0)))

    def state_from_field(self, temperature: np.ndarray, time_s: float = 0.0) -> RomState:
        """The M₀-orthogonal projection of a nodal field ``temperature`` (K)."""
        self._check_fitted()
        field = np.asarray(temperature, dtype=float)
        if field.shape != (self.modes_.shape[0],):
            raise RotorAreaError(f"field has shape {field.shape}, expected "
                                 f"({self.modes_.shape[0]},) nodal temperatures in K")
        return RomState(self.projector_[:, :self.n_modes_].T @ field, time_s)

    def field(self, state: RomState) -> np.ndarray:
        """Nodal temperatures (K) of ``state``."""
        return self.modes_[:, :self.n_modes_] @ self._coordinates(state)

    def _history(self, htc: np.ndarray, steam_temperature: np.ndarray, dt: float) -> SteamHistory:
        history = SteamHistory(htc, steam_temperature, dt)
        if history.htc.shape[1] != len(self.groups_):
            raise RotorAreaError(f"{history.htc.shape[1]} boundary groups given, the ROM has "
                                 f"{len(self.groups_)} ({', '.join(self.groups_)})")
        return history

    def _coordinates(self, state: RomState) -> np.ndarray:
        coordinates = np.ascontiguousarray(state.coordinates, dtype=float)
        if coordinates.shape != (self.n_modes_,):
            raise RotorAreaError(f"state has {coordinates.shape} coordinates, this ROM "
                                 f"{self.n_modes_} modes")
        return coordinates

    def simulate(self, history: SteamHistory, initial: RomState | None = None) -> RomRun:
        """Run a whole record (batch, compiled); ``initial`` defaults to the steady state at
        the first row's conditions."""
        self._check_fitted()
        history = self._history(history.htc, history.steam_temperature, history.dt)
        if initial is None:
            initial = self.initial_state(history.htc[0], history.steam_temperature[0])
        out = np.empty((history.steps, self._outputs.shape[1]))
        final = self._kernel(self._coordinates(initial), history, self._outputs,
                             self.output_offset_, out)
        k = self.temperature_nodes_.size
        return RomRun(out[:, :k], out[:, k:],
                      RomState(final, initial.time_s + history.steps * history.dt))

    def step(self, state: RomState, htc: np.ndarray, steam_temperature: np.ndarray,
             dt: float) -> RomState:
        """One streaming step of ``dt`` (s) under ``htc`` (W/(m²·K)) and ``steam_temperature``
        (K) per group; the same kernel as :meth:`simulate`, so the results agree bit for bit.
        Any array-like is accepted (e.g. a strided row of ``DataFrame.to_numpy()``): the
        compiled kernel reshapes, which numba allows on contiguous arrays only."""
        self._check_fitted()
        htc = np.ascontiguousarray(htc, dtype=float)
        steam_temperature = np.ascontiguousarray(steam_temperature, dtype=float)
        final = np.empty(0)
        if htc.shape == steam_temperature.shape == (len(self.groups_),):
            final = _checked_step(self._coordinates(state), htc, steam_temperature, float(dt),
                                  self.reference_temperatures_, *self._online)
        if not final.size:
            self._history(htc, steam_temperature, dt)  # raises the error that says what is wrong
        return RomState(final, state.time_s + dt)

    def observe(self, state: RomState) -> tuple[np.ndarray, np.ndarray]:
        """(temperature at the temperature nodes in K, output y = S·T + s₀) of ``state``."""
        self._check_fitted()
        out = np.empty((1, self._outputs.shape[1]))
        _observe(self._coordinates(state), self._outputs, self.output_offset_,
                 self.reference_temperatures_, self._online[-1], out, 0)
        k = self.temperature_nodes_.size
        return out[0, :k], out[0, k:]

    # --- file ------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write the fitted ROM to ``path`` (``.npz``: arrays plus a JSON ``metadata`` entry;
        no pickled objects). Returns the path written."""
        self._check_fitted()
        path = Path(path)
        metadata = {"format": FORMAT, "format_version": FORMAT_VERSION,
                    "groups": list(self.groups_), "n_modes": self.n_modes_,
                    "energy": self.energy, "max_modes": self.max_modes,
                    "tolerance": self.tolerance, "max_snapshots": self.max_snapshots,
                    "training_error_k": self.training_error_,
                    "units": {"temperature": "K", "htc": "W/(m2 K)", "time": "s"}}
        with path.open("wb") as handle:
            np.savez_compressed(handle, metadata=np.array(json.dumps(metadata)),
                                **{name.rstrip("_"): getattr(self, name) for name in _ARRAYS})
        return path

    @classmethod
    def load(cls, path: str | Path) -> ConductionRom:
        """Read a ROM :meth:`save` wrote; a clear :class:`RotorAreaError` naming the file and
        what is wrong otherwise."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as archive:
                arrays = {name: archive[name.rstrip("_")] for name in _ARRAYS}
                metadata = json.loads(str(archive["metadata"]))
        except (OSError, ValueError, KeyError) as error:
            raise RotorAreaError(f"{path}: not a rotor conduction ROM file ({error})") from None
        if metadata.get("format") != FORMAT or metadata.get("format_version") != FORMAT_VERSION:
            raise RotorAreaError(f"{path}: format {metadata.get('format')!r} version "
                                 f"{metadata.get('format_version')!r}, expected {FORMAT!r} "
                                 f"version {FORMAT_VERSION}")
        rom = cls(metadata["energy"], metadata["max_modes"], metadata["tolerance"],
                  metadata["max_snapshots"])
        for name, value in arrays.items():
            setattr(rom, name, value)
        rom.groups_ = tuple(metadata["groups"])
        rom.training_error_ = float(metadata["training_error_k"])
        n, modes = rom.modes_.shape
        expected = {"projector_": (n, modes), "mean_weights_": (modes,),
                    "reduced_mass_": (rom.reference_temperatures_.size, modes, modes),
                    "reduced_stiffness_": (rom.reference_temperatures_.size, modes, modes),
                    "reduced_robin_": (len(rom.groups_), modes, modes),
                    "reduced_load_": (len(rom.groups_), modes),
                    "output_matrix_": (*rom.output_offset_.shape, modes),
                    "output_offset_": (rom.reference_temperatures_.size,
                                       rom.output_offset_.shape[-1])}
        wrong = [f"{name.rstrip('_')} {getattr(rom, name).shape} (expected {shape})"
                 for name, shape in expected.items() if getattr(rom, name).shape != shape]
        if wrong or not 1 <= metadata["n_modes"] <= modes:
            raise RotorAreaError(f"{path}: inconsistent ROM arrays: {', '.join(wrong)}; "
                                 f"n_modes {metadata['n_modes']} of {modes}")
        rom._set_rank(int(metadata["n_modes"]))
        return rom
