"""Shared fixtures: the reference spec and one full-order model per test session."""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import TurbineSpec, load_spec

# Property tests draw the same examples on every run (CI included): a failure is reproducible
# and a green run stays green. HYPOTHESIS_PROFILE=explore searches afresh with more examples.
settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.register_profile("explore", max_examples=300)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))


@pytest.fixture(scope="session")
def reference_spec() -> TurbineSpec:
    return load_spec("reference")


@pytest.fixture(scope="session")
def reference_model(reference_spec: TurbineSpec) -> FullOrderModel:
    model = FullOrderModel(reference_spec)
    _ = model.design_  # design step (compiles the kernel) once per session
    return model
