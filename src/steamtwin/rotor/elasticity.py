"""Axisymmetric thermo-elastic stress in the rotor section with the centrifugal load.

Linear elasticity of a body of revolution under axisymmetric load (Timoshenko & Goodier,
*Theory of Elasticity*, 3rd ed., 1970, §§32, 150–151; Zienkiewicz, Taylor & Zhu, *The Finite
Element Method: Its Basis and Fundamentals*, 7th ed., 2013, ch. 6, axisymmetric stress
analysis): displacements u_r(r, z), u_z(r, z); strains ε_r = ∂u_r/∂r, ε_θ = u_r/r,
ε_z = ∂u_z/∂z, γ_rz = ∂u_r/∂z + ∂u_z/∂r; Hooke's law with the free thermal strain ε_th
(``material.thermal_strain`` of the nodal temperatures, interpolated like them) and E(T), ν(T)
evaluated at every quadrature point,

    σ_i = λ·(ε_r + ε_θ + ε_z) + 2μ·ε_i − (3λ + 2μ)·ε_th  (i = r, θ, z),   τ_rz = μ·γ_rz,

λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)); equilibrium in the weak form
∫σ:ε(v)·2πr dA = ∫ρω²r·v_r·2πr dA (the centrifugal body force ρω²r at angular speed ω).
Displacements are P2 (scikit-fem), the temperature and the thermal strain P1, so the thermal
strain and the strains of the displacement are both piecewise linear. On the axis r = 0 the
radial displacement is zero (the only regular axisymmetric field; Zienkiewicz et al., loc.
cit.); quadrature points lie inside the elements, so u_r/r is never evaluated on the axis.

End conditions at the axial ends z = z_min and z = z_max of the section (all homogeneous
constraints, written u = P·ū and solved as PᵀKP·ū = Pᵀf):

- ``"free"``: traction-free ends; the one rigid-body motion of an axisymmetric body, the axial
  translation, is removed by holding u_z at one node: every load here (thermal, radial body
  force) has zero net axial component, so that support carries no force.
- ``"fixed-axial"``: u_z = 0 on both ends (plane strain for a prism).
- ``"generalized-plane-strain"``: u_z = 0 on the lower end; on the upper end u_z is one extra
  unknown δ shared by all its nodes, so the end stays plane and moves axially by the uniform
  axial strain δ/(z_max − z_min); the equation of δ says the net axial force on that end is
  zero. This is the state of a section cut from a long free rotor, the state Timoshenko &
  Goodier's long-cylinder formulas (§151, eqs. 247–249) describe.

Stresses at points are evaluated on the element (see :mod:`steamtwin.rotor.stress_points`).

The ROM needs the stress at the critical points as a linear map.
:meth:`AxisymmetricElasticity.stress_operator` builds it with one *adjoint* solve per output:
with A the (4·n_points × n_dofs) map from displacement to stress at the points and C the map
from the nodal thermal strain to the load, the stress is A·P·(PᵀKP)⁻¹·Pᵀ·(C·ε_th + f_ω) +
(direct thermal term), so solving (PᵀKP)·Z = PᵀAᵀ for the 4·n_points columns of Z (K is
symmetric) gives the n_points × n_nodes matrix S = Zᵀ·Pᵀ·C (per unit thermal strain) —
4·n_points back-substitutions with one factorisation, against n_nodes for the direct way (Giles
& Pierce, Flow Turbul. Combust. 65 (2000) 393, on adjoint outputs). S is built with E, ν uniform
at T₀. For temperature-independent properties the stress is exactly affine in the nodal
temperature. For temperature-dependent ones the operator takes the nodal thermal strain as it is
and E/(1−ν) at the section's volume-mean temperature T̄ (the "properties at the mean
temperature" of thermal-stress practice; a long cylinder's thermal stresses scale with E/(1−ν)
at given strain, T&G §151): σ ≈ c(T̄)·S·ε_th(T) + centrifugal·ω², c =
(E/(1−ν))(T̄)/(E/(1−ν))(T₀). Its affine form for the ROM (:meth:`StressOperator.linearised`)
also replaces ε_th by its tangent about T̄: σ ≈ c·[α(T̄)·S·(T − T̄) + ε_th(T̄)·S·1] +
centrifugal·ω², α = dε_th/dT; T̄ is a linear functional of T, so a Galerkin ROM precomputes S·Φ
once and re-linearises per step with three scalar property look-ups. Measured on the reference
rotor with the tabulated 1CrMoV steel (groove root σ_z, radial fields ±40 K and ±80 K about 220,
370 and 520 °C, at rest and at 3000 rpm, E and ν frozen at 520 °C) against the full
temperature-dependent solve: the operator within 0.8 %; its tangent about T̄ within 1.3 %, 3.7 %
where ε_th(T)'s tabulated kink lies inside an 80 K spread; a tangent fixed at 520 °C up to 12 %
off, one at 20 °C up to 28 %.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike
from skfem import (
    Basis,
    BilinearForm,
    ElementTriP1,
    ElementTriP2,
    ElementVector,
    LinearForm,
    MeshTri,
    asm,
)

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.material import RotorMaterial
from steamtwin.rotor.stress_points import StressState, checked_points, point_evaluation

EndCondition = Literal["free", "fixed-axial", "generalized-plane-strain"]

RATED_SPEED = 2.0 * np.pi * 3000.0 / 60.0
"""rad/s, 3000 rpm: the speed of a two-pole 50 Hz unit."""

EXPANSION_STEP = 0.5
"""K, half the step of the central difference dε_th/dT of a tabulated thermal strain."""


def _strains(u, r):
    """(ε_r, ε_θ, ε_z, γ_rz) of a vector field at quadrature points of radius r."""
    return (u.grad[0][0], u[0] / r, u.grad[1][1], u.grad[0][1] + u.grad[1][0])


@BilinearForm
def _stiffness(u, v, w):
    r = w.x[0]
    eu, ev = _strains(u, r), _strains(v, r)
    normal = (w.lam * (eu[0] + eu[1] + eu[2]) * (ev[0] + ev[1] + ev[2])
              + 2.0 * w.mu * (eu[0] * ev[0] + eu[1] * ev[1] + eu[2] * ev[2]))
    return 2.0 * np.pi * r * (normal + w.mu * eu[3] * ev[3])


@LinearForm
def _thermal_load(v, w):
    r = w.x[0]
    ev = _strains(v, r)
    return 2.0 * np.pi * r * w.bulk_strain * (ev[0] + ev[1] + ev[2])


@BilinearForm
def _thermal_coupling(strain, v, w):
    r = w.x[0]
    ev = _strains(v, r)
    return 2.0 * np.pi * r * w.bulk * strain * (ev[0] + ev[1] + ev[2])


@LinearForm
def _volume(v, w):
    return 2.0 * np.pi * w.x[0] * v


@LinearForm
def _centrifugal_per_speed_squared(v, w):
    r = w.x[0]
    return 2.0 * np.pi * r * w.density * r * v[0]


def _lame(youngs_modulus: np.ndarray, poisson_ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lamé's λ and μ (Pa) from E (Pa) and ν."""
    lam = youngs_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio))
    return lam, youngs_modulus / (2.0 * (1.0 + poisson_ratio))


