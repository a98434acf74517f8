"""The kernel's exact valve-demand walk (issue 18, "GA ≤ 5 min") against the bisection it
replaced, and the model on noisy inputs against a run of the kernel before the change."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.model.kernel import _valve_demand
from steamtwin.model.operating import load_profile_inputs

# Characteristics (lift, flow share): linear, the reference's poppet valve, and one with a flat
# stretch (the least demand passing a flow on it is the stretch's start).
CHARACTERISTICS = (
    ((0.0, 1.0), (0.0, 1.0)),
    ((0.0, 0.2, 0.4, 0.6, 0.8, 1.0), (0.0, 0.30, 0.56, 0.76, 0.90, 1.0)),
    ((0.0, 0.3, 0.6, 1.0), (0.0, 0.5, 0.5, 1.0)),
)


def _bisection_demand(control, open_flux: float, flow: float) -> float:
    """The kernel's former search: 64 bisections of the scheduled flow, np.interp per level."""
    overlap = control.valve_overlap
    low, high = 0.0, (control.level_area.size - 1) * (1.0 - overlap) + 1.0
    for _ in range(64):
        middle = 0.5 * (low + high)
        lifts = np.clip(middle - np.arange(control.level_area.size) * (1.0 - overlap), 0.0, 1.0)
        shares = np.interp(lifts, control.characteristic_lift, control.characteristic_flow)
        if open_flux * (control.level_area * shares).sum() < flow:
            low = middle
        else:
            high = middle
    return high


def _control(reference_model, overlap: float, characteristic) -> object:
    return reference_model.design_.kernel.control._replace(
        valve_overlap=overlap, characteristic_lift=np.array(characteristic[0]),
        characteristic_flow=np.array(characteristic[1]))


@settings(max_examples=80)
@given(overlap=st.floats(0.01, 0.5), share=st.floats(0.0, 1.1),
       which=st.integers(0, len(CHARACTERISTICS) - 1))
def test_the_walk_finds_the_demand_the_bisection_found(reference_model, overlap, share, which):
    """Any overlap, characteristic and flow (up to 10 % over what every valve passes wide
    open): the same least demand as 64 bisections, to round-off (the demand spans 0…~3)."""
    control = _control(reference_model, overlap, CHARACTERISTICS[which])
    open_flux = 1.0e4  # kg/(s·m²); the schedule scales with it
    flow = share * open_flux * control.level_area.sum()
    assert _valve_demand(control, open_flux, flow) == pytest.approx(
        _bisection_demand(control, open_flux, flow), abs=1e-12)


def test_a_flow_on_a_flat_stretch_takes_the_least_demand(reference_model):
    """The first level passing exactly its plateau share (0.5 from lift 0.3 to 0.6) while the
    next is shut: demand 0.3, where the plateau starts."""
    control = _control(reference_model, 0.1, CHARACTERISTICS[2])
    open_flux = 1.0e4
    flow = 0.5 * open_flux * control.level_area[0]
    assert _valve_demand(control, open_flux, flow) == pytest.approx(0.3, abs=1e-12)


# The kernel before the valve-demand walk and the inlined per-sample solve (main of
# 2026-11-27, commit 25e950b): 600 s of DCS-like noisy inputs (σ 0.1 % of 16.7 MPa, 1 K, 0.5 %
# of rated flow, 0.1 % of 3.9 MPa; seed 3) at 34 % load and at 81.5 %, where GV1–2 are part
# open and GV3 lifts in their overlap. Columns: sample, control-stage pressure (Pa),
# control-stage, HP-exhaust and inner-casing temperatures (K).
BEFORE = {
    0.34: ((0, 4589679.370898921, 754.2166822974251, 582.2430393898608, 754.0454204908694),
           (299, 4571038.196639728, 756.3059092859976, 584.0623939850268, 753.787407396188),
           (599, 4559412.981345183, 755.8324912184082, 585.1884059110937, 753.8408318468689)),
    0.815: ((0, 10572275.525817167, 750.0413260809084, 580.8278505565409, 749.9048951957193),
            (299, 10567933.401391277, 752.2475137989104, 582.4464108747786, 749.709663693146),
            (599, 10556937.06308517, 752.0726100234776, 582.9555909800483, 749.6967432063506)),
}


@pytest.mark.parametrize("load", sorted(BEFORE))
def test_noisy_inputs_give_what_the_kernel_gave_before(reference_model, reference_spec, load):
    """Within 1e-4 K and 0.5 Pa of the former kernel (measured: ≤ 1e-8 K, ≤ 3e-5 Pa): the
    speed-ups change the results by round-off only, far inside the solver's tolerances
    (25 J/kg ≈ 0.01 K, 1e-4 of the control-stage pressure)."""
    frame = load_profile_inputs(reference_spec, np.full(600, load))
    random = np.random.default_rng(3)
    noise = {"main_steam_pressure": 0.001 * 16.7e6, "main_steam_temperature": 1.0,
             "main_steam_flow": 0.005 * 500.0, "hp_exhaust_pressure": 0.001 * 3.9e6}
    for column, sigma in noise.items():
        frame[column] += random.normal(0.0, sigma, len(frame))
    diagnostics = reference_model.simulate_detailed(frame, stages=False).diagnostics
    columns = ["control_stage_pressure", "control_stage_temperature", "hp_exhaust_temperature",
               "hp_inner_casing_temperature"]
    for sample, pressure, *temperatures in BEFORE[load]:
        row = diagnostics[columns].iloc[sample].to_numpy()
        assert row[0] == pytest.approx(pressure, abs=0.5)
        np.testing.assert_allclose(row[1:], temperatures, atol=1e-4, rtol=0.0)
