"""Shared fixtures of the geometry tests: ground-truth blades and one hp1 volume mesh."""

from __future__ import annotations

import pytest

from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.geometry.profile import Blade, make_blade
from steamtwin.geometry.volume_mesh import VolumeMesh
from steamtwin.spec import TurbineSpec


@pytest.fixture(scope="session")
def hp1_blade(reference_spec: TurbineSpec) -> Blade:
    return make_blade(reference_spec, "hp1")


@pytest.fixture(scope="session")
def hp1_mesh(reference_spec: TurbineSpec) -> VolumeMesh:
    return blade_volume_mesh(reference_spec, "hp1")
