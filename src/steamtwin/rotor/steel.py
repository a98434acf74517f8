"""Rotor steels as :class:`~steamtwin.rotor.material.RotorMaterial` implementations, with the
fatigue (strain-life) and creep-rupture data the life modules read.

One steel is registered: ``"30CrMoNiV5-11"`` (aliases ``"1CrMoV"``, ``"A470-8"``), the 1 % CrMoV
forging of HP/IP rotors (ASTM A470 Class 8, EN/SEW 555 30CrMoNiV5-11). Where no table for this
exact grade could be found, a table of its alloy group or of the closest CrMoV grade is used and
its ``source`` says so; docs/rotor.md "## Steel data" lists every table, its source and why.
Each table is kept in the units of its source and converted to SI on reading, so a table can be
checked against its source line by line.

Interpolation is linear in temperature between table points. Below the first point (20 or
21.1 °C) down to 0 °C the first value is held (the properties change by < 1 % over that span);
above the last point a property refuses with :class:`~steamtwin.errors.RotorAreaError`.

Strain-life constants follow the Uniform Material Law for unalloyed and low-alloy steels
(Bäumel & Seeger, *Materials Data for Cyclic Loading*, Suppl. 1, Elsevier, 1990), estimated
from the tensile strength and Young's modulus at temperature, since no measured
Manson–Coffin–Basquin constants of the rotor grade at 400–550 °C were found.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.material import REFERENCE_TEMPERATURE

__all__ = ["CreepRuptureData", "PropertyTable", "StrainLife", "TabulatedSteel", "steel",
           "steel_names"]

ZERO_CELSIUS = 273.15
"""K."""
PSI = 6894.757293168361
"""Pa per lbf/in² (NIST SP 811, Appendix B.8)."""


def fahrenheit_to_celsius(temperature_f: float) -> float:
    """°F → °C."""
    return (temperature_f - 32.0) / 1.8


@dataclass(frozen=True)
class PropertyTable:
    """One temperature-dependent property: ``values`` (SI) at ``temperatures_c`` (°C, ascending),
    with the ``source`` it was read from."""

    quantity: str
    temperatures_c: tuple[float, ...]
    values: tuple[float, ...]
    source: str

    def __post_init__(self) -> None:
        t = np.asarray(self.temperatures_c, dtype=float)
        if t.size != len(self.values) or t.size < 2 or np.any(np.diff(t) <= 0.0):
            raise RotorAreaError(f"{self.quantity} table: needs ≥ 2 strictly ascending "
                                 f"temperatures (°C) with one value each")

    @property
    def range_k(self) -> tuple[float, float]:
        """Valid temperature range, K: 0 °C (the first value held below the first point) to the
        last table point."""
        return ZERO_CELSIUS, self.temperatures_c[-1] + ZERO_CELSIUS

    def __call__(self, temperature: ArrayLike, steel_name: str = "") -> np.ndarray:
        """The property at ``temperature`` (K), linear between table points."""
        kelvin = np.asarray(temperature, dtype=float)
        low, high = self.range_k
        bad = ~np.isfinite(kelvin) | (kelvin < low) | (kelvin > high)
        if np.any(bad):
            first = float(kelvin[bad].flat[0]) if kelvin.ndim else float(kelvin)
            raise RotorAreaError(
                f"steel {steel_name!r}: {self.quantity} is tabulated for {low:.2f}–{high:.2f} K "
                f"(0–{high - ZERO_CELSIUS:.0f} °C), got temperature {first!r} K")
        return np.interp(kelvin - ZERO_CELSIUS, self.temperatures_c, self.values)


@dataclass(frozen=True)
class StrainLife:
    """Manson–Coffin–Basquin constants at one temperature (Dowling, *Mechanical Behavior of
    Materials*, 4th ed., 2013, ch. 14):  ε_a = σ'_f/E·(2N)^b + ε'_f·(2N)^c.

    Stresses in Pa, strains dimensionless, N in cycles; the fields may be arrays (one entry per
    cycle, each at its own temperature). The cyclic Ramberg–Osgood curve
    ε_a = σ_a/E + (σ_a/K')^(1/n') uses the compatibility relations n' = b/c and
    K' = σ'_f/ε'_f^(b/c) (Dowling ch. 14), so the Neuber loop and the life curve agree.
    """

    youngs_modulus: float | np.ndarray
    fatigue_strength_coefficient: float | np.ndarray
    fatigue_strength_exponent: float
    fatigue_ductility_coefficient: float | np.ndarray
    fatigue_ductility_exponent: float

    @property
    def cyclic_hardening_exponent(self) -> float:
        """n' = b/c (dimensionless)."""
        return self.fatigue_strength_exponent / self.fatigue_ductility_exponent

    @property
    def cyclic_strength_coefficient(self) -> float | np.ndarray:
        """K' = σ'_f / ε'_f^(b/c), Pa."""
        return (self.fatigue_strength_coefficient
                / self.fatigue_ductility_coefficient ** self.cyclic_hardening_exponent)

    def strain_amplitude(self, stress_amplitude: ArrayLike) -> np.ndarray:
        """Cyclic stress–strain curve ε_a(σ_a) (Ramberg–Osgood), σ_a in Pa (≥ 0)."""
        s = np.asarray(stress_amplitude, dtype=float)
        return (s / self.youngs_modulus
                + (s / self.cyclic_strength_coefficient) ** (1.0 / self.cyclic_hardening_exponent))