def _hooke_matrix(lam: np.ndarray, mu: np.ndarray) -> sp.csr_matrix:
    """Block-diagonal (4n × 4n) map from (ε_r, ε_θ, ε_z, γ_rz) to (σ_r, σ_θ, σ_z, τ_rz) per
    point, without the thermal term."""
    blocks = []
    for lam_p, mu_p in zip(lam, mu, strict=True):
        block = np.zeros((4, 4))
        block[:3, :3] = lam_p
        block[[0, 1, 2], [0, 1, 2]] += 2.0 * mu_p
        block[3, 3] = mu_p
        blocks.append(block)
    return sp.block_diag(blocks, format="csr")


def _check_speed(speed: float) -> None:
    if not np.isfinite(speed) or speed < 0.0:
        raise RotorAreaError(f"rotor speed must be finite and ≥ 0 rad/s, got {speed!r}")


@dataclass(frozen=True)
class ElasticSolution:
    """``displacement`` (m): the P2 dofs (u_r, u_z) in the order of the solver's ``basis``
    (``basis.nodal_dofs`` picks the mesh nodes'), under nodal ``temperature`` (K) at
    ``speed`` (rad/s)."""

    displacement: np.ndarray
    temperature: np.ndarray
    speed: float


def _expansion(material: RotorMaterial, temperature: np.ndarray) -> np.ndarray:
    """Instantaneous expansion coefficient dε_th/dT (1/K), central difference."""
    return ((np.asarray(material.thermal_strain(temperature + EXPANSION_STEP))
             - np.asarray(material.thermal_strain(temperature - EXPANSION_STEP)))
            / (2.0 * EXPANSION_STEP))


