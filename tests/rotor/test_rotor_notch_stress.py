"""Stress concentration at a notch of the rotor section, the groove-root stress fatigue life is
computed from: a spherical cavity on the axis against Goodier's exact solution, and a U-groove
in a shaft in tension against Peterson's chart."""

import numpy as np
import pytest

from steamtwin.geometry.volume_mesh import gmsh_session
from steamtwin.rotor.elasticity import AxisymmetricElasticity
from steamtwin.rotor.geometry import generated_triangles
from steamtwin.rotor.material import REFERENCE_TEMPERATURE, ConstantMaterial

NU = 0.3
STEEL = ConstantMaterial("steel", 7850.0, 460.0, 40.0, 2.1e11, NU, 1.2e-5)
RADIUS, LENGTH = 0.5, 1.0


def notched_mesh(corners, arc, notch_radius, fine):
    """gmsh mesh of the polygon ``corners`` (r, z) whose edge from corner ``arc`` to the next is
    a circular arc about ``centre``; elements of ``fine`` (m) within a notch radius of it."""
    start, centre = arc
    with gmsh_session() as gmsh:
        geo = gmsh.model.geo
        points = [geo.addPoint(r, z, 0.0) for r, z in corners]
        middle = geo.addPoint(*centre, 0.0)
        ends = [(points[i], points[(i + 1) % len(points)]) for i in range(len(points))]
        curves = [geo.addCircleArc(a, middle, b) if i == start else geo.addLine(a, b)
                  for i, (a, b) in enumerate(ends)]
        geo.addPlaneSurface([geo.addCurveLoop(curves)])
        geo.synchronize()
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "CurvesList", [curves[start]])
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", fine)
        field.setNumber(threshold, "SizeMax", 0.1)
        field.setNumber(threshold, "DistMin", 0.5 * notch_radius)
        field.setNumber(threshold, "DistMax", 4.0 * notch_radius + 0.1)
        field.setAsBackgroundMesh(threshold)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                       "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        return generated_triangles(gmsh)


def tension_concentration(mesh, root):
    """Peak axial stress at ``root`` over the far-field axial stress of a bar pulled by its
    ends: a uniform cooling with both ends held axially is a displacement-controlled tension
    test (the free thermal contraction is compatible, so only the end restraint stresses)."""
    model = AxisymmetricElasticity(mesh, STEEL, end="fixed-axial")
    solution = model.solve(np.full(mesh.p.shape[1], REFERENCE_TEMPERATURE - 100.0), speed=0.0)
    far = [[0.0, LENGTH], [0.5 * RADIUS, LENGTH], [RADIUS, LENGTH]]
    state = model.stress(solution, [root, *far])
    np.testing.assert_allclose(state.axial[1:], state.axial[1:].mean(), rtol=2e-3)  # uniform
    return state.axial[0] / state.axial[1:].mean()


def test_spherical_cavity_on_the_axis_matches_goodier_within_1_percent():
    # Goodier, "Concentration of stress around spherical and cylindrical inclusions and
    # flaws", J. Appl. Mech. 1 (1933) 39:
    # σ_max/σ∞ = (27 − 15ν) / (2(7 − 5ν)) at the equator of a small cavity under tension.
    cavity = 0.05
    mesh = notched_mesh([(cavity, 0.0), (RADIUS, 0.0), (RADIUS, LENGTH), (0.0, LENGTH),
                         (0.0, cavity)], (4, (0.0, 0.0)), cavity, cavity / 12)
    kt = tension_concentration(mesh, (cavity, 0.0))
    assert kt == pytest.approx((27 - 15 * NU) / (2 * (7 - 5 * NU)), rel=0.01)


def test_u_groove_in_a_shaft_in_tension_matches_peterson_within_7_percent():
    # Semicircular groove, depth h = ρ = 0.05 m in D = 1 m: Pilkey & Pilkey, Peterson's
    # Stress Concentration Factors, 3rd ed., 2008, chart 2.19, as fitted in Young & Budynas,
    # Roark's Formulas, 7th ed., 2002, table 17.1 case 18a: Kt = C1 + C2·x + C3·x² + C4·x³,
    # x = 2h/D, σ_nom = 4P/(πd²). The chart rests largely on Neuber's approximate theory,
    # which body-force-method analyses of notched round bars (Nisitani & Noda's series; Noda &
    # Takase, Int. J. Fatigue 28 (2006) 151) found non-conservative by up to about 7 %; this
    # solver gives 3.7–6.5 % above the fit over 2h/D = 0.05…0.3 (converged to 0.5 %), while it
    # meets Goodier's exact cavity (above) to 0.1 %.
    groove = 0.05
    mesh = notched_mesh([(0.0, 0.0), (RADIUS - groove, 0.0), (RADIUS, groove),
                         (RADIUS, LENGTH), (0.0, LENGTH)], (1, (RADIUS, 0.0)), groove, groove / 8)
    ratio, x = 1.0, 2 * groove / (2 * RADIUS)
    c1 = 0.89 + 2.208 * np.sqrt(ratio) - 0.094 * ratio
    c2 = -0.923 - 6.678 * np.sqrt(ratio) + 1.638 * ratio
    c3 = 2.893 + 6.448 * np.sqrt(ratio) - 2.516 * ratio
    c4 = -1.912 - 1.944 * np.sqrt(ratio) + 0.963 * ratio
    peterson = c1 + c2 * x + c3 * x ** 2 + c4 * x ** 3
    gross_to_net = (RADIUS / (RADIUS - groove)) ** 2
    kt = tension_concentration(mesh, (RADIUS - groove, 0.0)) / gross_to_net
    assert peterson < kt < 1.07 * peterson