# Uniform Material Law, unalloyed and low-alloy steels (Bäumel & Seeger 1990): σ'_f = 1.5·R_m,
# b = −0.087, ε'_f = 0.59·ψ, c = −0.58, ψ = 1 for R_m/E ≤ 0.003, else 1.375 − 125·R_m/E.
UML_STRENGTH_RATIO = 1.5
UML_STRENGTH_EXPONENT = -0.087
UML_DUCTILITY = 0.59
UML_DUCTILITY_EXPONENT = -0.58


@dataclass(frozen=True)
class CreepRuptureData:
    """Creep-rupture strength points (°C, h, MPa as in the source) and the Larson–Miller
    constant C of P = T·(C + log10 t_r) (T in K, t_r in h; Larson & Miller, Trans. ASME 74
    (1952) 765–775)."""

    points: tuple[tuple[float, float, float], ...]
    larson_miller_constant: float
    source: str

    @property
    def temperatures_k(self) -> np.ndarray:
        return np.array([p[0] for p in self.points]) + ZERO_CELSIUS

    @property
    def rupture_hours(self) -> np.ndarray:
        return np.array([p[1] for p in self.points])

    @property
    def stresses_pa(self) -> np.ndarray:
        return np.array([p[2] for p in self.points]) * 1e6


@dataclass(frozen=True)
class TabulatedSteel:
    """A rotor steel from property tables (see the module docstring); a ``RotorMaterial``."""

    name: str
    density_kg_m3: float
    density_source: str
    specific_heat_table: PropertyTable
    conductivity_table: PropertyTable
    youngs_modulus_table: PropertyTable
    poisson_ratio_value: float
    poisson_source: str
    expansion_table: PropertyTable
    expansion_reference_c: float
    tensile_strength_table: PropertyTable
    creep: CreepRuptureData

    def density(self) -> float:
        """kg/m³."""
        return self.density_kg_m3

    def specific_heat(self, temperature: ArrayLike) -> np.ndarray:
        """J/(kg·K) at ``temperature`` (K)."""
        return self.specific_heat_table(temperature, self.name)

    def conductivity(self, temperature: ArrayLike) -> np.ndarray:
        """W/(m·K) at ``temperature`` (K)."""
        return self.conductivity_table(temperature, self.name)

    def youngs_modulus(self, temperature: ArrayLike) -> np.ndarray:
        """Pa at ``temperature`` (K)."""
        return self.youngs_modulus_table(temperature, self.name)

    def poisson_ratio(self, temperature: ArrayLike) -> np.ndarray:
        """Dimensionless, temperature-independent (see ``poisson_source``); checks the range."""
        return np.full(np.shape(self.youngs_modulus(temperature)), self.poisson_ratio_value)

    def mean_expansion(self, temperature: ArrayLike) -> np.ndarray:
        """Mean coefficient of thermal expansion from ``expansion_reference_c`` to T, 1/K."""
        return self.expansion_table(temperature, self.name)

    def thermal_strain(self, temperature: ArrayLike) -> np.ndarray:
        """Free thermal strain from 20 °C: the source's mean-coefficient strain from its own
        reference re-based to 20 °C, ε(T) − ε(293.15 K), so it is zero at 20 °C exactly."""
        reference = self.expansion_reference_c + ZERO_CELSIUS
        kelvin = np.asarray(temperature, dtype=float)
        strain = self.mean_expansion(kelvin) * (kelvin - reference)
        at_20 = self.mean_expansion(REFERENCE_TEMPERATURE) * (REFERENCE_TEMPERATURE - reference)
        return strain - at_20

    def tensile_strength(self, temperature: ArrayLike) -> np.ndarray:
        """Ultimate tensile strength R_m, Pa, at ``temperature`` (K)."""
        return self.tensile_strength_table(temperature, self.name)

    def strain_life(self, temperature: ArrayLike) -> StrainLife:
        """Manson–Coffin–Basquin constants at ``temperature`` (K, scalar or array: the fields
        then are arrays) by the Uniform Material Law from R_m(T) and E(T) (module docstring);
        the range is that of the tensile table."""
        strength = self.tensile_strength(temperature)
        modulus = self.youngs_modulus(temperature)
        psi = np.where(strength / modulus <= 0.003, 1.0, 1.375 - 125.0 * strength / modulus)
        return StrainLife(youngs_modulus=modulus,
                          fatigue_strength_coefficient=UML_STRENGTH_RATIO * strength,
                          fatigue_strength_exponent=UML_STRENGTH_EXPONENT,
                          fatigue_ductility_coefficient=UML_DUCTILITY * psi,
                          fatigue_ductility_exponent=UML_DUCTILITY_EXPONENT)


