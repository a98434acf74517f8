"""Metal conduction chains against analytic solutions; the Dittus–Boelter coefficient."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from steamtwin.model.metal import (
    dittus_boelter_htc,
    factor_chain,
    finish_chain,
    finish_chains,
    prepare_chain,
    prepare_chains,
    surface_heat,
    surface_response,
)

K, RHO, C = 34.0, 7800.0, 600.0  # low-alloy steel near 500 °C (ASME II-D Group C)


def _step(old, capacity, conductance, surface, outer, fluid, ambient, inverse_dt):
    """One implicit step of a single chain: (heat from the fluid W, new temperatures K)."""
    pivot, rhs, new = np.empty((1, old.size)), np.empty((1, old.size)), np.empty((1, old.size))
    factor_chain(0, capacity[np.newaxis], conductance[np.newaxis], outer, inverse_dt, pivot)
    prepare_chain(0, old[np.newaxis], capacity[np.newaxis], conductance[np.newaxis], outer,
                  ambient, inverse_dt, pivot, rhs)
    base, response = surface_response(surface, pivot[0, 0], rhs[0, 0])
    finish_chain(0, base + response * fluid, conductance[np.newaxis], pivot, rhs, new)
    return surface_heat(surface, base, response, fluid), new[0]


def _wall(depth, nodes, area=1.0):
    dx = depth / nodes
    return np.full(nodes, RHO * C * area * dx), np.full(nodes - 1, K * area / dx), dx


def test_steady_wall_carries_the_series_resistance_flux():
    capacity, conductance, dx = _wall(0.2, 20)
    h, u = 5000.0, 0.6
    surface = 1.0 / (1.0 / h + dx / (2 * K))
    outer = 1.0 / (1.0 / u + dx / (2 * K))
    q, new = _step(np.full(20, 500.0), capacity, conductance, surface, outer, 800.0, 300.0, 0.0)
    assert q == pytest.approx((800.0 - 300.0) / (1 / h + 0.2 / K + 1 / u), rel=1e-9)
    assert np.all(np.diff(new) < 0)  # linear fall towards the lagging


def test_step_conserves_energy_exactly():
    capacity, conductance, _ = _wall(0.15, 8)
    old = np.linspace(700.0, 650.0, 8)
    surface, outer, dt = 3000.0, 0.5, 1.0
    q, new = _step(old, capacity, conductance, surface, outer, 780.0, 308.0, 1.0 / dt)
    stored = float(np.sum(capacity * (new - old))) / dt
    lost = outer * (new[-1] - 308.0)
    assert q == pytest.approx(stored + lost, rel=1e-12)


def test_step_matches_a_dense_solve():
    # the affine step equals a dense solve of the implicit-Euler system at any steam temperature
    capacity, conductance, _ = _wall(0.15, 8)
    old = np.linspace(700.0, 650.0, 8)
    surface, outer, inverse_dt = 3000.0, 0.5, 1.0
    matrix = np.diag(capacity * inverse_dt)
    for j, g in enumerate(conductance):
        matrix[j, j] += g
        matrix[j + 1, j + 1] += g
        matrix[j, j + 1] = matrix[j + 1, j] = -g
    matrix[0, 0] += surface
    matrix[-1, -1] += outer
    for fluid in (300.0, 900.0):
        rhs = capacity * inverse_dt * old
        rhs[0] += surface * fluid
        rhs[-1] += outer * 308.0
        _, new = _step(old, capacity, conductance, surface, outer, fluid, 308.0, inverse_dt)
        assert np.allclose(new, np.linalg.solve(matrix, rhs), rtol=0, atol=1e-9)


def test_slowest_mode_decays_at_the_analytic_rate():
    # plane wall, convection on one face, adiabatic other face: θ ~ exp(-λ1² α t / L²) with
    # λ1·tan λ1 = Bi (Incropera & DeWitt, eq. 5.39)
    depth, h, nodes = 0.1, 500.0, 200
    capacity, conductance, dx = _wall(depth, nodes)
    biot = h * depth / K
    lam = brentq(lambda x: x * math.tan(x) - biot, 1e-9, math.pi / 2 - 1e-9)
    rate = lam**2 * (K / (RHO * C)) / depth**2
    temps = np.full(nodes, 100.0)
    surface = 1.0 / (1.0 / h + dx / (2 * K))
    dt, steps = 2.0, 3000
    history = []
    for _ in range(steps):
        _, temps = _step(temps, capacity, conductance, surface, 0.0, 0.0, 0.0, 1.0 / dt)
        history.append(temps.mean())
    measured = math.log(history[1500] / history[2999]) / (1499 * dt)
    assert measured == pytest.approx(rate, rel=0.01)


def test_dittus_boelter_matches_hand_calculation():
    # steam near 13 MPa, 500 °C: v = 0.0245 m³/kg, μ = 3.0e-5 Pa s, k = 0.083 W/(m K),
    # cp = 3300 J/(kg K); 80 m/s in a 0.1 m hydraulic diameter
    reynolds = 80.0 * 0.1 / (3.0e-5 * 0.0245)
    prandtl = 3300.0 * 3.0e-5 / 0.083
    for heated, exponent in ((True, 0.4), (False, 0.3)):  # wall heats steam / steam heats wall
        h = dittus_boelter_htc(80.0, 0.1, 0.0245, 3.0e-5, 0.083, 3300.0, heated)
        expected = 0.023 * reynolds**0.8 * prandtl**exponent * 0.083 / 0.1
        assert h == pytest.approx(expected, rel=1e-12)
        assert 3000.0 < h < 20000.0  # HP blade-path range


def test_chains_are_independent_rows():
    # two different walls set up as rows of one array give what each gives alone
    walls = [_wall(0.15, 8), _wall(0.25, 8)]
    old = np.array([np.linspace(700.0, 650.0, 8), np.full(8, 600.0)])
    capacity = np.array([walls[0][0], walls[1][0]])
    conductance = np.array([walls[0][1], walls[1][1]])
    pivot, rhs, new = np.empty((2, 8)), np.empty((2, 8)), np.empty((2, 8))
    for chain in (1, 0):
        factor_chain(chain, capacity, conductance, 0.5, 0.1, pivot)
        prepare_chain(chain, old, capacity, conductance, 0.5, 308.0, 0.1, pivot, rhs)
    for chain in (0, 1):
        base, response = surface_response(2000.0, pivot[chain, 0], rhs[chain, 0])
        finish_chain(chain, base + response * 750.0, conductance, pivot, rhs, new)
        _, alone = _step(old[chain], capacity[chain], conductance[chain], 2000.0, 0.5, 750.0,
                         308.0, 0.1)
        assert np.allclose(new[chain], alone, rtol=0, atol=1e-12)


def test_all_chains_at_once_match_chain_by_chain():
    """prepare_chains / finish_chains (node by node across the chains, as the kernel runs them)
    give each chain's step as prepare_chain / finish_chain do, to round-off."""
    rng = np.random.default_rng(5)
    chains, nodes = 6, 16
    capacity = rng.uniform(1e3, 1e5, (chains, nodes))
    conductance = rng.uniform(10.0, 1e3, (chains, nodes - 1))
    outer = rng.uniform(0.1, 5.0, chains)
    old = rng.uniform(500.0, 800.0, (chains, nodes))
    surface_temperature = rng.uniform(600.0, 820.0, chains)
    pivot = np.zeros((chains, nodes))
    for chain in range(chains):
        factor_chain(chain, capacity, conductance, outer[chain], 1.0, pivot)
    rhs_one, rhs_all = np.zeros((chains, nodes)), np.zeros((chains, nodes))
    new_one, new_all = np.zeros((chains, nodes)), np.zeros((chains, nodes))
    for chain in range(chains):
        prepare_chain(chain, old, capacity, conductance, outer[chain], 300.0, 1.0, pivot, rhs_one)
        finish_chain(chain, surface_temperature[chain], conductance, pivot, rhs_one, new_one)
    prepare_chains(old, capacity, conductance, outer, 300.0, 1.0, pivot, rhs_all)
    new_all[:, 0] = surface_temperature
    finish_chains(conductance, pivot, rhs_all, new_all)
    np.testing.assert_allclose(rhs_all, rhs_one, rtol=1e-14)
    np.testing.assert_allclose(new_all, new_one, rtol=1e-14)
    assert not np.allclose(new_all[:, 1:], old[:, 1:])  # a real step was taken
