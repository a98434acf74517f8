"""The rotor package's public names resolve to the objects of the modules named for them."""

import importlib

import steamtwin.rotor as rotor


def test_every_public_rotor_name_is_the_object_of_its_module():
    for name in rotor.__all__:
        module = importlib.import_module(rotor._EXPORTS[name])
        assert getattr(rotor, name) is getattr(module, name)
    assert {"RotorModel", "rotor_life", "RampAdvisor", "rotor_stress"} <= set(dir(rotor))
