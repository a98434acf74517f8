"""Shared fixtures: the reference spec and one full-order model per test session."""

from __future__ import annotations

import pytest

from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import TurbineSpec, load_spec


@pytest.fixture(scope="session")
def reference_spec() -> TurbineSpec:
    return load_spec("reference")


@pytest.fixture(scope="session")
def reference_model(reference_spec: TurbineSpec) -> FullOrderModel:
    model = FullOrderModel(reference_spec)
    _ = model.design_  # design step (compiles the kernel) once per session
    return model
