"""The rotor conduction FEM: exact assembly, closed-form convergence, energy balance, invariants."""

from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq
from scipy.special import j0, j1
from skfem import Basis, BilinearForm, ElementTriP1, FacetBasis, Functional, LinearForm, MeshTri
from skfem.helpers import dot, grad

from steamtwin.errors import RotorAreaError
from steamtwin.rotor.conduction import RotorConduction, htc_column, steam_temperature_column
from steamtwin.rotor.material import ConstantMaterial

STEEL = ConstantMaterial("test", density_=7850.0, specific_heat_=460.0, conductivity_=40.0,
                         youngs_modulus_=2.1e11, poisson_ratio_=0.3, expansion_coefficient=1.2e-5)
INNER, OUTER, LENGTH = 0.1, 0.3, 0.05


@dataclass(frozen=True)
class LinearSteel:
    """A steel whose k and c change linearly with temperature, as CrMoV steels do (sign and
    size of ASME II-D Table TCD's trend for Group C near 500 °C)."""

    name: str = "linear"

    def density(self) -> float:
        return 7850.0

    def specific_heat(self, temperature):
        return 460.0 + 0.4 * (np.asarray(temperature) - 293.15)

    def conductivity(self, temperature):
        return 42.0 - 0.015 * (np.asarray(temperature) - 293.15)

    def youngs_modulus(self, temperature):
        return np.full(np.shape(temperature), 2.1e11)

    def poisson_ratio(self, temperature):
        return np.full(np.shape(temperature), 0.3)

    def thermal_strain(self, temperature):
        return 1.2e-5 * (np.asarray(temperature) - 293.15)


