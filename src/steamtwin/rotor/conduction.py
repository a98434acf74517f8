"""Transient heat conduction in the axisymmetric rotor section (P1 finite elements).

The axisymmetric heat equation in (r, z) (Carslaw & Jaeger, *Conduction of Heat in Solids*,
2nd ed., 1959, §1.6), ρ·c(T)·∂T/∂t = (1/r)·∂(r·k(T)·∂T/∂r)/∂r + ∂(k(T)·∂T/∂z)/∂z, with
−k·∂T/∂n = h_g·(T − T_g) on the surface wetted by group g's steam and adiabatic elsewhere, in
Galerkin form on linear triangles with every integral weighted by 2πr (Zienkiewicz, Taylor & Zhu,
*The Finite Element Method*, 7th ed., 2013, §4.2 and ch. 7) — the system
:class:`~steamtwin.rotor.operators.AffineConduction` holds. The element integrals are exact
closed forms: ∇φ is constant on a P1 triangle, so K_e = 2π·r̄_e·A_e·k_e·∇φᵢ·∇φⱼ (r̄_e the
centroid radius), and with r = Σ r_k·φ_k the mass and boundary integrals follow from
∫φᵢ^a·φⱼ^b·φ_k^c dA = 2A·a!·b!·c!/(a+b+c+2)! (Zienkiewicz et al., eq. 6.37). The properties
k and c are taken per element at its mean nodal temperature.

Time integration is implicit Euler — first order in time, unconditionally stable
(Hairer & Wanner, *Solving ODEs II*, §IV.3) — with the properties of step n taken from the
temperature of step n − 1 (a linearly implicit step: each step is one linear solve, the property
lag adds an O(Δt) error of the same order as the scheme's). Steady state solves
(K(T) + Σh·H)·T = Σh·T_g·b by Picard iteration on k(T). The P1 functions sum to one, so
K·1 = 0 and Hᵍ·1 = bᵍ: summing the equations gives Σ_g h_g·(T_g·Σbᵍ − bᵍ·Tⁿ) =
1ᵀ·Mⁿ⁻¹·(Tⁿ − Tⁿ⁻¹)/Δt, the energy balance to solver round-off (exactly ∫ρc·ΔT dV for a
temperature-independent c). Sparse LU (SuperLU, symmetric mode) solves each step.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike
from skfem import MeshTri

from steamtwin.errors import RotorAreaError
from steamtwin.progress import ProgressCallback
from steamtwin.rotor.geometry import STEAM_PREFIX
from steamtwin.rotor.material import RotorMaterial
from steamtwin.rotor.operators import AffineConduction

#: Default tolerance (K) of the steady Picard iteration on k(T).
STEADY_TOLERANCE = 1e-6


def steam_temperature_column(group: str) -> str:
    """Column of a boundary-condition frame holding ``group``'s steam temperature (K)."""
    return f"steam_temperature:{group}"


def htc_column(group: str) -> str:
    """Column of a boundary-condition frame holding ``group``'s rotor htc (W/(m²·K))."""
    return f"htc:{group}"


def cooling_factor_column(group: str) -> str:
    """Column of a boundary-condition frame holding the factor (dimensionless, > 0; Pr^0.1
    for Dittus–Boelter) on ``group``'s htc while the rotor surface is hotter than the steam."""
    return f"cooling_factor:{group}"


@dataclass(frozen=True)
class TransientResult:
    """A transient run: ``times`` (s, N + 1 samples from the initial one); ``probes`` (K) the
    temperature at each named node per sample; ``heat_in`` (W) the heat the steam gives the
    rotor at each sample (implicit-Euler flux at the step's end; row 0 at the initial field);
    ``stored`` (J) the change of 1ᵀ·M·T over each step (row 0 zero); ``final`` (K) the last
    field; ``snapshots`` (K, rows = sampled fields) every ``snapshot_every`` steps from the
    first, empty when not asked for; ``htc`` (W/(m²·K), samples × groups) what each step
    applied, the cooling factor included."""

    times: np.ndarray
    probes: pd.DataFrame
    heat_in: np.ndarray
    stored: np.ndarray
    final: np.ndarray
    snapshots: np.ndarray
    htc: np.ndarray


