"""Governing-valve data of real units (issue 17, item 1): a rated point between valve points
(design.valve_outlet_pressure), nozzle-group throat areas given directly, and the valves' flow
characteristic (lift against flow share)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.model.design import kernel_constants
from steamtwin.model.design_check import design_line, valve_openings
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.kernel import _level_lift, _level_share, _valve_demand
from steamtwin.model.steampath import KAPPA_SUPERHEATED, nozzle_flow_function
from steamtwin.spec import TurbineSpec
from steamtwin.steam import if97

# A poppet valve passes most of its flow early in its lift [Cotton, ch. 6].
CONCAVE = ((0.0, 0.3, 1.0), (0.0, 0.8, 1.0))


def _wide_open_outlet(spec: TurbineSpec) -> float:
    return spec.design.main_steam_pressure * (1.0 - spec.design.valve_pressure_drop)


def _with_design(spec: TurbineSpec, **changes: float) -> TurbineSpec:
    return dataclasses.replace(spec, design=dataclasses.replace(spec.design, **changes))


def _with_control(spec: TurbineSpec, **changes: object) -> TurbineSpec:
    return dataclasses.replace(spec, control_stage=dataclasses.replace(spec.control_stage,
                                                                       **changes))


def _flux(spec: TurbineSpec, p_valve: float) -> float:
    """Saint-Venant nozzle flow per unit throat area (kg/(s·m²)) at the design point, fed at
    ``p_valve`` (Pa) after an isenthalpic throttle — computed here independently of the model."""
    design = spec.design
    h0 = float(if97.enthalpy_pt(design.main_steam_pressure, design.main_steam_temperature))
    v = float(if97.specific_volume_ph(p_valve, h0))
    psi = nozzle_flow_function(design.control_stage_pressure / p_valve, KAPPA_SUPERHEATED)
    return psi * math.sqrt(p_valve / v)


def test_a_rated_point_between_valve_points_throttles_the_last_open_group(sequential_spec):
    """GV3 (the last group open at design) throttled to 99 % of the wide-open valve outlet at
    design: the throats grow so that GV1–3 still pass the rated flow, and at rated load the
    model's GV3 passes the share of its wide-open flow that the nozzle law gives there."""
    outlet = 0.99 * _wide_open_outlet(sequential_spec)
    spec = _with_design(sequential_spec, valve_outlet_pressure=outlet)
    before = kernel_constants(sequential_spec).control.level_area
    after = kernel_constants(spec).control.level_area
    # rated flow = A/arc·(arc_12·flux_wide + arc_3·flux_throttled): solved for A/arc
    arcs = kernel_constants(spec).control.level_arc
    ratio = _flux(spec, outlet) / _flux(spec, _wide_open_outlet(spec))
    assert after / before == pytest.approx(
        np.full(3, (arcs[0] + arcs[1]) / (arcs[0] + arcs[1] * ratio)), rel=1e-12)
    line = design_line(spec, (1.0,))
    assert line["GV3_opening"].iloc[0] == pytest.approx(ratio, rel=3e-3)
    assert line["GV1_opening"].iloc[0] == 1.0 and line["GV4_opening"].iloc[0] == 0.0
    # the stages are unchanged, so the control-stage pressure still meets the design's
    assert line["control_stage_pressure"].iloc[0] == pytest.approx(
        spec.design.control_stage_pressure, rel=0.005)


def test_the_wide_open_valve_outlet_is_the_valve_point(reference_spec):
    """Limiting case: an outlet pressure equal to the wide-open one sizes the same throats."""
    spec = _with_design(reference_spec, valve_outlet_pressure=_wide_open_outlet(reference_spec))
    np.testing.assert_allclose(kernel_constants(spec).control.level_area,
                               kernel_constants(reference_spec).control.level_area, rtol=1e-12)


def test_given_throat_areas_replace_the_sizing(reference_spec):
    """The throats the design step sized (at the model's own design control-stage pressure)
    given back as data give the same model; 10 % larger throats let the last open group
    throttle more at rated load."""
    control = FullOrderModel(reference_spec).design_.kernel.control
    orders = sorted({v.opening_order for v in reference_spec.control_stage.valves})

    def with_areas(scale: float) -> TurbineSpec:
        valves = tuple(dataclasses.replace(
            valve, throat_area=scale * valve.admission_arc
            * control.level_area[orders.index(valve.opening_order)]
            / control.level_arc[orders.index(valve.opening_order)])
            for valve in reference_spec.control_stage.valves)
        return _with_control(reference_spec, valves=valves)

    np.testing.assert_allclose(kernel_constants(with_areas(1.0)).control.level_area,
                               control.level_area, rtol=1e-12)
    sized = design_line(reference_spec, (1.0,))
    given_back = design_line(with_areas(1.0), (1.0,))
    assert given_back["control_stage_temperature"].iloc[0] == pytest.approx(
        sized["control_stage_temperature"].iloc[0], abs=1e-6)
    larger = design_line(with_areas(1.1), (1.0,))
    assert larger["GV3_opening"].iloc[0] < sized["GV3_opening"].iloc[0] - 0.2


@settings(max_examples=60, deadline=None)
@given(overlap=st.floats(0.01, 0.5), share=st.floats(0.01, 1.0))
def test_the_lift_schedule_passes_the_flow_through_the_characteristic(reference_spec, overlap,
                                                                      share):
    """With a non-linear characteristic the levels' flow shares at the solved demand pass
    exactly the flow asked, and each share is the characteristic at the level's lift."""
    spec = _with_control(reference_spec, valve_overlap=overlap, valve_characteristic=CONCAVE)
    control = kernel_constants(spec).control
    open_flux = 1.0e4  # kg/(s·m²), any positive value: the schedule scales with it
    wide_open = open_flux * control.level_area
    flow = share * wide_open.sum()
    demand = _valve_demand(control, open_flux, flow)
    shares = np.array([_level_share(control, level, demand) for level in range(wide_open.size)])
    lifts = np.array([_level_lift(overlap, level, demand) for level in range(wide_open.size)])
    assert (wide_open * shares).sum() == pytest.approx(flow, rel=1e-12)
    np.testing.assert_allclose(shares, np.interp(lifts, *CONCAVE), rtol=1e-14)


def test_openings_are_reported_as_lifts(sequential_spec):
    """GV1–2 wide open and GV3 passing 80 % of its wide-open flow: with the concave
    characteristic GV3 stands at 30 % lift (linear: 80 %)."""
    arcs = kernel_constants(sequential_spec).control.level_arc
    arc = arcs[0] + 0.8 * arcs[1]
    concave = _with_control(sequential_spec, valve_characteristic=CONCAVE)
    assert valve_openings(concave, arc)["GV3"] == pytest.approx(0.3, abs=1e-9)
    assert valve_openings(sequential_spec, arc)["GV3"] == pytest.approx(0.8, abs=1e-9)
    assert valve_openings(concave, arc)["GV1"] == 1.0
    assert valve_openings(concave, arc)["GV4"] == 0.0
