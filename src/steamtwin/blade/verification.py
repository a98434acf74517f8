"""Verification of the conduction FEM: analytic solutions, error norms, mesh convergence.

* **Slab** with convection on both faces (Incropera & DeWitt, *Fundamentals of Heat and Mass
  Transfer*, 6th ed., 2007, §3.1, thermal circuit): linear profile, heat flux
  q = (T_a − T_b)/(1/h_a + L/k + 1/h_b). P1 elements reproduce it to round-off.
* **Fin with convection, two-dimensional** (separation of variables, Incropera & DeWitt §4.2):
  in 0 < x < L, −b < y < b, T − T∞ = A·cosh(m·x)·cos(m·y) satisfies ∇²T = 0; convection h on
  y = ±b needs k·m·tan(m·b) = h, i.e. ζ·tan ζ = Bi with ζ = m·b, Bi = h·b/k (the eigen-condition
  of the plane wall with convection, Incropera & DeWitt eq. 5.39c); x = 0 is adiabatic
  (symmetry plane of a fin of length 2L), and the end x = L convects with h_L to the ambient
  T_L(y) = T∞ + A·cos(m·y)·(cosh(m·L) + k·m·sinh(m·L)/h_L). Unlike the 1-D fin of the textbook
  (Incropera Table 3.4), this is exact for any Biot number, so the P1 error converges at the
  theoretical rates: O(h²) in L², O(h) in the energy (H¹) semi-norm.
* **Lumped body** (Incropera §5.1): a body with Bi ≪ 1 cools as exp(−h·A·t/(ρ·c·V)).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from skfem.helpers import dot

from steamtwin.blade.conduction import BladeConduction, Convection
from steamtwin.progress import ProgressCallback


@dataclass(frozen=True)
class FinSolution:
    """The exact 2-D fin mode A·cosh(m·x)·cos(m·y) + T∞ on x ∈ [0, L], y ∈ [−b, b] (SI).

    Sides y = ±b are the mesh regions ``pressure_side``/``suction_side``, the end x = L is
    ``trailing_edge``; other faces adiabatic.
    """

    conductivity: float  # W/(m·K)
    wavenumber: float  # m, 1/m
    half_thickness: float  # b, m
    length: float  # L, m
    amplitude: float  # A, K
    ambient: float  # T∞, K
    end_htc: float  # h_L, W/(m²·K)

    @property
    def side_htc(self) -> float:
        """h on y = ±b that makes the mode exact: k·m·tan(m·b) (W/(m²·K))."""
        return self.conductivity * self.wavenumber * math.tan(self.wavenumber * self.half_thickness)

    def temperature(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Exact temperature (K) at coordinates x, y (m)."""
        m = self.wavenumber
        return self.ambient + self.amplitude * np.cosh(m * x) * np.cos(m * y)

    def gradient(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact ∂T/∂x, ∂T/∂y (K/m)."""
        m, a = self.wavenumber, self.amplitude
        return a * m * np.sinh(m * x) * np.cos(m * y), -a * m * np.cosh(m * x) * np.sin(m * y)

    def convection(self, conduction: BladeConduction) -> Convection:
        """The boundary conditions on a block mesh of the fin."""
        m, k, length = self.wavenumber, self.conductivity, self.length
        end = conduction.quadrature("trailing_edge").points
        end_ambient = self.ambient + self.amplitude * np.cos(m * end[1]) * (
            math.cosh(m * length) + k * m * math.sinh(m * length) / self.end_htc)
        return {
            "pressure_side": (self.side_htc, self.ambient),
            "suction_side": (self.side_htc, self.ambient),
            "trailing_edge": (self.end_htc, end_ambient),
        }


def fin_errors(conduction: BladeConduction, temperature: np.ndarray, fin: FinSolution
               ) -> dict[str, float]:
    """L² error (K·m^1.5), H¹ semi-norm error (K·m^0.5) and max nodal error (K) of a P1 field."""
    basis = conduction.mass_basis
    x = np.asarray(basis.global_coordinates())
    field = basis.interpolate(temperature)
    exact = fin.temperature(x[0], x[1])
    gx, gy = fin.gradient(x[0], x[1])
    exact_gradient = np.stack([gx, gy, np.zeros_like(gx)])
    gradient_error = field.grad - exact_gradient
    points = conduction.mesh.points
    return {
        "l2": float(np.sqrt(np.sum((np.asarray(field) - exact) ** 2 * basis.dx))),
        "h1": float(np.sqrt(np.sum(dot(gradient_error, gradient_error) * basis.dx))),
        "max_nodal": float(np.max(np.abs(temperature - fin.temperature(points[:, 0],
                                                                       points[:, 1])))),
    }


def observed_order(sizes: Sequence[float], errors: Sequence[float]) -> float:
    """Least-squares slope of log(error) against log(size): the observed convergence order."""
    slope, _ = np.polyfit(np.log(np.asarray(sizes, float)), np.log(np.asarray(errors, float)), 1)
    return float(slope)


@dataclass(frozen=True)
class ConvergenceRow:
    """One mesh of a convergence study: element size (m), nodes and the monitored quantities."""

    element_size: float
    nodes: int
    quantities: dict[str, float]


def mesh_convergence(build: Callable[[float], tuple[BladeConduction, Convection]],
                     element_sizes: Sequence[float],
                     monitor: Callable[[BladeConduction, np.ndarray, Convection], dict[str, float]],
                     progress: ProgressCallback | None = None) -> list[ConvergenceRow]:
    """Solve the steady problem on meshes of decreasing ``element_sizes`` (m).

    ``build(size)`` returns the conduction model on a mesh of that size and its convection;
    ``monitor`` extracts the quantities to compare (e.g. max temperature, root heat flow).
    """
    rows = []
    for i, size in enumerate(element_sizes):
        conduction, convection = build(size)
        temperature = conduction.solve_steady(convection)
        rows.append(ConvergenceRow(size, conduction.n_nodes,
                                   monitor(conduction, temperature, convection)))
        if progress is not None:
            progress((i + 1) / len(element_sizes), f"mesh {i + 1}/{len(element_sizes)}")
    return rows


def richardson(rows: Sequence[ConvergenceRow], quantity: str) -> dict[str, float]:
    """Richardson extrapolation from the three finest meshes (constant refinement ratio).

    Returns the observed order p, the extrapolated value and the finest mesh's estimated error
    (Roache, *Verification and Validation in Computational Science and Engineering*, 1998, §5).
    """
    if len(rows) < 3:
        raise ValueError("Richardson extrapolation needs three meshes")
    coarse, medium, fine = (rows[i].quantities[quantity] for i in (-3, -2, -1))
    ratio = rows[-2].element_size / rows[-1].element_size
    differences = (coarse - medium, medium - fine)
    if differences[1] == 0.0 or differences[0] / differences[1] <= 0.0:
        return {"order": math.nan, "extrapolated": fine, "error_estimate": 0.0}
    order = math.log(differences[0] / differences[1]) / math.log(ratio)
    extrapolated = fine + (fine - medium) / (ratio**order - 1.0)
    return {"order": order, "extrapolated": extrapolated, "error_estimate": fine - extrapolated}