class RotorConduction:
    """The rotor's conduction FEM on ``mesh`` (x = r, y = z in m; steam boundaries named
    ``"steam:<group>"``) with ``material``'s temperature-dependent properties.

    ``groups`` orders the steam groups (default: the mesh's steam boundaries in its order);
    every array of steam temperatures or htc has one column per group in that order.
    """

    def __init__(self, mesh: MeshTri, material: RotorMaterial,
                 groups: Sequence[str] | None = None) -> None:
        boundaries = mesh.boundaries or {}
        found = tuple(name.removeprefix(STEAM_PREFIX) for name in boundaries
                      if name.startswith(STEAM_PREFIX))
        self.groups = tuple(groups) if groups is not None else found
        missing = [group for group in self.groups if group not in found]
        if missing or not self.groups:
            raise RotorAreaError(f"the mesh has no steam boundary for {missing or 'any group'}: "
                                 f"its steam boundaries are {list(found)} (named "
                                 f"'{STEAM_PREFIX}<group>', as rotor_mesh names them)")
        if np.any(mesh.p[0] < 0.0):
            raise RotorAreaError("mesh x coordinates are radii and must be ≥ 0 m, got "
                                 f"{mesh.p[0].min():g} m")
        self.mesh, self.material = mesh, material
        self._volume_pattern = _Pattern(mesh.t, mesh.p.shape[1])
        self._unit_stiffness, self._unit_mass = _element_matrices(mesh.p, mesh.t)
        self._robin = tuple(_robin_terms(mesh, boundaries[STEAM_PREFIX + group])
                            for group in self.groups)
        # each group's H in the volume pattern (its facets are triangle edges), so a step sums
        # data vectors instead of sparse matrices
        self._robin_data = np.array([self._volume_pattern.data_of(matrix)
                                     for matrix, _ in self._robin])
        self._robin_loads = np.array([load for _, load in self._robin])
        empty = [g for g, load in zip(self.groups, self._robin_loads, strict=True)
                 if not load.sum() > 0.0]
        if empty:
            raise RotorAreaError(f"the steam boundaries of {empty} have no wetted area")

    @property
    def size(self) -> int:
        """Number of nodes (temperature unknowns)."""
        return self.mesh.p.shape[1]

    def _element_temperature(self, temperature: ArrayLike) -> np.ndarray:
        field = np.broadcast_to(np.asarray(temperature, dtype=float), (self.size,))
        return field[self.mesh.t].mean(axis=0)

    def _volume_data(self, temperature: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Data vectors of M and K in the volume pattern at ``temperature`` (K)."""
        element = self._element_temperature(temperature)
        conductivity = self.material.conductivity(element)
        capacity = self.material.density() * self.material.specific_heat(element)
        pattern = self._volume_pattern
        return (pattern.sum(self._unit_mass * capacity[:, None]),
                pattern.sum(self._unit_stiffness * conductivity[:, None]))

    def matrices(self, temperature: ArrayLike) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        """(M in J/K, K in W/K) with the properties at ``temperature`` (K, per node or one)."""
        mass, stiffness = self._volume_data(temperature)
        return self._volume_pattern.matrix(mass), self._volume_pattern.matrix(stiffness)

    def system(self, temperature: ArrayLike) -> AffineConduction:
        """The affine system with the properties at ``temperature`` (K, per node or one)."""
        mass, stiffness = self.matrices(temperature)
        return AffineConduction(mass=mass, stiffness=stiffness,
                                robin=tuple(matrix for matrix, _ in self._robin),
                                robin_load=tuple(load for _, load in self._robin),
                                groups=self.groups)

    def _inputs(self, values: ArrayLike, name: str, rows: int | None = None) -> np.ndarray:
        """``values`` checked: shape (groups,) or (rows, groups), finite, htc ≥ 0, T > 0 K;
        the error names the first bad sample (1-based) and group."""
        array = np.asarray(values, dtype=float)
        shape = (len(self.groups),) if rows is None else (rows, len(self.groups))
        if array.shape != shape:
            raise RotorAreaError(f"{name} must have shape {shape} (one column per group "
                                 f"{list(self.groups)}), got shape {array.shape}")
        low, unit = {"htc": (0.0, "W/(m²·K), ≥ 0"), "cooling_factor": (1e-300, "(-), > 0")
                      }.get(name, (1e-300, "K, > 0"))
        bad = np.argwhere(~(np.isfinite(array) & (array >= low)))
        if bad.size:
            *row, column = bad[0]
            where = f"sample {row[0] + 1} (1-based), " if row else ""
            raise RotorAreaError(f"{name} at {where}group {self.groups[column]!r} is "
                                 f"{float(array[tuple(bad[0])])!r}: expected a finite value in "
                                 f"{unit}")
        return array

    def heat_in(self, temperature: np.ndarray, htc: np.ndarray,
                steam_temperature: np.ndarray) -> float:
        """Heat (W) the steam gives the rotor at field ``temperature`` (K): Σ h·(T_g·Σb − b·T)."""
        return float(sum(h * (t * load.sum() - load @ temperature)
                         for h, t, (_, load) in zip(htc, steam_temperature, self._robin,
                                                    strict=True)))

    def steady(self, htc: ArrayLike, steam_temperature: ArrayLike,
               tolerance: float = STEADY_TOLERANCE, max_iterations: int = 50) -> np.ndarray:
        """Steady field (K) for ``htc`` (W/(m²·K)) and ``steam_temperature`` (K) per group,
        Picard-iterated on k(T) until no node moves by more than ``tolerance`` K."""
        h = self._inputs(htc, "htc")
        steam = self._inputs(steam_temperature, "steam_temperature")
        if not np.any(h > 0.0):
            raise RotorAreaError("a steady state needs a positive htc on some group")
        load = sum(g * s * b for g, s, (_, b) in zip(h, steam, self._robin, strict=True))
        robin = sum(g * matrix for g, (matrix, _) in zip(h, self._robin, strict=True))
        temperature = np.full(self.size, steam.mean())
        for _ in range(max_iterations):
            _, stiffness = self.matrices(temperature)
            operator = stiffness + robin
            new = _factorized(operator)(load)
            change = np.max(np.abs(new - temperature))
            temperature = new
            if change <= tolerance:
                return temperature
        raise RotorAreaError(f"steady conduction did not converge to {tolerance:g} K in "
                             f"{max_iterations} Picard iterations (last change {change:g} K)")

    def transient(self, initial: ArrayLike, times: ArrayLike, htc: ArrayLike,
                  steam_temperature: ArrayLike, probes: Mapping[str, int] | None = None,
                  snapshot_every: int = 0, progress: ProgressCallback | None = None,
                  cooling_factor: ArrayLike | None = None) -> TransientResult:
        """March from ``initial`` (K, per node or one) at ``times[0]`` through ``times`` (s,
        increasing) with ``htc`` (W/(m²·K)) and ``steam_temperature`` (K), arrays (samples,
        groups): implicit Euler, the inputs of sample n act over the step ending at it.
        ``probes`` names nodes whose temperature is recorded (e.g. :func:`critical_nodes`).
        ``cooling_factor`` (samples, groups; default 1) multiplies a group's htc in a step
        whose previous field has the group's mean surface temperature above the steam's — the
        kernel's switch of Dittus–Boelter's Prandtl exponent (steamtwin.model.metal)."""
        t = np.asarray(times, dtype=float)
        if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0.0) or not np.all(np.isfinite(t)):
            raise RotorAreaError("times must be ≥ 2 finite, strictly increasing seconds")
        given = self._inputs(htc, "htc", t.size)
        steam = self._inputs(steam_temperature, "steam_temperature", t.size)
        factor = (np.ones_like(given) if cooling_factor is None
                  else self._inputs(cooling_factor, "cooling_factor", t.size))
        field = np.array(np.broadcast_to(np.asarray(initial, dtype=float), (self.size,)))
        wetted = self._robin_loads.sum(axis=1)
        h = given.copy()  # the htc each step applies, the cooling factor's switch included
        h[0] = np.where(self._robin_loads @ field / wetted > steam[0], factor[0] * given[0],
                        given[0])
        probes = dict(probes or {})
        nodes = np.array(list(probes.values()), dtype=int)
        recorded = np.empty((t.size, nodes.size))
        heat, stored = np.zeros(t.size), np.zeros(t.size)
        recorded[0], heat[0] = field[nodes], self.heat_in(field, h[0], steam[0])
        snapshots = [field.copy()] if snapshot_every else []
        pattern = self._volume_pattern
        key, solve = None, None
        for n in range(1, t.size):
            dt = t[n] - t[n - 1]
            cooled = self._robin_loads @ field / wetted > steam[n]
            h[n] = np.where(cooled, factor[n] * given[n], given[n])
            mass_data, stiffness_data = self._volume_data(field)
            mass = pattern.matrix(mass_data)
            step_key = (dt, tuple(h[n]), mass_data.tobytes(), stiffness_data.tobytes())
            if step_key != key:
                operator = pattern.matrix(mass_data / dt + stiffness_data + h[n] @ self._robin_data)
                solve, key = _factorized(operator), step_key
            new = solve(mass @ field / dt + (h[n] * steam[n]) @ self._robin_loads)
            stored[n] = float(np.sum(mass @ (new - field)))
            field = new
            recorded[n], heat[n] = field[nodes], self.heat_in(field, h[n], steam[n])
            if snapshot_every and n % snapshot_every == 0:
                snapshots.append(field.copy())
            if progress is not None and (n % 1000 == 0 or n == t.size - 1):
                progress(n / (t.size - 1), f"rotor conduction: step {n} of {t.size - 1}")
        return TransientResult(times=t, probes=pd.DataFrame(recorded, index=t,
                                                            columns=list(probes)),
                               heat_in=heat, stored=stored, final=field,
                               snapshots=np.array(snapshots).reshape(-1, self.size), htc=h)

    def transient_frame(self, initial: ArrayLike, frame: pd.DataFrame,
                        probes: Mapping[str, int] | None = None, snapshot_every: int = 0,
                        progress: ProgressCallback | None = None) -> TransientResult:
        """:meth:`transient` over a frame of :func:`steam_temperature_column` (K) and
        :func:`htc_column` (W/(m²·K)) columns per group (and :func:`cooling_factor_column`,
        used when there for every group), indexed by seconds or by time stamps (times from the
        first), as :func:`steamtwin.rotor.steam_side.steam_side` makes it."""
        columns = [name for group in self.groups
                   for name in (steam_temperature_column(group), htc_column(group))]
        missing = [name for name in columns if name not in frame.columns]
        if missing:
            raise RotorAreaError(f"boundary-condition frame lacks the columns {missing} "
                                 f"(has {list(frame.columns)})")
        index = frame.index
        seconds = ((index - index[0]).total_seconds() if isinstance(index, pd.DatetimeIndex)
                   else index)
        factors = [cooling_factor_column(g) for g in self.groups]
        return self.transient(
            initial, np.asarray(seconds, dtype=float),
            frame[[htc_column(g) for g in self.groups]].to_numpy(dtype=float),
            frame[[steam_temperature_column(g) for g in self.groups]].to_numpy(dtype=float),
            probes, snapshot_every, progress,
            frame[factors].to_numpy(dtype=float) if set(factors) <= set(frame.columns) else None)


def _factorized(matrix: sp.spmatrix) -> Callable[[np.ndarray], np.ndarray]:
    """Solver of the symmetric positive-definite ``matrix``: SuperLU in symmetric mode with a
    minimum-degree ordering of A + Aᵀ (Li, ACM TOMS 31 (2005) 302; about 1.5× faster than the
    default column ordering on the reference rotor's 1105-node system)."""
    return spla.splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A",
                     options={"SymmetricMode": True}).solve


class _Pattern:
    """Sums per-element 3×3 matrices into one CSR matrix of a fixed sparsity pattern."""

    def __init__(self, triangles: np.ndarray, nodes: int) -> None:
        rows = np.repeat(triangles.T, 3, axis=1).ravel()
        cols = np.tile(triangles.T, (1, 3)).ravel()
        keys, self.position = np.unique(rows.astype(np.int64) * nodes + cols,
                                        return_inverse=True)
        self.indices = (keys % nodes).astype(np.int32)
        self.indptr = np.searchsorted(keys // nodes, np.arange(nodes + 1)).astype(np.int32)
        self.keys, self.shape = keys, (nodes, nodes)

    def sum(self, element_values: np.ndarray) -> np.ndarray:
        """Data vector of the sum of ``element_values`` (elements, 9: row-major 3×3 each)."""
        return np.bincount(self.position, weights=element_values.ravel(),
                           minlength=self.indices.size)

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """The CSR matrix of a data vector in this pattern."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=self.shape)

    def data_of(self, matrix: sp.spmatrix) -> np.ndarray:
        """``matrix`` (whose entries lie in the pattern) as a data vector of this pattern."""
        entries = matrix.tocoo()
        data = np.zeros(self.indices.size)
        np.add.at(data, np.searchsorted(self.keys, entries.row.astype(np.int64) * self.shape[0]
                                        + entries.col), entries.data)
        return data


def _element_matrices(points: np.ndarray, triangles: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Per-element (E, 9) ∫2πr·∇φᵢ·∇φⱼ dA (m) and ∫2πr·φᵢφⱼ dA (m³), exact for P1."""
    r, z = points[0][triangles], points[1][triangles]  # (3, E)
    # ∇φᵢ = (z_j − z_k, r_k − r_j)/(2A) for (i, j, k) cyclic
    b = np.array([z[1] - z[2], z[2] - z[0], z[0] - z[1]])
    c = np.array([r[2] - r[1], r[0] - r[2], r[1] - r[0]])
    area = 0.5 * (b[0] * c[1] - b[1] * c[0])  # signed: negative for clockwise triangles
    if np.any(area == 0.0):
        raise RotorAreaError("the mesh has degenerate (zero-area) triangles")
    gradients = (b[:, None] * b[None, :] + c[:, None] * c[None, :]) / (4.0 * area**2)
    stiffness = 2.0 * np.pi * r.mean(axis=0) * np.abs(area) * gradients  # (3, 3, E)
    area = np.abs(area)
    # ∫φᵢφⱼ·r dA = Σ_k r_k∫φᵢφⱼφ_k: A/10 (i=j=k), A/30 (two equal), A/60 (all different)
    total = r.sum(axis=0)
    mass = np.empty((3, 3, r.shape[1]))
    for i in range(3):
        for j in range(3):
            mass[i, j] = (area / 30.0 * (2.0 * r[i] + total) if i == j
                          else area / 60.0 * (r[i] + r[j] + total))
    mass *= 2.0 * np.pi
    return (stiffness.transpose(2, 0, 1).reshape(-1, 9), mass.transpose(2, 0, 1).reshape(-1, 9))


def _robin_terms(mesh: MeshTri, facets: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """H = ∫2πr·φᵢφⱼ ds (m², sparse) and b = ∫2πr·φᵢ ds (m²) over boundary ``facets``, exact
    for P1: on a segment of length L, ∫φₐ²r = L(3rₐ + r_b)/12, ∫φₐφ_b·r = L(rₐ + r_b)/12,
    ∫φₐ·r = L(2rₐ + r_b)/6."""
    n = mesh.p.shape[1]
    a, b = mesh.facets[:, facets]
    ra, rb = mesh.p[0, a], mesh.p[0, b]
    length = np.hypot(*(mesh.p[:, a] - mesh.p[:, b]))
    scale = 2.0 * np.pi * length
    rows = np.concatenate([a, b, a, b])
    cols = np.concatenate([a, b, b, a])
    values = np.concatenate([scale * (3 * ra + rb) / 12, scale * (ra + 3 * rb) / 12,
                             scale * (ra + rb) / 12, scale * (ra + rb) / 12])
    matrix = sp.coo_matrix((values, (rows, cols)), shape=(n, n)).tocsr()
    load = np.bincount(np.concatenate([a, b]), np.concatenate([scale * (2 * ra + rb) / 6,
                                                               scale * (ra + 2 * rb) / 6]),
                       minlength=n)
    return matrix, load
