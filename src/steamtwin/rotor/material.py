"""What the rotor solvers read of a steel: temperature-dependent properties in SI units.

The conduction solver reads density, specific heat and conductivity; the stress solver
Young's modulus, Poisson's ratio and the thermal strain from 20 °C (ε_th = ᾱ(T)·(T − 293.15 K)
with the *mean* coefficient ᾱ from 20 °C, as ASME BPVC II-D Table TE-1 "coefficient B" and
EN 10269 tabulate it). Any object with these methods is a rotor material; :class:`ConstantMaterial`
is the temperature-independent one the closed-form checks (Timoshenko & Goodier, *Theory of
Elasticity*, 3rd ed., 1970, §150–151) assume.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from steamtwin.errors import RotorAreaError

REFERENCE_TEMPERATURE = 293.15
"""K, the zero of the thermal strain (20 °C, the reference of ASME II-D Table TE-1)."""


@runtime_checkable
class RotorMaterial(Protocol):
    """Temperature-dependent properties; every method takes temperatures in K (array-like)."""

    name: str

    def density(self) -> float:
        """kg/m³ (constant: the change with temperature is the thermal strain's)."""

    def specific_heat(self, temperature: ArrayLike) -> np.ndarray:
        """J/(kg·K)."""

    def conductivity(self, temperature: ArrayLike) -> np.ndarray:
        """W/(m·K)."""

    def youngs_modulus(self, temperature: ArrayLike) -> np.ndarray:
        """Pa."""

    def poisson_ratio(self, temperature: ArrayLike) -> np.ndarray:
        """Dimensionless."""

    def thermal_strain(self, temperature: ArrayLike) -> np.ndarray:
        """Free thermal strain from 20 °C (dimensionless), ᾱ(T)·(T − 293.15 K)."""


@dataclass(frozen=True)
class ConstantMaterial:
    """A material with temperature-independent properties (SI: kg/m³, J/(kg·K), W/(m·K), Pa,
    1/K), as the closed-form solutions assume."""

    name: str
    density_: float
    specific_heat_: float
    conductivity_: float
    youngs_modulus_: float
    poisson_ratio_: float
    expansion_coefficient: float

    def __post_init__(self) -> None:
        positive = {"density_": self.density_, "specific_heat_": self.specific_heat_,
                    "conductivity_": self.conductivity_, "youngs_modulus_": self.youngs_modulus_,
                    "expansion_coefficient": self.expansion_coefficient}
        for field, value in positive.items():
            if not np.isfinite(value) or value <= 0.0:
                raise RotorAreaError(f"material {self.name!r}: {field.rstrip('_')} must be a "
                                     f"positive finite number in SI units, got {value!r}")
        if not 0.0 <= self.poisson_ratio_ < 0.5:
            raise RotorAreaError(f"material {self.name!r}: Poisson's ratio must lie in "
                                 f"[0, 0.5), got {self.poisson_ratio_!r}")

    def density(self) -> float:
        return self.density_

    def specific_heat(self, temperature: ArrayLike) -> np.ndarray:
        return np.full(np.shape(temperature), self.specific_heat_)

    def conductivity(self, temperature: ArrayLike) -> np.ndarray:
        return np.full(np.shape(temperature), self.conductivity_)

    def youngs_modulus(self, temperature: ArrayLike) -> np.ndarray:
        return np.full(np.shape(temperature), self.youngs_modulus_)

    def poisson_ratio(self, temperature: ArrayLike) -> np.ndarray:
        return np.full(np.shape(temperature), self.poisson_ratio_)

    def thermal_strain(self, temperature: ArrayLike) -> np.ndarray:
        return self.expansion_coefficient * (np.asarray(temperature, dtype=float)
                                             - REFERENCE_TEMPERATURE)
