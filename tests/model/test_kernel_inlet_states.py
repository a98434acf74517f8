"""The per-sample look-ups that depend on the inputs alone (``kernel.inlet_states``), computed
once per series and kept on its ``CheckedInputs``: the same numbers the time loop computed at
every run before, and the same runs from a kept or a fresh copy."""

from __future__ import annotations

import numpy as np

from steamtwin.model import kernel
from steamtwin.model.operating import load_profile_inputs, ramp_profile
from steamtwin.model.parameters import ModelParameters
from steamtwin.steam.tables import (
    enthalpy_pt_at,
    entropy_and_pv_at,
    locate_pressure,
    ph_domain_position_at,
    pressure_in_range,
    steam_tables,
)


def _per_sample(constants: kernel.KernelConstants, p0, t0, flow, p_exhaust) -> np.ndarray:
    """What the time loop computed at each sample (as written there before): h0, the valve
    outlet's entropy and p·v, the Reynolds factor's excess; NaN h0 off the tables."""
    tables = steam_tables()
    out = np.full((kernel.INLET_ROWS, p0.size), np.nan)
    for k in range(p0.size):
        if not pressure_in_range(tables, p0[k]) or not pressure_in_range(tables, p_exhaust[k]):
            continue
        cell, coordinate = locate_pressure(tables, p0[k])
        h0 = enthalpy_pt_at(tables, cell, coordinate, t0[k])
        if not 0.0 <= ph_domain_position_at(tables, cell, coordinate, h0) <= 1.0:
            continue
        p_valve = p0[k] * (1.0 - constants.control.valve_pressure_drop)
        cell_v, coordinate_v = locate_pressure(tables, p_valve)
        out[0, k] = h0
        out[1, k], out[2, k] = entropy_and_pv_at(tables, cell_v, coordinate_v, h0)
        out[3, k] = (flow[k] / constants.design_flow) ** -constants.reynolds_exponent - 1.0
    return out


def test_inlet_states_are_the_loops_former_look_ups_to_the_bit(reference_spec, reference_model):
    inputs = load_profile_inputs(reference_spec, ramp_profile(0.4, 1.0, 0.05, 30.0, 30.0))
    checked = reference_model.check_inputs(inputs)
    constants = reference_model.design_.kernel
    columns = [checked.columns[name] for name in reference_model.input_signals]
    kept = checked.inlet_states(constants)
    np.testing.assert_array_equal(kept, _per_sample(constants, *columns))
    assert checked.inlet_states(constants) is kept  # computed once per series


def test_inputs_off_the_tables_give_nan_for_the_kernel_to_report(reference_model):
    constants = reference_model.design_.kernel
    # 30 MPa: above the tables' 25 MPa; an exhaust at 0.02 MPa: below their 0.05 MPa
    p0 = np.array([16.0e6, 30.0e6, 16.0e6])
    t0, flow = np.full(3, 810.0), np.full(3, 400.0)
    p_exhaust = np.array([3.5e6, 3.5e6, 0.02e6])
    inlet = np.empty((kernel.INLET_ROWS, 3))
    kernel.inlet_states(steam_tables(), constants.control.valve_pressure_drop,
                        constants.design_flow, constants.reynolds_exponent, p0, t0, flow,
                        p_exhaust, inlet)
    assert np.isfinite(inlet[:, 0]).all()
    assert np.isnan(inlet[0, 1:]).all()
    np.testing.assert_array_equal(inlet[:, :1], _per_sample(constants, p0, t0, flow,
                                                            p_exhaust)[:, :1])


def test_a_kept_copy_runs_as_a_fresh_one(reference_spec, reference_model):
    """Runs of one checked series reuse its inlet states: same readings as a series checked
    anew, for parameters that change the flow split and the Reynolds-independent parts."""
    inputs = load_profile_inputs(reference_spec, ramp_profile(0.5, 0.8, 0.05, 20.0, 20.0))
    kept = reference_model.check_inputs(inputs)
    for params in (ModelParameters(), ModelParameters(0.97, 1.3, 0.6)):
        again = reference_model.simulate_checked(kept, params)
        fresh = reference_model.simulate_checked(reference_model.check_inputs(inputs), params)
        np.testing.assert_array_equal(again, fresh)
        np.testing.assert_array_equal(fresh, reference_model.simulate(inputs, params).to_numpy())