# --- 30CrMoNiV5-11 / 1CrMoV / ASTM A470 Class 8 -------------------------------------------------

# ASME B31.1 Table C-6 (= ASME BPVC II-D Table TM-1), "Cr-Mo steels, Cr 1/2 %–2 %", E in 10⁶ psi
# at °F. 1CrMoV (1.05–1.50 % Cr) lies in this group; group value, not a measurement of the grade.
_E_F = (70.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0, 900.0, 1000.0, 1100.0, 1200.0)
_E_MSI = (29.7, 29.0, 28.5, 27.9, 27.5, 26.9, 26.3, 25.5, 24.8, 23.9, 23.0, 21.8)

# ASME BPVC II-D (2001) Table TE-1, "Carbon and low alloy steels (Group 1)", coefficient B: the
# mean coefficient from 70 °F to T, 10⁻⁶/°F. Group value for the Cr–Mo(–V) low-alloy steels.
_TE_F = (70.0, 100.0, 150.0, 200.0, 250.0, 300.0, 350.0, 400.0, 450.0, 500.0, 550.0, 600.0,
         650.0, 700.0, 750.0, 800.0, 850.0, 900.0, 950.0, 1000.0, 1050.0, 1100.0, 1150.0)
_TE_B = (6.4, 6.5, 6.6, 6.7, 6.8, 6.9, 7.0, 7.1, 7.2, 7.3, 7.3, 7.4,
         7.5, 7.6, 7.7, 7.8, 7.9, 7.9, 8.0, 8.1, 8.1, 8.2, 8.3)

_GROUP_C = (20.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0)