def _thermal_stiffness(material: RotorMaterial, temperature: float) -> float:
    """E/(1 − ν) (Pa) at ``temperature`` (K): the factor thermal stresses of a long cylinder
    scale with at given thermal strain (Timoshenko & Goodier §151)."""
    return float(material.youngs_modulus(temperature)) / (
        1.0 - float(material.poisson_ratio(temperature)))


def _nodal_field(field: np.ndarray, n_nodes: int) -> np.ndarray:
    if field.ndim not in (1, 2) or field.shape[-1:] != (n_nodes,):
        raise RotorAreaError(f"temperature field has shape {field.shape}, expected "
                             f"({n_nodes},) or (n_times, {n_nodes}) nodal values in K")
    if not np.all(np.isfinite(field)):
        raise RotorAreaError("temperature field must be finite (K)")
    return field


def _affine(matrix: np.ndarray, field: np.ndarray, constant: np.ndarray) -> StressState:
    """matrix (4, p, n) · field (…, n) + constant (4, p) as a StressState of shape (…, p)."""
    components = np.moveaxis(np.tensordot(field, matrix, axes=([-1], [2])), -2, 0)
    shape = (4,) + (1,) * (field.ndim - 1) + (constant.shape[1],)
    return StressState.from_components(components + constant.reshape(shape))


@dataclass(frozen=True)
class LinearisedStress:
    """Stress at the operator's points affine in the nodal temperature T (K) and ω² (rad/s)²:
    σ = thermal·T + offset + centrifugal·ω², with ``thermal`` (4, n_points, n_nodes) in Pa/K,
    ``offset`` (4, n_points) in Pa and ``centrifugal`` (4, n_points) in Pa/(rad/s)²
    (components σ_r, σ_θ, σ_z, τ_rz): what a Galerkin ROM multiplies by its modes once."""

    thermal: np.ndarray
    offset: np.ndarray
    centrifugal: np.ndarray

    def __call__(self, temperature: ArrayLike, speed: float = RATED_SPEED) -> StressState:
        """Stress (Pa) for nodal temperatures (n_nodes,) or (n_times, n_nodes) in K."""
        _check_speed(speed)
        field = _nodal_field(np.asarray(temperature, dtype=float), self.thermal.shape[-1])
        return _affine(self.thermal, field, self.offset + self.centrifugal * float(speed) ** 2)


