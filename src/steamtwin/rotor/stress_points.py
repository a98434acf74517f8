"""Stresses at given points of the rotor section: where they lie, how they are evaluated, and
the invariants fatigue life is computed from.

Recovery. The stress at a point is evaluated *on the element* that contains it, from the
derivatives of the P2 displacement and the P1 temperature interpolated at the point; where a
point lies on an edge or vertex shared by several elements the element values are averaged.
For quadratic elements the pointwise error of the gradient is O(h²) up to and including the
boundary (Rannacher & Scott, Math. Comp. 38 (1982) 437; Ciarlet, *The Finite Element Method for
Elliptic Problems*, 1978, §3.3), so no recovery step is needed to reach second order at the
groove root and the bore. Superconvergent patch recovery (Zienkiewicz & Zhu, IJNME 33 (1992)
1331) gains an order only in the interior; at boundary points its patches are one-sided and it
loses that gain, which is why it is not used here. A point on a curved surface (groove root)
may lie just outside the polygonal mesh, by the chord's sagitta ≈ h²/(8R); such a point is
evaluated on the nearest element by extending that element's polynomial, which keeps the O(h²)
error, while a point farther out is refused.

Invariants (Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed., 1970, §77): in axisymmetry
σ_θ is a principal stress; the other two are those of the (r, z) block; von Mises
σ_vM = √(½[(σ_r−σ_θ)² + (σ_θ−σ_z)² + (σ_z−σ_r)²] + 3τ_rz²).

Fatigue scalar (:func:`equivalent_stress`). Rainflow counting needs one signed scalar per
instant, and the von Mises stress has no sign. Signing it by the principal stress of largest
magnitude (or by the hydrostatic stress: at a free surface, σ_r = τ_rz = 0, the two rules flip
at the same place, σ_θ = −σ_z) jumps from +σ_vM to −σ_vM where that sign changes, so two
solutions whose components agree within a fraction of a per cent can differ by 2·σ_vM there.
Instead the scalar is the stress projected, in the von Mises metric, on one fixed deviatoric
direction N per location (vM(N) = 1, tr N = 0): σ_eq = (3/2)·σ:N, linear in the components
and so continuous, with |Δσ_eq| ≤ vM(Δσ) (Cauchy–Schwarz). N is the direction of largest
variance of the stress path (:func:`equivalent_direction`: the first principal component of the
deviatoric stresses), the idea of Susmel's Maximum Variance Method for the critical plane
(Int. J. Fatigue 32 (2010) 1875), here in the deviatoric space. For a proportional path
(σ(t) − σ̄ ∥ N) the range between two instants is exactly the von Mises equivalent of the
component differences — the equivalent stress range of ASME BPVC VIII-2 (2019) §5.5.3.2
(eq. 5.30) — and for a non-proportional one it is the part along N, never more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike
from skfem import CellBasis, MeshTri

from steamtwin.errors import RotorAreaError

OUTSIDE_TOLERANCE = 0.05
"""Largest negative barycentric coordinate (fraction of the element) of a point evaluated on
the nearest element because it lies just outside the polygonal mesh."""

COMPONENTS = ("radial", "hoop", "axial", "shear")
"""The stress components in the order of every (4, …) array: σ_r, σ_θ, σ_z, τ_rz."""


@dataclass(frozen=True)
class StressState:
    """Stress components (Pa) at points (and, if 2-D, times × points), same shape each."""

    radial: np.ndarray
    hoop: np.ndarray
    axial: np.ndarray
    shear: np.ndarray

    @classmethod
    def from_components(cls, components: np.ndarray) -> StressState:
        """From an array (4, …) in the order of :data:`COMPONENTS` (Pa)."""
        return cls(*(np.asarray(c, dtype=float) for c in components))

    @property
    def von_mises(self) -> np.ndarray:
        """Von Mises equivalent stress (Pa)."""
        return np.sqrt(0.5 * ((self.radial - self.hoop) ** 2 + (self.hoop - self.axial) ** 2
                              + (self.axial - self.radial) ** 2) + 3.0 * self.shear ** 2)

    @property
    def principal(self) -> np.ndarray:
        """Principal stresses σ₁ ≥ σ₂ ≥ σ₃ (Pa) in a last axis of length 3."""
        centre = 0.5 * (self.radial + self.axial)
        radius = np.hypot(0.5 * (self.radial - self.axial), self.shear)
        return -np.sort(-np.stack([centre + radius, centre - radius, self.hoop], axis=-1),
                        axis=-1)


def _von_mises_vectors(components: np.ndarray) -> np.ndarray:
    """Vectors (…, 4) whose Euclidean norm is the von Mises stress of ``components`` (…, 4) in
    the order of :data:`COMPONENTS`: √(3/2)·(s_r, s_θ, s_z, √2·τ_rz), s the deviator."""
    normal = components[..., :3] - components[..., :3].mean(axis=-1, keepdims=True)
    return np.sqrt(1.5) * np.concatenate([normal, np.sqrt(2.0) * components[..., 3:]], axis=-1)


def equivalent_direction(components: ArrayLike) -> np.ndarray:
    """The unit deviatoric direction N (4,: σ_r, σ_θ, σ_z, τ_rz with vM(N) = 1, tr N = 0) of
    largest variance of a stress path ``components`` (samples, 4) in Pa (module docstring),
    signed so that σ_eq grows with the hydrostatic stress along the path (tensile excursions
    positive)."""
    path = np.asarray(components, dtype=float)
    if path.ndim != 2 or path.shape[1] != 4 or path.shape[0] < 2 or not np.all(
            np.isfinite(path)):
        raise RotorAreaError(f"stress path: expected finite (samples ≥ 2, 4) components in Pa "
                             f"({', '.join(COMPONENTS)}), got shape {path.shape}")
    vectors = _von_mises_vectors(path)
    centred = vectors - vectors.mean(axis=0)
    _, singular, rows = np.linalg.svd(centred, full_matrices=False)
    if singular[0] <= 0.0:
        raise RotorAreaError("stress path: the deviatoric stress does not vary, so it has no "
                             "direction of largest variance")
    e = rows[0]  # unit in the von Mises metric; back to components: s = e/√(3/2), τ = e₃/√3
    direction = np.concatenate([e[:3] / np.sqrt(1.5), e[3:] / np.sqrt(3.0)])
    hydrostatic = path[:, :3].sum(axis=1)
    projected = equivalent_stress(StressState.from_components(path.T), direction)
    if np.dot(projected - projected.mean(), hydrostatic - hydrostatic.mean()) < 0.0:
        direction = -direction
    return direction


def equivalent_stress(state: StressState, direction: ArrayLike) -> np.ndarray:
    """The signed equivalent stress (Pa) of ``state`` along the unit deviatoric ``direction``
    (:func:`equivalent_direction`): σ_eq = (3/2)·σ:N = (3/2)·(σ_r N_r + σ_θ N_θ + σ_z N_z +
    2 τ_rz N_rz) (module docstring)."""
    n = np.asarray(direction, dtype=float)
    if n.shape != (4,) or abs(float(n[:3].sum())) > 1e-9 or abs(
            float(np.linalg.norm(_von_mises_vectors(n))) - 1.0) > 1e-9:
        raise RotorAreaError(f"equivalent-stress direction must be a deviator (trace 0) of von "
                             f"Mises norm 1 in the order {COMPONENTS}, got {n.tolist()}")
    return 1.5 * (state.radial * n[0] + state.hoop * n[1] + state.axial * n[2]
                  + 2.0 * state.shear * n[3])


def checked_points(points: ArrayLike) -> np.ndarray:
    """Points as an (n, 2) array of (r, z) in m; refuses other shapes, NaN and r < 0."""
    array = np.atleast_2d(np.asarray(points, dtype=float))
    if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] == 0:
        raise RotorAreaError(f"stress points must be an (n, 2) array of (r, z) in m, got shape "
                             f"{np.shape(points)}")
    if not np.all(np.isfinite(array)):
        raise RotorAreaError(f"stress points must be finite, got {array.tolist()}")
    if np.any(array[:, 0] < 0.0):
        raise RotorAreaError(f"stress point radius must be ≥ 0 m, got r = "
                             f"{array[array[:, 0] < 0.0, 0].tolist()}")
    return array


def _barycentric(mesh: MeshTri, point: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (3, n_elements) of ``point`` in every triangle."""
    corners = mesh.p[:, mesh.t]  # (2, 3, n_elements)
    v0, v1, v2 = corners[:, 0], corners[:, 1], corners[:, 2]
    det = (v1[0] - v0[0]) * (v2[1] - v0[1]) - (v2[0] - v0[0]) * (v1[1] - v0[1])
    l1 = ((point[0] - v0[0]) * (v2[1] - v0[1]) - (v2[0] - v0[0]) * (point[1] - v0[1])) / det
    l2 = ((v1[0] - v0[0]) * (point[1] - v0[1]) - (point[0] - v0[0]) * (v1[1] - v0[1])) / det
    return np.stack([1.0 - l1 - l2, l1, l2])


