"""Accuracy and behaviour of the spline steam tables (steamtwin.steam.tables).

The reference is the IAPWS-IF97 *basic* equation through ``steamtwin.steam.if97``: random
states are generated in (p, T), their h, s, v, cp, mu, k evaluated with the forward functions,
and the tables must reproduce T(p, h), s(p, h), … , h(p, s) and h(p, T).  No IF97 backward
equation is involved, so the errors below are the tables' own interpolation errors.

Bounds asserted here (measured maximum over 10⁶ random points in parentheses, 10 % of them in
the 0.05 K margin between the region-2 boundary and the table's lower edge, which is served by
extrapolation; grid nx = 180 + 48, ny = 128/128/160):
  T(p,h) 1 mK (0.135 mK), s(p,h) 1e-3 J/(kg K) (1.2e-4), v(p,h) 2e-6 rel. (4.2e-7),
  cp 1e-4 rel. (2.0e-5), mu 1e-5 rel. (1.8e-6), k 1e-4 rel. (3.5e-5),
  h(p,s) 0.5 J/kg (0.076), h(p,T) 2 J/kg (0.65 inside the table, 1.21 in the margin).
No relaxation near the boundary was needed: the (p,T) table clusters its nodes there.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from steamtwin.steam import if97
from steamtwin.steam import tables as tb

pytestmark = pytest.mark.slow  # 5 s of the full suite (2026-11-27): not in the quick loop

TOL_T = 1e-3  # K
TOL_S = 1e-3  # J/(kg K)
RTOL_V = 2e-6
RTOL_CP = 1e-4
RTOL_MU = 1e-5
RTOL_K = 1e-4
TOL_H_PS = 0.5  # J/kg
TOL_H_PT = 2.0  # J/kg

RTOL = {tb.PH_V: RTOL_V, tb.PH_CP: RTOL_CP, tb.PH_MU: RTOL_MU, tb.PH_K: RTOL_K}

FORWARD = {
    tb.PH_S: if97.entropy_pt,
    tb.PH_V: if97.specific_volume_pt,
    tb.PH_CP: if97.isobaric_heat_capacity_pt,
    tb.PH_MU: if97.viscosity_pt,
    tb.PH_K: if97.thermal_conductivity_pt,
}

LN_P = st.floats(math.log(tb.P_MIN), math.log(tb.P_MAX))
UNIT = st.floats(0.0, 1.0)


def pressure(ln_p: float) -> float:
    """exp(ln p) clipped to the table range (exp(log(P_MAX)) may round above P_MAX)."""
    return min(max(math.exp(ln_p), tb.P_MIN), tb.P_MAX)


@pytest.fixture(scope="session")
def tables() -> tb.SteamTables:
    return tb.steam_tables()


def domain_temperature(p, y):
    """T at normalised position y ∈ [0, 1] between the table's lower edge and T_MAX."""
    t_low = tb.lower_boundary_temperature(p) + tb.T_MARGIN
    return t_low + y * (tb.T_MAX - t_low)


@pytest.fixture(scope="module")
def sample():
    """Random states: 20 000 in the table (half clustered near the lower edge) and 5 000 in
    the margin between the region-2 boundary and the table's lower edge."""
    rng = np.random.default_rng(20240611)
    n, m = 20_000, 5_000
    p = np.exp(rng.uniform(math.log(tb.P_MIN), math.log(tb.P_MAX), n + m))
    y = rng.uniform(0.0, 1.0, n)
    y[::2] **= 3
    T = np.concatenate(
        [
            domain_temperature(p[:n], y),
            tb.lower_boundary_temperature(p[n:]) + rng.uniform(1e-3, tb.T_MARGIN, m),
        ]
    )
    return {
        "p": p,
        "T": T,
        "h": if97.enthalpy_pt(p, T),
        tb.PH_T: T,
        **{prop: f(p, T) for prop, f in FORWARD.items()},
    }


# ------------------------------------------------------------------------------------------
# Structure
# ------------------------------------------------------------------------------------------


