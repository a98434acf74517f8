"""Benchmark of the spline steam tables (steamtwin.steam.tables) against CoolProp IF97.

Run: ``python benchmarks/bench_steam_tables.py [--n-lookup 1000000] [--n-check 100000]``.
Prints look-up cost (numba loops over random superheated states), CoolProp array-call cost,
table build/load time and the maximum table errors against the IF97 basic equation.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit

from steamtwin.steam import if97
from steamtwin.steam import tables as tb


@njit(cache=False)
def _loop_ph(tables, prop, p, h):
    acc = 0.0
    for i in range(p.size):
        acc += tb.ph_property(tables, prop, p[i], h[i])
    return acc


@njit(cache=False)
def _loop_ph_all(tables, p, h):
    acc = 0.0
    out = np.empty(6)
    for i in range(p.size):
        tb.ph_properties(tables, p[i], h[i], out)
        acc += out[0]
    return acc


@njit(cache=False)
def _loop_ps(tables, p, s):
    acc = 0.0
    for i in range(p.size):
        acc += tb.enthalpy_ps(tables, p[i], s[i])
    return acc


@njit(cache=False)
def _loop_pt(tables, p, T):
    acc = 0.0
    for i in range(p.size):
        acc += tb.enthalpy_pt(tables, p[i], T[i])
    return acc


def _states(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Random (p, T) in the table domain: log-uniform p, uniform T between the edges."""
    rng = np.random.default_rng(seed)
    p = np.exp(rng.uniform(math.log(tb.P_MIN), math.log(tb.P_MAX), n))
    t_low = tb.lower_boundary_temperature(p) + tb.T_MARGIN
    return p, t_low + rng.uniform(0.0, 1.0, n) * (tb.T_MAX - t_low)


def _best_time(func, *args, repeat: int = 3) -> float:
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        func(*args)
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n-lookup", type=int, default=1_000_000)
    parser.add_argument("--n-coolprop", type=int, default=20_000)
    parser.add_argument("--n-check", type=int, default=100_000)
    args = parser.parse_args()

    from CoolProp.CoolProp import PropsSI  # imported before timing the build

    t0 = time.perf_counter()
    tables = tb.build_steam_tables()
    t_build = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "tables.npz"
        tb.load_or_build_steam_tables(path)
        t0 = time.perf_counter()
        tb.load_or_build_steam_tables(path)
        t_load = time.perf_counter() - t0
    size_mb = sum(a.nbytes for a in tables) / 1e6

    # --- look-up speed --------------------------------------------------------------------
    n = args.n_lookup
    p, T = _states(n, 1)
    h = if97.enthalpy_pt(p, T)
    s = if97.entropy_pt(p, T)
    _loop_ph(tables, tb.PH_T, p[:10], h[:10])  # compile
    _loop_ph_all(tables, p[:10], h[:10])
    _loop_ps(tables, p[:10], s[:10])
    _loop_pt(tables, p[:10], T[:10])
    order = np.argsort(p)  # sorted pressures: more cache-friendly, like a turbine sweep
    rows = [
        ("ph_property(PH_T), random", _best_time(_loop_ph, tables, tb.PH_T, p, h) / n),
        (
            "ph_property(PH_T), sorted p",
            _best_time(_loop_ph, tables, tb.PH_T, p[order], h[order]) / n,
        ),
        ("ph_property(PH_V), random", _best_time(_loop_ph, tables, tb.PH_V, p, h) / n),
        ("ph_properties (all 6), random", _best_time(_loop_ph_all, tables, p, h) / n),
        ("enthalpy_ps, random", _best_time(_loop_ps, tables, p, s) / n),
        ("enthalpy_pt, random", _best_time(_loop_pt, tables, p, T) / n),
    ]

    m = args.n_coolprop
    fl = if97.FLUID
    cp_rows = [
        ("PropsSI H(p,T)", _best_time(PropsSI, "H", "P", p[:m], "T", T[:m], fl, repeat=1) / m),
        (
            "PropsSI T(p,h) [backward eq.]",
            _best_time(PropsSI, "T", "P", p[:m], "H", h[:m], fl, repeat=1) / m,
        ),
        ("PropsSI H(p,s)", _best_time(PropsSI, "H", "P", p[:m], "S", s[:m], fl, repeat=1) / m),
        (
            "if97.temperature_ph [exact]",
            _best_time(if97.temperature_ph, p[:m], h[:m], repeat=1) / m,
        ),
        ("if97.enthalpy_ps [exact]", _best_time(if97.enthalpy_ps, p[:m], s[:m], repeat=1) / m),
    ]

    # --- accuracy -------------------------------------------------------------------------
    k = args.n_check
    pc, Tc = _states(k, 2)
    hc, sc = if97.enthalpy_pt(pc, Tc), if97.entropy_pt(pc, Tc)
    errors = [
        ("T(p,h)", "K", np.abs(tb.tables_temperature_ph(pc, hc, tables) - Tc).max()),
        ("s(p,h)", "J/(kg K)", np.abs(tb.tables_ph_property(tb.PH_S, pc, hc, tables) - sc).max()),
    ]
    for prop, func in [
        (tb.PH_V, if97.specific_volume_pt),
        (tb.PH_CP, if97.isobaric_heat_capacity_pt),
        (tb.PH_MU, if97.viscosity_pt),
        (tb.PH_K, if97.thermal_conductivity_pt),
    ]:
        rel = tb.tables_ph_property(prop, pc, hc, tables) / func(pc, Tc) - 1.0
        errors.append((f"{tb.PH_NAMES[prop]}(p,h)", "relative", np.abs(rel).max()))
    errors += [
        ("h(p,s)", "J/kg", np.abs(tb.tables_enthalpy_ps(pc, sc, tables) - hc).max()),
        ("h(p,T)", "J/kg", np.abs(tb.tables_enthalpy_pt(pc, Tc, tables) - hc).max()),
        (
            "T(p,h) CoolProp backward eq.",
            "K",
            np.abs(PropsSI("T", "P", pc, "H", hc, fl) - Tc).max(),
        ),
    ]

    g = tb._GRID
    print(
        f"steam tables: ln p cells {g.nx_a}+{g.nx_b}, Y cells ph/ps/pt "
        f"{g.ny_ph}/{g.ny_ps}/{g.ny_pt}, {size_mb:.1f} MB"
    )
    print(f"build (sample IF97 + fit): {t_build:6.2f} s    load from cache + fit: {t_load:6.2f} s")
    print()
    print(f"{'look-up (numba loop, n=' + str(n) + ')':40s} {'ns/call':>10s}")
    for name, sec in rows:
        print(f"{name:40s} {sec * 1e9:10.1f}")
    print()
    print(f"{'CoolProp IF97 array call (n=' + str(m) + ')':40s} {'us/point':>10s}")
    for name, sec in cp_rows:
        print(f"{name:40s} {sec * 1e6:10.2f}")
    print()
    print(f"{'max |error| vs IF97 (n=' + str(k) + ')':40s} {'value':>10s}  unit")
    for name, unit, err in errors:
        print(f"{name:40s} {err:10.3e}  {unit}")


if __name__ == "__main__":
    main()
