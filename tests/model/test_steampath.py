"""Stage physics: nozzle flow function, Stodola's law, velocity-ratio efficiency."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from steamtwin.model.steampath import (
    critical_pressure_ratio,
    nozzle_flow_function,
    optimum_velocity_ratio,
    stage_efficiency,
    stodola_inlet_pressure,
)


def test_critical_ratio_of_superheated_steam():
    assert critical_pressure_ratio(1.3) == pytest.approx(0.5457, abs=1e-4)


def test_flow_function_limits():
    assert nozzle_flow_function(1.0, 1.3) == 0.0
    choked = nozzle_flow_function(critical_pressure_ratio(1.3), 1.3)
    # κ·(2/(κ+1))^((κ+1)/(κ−1)) under the root for choked flow
    assert choked == pytest.approx(math.sqrt(1.3 * (2 / 2.3) ** (2.3 / 0.3)), rel=1e-12)
    assert nozzle_flow_function(0.2, 1.3) == choked


@given(st.floats(0.55, 0.999), st.floats(1e-4, 0.04))
def test_flow_function_falls_as_back_pressure_rises(ratio, step):
    assert nozzle_flow_function(min(ratio + step, 1.0), 1.3) < nozzle_flow_function(ratio, 1.3)


@given(flow=st.floats(1.0, 600.0), capacity=st.floats(0.01, 0.2), outlet=st.floats(1e5, 15e6),
       pv=st.floats(1e5, 4e5))
def test_stodola_inverse_returns_the_flow(flow, capacity, outlet, pv):
    p_in = stodola_inlet_pressure(flow, capacity, outlet, pv)
    assert p_in > outlet
    # compare p_in² − p_out² directly: the difference of squares is round-off limited
    assert p_in**2 - outlet**2 == pytest.approx((flow / capacity) ** 2 * pv, rel=1e-9,
                                                abs=1e-14 * p_in**2)


def test_velocity_ratio_law_peaks_at_the_optimum():
    optimum = optimum_velocity_ratio(math.radians(13.0), 0.0)
    assert optimum == pytest.approx(math.cos(math.radians(13.0)) / 2)
    assert optimum_velocity_ratio(math.radians(16.0), 0.5) == pytest.approx(
        math.cos(math.radians(16.0)) / math.sqrt(2))
    peak = stage_efficiency(optimum, optimum, 0.9, 0.03)
    assert peak == pytest.approx(0.87)
    assert stage_efficiency(0.8 * optimum, optimum, 0.9, 0.03) < peak
    assert stage_efficiency(1.2 * optimum, optimum, 0.9, 0.03) < peak
    assert stage_efficiency(5 * optimum, optimum, 0.9, 0.03) == 0.0