def test_tables_are_a_namedtuple_of_float64_arrays(tables):
    assert isinstance(tables, tuple)
    assert tables._fields == ("meta", "bounds", "ph", "ps", "pt")
    for arr in tables:
        assert isinstance(arr, np.ndarray)
        assert arr.dtype == np.float64
        assert arr.flags.c_contiguous
    assert tables.ph.shape[0] == len(tb.PH_NAMES) == 6
    assert tb.steam_tables() is tables  # built once per process


def test_b23_boundary_check_value():
    # IF97 B23 check: T = 623.15 K <-> p = 16.5291643 MPa
    assert pytest.approx(16.5291643e6, rel=1e-8) == tb.P_SPLIT
    assert tb._t_b23(np.array(16.5291643e6)) == pytest.approx(623.15, abs=1e-6)


def test_lower_boundary_is_continuous_at_the_split():
    below = tb.lower_boundary_temperature(tb.P_SPLIT * (1 - 1e-9))
    above = tb.lower_boundary_temperature(tb.P_SPLIT * (1 + 1e-9))
    assert below == pytest.approx(623.15, abs=1e-4)
    assert above == pytest.approx(623.15, abs=1e-4)
    p = np.array([0.1e6, 1e6, 10e6, 20e6])
    T_b = tb.lower_boundary_temperature(p)
    assert T_b[:3] == pytest.approx(if97.saturation_temperature(p[:3]), abs=1e-9)
    assert T_b[3] > float(if97.saturation_temperature(20e6))  # B23 lies above Tsat


# ------------------------------------------------------------------------------------------
# Accuracy against IF97
# ------------------------------------------------------------------------------------------


def test_temperature_ph_accuracy(tables, sample):
    T = tb.tables_temperature_ph(sample["p"], sample["h"], tables)
    assert np.max(np.abs(T - sample["T"])) <= TOL_T


def test_entropy_ph_accuracy(tables, sample):
    s = tb.tables_ph_property(tb.PH_S, sample["p"], sample["h"], tables)
    assert np.max(np.abs(s - sample[tb.PH_S])) <= TOL_S


@pytest.mark.parametrize("prop", [tb.PH_V, tb.PH_CP, tb.PH_MU, tb.PH_K])
def test_relative_accuracy_ph(tables, sample, prop):
    got = tb.tables_ph_property(prop, sample["p"], sample["h"], tables)
    assert np.max(np.abs(got / sample[prop] - 1.0)) <= RTOL[prop]


def test_enthalpy_ps_accuracy(tables, sample):
    h = tb.tables_enthalpy_ps(sample["p"], sample[tb.PH_S], tables)
    assert np.max(np.abs(h - sample["h"])) <= TOL_H_PS


def test_enthalpy_pt_accuracy(tables, sample):
    h = tb.tables_enthalpy_pt(sample["p"], sample["T"], tables)
    assert np.max(np.abs(h - sample["h"])) <= TOL_H_PT


@settings(max_examples=300, deadline=None)
@given(ln_p=LN_P, y=UNIT)
def test_ph_properties_hypothesis(ln_p, y):
    tables = tb.steam_tables()  # not a fixture: hypothesis would repr it
    p = pressure(ln_p)
    T = float(domain_temperature(p, y))
    h = float(if97.enthalpy_pt(p, T))
    assert tb.tables_temperature_ph(p, h, tables) == pytest.approx(T, abs=TOL_T)
    s = tb.tables_ph_property(tb.PH_S, p, h, tables)
    assert s == pytest.approx(if97.entropy_pt(p, T), abs=TOL_S)
    for prop, rtol in RTOL.items():
        got = tb.tables_ph_property(prop, p, h, tables)
        assert got == pytest.approx(FORWARD[prop](p, T), rel=rtol), tb.PH_NAMES[prop]


