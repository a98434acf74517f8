"""The discrete conduction system the rotor's FEM hands to its reduced-order model.

Semi-discrete axisymmetric heat equation (Galerkin, P1 on the (r, z) half-section, every
integral weighted by 2πr; Zienkiewicz, Taylor & Zhu, *The Finite Element Method*, 7th ed.,
2013, §4.2 and ch. 7):

    M·dT/dt + (K + Σ_g h_g(t)·H_g)·T = Σ_g h_g(t)·T_g(t)·b_g,

M = ∫ρc·φᵢφⱼ dV (J/K), K = ∫k·∇φᵢ·∇φⱼ dV (W/K), H_g = ∫_Γg φᵢφⱼ dA and b_g = ∫_Γg φᵢ dA (m²)
on the steam-wetted boundary Γ_g of group g, whose steam has temperature T_g (K) and
heat-transfer coefficient h_g (W/(m²·K)); boundaries in no group are adiabatic. The terms are
affine in the inputs h_g and h_g·T_g, which is what lets a Galerkin projection precompute them
(Rozza, Huynh & Patera, Arch. Comput. Methods Eng. 15 (2008) 229). Because the P1 functions
sum to one, H_g·1 = b_g and K·1 = 0: a uniform field in equilibrium with uniform steam stays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from steamtwin.errors import RotorAreaError


@dataclass(frozen=True)
class AffineConduction:
    """``mass`` (J/K) and ``stiffness`` (W/K) n×n sparse; per boundary group ``robin`` n×n
    sparse (m²) and ``robin_load`` length-n (m²), in the order of ``groups``."""

    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    robin: tuple[sp.csr_matrix, ...]
    robin_load: tuple[np.ndarray, ...]
    groups: tuple[str, ...]

    def __post_init__(self) -> None:
        n = self.mass.shape[0]
        if self.mass.shape != (n, n) or self.stiffness.shape != (n, n):
            raise RotorAreaError(f"mass {self.mass.shape} and stiffness "
                                 f"{self.stiffness.shape} must both be square and equal")
        if not (len(self.robin) == len(self.robin_load) == len(self.groups)):
            raise RotorAreaError(f"{len(self.groups)} groups need as many robin matrices "
                                 f"({len(self.robin)}) and loads ({len(self.robin_load)})")
        for name, matrix, load in zip(self.groups, self.robin, self.robin_load, strict=True):
            if matrix.shape != (n, n) or np.shape(load) != (n,):
                raise RotorAreaError(f"boundary group {name!r}: robin {matrix.shape} and load "
                                     f"{np.shape(load)} do not fit {n} nodes")

    @property
    def size(self) -> int:
        """Number of temperature unknowns (nodes)."""
        return self.mass.shape[0]

    def operator(self, htc: np.ndarray) -> sp.csr_matrix:
        """K + Σ_g h_g·H_g (W/K) for heat-transfer coefficients ``htc`` (W/(m²·K)) per group."""
        total = self.stiffness.copy()
        for h, matrix in zip(np.asarray(htc, dtype=float), self.robin, strict=True):
            total = total + h * matrix
        return total.tocsr()

    def load(self, htc: np.ndarray, steam_temperature: np.ndarray) -> np.ndarray:
        """Σ_g h_g·T_g·b_g (W) for ``htc`` (W/(m²·K)) and ``steam_temperature`` (K) per group."""
        weights = np.asarray(htc, dtype=float) * np.asarray(steam_temperature, dtype=float)
        return sum((w * b for w, b in zip(weights, self.robin_load, strict=True)),
                   np.zeros(self.size))
