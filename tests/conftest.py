"""Shared fixtures: the reference spec and one full-order model per test session."""

from __future__ import annotations

import dataclasses
import os

import pytest
from hypothesis import settings

from steamtwin.model.fom import FullOrderModel
from steamtwin.spec import ControlStage, TurbineSpec, load_spec

# Property tests draw the same examples on every run (CI included): a failure is reproducible
# and a green run stays green. HYPOTHESIS_PROFILE=explore searches afresh with more examples.
# No per-example deadline: a test's speed is a benchmark's business, not a pass/fail criterion
# (hypothesis's 200-ms deadline failed a profile test that took 311 ms once on a loaded machine).
settings.register_profile("deterministic", derandomize=True, print_blob=True, deadline=None)
settings.register_profile("explore", max_examples=300, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))


@pytest.fixture(scope="session")
def reference_spec() -> TurbineSpec:
    return load_spec("reference")


@pytest.fixture(scope="session")
def reference_model(reference_spec: TurbineSpec) -> FullOrderModel:
    model = FullOrderModel(reference_spec)
    _ = model.design_  # design step (compiles the kernel) once per session
    return model


@pytest.fixture(scope="session")
def sequential_spec(reference_spec: TurbineSpec) -> TurbineSpec:
    """The reference unit without its valve management: governing valves opened strictly in
    sequence, flow linear in lift (the spec defaults) — the premise of the valve-schedule tests
    written before the reference stated its overlap and characteristic."""
    control = dataclasses.replace(reference_spec.control_stage,
                                  valve_overlap=ControlStage.valve_overlap,
                                  valve_characteristic=ControlStage.valve_characteristic)
    return dataclasses.replace(reference_spec, control_stage=control)


@pytest.fixture(scope="session")
def sequential_model(sequential_spec: TurbineSpec) -> FullOrderModel:
    model = FullOrderModel(sequential_spec)
    _ = model.design_
    return model


def model_as_plant(spec: TurbineSpec, loads, flow_coefficient, sigma, *, seed: int,
                   step_seconds: float = 1.0, friction_coefficient: float = 1.0):
    """The model itself as the plant: ``loads`` (fraction per sample) on the operating line, a
    time-varying ``flow_coefficient`` (per sample), each sensor of ``sigma`` (SI) read with
    white noise of that σ; the frame also has the inputs and the load (W)."""
    import numpy as np
    import pandas as pd

    from steamtwin.model.operating import load_profile_inputs

    model = FullOrderModel(spec)
    inputs = load_profile_inputs(spec, np.asarray(loads, dtype=float), step_seconds=step_seconds)
    parameters = pd.DataFrame({"flow_coefficient": flow_coefficient,
                               "friction_coefficient": friction_coefficient,
                               "heat_transfer_coefficient": 1.0}, index=inputs.index)
    outputs = model.simulate_varying(inputs, parameters).outputs
    rng = np.random.default_rng(seed)
    data = inputs.copy()
    for name, error in sigma.items():
        data[name] = outputs[name].to_numpy() + rng.normal(0.0, error, len(outputs))
    data["load"] = np.asarray(loads, dtype=float) * spec.design.generator_power
    return data


@pytest.fixture(scope="session")
def model_plant():
    """:func:`model_as_plant`, for tests that need a plant the twin matches exactly."""
    return model_as_plant