CRMOV_ROTOR = TabulatedSteel(
    name="30CrMoNiV5-11",
    density_kg_m3=7850.0,
    density_source="EN 10269 data for 21CrMoV5-7 (1.7709), 7.85 g/cm³ at 20 °C; CrMoV group value",
    specific_heat_table=PropertyTable(
        "specific heat", _GROUP_C, (461.0, 479.0, 499.0, 517.0, 536.0, 558.0, 587.0),
        "low-alloy Cr steel group values (MatWeb-derived records of 55Cr3, EN 10089, and "
        "20MnCr5, DIN 1652-3; identical tables), J/(kg·K); representative, not the grade"),
    conductivity_table=PropertyTable(
        "thermal conductivity", _GROUP_C, (45.1, 45.1, 44.1, 41.9, 39.4, 36.9, 34.4),
        "low-alloy Cr steel 55Cr3 (EN 10089) record, W/(m·K); representative of the group, "
        "not the grade (no CrMoV table found, see docs/rotor.md)"),
    youngs_modulus_table=PropertyTable(
        "Young's modulus", tuple(fahrenheit_to_celsius(f) for f in _E_F),
        tuple(m * 1e6 * PSI for m in _E_MSI),
        "ASME B31.1 Table C-6 / BPVC II-D Table TM-1, Cr-Mo steels 1/2–2 % Cr (group value)"),
    poisson_ratio_value=0.30,
    poisson_source="0.30, temperature-independent: the 31CrMo12 (EN 10085) record; the "
                   "20MnCr5/55Cr3 records give 0.28 (low-alloy steel group value)",
    expansion_table=PropertyTable(
        "mean thermal expansion", tuple(fahrenheit_to_celsius(f) for f in _TE_F),
        tuple(b * 1.8e-6 for b in _TE_B),
        "ASME BPVC II-D (2001) Table TE-1, Group 1 coefficient B (mean from 70 °F), group value"),
    expansion_reference_c=fahrenheit_to_celsius(70.0),
    tensile_strength_table=PropertyTable(
        "tensile strength", (20.0, 500.0, 525.0, 550.0), (900e6, 700e6, 650e6, 600e6),
        "Aubert & Duval data sheet 21CrMoV5-7 (1.5Cr-0.6Mo-0.2V, quenched + tempered 690 °C); "
        "the nearest CrMoV grade with tabulated hot strength; A470 Cl. 8 requires 725–860 MPa "
        "at 20 °C (Landolt-Börnstein VIII/2B §2.2.6)"),
    creep=CreepRuptureData(
        points=((500.0, 1e3, 350.0), (500.0, 1e4, 290.0), (500.0, 1e5, 220.0),
                (525.0, 1e3, 330.0), (525.0, 1e4, 220.0), (525.0, 1e5, 150.0),
                (550.0, 1e3, 270.0), (550.0, 1e4, 180.0), (550.0, 1e5, 120.0)),
        larson_miller_constant=20.0,
        source="mean creep-rupture strength of 21CrMoV5-7 (Aubert & Duval data sheet) at 500, "
               "525, 550 °C and 10³, 10⁴, 10⁵ h; C = 20 (Larson & Miller 1952), which puts the "
               "nine points on one master curve"),
)

_REGISTRY: dict[str, TabulatedSteel] = {
    "30CrMoNiV5-11": CRMOV_ROTOR, "1CrMoV": CRMOV_ROTOR, "A470-8": CRMOV_ROTOR,
}


def steel_names() -> list[str]:
    """The registered steel names (aliases included)."""
    return sorted(_REGISTRY)


def steel(name: str) -> TabulatedSteel:
    """The registered steel called ``name`` (case-insensitive)."""
    for known, material in _REGISTRY.items():
        if known.lower() == str(name).strip().lower():
            return material
    raise RotorAreaError(f"unknown rotor steel {name!r}; known steels: "
                         f"{', '.join(steel_names())}")
