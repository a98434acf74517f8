"""A small axisymmetric rotor section for the ROM tests and benchmark (not a test module).

Rectangle r ∈ [0.05, 0.35] m (bore to rim), z ∈ [0, 0.3] m; the rim is wetted by three steam
groups (control stage, stages 2 and 3), the bore and the faces are adiabatic. P1 forms with the
2πr weight (Zienkiewicz, Taylor & Zhu, 7th ed., §4.2). Properties: linear fits in the range of
1CrMoV rotor steel (ASME BPVC II-D Table TCD, group "1Cr-½Mo-¼V"-like: k ≈ 37 W/(m·K) at 20 °C
falling to ≈ 31 at 500 °C; c from ≈ 460 to ≈ 640 J/(kg·K)); ρ = 7850 kg/m³. Steam side from
the load: h ∝ load^0.8 (Dittus–Boelter, h ∝ Re^0.8 with the mass flow ∝ load) and the control
stage's steam temperature falling with load (nozzle-governed unit, tens of kelvin at 30 %).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import scipy.sparse.linalg as spla
from skfem import Basis, BilinearForm, ElementTriP1, FacetBasis, LinearForm, MeshTri, asm
from skfem.helpers import dot, grad

from steamtwin.rotor.implicit_euler import SteamHistory
from steamtwin.rotor.operators import AffineConduction

BORE, RIM, LENGTH = 0.05, 0.35, 0.3
DENSITY = 7850.0
GROUPS = ("control_stage", "stage_2", "stage_3")
FULL_LOAD_STEAM_K = np.array([810.0, 790.0, 770.0])
STEAM_DROP_AT_30_K = np.array([70.0, 55.0, 45.0])
FULL_LOAD_HTC = np.array([3000.0, 2000.0, 1500.0])


def conductivity(temperature):
    return 37.0 - 0.0125 * (np.asarray(temperature) - 293.15)


def specific_heat(temperature):
    return 460.0 + 0.375 * (np.asarray(temperature) - 293.15)


@BilinearForm
def _capacity(u, v, w):
    return DENSITY * w["c"] * u * v * 2 * np.pi * w.x[0]


@BilinearForm
def _conduction(u, v, w):
    return w["k"] * dot(grad(u), grad(v)) * 2 * np.pi * w.x[0]


@BilinearForm
def _robin(u, v, w):
    return u * v * 2 * np.pi * w.x[0]


@LinearForm
def _robin_load(v, w):
    return v * 2 * np.pi * w.x[0]


_volume = _robin_load  # ∫φᵢ·2πr: on facets the wetted area, on cells the volume (m², m³)


class Section:
    """The mesh, its bases and the assembled operators."""

    def __init__(self, nr: int = 10, nz: int = 8) -> None:
        self.mesh = MeshTri.init_tensor(np.linspace(BORE, RIM, nr + 1),
                                        np.linspace(0.0, LENGTH, nz + 1))
        self.basis = Basis(self.mesh, ElementTriP1())
        bands = np.linspace(0.0, LENGTH, len(GROUPS) + 1)
        robin, loads = [], []
        for low, high in pairwise(bands):
            facets = self.mesh.facets_satisfying(
                lambda x, low=low, high=high: (x[0] > RIM - 1e-9) & (x[1] >= low - 1e-9)
                & (x[1] <= high + 1e-9))
            facet_basis = FacetBasis(self.mesh, ElementTriP1(), facets=facets)
            robin.append(asm(_robin, facet_basis).tocsr())
            loads.append(asm(_robin_load, facet_basis))
        self.robin, self.robin_load = tuple(robin), tuple(loads)

    def node(self, r: float, z: float) -> int:
        return int(np.argmin(np.hypot(self.mesh.p[0] - r, self.mesh.p[1] - z)))

    def operators(self, temperature: float) -> AffineConduction:
        """Operators with the properties at one ``temperature`` (K)."""
        return self._assemble(np.full(self.basis.N, temperature))

    def _assemble(self, field: np.ndarray) -> AffineConduction:
        t = self.basis.interpolate(field)
        return AffineConduction(asm(_capacity, self.basis, c=specific_heat(t)).tocsr(),
                                asm(_conduction, self.basis, k=conductivity(t)).tocsr(),
                                self.robin, self.robin_load, GROUPS)

    def local_property_run(self, history: SteamHistory, initial: np.ndarray) -> np.ndarray:
        """Implicit Euler with k(T), c(T) at each quadrature point of the previous field."""
        fields = [initial]
        for htc, steam in zip(history.htc, history.steam_temperature, strict=True):
            ops = self._assemble(fields[-1])
            mass_dt = ops.mass / history.dt
            fields.append(spla.spsolve((mass_dt + ops.operator(htc)).tocsc(),
                                       mass_dt @ fields[-1] + ops.load(htc, steam)))
        return np.array(fields)


def steam_history(load: np.ndarray, dt: float) -> SteamHistory:
    """Steam-side conditions for a load history (fraction of full load, one value per step)."""
    load = np.asarray(load, dtype=float)[:, None]
    return SteamHistory(FULL_LOAD_HTC * load ** 0.8,
                        FULL_LOAD_STEAM_K - STEAM_DROP_AT_30_K * (1.0 - load) / 0.7, dt)


def ramp(rate_per_min: float, dt: float, hold_s: float = 600.0) -> np.ndarray:
    """Load 100 → 30 % at ``rate_per_min`` (% per minute), a hold, and back, with holds."""
    ramp_s = 70.0 / rate_per_min * 60.0
    times = np.arange(1, int((3 * hold_s + 2 * ramp_s) / dt) + 1) * dt
    knots = np.cumsum([0.0, hold_s, ramp_s, hold_s, ramp_s, hold_s])
    return np.interp(times, knots, [1.0, 1.0, 0.3, 0.3, 1.0, 1.0])


def peak_shaving_day(dt: float, random_state: int) -> np.ndarray:
    """24 h of load: ramps between random levels in [30, 100] % at random rates of 1–8 %/min,
    each followed by a hold of 10–90 min (a deep peak-shaving day)."""
    rng = np.random.default_rng(random_state)
    knots_s, levels = [0.0], [1.0]
    while knots_s[-1] < 86400.0:
        target = rng.uniform(0.3, 1.0)
        knots_s.append(knots_s[-1] + abs(target - levels[-1]) * 100.0 / rng.uniform(1, 8) * 60)
        levels.append(target)
        knots_s.append(knots_s[-1] + rng.uniform(600.0, 5400.0))
        levels.append(target)
    return np.interp(np.arange(1, int(86400 / dt) + 1) * dt, knots_s, levels)


def surface_stress_operator(section: Section, nodes: list[int]) -> np.ndarray:
    """S with σ_i = E·α/(1 − ν)·(T̄ − T_i) (Pa), the surface thermal stress of a long cylinder
    (Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed., 1970, §150) at ``nodes``, T̄ the
    volume mean; CrMoV-like E = 210 GPa, α = 13e-6 /K, ν = 0.3."""
    volume = asm(_volume, section.basis)
    rows = np.tile(volume / volume.sum(), (len(nodes), 1))
    rows[np.arange(len(nodes)), nodes] -= 1.0
    return 2.1e11 * 1.3e-5 / (1 - 0.3) * rows


def random_walk(steps: int, random_state: int) -> np.ndarray:
    """A load random walk within [30, 100] % (steps of ≤ 3 % per step, reflected)."""
    rng = np.random.default_rng(random_state)
    load = 1.0 + np.cumsum(rng.uniform(-0.03, 0.03, steps))
    return 1.0 - np.abs((load - 0.3) % 1.4 - 0.7)