@dataclass(frozen=True)
class StressOperator:
    """Stress at ``points`` (n_points × 2, (r, z) in m) of a nodal temperature field.

    ``strain_response`` (4, n_points, n_nodes): Pa per unit nodal thermal strain with E and ν
    uniform at ``frozen_temperature`` (K); ``centrifugal`` (4, n_points): Pa/(rad/s)²;
    ``volume_weights`` (n_nodes): the section's volume-mean temperature is their dot product
    with the nodal field. Components σ_r, σ_θ, σ_z, τ_rz.
    """

    points: np.ndarray
    strain_response: np.ndarray
    centrifugal: np.ndarray
    volume_weights: np.ndarray
    material: RotorMaterial
    frozen_temperature: float

    def linearised(self, around: float) -> LinearisedStress:
        """The affine map in T (K) with E/(1−ν) and dε_th/dT at the uniform temperature
        ``around`` (K): σ = c·[α(T̄)·S·(T − T̄) + ε_th(T̄)·S·1] + centrifugal·ω², with
        c = (E/(1−ν))(T̄) / (E/(1−ν))(T₀)."""
        base = float(around)
        if not np.isfinite(base) or base <= 0.0:
            raise RotorAreaError(f"the linearisation temperature must be finite and positive "
                                 f"(K), got {around!r}")
        scale = _thermal_stiffness(self.material, base) / _thermal_stiffness(
            self.material, self.frozen_temperature)
        slope = float(_expansion(self.material, np.asarray(base)))
        intercept = float(self.material.thermal_strain(base)) - slope * base
        return LinearisedStress(thermal=scale * slope * self.strain_response,
                                offset=scale * intercept * self.strain_response.sum(axis=-1),
                                centrifugal=self.centrifugal)

    def mean_temperature(self, temperature: ArrayLike) -> np.ndarray:
        """Volume-mean temperature (K) of nodal fields (n_nodes,) or (n_times, n_nodes)."""
        field = _nodal_field(np.asarray(temperature, dtype=float), self.volume_weights.size)
        return field @ self.volume_weights

    def __call__(self, temperature: ArrayLike, speed: float = RATED_SPEED) -> StressState:
        """Stress (Pa) for nodal temperatures (n_nodes,) or (n_times, n_nodes) in K at
        ``speed`` (rad/s): c(T̄)·S·ε_th(T) + centrifugal·ω², the nodal thermal strain as it is
        and E/(1−ν) at each field's volume-mean temperature; arrays (n_points,) or
        (n_times, n_points)."""
        _check_speed(speed)
        field = np.asarray(temperature, dtype=float)
        means = np.atleast_1d(self.mean_temperature(field))
        frozen = _thermal_stiffness(self.material, self.frozen_temperature)
        scale = np.array([_thermal_stiffness(self.material, mean) for mean in means]) / frozen
        strain = np.asarray(self.material.thermal_strain(np.atleast_2d(field))) * scale[:, None]
        state = _affine(self.strain_response, strain, self.centrifugal * float(speed) ** 2)
        if field.ndim == 2:
            return state
        return StressState(*(component[0] for component in
                             (state.radial, state.hoop, state.axial, state.shear)))