def point_elements(mesh: MeshTri, point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The elements whose closure holds ``point`` (r, z in m) and its reference coordinates in
    each (2, k); the nearest element if the point lies just outside the mesh."""
    coords = _barycentric(mesh, point)
    smallest = coords.min(axis=0)
    inside = np.flatnonzero(smallest >= -1e-10)
    if inside.size == 0:
        nearest = int(np.argmax(smallest))
        if smallest[nearest] < -OUTSIDE_TOLERANCE:
            raise RotorAreaError(f"stress point (r, z) = ({point[0]:.6g}, {point[1]:.6g}) m lies "
                                 "outside the rotor section")
        inside = np.array([nearest])
    return inside, coords[1:, inside]


@dataclass(frozen=True)
class PointEvaluation:
    """Linear maps from the solution to the points: ``strain`` (4·n_points × n_dofs, rows
    point-major in the order ε_r, ε_θ, ε_z, γ_rz, 1/m·m) and ``temperature`` (n_points ×
    n_nodes, P1 interpolation)."""

    strain: sp.csr_matrix
    temperature: sp.csr_matrix


def point_evaluation(basis: CellBasis, points: np.ndarray) -> PointEvaluation:
    """Strain and temperature evaluation at ``points`` (n, 2) for the displacement ``basis``
    (vector element, u_r and u_z), averaged over the elements sharing a point."""
    mesh, element = basis.mesh, basis.elem
    strain_rows, strain_cols, strain_vals = [], [], []
    temp_rows, temp_cols, temp_vals = [], [], []
    for index, point in enumerate(points):
        elements, reference = point_elements(mesh, point)
        share = 1.0 / elements.size
        for element_index, xi in zip(elements, reference.T, strict=True):
            cell = CellBasis(mesh, element, elements=np.array([element_index]),
                             quadrature=(xi[:, None], np.array([1.0])))
            dofs = cell.element_dofs[:, 0]
            for dof, (phi,) in zip(dofs, cell.basis, strict=True):
                grad, value = phi.grad[:, :, 0, 0], np.asarray(phi)[:, 0, 0]
                # ε_r = ∂u_r/∂r, ε_θ = u_r/r, ε_z = ∂u_z/∂z, γ_rz = ∂u_r/∂z + ∂u_z/∂r;
                # at r = 0 the constrained u_r vanishes and ε_θ = ε_r (l'Hôpital).
                hoop = value[0] / point[0] if point[0] > 0.0 else grad[0, 0]
                for component, entry in enumerate((grad[0, 0], hoop, grad[1, 1],
                                                   grad[0, 1] + grad[1, 0])):
                    strain_rows.append(4 * index + component)
                    strain_cols.append(dof)
                    strain_vals.append(share * entry)
            weights = np.array([1.0 - xi.sum(), xi[0], xi[1]])
            temp_rows.extend([index] * 3)
            temp_cols.extend(mesh.t[:, element_index])
            temp_vals.extend(share * weights)
    strain = sp.csr_matrix((strain_vals, (strain_rows, strain_cols)),
                           shape=(4 * len(points), basis.N))
    temperature = sp.csr_matrix((temp_vals, (temp_rows, temp_cols)),
                                shape=(len(points), mesh.p.shape[1]))
    return PointEvaluation(strain=strain, temperature=temperature)
