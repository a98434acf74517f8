"""The constant material: its properties, its thermal strain's zero, its refusals."""

import numpy as np
import pytest

from steamtwin.errors import SteamtwinError
from steamtwin.rotor.material import REFERENCE_TEMPERATURE, ConstantMaterial, RotorMaterial


def steel(**changes):
    values = dict(name="test", density_=7850.0, specific_heat_=460.0, conductivity_=40.0,
                  youngs_modulus_=2.1e11, poisson_ratio_=0.3, expansion_coefficient=1.2e-5)
    values.update(changes)
    return ConstantMaterial(**values)


def test_constant_material_is_a_rotor_material_with_zero_strain_at_20_degC():
    material = steel()
    assert isinstance(material, RotorMaterial)
    temperatures = np.array([REFERENCE_TEMPERATURE, REFERENCE_TEMPERATURE + 100.0])
    np.testing.assert_allclose(material.thermal_strain(temperatures), [0.0, 1.2e-3])
    assert material.conductivity(temperatures).shape == (2,)


@pytest.mark.parametrize("change", [{"conductivity_": -1.0}, {"density_": float("nan")},
                                    {"poisson_ratio_": 0.5}])
def test_constant_material_refuses_unphysical_values(change):
    with pytest.raises(SteamtwinError, match="material 'test'"):
        steel(**change)
