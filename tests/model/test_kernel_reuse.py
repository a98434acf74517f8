"""The first sweep's reuse of the predictor's control stage (kernel._shifted_control_stage)."""

from __future__ import annotations

import numpy as np
import pytest

from steamtwin.model import kernel
from steamtwin.steam.tables import (
    enthalpy_pt,
    entropy_and_pv_at,
    locate_pressure,
    steam_tables,
)


def _stage(constants, tables, flow, p0, t0, p1, throttled):
    """Full control-stage evaluation: outlet enthalpy (J/kg) and its out array."""
    p_valve = p0 * (1.0 - constants.control.valve_pressure_drop)
    h0 = enthalpy_pt(tables, p0, t0)
    cell, coordinate = locate_pressure(tables, p_valve)
    s_valve, pv_valve = entropy_and_pv_at(tables, cell, coordinate, h0)
    out = np.zeros(7)
    cell_1, coordinate_1 = locate_pressure(tables, p1)
    h1 = kernel._control_stage(constants.control, tables, flow, p_valve, s_valve, pv_valve, h0,
                               p1, cell_1, coordinate_1, np.array([1.0, 1.0, 1.0]), throttled,
                               out, kernel.THROTTLE_TOLERANCE)
    return h1, out


@pytest.mark.parametrize("load", [0.35, 0.6, 0.97])
def test_a_secant_slope_from_the_last_sample_shifts_the_outlet_to_within_5_percent(
        reference_model, load):
    """Measured on one sample's inputs, used on the next one's (flow +0.5 %, main steam
    +1 K: a DCS-noise step), the shifted outlet enthalpy and power stay within 5 % of the
    shift of a full evaluation; the shift the kernel allows (REUSE_SHARE × 25 J/kg) thus
    errs by ≤ 5 J/kg ≈ 0.002 K."""
    constants = reference_model.design_.kernel
    tables = steam_tables()
    design_flow = constants.design_flow
    p0, t0 = 16.7e6, 811.0
    flow = load * design_flow
    p1 = 13.03e6 * load  # Stodola: the control-stage pressure ∝ flow
    throttled = np.zeros((2, constants.control.level_area.size))
    throttled[0, :] = p0
    step = 2e-4 * p1
    h_a, out_a = _stage(constants, tables, flow, p0, t0, p1, throttled)
    h_b, _ = _stage(constants, tables, flow, p0, t0, p1 + step, throttled)
    assert out_a[4] > 0.0, "a valve must be part open at this load"
    slope = (h_b - h_a) / step
    assert 0.0 < slope < 0.05  # m³/kg: η·v of superheated steam at the control stage
    # next sample: other inputs, the predictor's p1 and then the first sweep's p1 + shift
    flow, t0 = flow * 1.005, t0 + 1.0
    h_p, out_p = _stage(constants, tables, flow, p0, t0, p1, throttled)
    assert out_p[4] == out_a[4]
    for shift in (-4.0 * 25.0 / slope, 25.0 / slope, 4.0 * 25.0 / slope):
        shifted_out = out_p.copy()
        shifted_out[5] = slope
        shifted = kernel._shifted_control_stage(h_p, shift, flow, shifted_out)
        full, full_out = _stage(constants, tables, flow, p0, t0, p1 + shift, throttled.copy())
        assert abs(shifted - full) <= 0.05 * abs(full - h_p)
        assert abs(shifted_out[1] - full_out[1]) <= 0.05 * abs(full_out[1] - out_p[1])