def annulus(cells: int) -> MeshTri:
    """Hollow cylinder cross-section INNER…OUTER, 0…LENGTH; both radial faces wetted."""
    mesh = MeshTri.init_tensor(np.linspace(INNER, OUTER, cells + 1),
                               np.linspace(0.0, LENGTH, max(cells // 4, 1) + 1))
    return mesh.with_boundaries({"steam:inner": lambda x: np.isclose(x[0], INNER),
                                 "steam:outer": lambda x: np.isclose(x[0], OUTER)})


def test_assembly_equals_scikit_fem_quadrature_of_the_2_pi_r_weighted_forms():
    mesh = annulus(4)
    system = RotorConduction(mesh, STEEL).system(500.0)
    basis = Basis(mesh, ElementTriP1(), intorder=4)
    stiffness = BilinearForm(lambda u, v, w: 40.0 * 2 * np.pi * w.x[0] * dot(grad(u), grad(v)))
    mass = BilinearForm(lambda u, v, w: 7850.0 * 460.0 * 2 * np.pi * w.x[0] * u * v)
    np.testing.assert_allclose(system.stiffness.toarray(), stiffness.assemble(basis).toarray(),
                               atol=1e-10 * abs(system.stiffness).max())
    np.testing.assert_allclose(system.mass.toarray(), mass.assemble(basis).toarray(),
                               atol=1e-10 * abs(system.mass).max())
    facets = FacetBasis(mesh, ElementTriP1(), facets=mesh.boundaries["steam:outer"], intorder=4)
    robin = BilinearForm(lambda u, v, w: 2 * np.pi * w.x[0] * u * v)
    load = LinearForm(lambda v, w: 2 * np.pi * w.x[0] * v)
    np.testing.assert_allclose(system.robin[1].toarray(), robin.assemble(facets).toarray(),
                               atol=1e-15)
    np.testing.assert_allclose(system.robin_load[1], load.assemble(facets), atol=1e-15)
    assert system.robin_load[1].sum() == pytest.approx(2 * np.pi * OUTER * LENGTH, rel=1e-12)


def hollow_cylinder_profile(r, h_inner, t_inner, h_outer, t_outer, k):
    """Steady radial conduction through a hollow cylinder between two convective surfaces:
    resistances 1/(2π·r_i·h_i), ln(r_o/r_i)/(2π·k), 1/(2π·r_o·h_o) per unit length in series
    (Carslaw & Jaeger 1959, §7.2; Incropera & DeWitt, eq. 3.32)."""
    total = 1 / (h_inner * INNER) + np.log(OUTER / INNER) / k + 1 / (h_outer * OUTER)
    per_radian = (t_inner - t_outer) / total  # q'/(2π), W/m per radian
    return t_inner - per_radian * (1 / (h_inner * INNER) + np.log(r / INNER) / k)


def test_steady_hollow_cylinder_converges_at_second_order_to_the_closed_form():
    """P1 converges as O(h²) in L² (Brenner & Scott 2008, ch. 5); docs/rotor.md reports it."""
    errors = []
    for cells in (8, 16, 32):
        mesh = annulus(cells)
        field = RotorConduction(mesh, STEEL).steady([800.0, 300.0], [800.0, 500.0])
        basis = Basis(mesh, ElementTriP1(), intorder=4)
        r = basis.global_coordinates()[0]
        exact = hollow_cylinder_profile(r, 800.0, 800.0, 300.0, 500.0, 40.0)
        squared = Functional(lambda w: (w.field - w.exact) ** 2)
        errors.append(np.sqrt(squared.assemble(basis, field=basis.interpolate(field),
                                               exact=exact)
                              / (LENGTH * (OUTER - INNER))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 1.9) & (orders < 2.1)), (errors, orders)
    assert errors[-1] < 0.03  # K (RMS), over a 160 K drop


def test_a_uniform_field_in_equilibrium_with_the_steam_stays_uniform():
    mesh = annulus(6)
    times = np.arange(0.0, 50.0, 5.0)
    htc = np.column_stack([np.linspace(100.0, 3000.0, times.size), np.full(times.size, 50.0)])
    run = RotorConduction(mesh, LinearSteel()).transient(780.0, times, htc,
                                                         np.full((times.size, 2), 780.0))
    np.testing.assert_allclose(run.final, 780.0, rtol=1e-12)
    np.testing.assert_allclose(run.heat_in, 0.0, atol=1e-8)


@pytest.mark.parametrize("material", [STEEL, LinearSteel()], ids=["constant", "linear"])
def test_heat_through_the_surface_equals_the_change_of_stored_energy(material):
    mesh = annulus(6)
    conduction = RotorConduction(mesh, material)
    times = np.concatenate([np.arange(0.0, 60.0, 2.0), np.arange(60.0, 600.0, 30.0)])
    steam = np.column_stack([600.0 + 0.5 * times, 620.0 - 0.1 * times])
    htc = np.column_stack([np.full(times.size, 2000.0), 500.0 + times])
    run = conduction.transient(600.0, times, htc, steam)
    supplied = run.heat_in[1:] * np.diff(times)  # implicit Euler: flux at each step's end
    np.testing.assert_allclose(supplied, run.stored[1:], rtol=1e-9,
                               atol=1e-9 * np.abs(run.stored).max())
    if material is STEEL:  # ∫ρc·T dV = 1ᵀ·M·T exactly for a constant ρc
        mass, _ = conduction.matrices(600.0)
        assert supplied.sum() == pytest.approx(np.sum(mass @ (run.final - 600.0)), rel=1e-10)
        assert supplied.sum() > 0.0


def test_the_frame_form_matches_the_array_form_and_probes_record_nodes():
    mesh = annulus(4)
    conduction = RotorConduction(mesh, STEEL)
    times = np.array([0.0, 10.0, 20.0])
    frame = pd.DataFrame({steam_temperature_column("inner"): [700.0, 720.0, 740.0],
                          htc_column("inner"): [1000.0, 1000.0, 1000.0],
                          steam_temperature_column("outer"): [700.0, 700.0, 700.0],
                          htc_column("outer"): [0.0, 0.0, 0.0]},
                         index=pd.to_datetime(times, unit="s"))
    by_frame = conduction.transient_frame(700.0, frame, probes={"inner": 0})
    by_array = conduction.transient(700.0, times, frame[["htc:inner", "htc:outer"]],
                                    frame[["steam_temperature:inner",
                                           "steam_temperature:outer"]])
    np.testing.assert_array_equal(by_frame.final, by_array.final)
    np.testing.assert_array_equal(by_frame.times, times)
    assert by_frame.probes["inner"].iloc[-1] == by_frame.final[0]


def test_bad_inputs_are_refused_with_what_was_expected():
    mesh = annulus(2)
    with pytest.raises(RotorAreaError, match="no steam boundary for \\['nozzle'\\]"):
        RotorConduction(mesh, STEEL, groups=["nozzle"])
    conduction = RotorConduction(mesh, STEEL)
    with pytest.raises(RotorAreaError, match=r"htc must have shape \(3, 2\)"):
        conduction.transient(600.0, [0.0, 1.0, 2.0], np.ones((3, 3)), np.ones((3, 2)))
    steam = np.full((3, 2), 600.0)
    steam[2, 1] = np.nan
    with pytest.raises(RotorAreaError, match=r"steam_temperature at sample 3 \(1-based\), "
                                             r"group 'outer' is nan: expected .* in K, > 0"):
        conduction.transient(600.0, [0.0, 1.0, 2.0], np.ones((3, 2)), steam)
    with pytest.raises(RotorAreaError, match="strictly increasing"):
        conduction.transient(600.0, [0.0, 0.0], np.ones((2, 2)), np.ones((2, 2)))
    with pytest.raises(RotorAreaError, match="positive htc"):
        conduction.steady([0.0, 0.0], [600.0, 600.0])


def solid_cylinder_step(r, t, radius, biot, diffusivity, roots=60):
    """Solid cylinder at 0, its surface exposed at t = 0 to unit steam temperature through a
    Biot number h·a/k: Carslaw & Jaeger 1959, §7.7 eq. (6), θ = 1 − Σ 2·Bi·J0(βₙr/a)·
    exp(−βₙ²·κt/a²)/((βₙ² + Bi²)·J0(βₙ)) over the roots of β·J1(β) = Bi·J0(β)."""
    def condition(beta):
        return beta * j1(beta) - biot * j0(beta)

    grid = np.linspace(1e-9, 4.0 * roots, 40 * roots)
    values = condition(grid)
    brackets = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[:roots]
    beta = np.array([brentq(condition, grid[i], grid[i + 1]) for i in brackets])
    terms = (2 * biot * j0(np.outer(r / radius, beta)) / ((beta**2 + biot**2) * j0(beta))
             * np.exp(-beta**2 * diffusivity * t / radius**2))
    return 1.0 - terms.sum(axis=1)


def test_implicit_euler_converges_at_first_order_in_time_to_the_solid_cylinder_series():
    radius, htc, duration = 0.3, 1000.0, 1800.0
    mesh = MeshTri.init_tensor(np.linspace(0.0, radius, 65), np.linspace(0.0, 0.02, 2))
    mesh = mesh.with_boundaries({"steam:surface": lambda x: np.isclose(x[0], radius)})
    conduction = RotorConduction(mesh, STEEL)
    exact = solid_cylinder_step(mesh.p[0], duration, radius, htc * radius / 40.0,
                                40.0 / (7850.0 * 460.0))
    errors = []
    for steps in (15, 30, 60):
        times = np.linspace(0.0, duration, steps + 1)
        run = conduction.transient(0.0, times, np.full((steps + 1, 1), htc),
                                   np.ones((steps + 1, 1)))
        errors.append(np.max(np.abs(run.final - exact)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 0.85) & (orders < 1.1)), (errors, orders)


def test_the_cooling_factor_applies_only_while_the_surface_is_hotter_than_the_steam():
    """The kernel's switch of Dittus–Boelter's Prandtl exponent: a rotor cooled by its steam
    sees factor × htc, one heated by it the htc as given."""
    conduction = RotorConduction(annulus(4), STEEL)
    times = np.arange(0.0, 100.0, 10.0)
    htc = np.full((times.size, 2), 500.0)
    factor = np.full((times.size, 2), 2.0)
    for steam, expected_factor in ((500.0, 2.0), (700.0, 1.0)):  # rotor at 600 K
        temperature = np.full((times.size, 2), steam)
        switched = conduction.transient(600.0, times, htc, temperature, cooling_factor=factor)
        plain = conduction.transient(600.0, times, expected_factor * htc, temperature)
        np.testing.assert_array_equal(switched.final, plain.final)
        np.testing.assert_array_equal(switched.htc, expected_factor * htc)


def test_steady_state_with_temperature_dependent_conductivity_meets_kirchhoffs_transform():
    """With U = ∫k dT (Kirchhoff's transform, Carslaw & Jaeger 1959, §1.7) the steady radial
    field has U linear in ln r between the surface temperatures (here held by h = 10⁸)."""
    mesh = annulus(32)
    steel = LinearSteel()
    field = RotorConduction(mesh, steel).steady([1e8, 1e8], [800.0, 500.0])

    def kirchhoff(t):
        return 42.0 * (t - 293.15) - 0.0075 * (t - 293.15) ** 2

    share = np.log(mesh.p[0] / INNER) / np.log(OUTER / INNER)
    expected = kirchhoff(800.0) + (kirchhoff(500.0) - kirchhoff(800.0)) * share
    np.testing.assert_allclose(kirchhoff(field), expected, atol=42.0 * 0.05)  # 0.05 K
