"""The rotor steel tables against their sources and against a second source of the same group."""

import numpy as np
import pytest

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.material import REFERENCE_TEMPERATURE, RotorMaterial
from steamtwin.rotor.steel import steel, steel_names

C = 273.15


def test_registry_finds_aliases_case_insensitively_and_lists_names_on_a_miss():
    assert steel("1crmov") is steel("30CrMoNiV5-11") is steel(" A470-8 ")
    assert isinstance(steel("1CrMoV"), RotorMaterial)
    with pytest.raises(RotorAreaError, match="known steels: 1CrMoV, 30CrMoNiV5-11, A470-8"):
        steel("X20CrMoV12-1")
    assert steel_names() == ["1CrMoV", "30CrMoNiV5-11", "A470-8"]


def test_youngs_modulus_reproduces_asme_table_points_in_si():
    material = steel("1CrMoV")
    # ASME B31.1 Table C-6, Cr-Mo 1/2-2 % Cr: 29.7 Msi at 70 °F, 23.9 Msi at 1000 °F.
    at = np.array([(70.0 - 32) / 1.8, (1000.0 - 32) / 1.8]) + C
    np.testing.assert_allclose(material.youngs_modulus(at), np.array([29.7, 23.9]) * 6.894757e9,
                               rtol=1e-6)


@pytest.mark.parametrize(("celsius", "other_gpa"), [(20.0, 212.0), (500.0, 175.0), (600.0, 164.0)])
def test_youngs_modulus_agrees_with_the_en_low_alloy_records_within_5_percent(celsius, other_gpa):
    # 20MnCr5 / 55Cr3 / 31CrMo12 records: 212, 175, 164 GPa at 20, 500, 600 °C.
    assert steel("1CrMoV").youngs_modulus(celsius + C) == pytest.approx(other_gpa * 1e9, rel=0.05)


def test_thermal_strain_is_zero_at_20_degC_and_matches_the_crmov_data_sheet():
    material = steel("1CrMoV")
    assert material.thermal_strain(REFERENCE_TEMPERATURE) == pytest.approx(0.0, abs=1e-15)
    # Aubert & Duval 21CrMoV5-7: mean coefficient 20 °C → 200/400/600 °C = 12.5/13.5/14.3e-6/K.
    celsius = np.array([200.0, 400.0, 600.0])
    mean_from_20 = material.thermal_strain(celsius + C) / (celsius - 20.0)
    np.testing.assert_allclose(mean_from_20, [12.5e-6, 13.5e-6, 14.3e-6], rtol=0.04)
    # ASME TE-1 coefficient B at 1000 °F: 8.1e-6/°F, mean from 70 °F.
    assert material.mean_expansion((1000.0 - 32) / 1.8 + C) == pytest.approx(8.1e-6 * 1.8)


def test_properties_are_positive_and_conductivity_falls_with_temperature():
    material = steel("1CrMoV")
    kelvin = np.linspace(C, 600.0 + C, 61)
    k = material.conductivity(kelvin)
    assert np.all(np.diff(k) <= 0.0) and k[0] == pytest.approx(45.1)
    assert np.all(np.diff(material.specific_heat(kelvin[2:])) > 0.0)  # from 20 °C up
    assert np.all(material.poisson_ratio(kelvin) == 0.30)
    assert material.density() == 7850.0


@pytest.mark.parametrize("kelvin", [250.0, 700.0 + C, float("nan")])
def test_properties_refuse_temperatures_outside_the_tables_and_name_the_range(kelvin):
    with pytest.raises(RotorAreaError, match=r"conductivity is tabulated for 273.15–873.15 K"):
        steel("1CrMoV").conductivity(np.array([500.0, kelvin]))


def test_uniform_material_law_constants_by_hand_at_500_degC():
    material = steel("1CrMoV")
    curve = material.strain_life(500.0 + C)
    e = float(material.youngs_modulus(500.0 + C))
    psi = 1.375 - 125.0 * 700e6 / e  # R_m/E = 0.0041 > 0.003
    assert curve.fatigue_strength_coefficient == pytest.approx(1.5 * 700e6)
    assert curve.fatigue_ductility_coefficient == pytest.approx(0.59 * psi)
    assert (curve.fatigue_strength_exponent, curve.fatigue_ductility_exponent) == (-0.087, -0.58)
    # Compatibility: the cyclic curve passes through the life curve's (σ_a, ε_pa) at any life.
    reversals = 1e4
    sigma_a = 1.5 * 700e6 * reversals ** -0.087
    eps_pa = 0.59 * psi * reversals ** -0.58
    assert curve.strain_amplitude(sigma_a) == pytest.approx(sigma_a / e + eps_pa, rel=1e-12)
    with pytest.raises(RotorAreaError, match="tensile strength is tabulated for"):
        material.strain_life(560.0 + C)