@settings(max_examples=300, deadline=None)
@given(ln_p=LN_P, y=UNIT)
def test_enthalpy_ps_pt_hypothesis(ln_p, y):
    tables = tb.steam_tables()  # not a fixture: hypothesis would repr it
    p = pressure(ln_p)
    T = float(domain_temperature(p, y))
    h = float(if97.enthalpy_pt(p, T))
    s = float(if97.entropy_pt(p, T))
    assert tb.tables_enthalpy_ps(p, s, tables) == pytest.approx(h, abs=TOL_H_PS)
    assert tb.tables_enthalpy_pt(p, T, tables) == pytest.approx(h, abs=TOL_H_PT)


@settings(max_examples=200, deadline=None)
@given(ln_p=LN_P, y=UNIT)
def test_round_trips(ln_p, y):
    tables = tb.steam_tables()  # not a fixture: hypothesis would repr it
    p = pressure(ln_p)
    T = float(domain_temperature(p, y))
    h = float(if97.enthalpy_pt(p, T))
    # h -> T(p, h) -> h(p, T)
    T_tab = tb.tables_temperature_ph(p, h, tables)
    cp = float(if97.isobaric_heat_capacity_pt(p, T))
    assert tb.tables_enthalpy_pt(p, T_tab, tables) == pytest.approx(h, abs=TOL_H_PT + cp * TOL_T)
    # h -> s(p, h) -> h(p, s)
    s_tab = tb.tables_ph_property(tb.PH_S, p, h, tables)
    assert tb.tables_enthalpy_ps(p, s_tab, tables) == pytest.approx(h, abs=TOL_H_PS + T * TOL_S)


def test_nodes_reproduce_if97_exactly(tables):
    """At the boundary nodes the table is exact (interpolating spline)."""
    p = tb._p_nodes(tb._GRID)
    T_low = tb.lower_boundary_temperature(p) + tb.T_MARGIN
    h_low = if97.enthalpy_pt(p, T_low)
    h_high = if97.enthalpy_pt(p, tb.T_MAX)
    assert tb.tables_temperature_ph(p, h_low, tables) == pytest.approx(T_low, abs=1e-9)
    assert tb.tables_temperature_ph(p, h_high, tables) == pytest.approx(tb.T_MAX, abs=1e-9)
    assert tb.tables_ph_domain_position(p, h_low, tables) == pytest.approx(0.0, abs=1e-12)
    assert tb.tables_ph_domain_position(p, h_high, tables) == pytest.approx(1.0, abs=1e-12)


# ------------------------------------------------------------------------------------------
# Domain
# ------------------------------------------------------------------------------------------


def test_domain_position_below_saturation_is_negative(tables):
    p = np.array([0.05e6, 0.5e6, 5e6, 15e6, 16.5e6])
    h_g = if97.saturated_vapour_enthalpy(p)
    T_sat = if97.saturation_temperature(p)
    h_f = if97.enthalpy_pt(p, T_sat - 1.0)  # subcooled liquid
    for h in (h_g, 0.9 * h_g + 0.1 * h_f, h_f):  # saturated vapour, wet steam, liquid
        assert np.all(tb.tables_ph_domain_position(p, h, tables) < 0.0)


def test_domain_position_between_b23_and_saturation_is_negative(tables):
    # region 3 (between the saturation line and the B23 line) at 20 MPa
    p = 20e6
    T = 0.5 * (float(if97.saturation_temperature(p)) + float(tb._t_b23(np.array(p))))
    h = if97.enthalpy_pt(p, T)
    assert tb.tables_ph_domain_position(p, h, tables) < 0.0


@settings(max_examples=200, deadline=None)
@given(ln_p=LN_P, y=UNIT)
def test_domain_position_is_normalised_enthalpy(ln_p, y):
    tables = tb.steam_tables()  # not a fixture: hypothesis would repr it
    p = pressure(ln_p)
    T = float(domain_temperature(p, y))
    h = float(if97.enthalpy_pt(p, T))
    h_low = float(if97.enthalpy_pt(p, domain_temperature(p, 0.0)))
    h_high = float(if97.enthalpy_pt(p, tb.T_MAX))
    expected = (h - h_low) / (h_high - h_low)
    assert tb.tables_ph_domain_position(p, h, tables) == pytest.approx(expected, abs=1e-6)
    assert -1e-6 <= tb.tables_ph_domain_position(p, h, tables) <= 1 + 1e-6