class AxisymmetricElasticity:
    """Thermo-elastic stress of the rotor section ``mesh`` (skfem MeshTri, x = r ≥ 0 and
    y = z in m) made of ``material`` with the axial ``end`` condition; ``intorder`` is the
    quadrature order of the assembly."""

    def __init__(self, mesh: MeshTri, material: RotorMaterial,
                 end: EndCondition = "generalized-plane-strain", intorder: int = 4) -> None:
        if end not in get_args(EndCondition):
            raise RotorAreaError(f"end condition must be one of {get_args(EndCondition)}, "
                                 f"got {end!r}")
        radius = mesh.p[0]
        if not np.all(np.isfinite(mesh.p)):
            raise RotorAreaError("rotor mesh has non-finite node coordinates")
        if radius.min() < 0.0:
            raise RotorAreaError(f"rotor mesh has nodes at negative radius (min r = "
                                 f"{radius.min():.6g} m); x must be the radius r ≥ 0")
        self.mesh = mesh
        self.material = material
        self.end = end
        self.basis = Basis(mesh, ElementVector(ElementTriP2()), intorder=intorder)
        self.temperature_basis = self.basis.with_element(ElementTriP1())
        self.constraint = self._constraint_matrix()
        centrifugal = asm(_centrifugal_per_speed_squared, self.basis,
                          density=float(material.density()))
        self._centrifugal_load = np.asarray(centrifugal)
        self._factor_key: tuple[np.ndarray, np.ndarray] | None = None
        self._factor = None

    @property
    def n_nodes(self) -> int:
        """Number of nodal temperatures the solver takes."""
        return self.mesh.p.shape[1]

    def _constraint_matrix(self) -> sp.csr_matrix:
        """P (n_dofs × n_free): the free dofs and, for generalized plane strain, the column of
        the upper end's common axial displacement."""
        r, z = self.mesh.p
        tol = 1e-9 * max(np.ptp(r), np.ptp(z))
        z_min, z_max = z.min(), z.max()

        def dofs(test, component: str) -> np.ndarray:
            facets = self.mesh.facets_satisfying(test, boundaries_only=True)
            if facets.size == 0:
                return np.zeros(0, dtype=int)
            return np.asarray(self.basis.get_dofs(facets).all(component), dtype=int)

        on_axis = r.min() < tol
        removed = [dofs(lambda x: x[0] < tol, "u^1") if on_axis else np.zeros(0, dtype=int)]
        lower = dofs(lambda x: x[1] < z_min + tol, "u^2")
        upper = dofs(lambda x: x[1] > z_max - tol, "u^2")
        if self.end != "free" and (lower.size == 0 or upper.size == 0):
            raise RotorAreaError(f"end condition {self.end!r} needs flat axial ends at z = "
                                 f"{z_min:.6g} m and z = {z_max:.6g} m; the mesh has none")
        tied = np.zeros(0, dtype=int)
        if self.end == "free":
            lowest = np.lexsort((r, z))[0]
            removed.append(np.array([self.basis.nodal_dofs[1, lowest]]))
        elif self.end == "fixed-axial":
            removed += [lower, upper]
        else:
            removed.append(lower)
            tied = upper
        fixed = np.union1d(np.concatenate(removed), tied)
        free = np.setdiff1d(np.arange(self.basis.N), fixed)
        rows = np.concatenate([free, tied])
        cols = np.concatenate([np.arange(free.size), np.full(tied.size, free.size)])
        n_free = free.size + (1 if tied.size else 0)
        return sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(self.basis.N, n_free))

    def _checked_temperature(self, temperature: ArrayLike) -> np.ndarray:
        field = np.asarray(temperature, dtype=float)
        if field.shape != (self.n_nodes,):
            raise RotorAreaError(f"temperature field has shape {field.shape}, expected "
                                 f"({self.n_nodes},) nodal values in K")
        if not np.all(np.isfinite(field)) or field.min() <= 0.0:
            raise RotorAreaError("temperature field must be finite and positive (K)")
        return field

    def _quadrature_lame(self, temperature: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """λ and μ (Pa) at the quadrature points of the nodal ``temperature`` (K)."""
        at_points = np.asarray(self.temperature_basis.interpolate(temperature))
        return _lame(np.asarray(self.material.youngs_modulus(at_points)),
                     np.asarray(self.material.poisson_ratio(at_points)))

    def _solver(self, lam: np.ndarray, mu: np.ndarray):
        """LU factors of PᵀKP for these Lamé fields (reused while they do not change)."""
        key = self._factor_key
        if key is None or not (np.array_equal(key[0], lam) and np.array_equal(key[1], mu)):
            stiffness = asm(_stiffness, self.basis, lam=lam, mu=mu)
            reduced = (self.constraint.T @ stiffness @ self.constraint).tocsc()
            # PᵀKP is symmetric positive definite: a symmetric fill-reducing order (minimum
            # degree on A+Aᵀ) without pivoting halves the fill of SuperLU's default COLAMD.
            self._factor = spla.splu(reduced, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                     options={"SymmetricMode": True})
            self._factor_key = (lam, mu)
        return self._factor

    def solve(self, temperature: ArrayLike, speed: float = RATED_SPEED) -> ElasticSolution:
        """Displacement under nodal ``temperature`` (K, thermal strain from 20 °C) and the
        centrifugal load at ``speed`` (rad/s, default 3000 rpm)."""
        field = self._checked_temperature(temperature)
        _check_speed(speed)
        lam, mu = self._quadrature_lame(field)
        strain = np.asarray(self.temperature_basis.interpolate(
            np.asarray(self.material.thermal_strain(field))))
        load = (asm(_thermal_load, self.basis, bulk_strain=(3.0 * lam + 2.0 * mu) * strain)
                + float(speed) ** 2 * self._centrifugal_load)
        reduced = self._solver(lam, mu).solve(self.constraint.T @ load)
        return ElasticSolution(displacement=self.constraint @ reduced, temperature=field,
                               speed=float(speed))

    def stress(self, solution: ElasticSolution, points: ArrayLike) -> StressState:
        """σ_r, σ_θ, σ_z, τ_rz (Pa) of ``solution`` at ``points`` ((n, 2), r and z in m)."""
        evaluation = point_evaluation(self.basis, checked_points(points))
        strain = (evaluation.strain @ solution.displacement).reshape(-1, 4).T
        at_points = evaluation.temperature @ solution.temperature
        lam, mu = _lame(np.asarray(self.material.youngs_modulus(at_points)),
                        np.asarray(self.material.poisson_ratio(at_points)))
        nodal_strain = np.asarray(self.material.thermal_strain(solution.temperature))
        thermal = (3.0 * lam + 2.0 * mu) * (evaluation.temperature @ nodal_strain)
        trace = strain[0] + strain[1] + strain[2]
        normal = lam * trace + 2.0 * mu * strain[:3] - thermal
        return StressState.from_components(np.vstack([normal, mu * strain[3]]))

    def stress_operator(self, points: ArrayLike, frozen_temperature: float) -> StressOperator:
        """The stress at ``points`` (n, 2) (r, z in m) as a map of the nodal temperature, by
        one adjoint solve per output, with E and ν at the uniform ``frozen_temperature`` (K;
        immaterial when they are constant)."""
        point_array = checked_points(points)
        frozen = float(frozen_temperature)
        uniform = self._checked_temperature(np.full(self.n_nodes, frozen))
        lam, mu = self._quadrature_lame(uniform)
        coupling = asm(_thermal_coupling, self.temperature_basis, self.basis,
                       bulk=3.0 * lam + 2.0 * mu)
        volumes = np.asarray(asm(_volume, self.temperature_basis))

        evaluation = point_evaluation(self.basis, point_array)
        at_points = np.full(point_array.shape[0], frozen)
        lam_p, mu_p = _lame(np.asarray(self.material.youngs_modulus(at_points)),
                            np.asarray(self.material.poisson_ratio(at_points)))
        to_stress = _hooke_matrix(lam_p, mu_p) @ evaluation.strain
        adjoint = self._solver(lam, mu).solve((self.constraint.T @ to_stress.T).toarray())
        response = (self.constraint @ adjoint).T  # stress per unit nodal load (4n × n_dofs)

        n_points = point_array.shape[0]
        strain_response = (coupling.T @ response.T).T.reshape(n_points, 4, -1)
        strain_response[:, :3, :] -= ((3.0 * lam_p + 2.0 * mu_p)[:, None, None]
                                      * evaluation.temperature.toarray()[:, None, :])
        centrifugal = (response @ self._centrifugal_load).reshape(n_points, 4)
        return StressOperator(points=point_array,
                              strain_response=np.transpose(strain_response, (1, 0, 2)),
                              centrifugal=centrifugal.T, volume_weights=volumes / volumes.sum(),
                              material=self.material, frozen_temperature=frozen)
