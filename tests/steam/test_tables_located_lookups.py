"""The located-pressure look-ups the kernel uses against the plain (p, h) look-ups.

A caller that locates a pressure once (``locate_pressure`` / ``locate_log_pressure``) must get
bit for bit what the look-ups that locate it themselves give: the kernel's outputs may not
move when it reuses a located cell (tables module docstring; IAPWS G13-15 SBTL).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from steamtwin.steam.tables import (
    PH_CP,
    PH_K,
    PH_MU,
    PH_S,
    PH_T,
    PH_V,
    enthalpy_pt,
    enthalpy_pt_at,
    heat_transfer_properties_at,
    locate_log_pressure,
    locate_pressure,
    ph_domain_position,
    ph_domain_position_at,
    ph_properties,
    ph_property,
    ph_property_and_position_at,
    steam_tables,
)


@pytest.fixture(scope="module")
def states():
    """Superheated states over the table's pressures (both ln p segments) and beyond its edges."""
    rng = np.random.default_rng(3)
    p = np.exp(rng.uniform(math.log(0.06e6), math.log(24e6), 200))
    p[:3] = (16.5291643e6, 0.05e6, 25e6)  # the kink and the ends
    y = rng.uniform(-0.05, 1.05, p.size)  # a little outside: extrapolated cells
    tables = steam_tables()
    h = np.array([
        (1 - yk) * enthalpy_pt(tables, pk, 700.0) + yk * enthalpy_pt(tables, pk, 900.0)
        for pk, yk in zip(p, y, strict=True)
    ])
    return tables, p, h


def test_log_location_is_the_pressure_location(states):
    tables, p, _ = states
    for pk in p:
        assert locate_log_pressure(tables, math.log(pk)) == locate_pressure(tables, pk)


def test_located_look_ups_equal_the_plain_ones(states):
    tables, p, h = states
    out, full = np.full(6, -1.0), np.empty(6)
    for pk, hk in zip(p, h, strict=True):
        i, t = locate_pressure(tables, pk)
        position = ph_domain_position(tables, pk, hk)
        assert ph_domain_position_at(tables, i, t, hk) == position
        for prop in (PH_T, PH_V, PH_S):
            value, at_position = ph_property_and_position_at(tables, prop, i, t, pk, hk)
            assert value == ph_property(tables, prop, pk, hk)
            assert at_position == position
        out[PH_S] = -1.0
        assert heat_transfer_properties_at(tables, i, t, pk, hk, out) == position
        ph_properties(tables, pk, hk, full)
        for prop in (PH_T, PH_V, PH_CP, PH_MU, PH_K):
            assert out[prop] == full[prop]
        assert out[PH_S] == -1.0  # the entropy is not computed
        assert enthalpy_pt_at(tables, i, t, 800.0) == enthalpy_pt(tables, pk, 800.0)


def test_geometric_mean_located_by_the_mean_logarithm(states):
    """sqrt(p_a·p_b) located at (ln p_a + ln p_b)/2: the same cell, t within round-off, so the
    temperature there within 1e-9 K of the plain look-up."""
    tables, p, h = states
    for pa, pb, hk in zip(p[:-1], p[1:], h[1:], strict=True):
        mean = math.sqrt(pa * pb)
        i, t = locate_log_pressure(tables, 0.5 * (math.log(pa) + math.log(pb)))
        i_ref, t_ref = locate_pressure(tables, mean)
        if i != i_ref:  # on a cell face: the neighbour's t is 1 or 0
            assert abs((i + t) - (i_ref + t_ref)) < 1e-11
            continue
        assert abs(t - t_ref) < 1e-11
        temperature, _ = ph_property_and_position_at(tables, PH_T, i, t, mean, hk)
        assert abs(temperature - ph_property(tables, PH_T, mean, hk)) < 1e-9