def test_domain_position_edges(tables):
    p = np.array([0.1e6, 3e6, 20e6])
    T_b = tb.lower_boundary_temperature(p)
    above = tb.tables_ph_domain_position(p, if97.enthalpy_pt(p, T_b + 2 * tb.T_MARGIN), tables)
    below = tb.tables_ph_domain_position(p, if97.enthalpy_pt(p, T_b + 0.5 * tb.T_MARGIN), tables)
    hot = tb.tables_ph_domain_position(p, if97.enthalpy_pt(p, tb.T_MAX + 5.0), tables)
    assert np.all(above > 0.0)
    assert np.all(below < 0.0)
    assert np.all(hot > 1.0)
    out = tb.tables_ph_domain_position([0.04e6, 26e6, np.nan, -1.0], 3e6, tables)
    assert np.all(np.isnan(out))


@njit(cache=False)
def _kernel_probe(tables, p, h, s, T):
    """All kernels from nopython code; returns an array of results."""
    out = np.empty(14)
    out[0] = tb.ph_property(tables, tb.PH_T, p, h)
    out[1] = tb.enthalpy_ps(tables, p, s)
    out[2] = tb.enthalpy_pt(tables, p, T)
    out[3] = tb.ph_domain_position(tables, p, h)
    out[4] = 1.0 if tb.pressure_in_range(tables, p) else 0.0
    out[5] = tb.ps_domain_position(tables, p, s)
    out[6] = tb.pt_domain_position(tables, p, T)
    props = np.empty(6)
    tb.ph_properties(tables, p, h, props)
    out[7] = props[tb.PH_T]
    out[8] = props[tb.PH_S]
    out[9] = props[tb.PH_V]
    out[10] = props[tb.PH_CP]
    out[11] = props[tb.PH_MU]
    out[12] = props[tb.PH_K]
    out[13] = tb.ph_property(tables, 99, p, h)
    return out


def test_kernels_in_nopython_mode(tables):
    p, T = 5e6, 700.0
    h, s = float(if97.enthalpy_pt(p, T)), float(if97.entropy_pt(p, T))
    r = _kernel_probe(tables, p, h, s, T)
    assert r[0] == pytest.approx(T, abs=TOL_T)
    assert r[1] == pytest.approx(h, abs=TOL_H_PS)
    assert r[2] == pytest.approx(h, abs=TOL_H_PT)
    assert 0.0 < r[3] < 1.0
    assert r[4] == 1.0
    assert 0.0 < r[5] < 1.0
    assert 0.0 < r[6] < 1.0
    for k in range(6):
        assert r[7 + k] == tb.tables_ph_property(k, p, h, tables)
    assert math.isnan(r[13])  # unknown property index


@pytest.mark.parametrize("p", [np.nan, 0.0, -1e5, np.inf])
def test_kernels_do_not_raise_on_bad_input(tables, p):
    r = _kernel_probe(tables, p, 3e6, 7e3, 700.0)
    assert r[4] == 0.0
    assert math.isnan(r[3])
    assert not np.isfinite(r[0])


def test_kernels_extrapolate_outside_the_domain(tables):
    # finite values (no exceptions) slightly outside in p and h
    for p, h in [(0.04e6, 3.0e6), (26e6, 3.2e6), (1e6, 2.5e6), (1e6, 4.0e6)]:
        assert np.isfinite(tb.tables_temperature_ph(p, h, tables))
    assert not tb.pressure_in_range(tables, 0.049e6)
    assert tb.pressure_in_range(tables, tb.P_MIN)
    assert tb.pressure_in_range(tables, tb.P_MAX)
    assert not tb.pressure_in_range(tables, np.nan)


def test_array_conveniences_broadcast(tables):
    p = np.array([[1e6], [2e6]])
    h = np.array([3.0e6, 3.1e6, 3.2e6])
    assert tb.tables_temperature_ph(p, h, tables).shape == (2, 3)
    assert tb.tables_enthalpy_pt(1e6, np.array([600.0, 700.0]), tables).shape == (2,)
    assert tb.tables_enthalpy_ps(1e6, 7e3, tables).shape == ()
    with pytest.raises(ValueError, match="prop"):
        tb.tables_ph_property(6, 1e6, 3e6, tables)


# ------------------------------------------------------------------------------------------
# Cache
# ------------------------------------------------------------------------------------------

SMALL_GRID = tb._Grid(nx_a=8, nx_b=4, ny_ph=6, ny_ps=6, ny_pt=6, c_ph=1.0, c_ps=1.0, c_pt=0.3)


@pytest.fixture
def small_grid(monkeypatch):
    monkeypatch.setattr(tb, "_GRID", SMALL_GRID)
    calls = []
    real_sample = tb._sample

    def counting_sample(grid):
        calls.append(grid)
        return real_sample(grid)

    monkeypatch.setattr(tb, "_sample", counting_sample)
    return calls


def test_cache_path_honours_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("STEAMTWIN_CACHE_DIR", str(tmp_path))
    path = tb.steam_tables_cache_path()
    assert path.parent == tmp_path
    assert f"v{tb.TABLE_FORMAT_VERSION}" in path.name
    assert tb._coolprop_version() in path.name
    assert path.suffix == ".npz"
    monkeypatch.delenv("STEAMTWIN_CACHE_DIR")
    assert tb.steam_tables_cache_path().parent.parts[-2:] == (".cache", "steamtwin")


def test_cache_is_written_and_reused(small_grid, tmp_path):
    path = tmp_path / "sub" / "tables.npz"
    first = tb.load_or_build_steam_tables(path)
    assert path.is_file()
    assert len(small_grid) == 1
    second = tb.load_or_build_steam_tables(path)
    assert len(small_grid) == 1  # loaded, not rebuilt
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not list(path.parent.glob("*.tmp"))


def test_corrupt_cache_is_rebuilt(small_grid, tmp_path):
    path = tmp_path / "tables.npz"
    reference = tb.load_or_build_steam_tables(path)
    for garbage in (b"", b"not a zip file", path.read_bytes()[:200]):
        path.write_bytes(garbage)
        rebuilt = tb.load_or_build_steam_tables(path)
        np.testing.assert_array_equal(rebuilt.ph, reference.ph)
    assert len(small_grid) == 4
    tb.load_or_build_steam_tables(path)  # the rebuilt file is valid again
    assert len(small_grid) == 4


def _rewrite(path, **changes):
    with np.load(path) as data:
        content = {k: data[k] for k in data.files}
    content.update(changes)
    np.savez(path, **content)


def test_mismatched_cache_is_rebuilt(small_grid, tmp_path):
    path = tmp_path / "tables.npz"
    tb.load_or_build_steam_tables(path)
    _rewrite(path, coolprop_version=np.array("0.0.1"))
    tb.load_or_build_steam_tables(path)
    assert len(small_grid) == 2
    with np.load(path) as data:
        sig = data["signature"].copy()
    sig[0] += 1  # other table-format version
    _rewrite(path, signature=sig)
    tb.load_or_build_steam_tables(path)
    assert len(small_grid) == 3
    with np.load(path) as data:
        ph = data["ph"].copy()
    ph[0, 0, 0] = np.nan  # non-finite content
    _rewrite(path, ph=ph)
    tb.load_or_build_steam_tables(path)
    assert len(small_grid) == 4
    _rewrite(path, ps=np.zeros((3, 3)))  # wrong shape
    tb.load_or_build_steam_tables(path)
    assert len(small_grid) == 5


def test_unwritable_cache_location_still_builds(small_grid, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    tables = tb.load_or_build_steam_tables(blocker / "tables.npz")
    assert tables.ph.shape[:3] == (6, 12, 6)
