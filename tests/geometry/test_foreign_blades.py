"""The independent test family (foreign_blades.py) against closed forms, and the current
reconstruction on the members it handles today."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import trimesh
from foreign_blades import (
    FAMILY,
    MESH_SAG,
    NACA4_AREA,
    RING_SAG,
    BladeSpec,
    ForeignBlade,
    Section,
    SectionSpec,
    arc_sagitta,
    compare_with_exact,
    family_blade,
    laser_cloud,
    naca4_half_thickness,
    naca4_max_camber,
    piece_grids,
    polygon_area,
    random_pose,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.geometry.reconstruct import reconstruct_blade

pytestmark = pytest.mark.slow  # 20 s of the full suite (2026-11-27): not in the quick loop


@pytest.fixture(scope="module")
def blades() -> dict[str, ForeignBlade]:
    return {name: family_blade(name) for name in FAMILY}


def _symmetric(kind: str, thickness: float, stagger: float = 0.0) -> SectionSpec:
    """A symmetric 40 mm section with a leading-edge radius 10 % above the native nose
    (4-digit: 1.1019 t² c; 65-series 0.687 % c (t/0.1)²) and a 0.15 mm trailing edge (above
    the 4-digit form's half thickness there, ≤ 0.0105 t c)."""
    le = {"naca4": 1.1019 * thickness**2, "naca65": 0.00687 * (thickness / 0.1) ** 2,
          "dca": 0.002}[kind] * 1.1 * 0.04
    return SectionSpec(kind, 0.04, stagger, 0.0, thickness, le, 0.15e-3)


def _cut(polygon: np.ndarray, x: float) -> float:
    """Thickness (m) of a polygon along the line X = x (two crossings)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    crossing = (a[:, 0] - x) * (b[:, 0] - x) < 0
    f = (x - a[crossing, 0]) / (b[crossing, 0] - a[crossing, 0])
    y = a[crossing, 1] + f * (b[crossing, 1] - a[crossing, 1])
    assert len(y) == 2
    return float(abs(y[1] - y[0]))


def _circle(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares circle (Kåsa 1976: linear in the centre and c = r² − |centre|²)."""
    a = np.column_stack([2 * points, np.ones(len(points))])
    solution = np.linalg.lstsq(a, (points**2).sum(axis=1), rcond=None)[0]
    centre = solution[:2]
    return centre, float(np.sqrt(solution[2] + centre @ centre))


def _principal_angle(polygon: np.ndarray) -> float:
    """Direction (deg, in (−90, 90]) of the major principal axis of a polygon's area, from its
    second moments about the centroid (Green's theorem)."""
    x, y = polygon[:, 0], polygon[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    area = cross.sum() / 2
    cx, cy = ((x + x1) * cross).sum() / (6 * area), ((y + y1) * cross).sum() / (6 * area)
    ixx = ((y**2 + y * y1 + y1**2) * cross).sum() / 12 - area * cy**2
    iyy = ((x**2 + x * x1 + x1**2) * cross).sum() / 12 - area * cx**2
    ixy = ((x * y1 + 2 * x * y + 2 * x1 * y1 + x1 * y) * cross).sum() / 24 - area * cx * cy
    return math.degrees(0.5 * math.atan2(2 * ixy, iyy - ixx))


# --- sections ------------------------------------------------------------------------------------


def test_naca4_thickness_at_030_is_the_formulas_maximum():
    """Thickness measured across the generated 0012 section at x/c = 0.3 (the 4-digit law's
    maximum, A&vD §6.4) equals the formula's maximum, and no other cut is thicker."""
    spec = _symmetric("naca4", 0.12)
    polygon = Section(spec).polygon()
    c = spec.chord
    formula = 2 * naca4_half_thickness(np.linspace(0.0, 1.0, 100_001), 0.12).max() * c
    assert _cut(polygon, (0.3 - 0.5) * c) == pytest.approx(formula, abs=2 * RING_SAG)
    cuts = [_cut(polygon, (x - 0.5) * c) for x in np.linspace(0.05, 0.95, 181)]
    assert max(cuts) <= formula + 2 * RING_SAG
    assert formula == pytest.approx(0.12 * c, rel=1e-3)  # the form's nominal t


@pytest.mark.parametrize("thickness", [0.04, 0.12, 0.21])
def test_naca00tt_area_is_abbott_and_von_doenhoffs(thickness):
    """Area of 00tt = 0.68508 t c² (A&vD: 0.685 t c²; the integral of the thickness law).
    Edge circles 2 % above the native nose and 30 % above the trailing edge's half thickness
    (0.0105 t c) replace slivers of the form: measured 4–8e-5 of the area."""
    c = 0.04
    spec = SectionSpec("naca4", c, 0.0, 0.0, thickness, 1.02 * 1.1019 * thickness**2 * c,
                       1.3 * 0.0105 * thickness * c)
    assert abs(NACA4_AREA - 0.6851) < 1e-4
    area = Section(spec).area()
    assert area == pytest.approx(NACA4_AREA * thickness * c**2, rel=2e-4)


@settings(max_examples=10, deadline=None)
@given(kind=st.sampled_from(["naca4", "naca65", "dca"]), stagger=st.floats(0.0, 70.0),
       thickness=st.floats(0.04, 0.2))
def test_measured_stagger_of_symmetric_sections(kind, stagger, thickness):
    """A symmetric section's major principal axis is its chord: measured stagger = requested."""
    polygon = Section(_symmetric(kind, thickness, stagger)).polygon()
    measured = _principal_angle(polygon)
    assert measured == pytest.approx(stagger, abs=1e-4)


@settings(max_examples=10, deadline=None)
@given(stagger=st.floats(0.0, 70.0), camber=st.floats(20.0, 60.0),
       thickness=st.floats(0.03, 0.08))
def test_measured_stagger_and_camber_of_double_circular_arcs(stagger, camber, thickness):
    """Circles fitted to the two sides of a DCA section cross at the chord's ends: the chord
    line gives the stagger, the sides' mean sagitta h gives the camber 4 atan(2h/c)."""
    spec = SectionSpec("dca", 0.03, stagger, camber, thickness, 0.1e-3, 0.1e-3)
    section = Section(spec)
    w = np.linspace(0.0, 1.0, 200)
    sagittas, circles = [], []
    for side in ("upper", "lower"):
        centre, radius = _circle(section.piece(side, w))
        circles.append((centre, radius))
    (c0, r0), (c1, r1) = circles
    d = np.linalg.norm(c1 - c0)
    along = (r0**2 - r1**2 + d**2) / (2 * d)
    mid = c0 + along * (c1 - c0) / d
    half = math.sqrt(r0**2 - along**2)
    normal = np.array([-(c1 - c0)[1], (c1 - c0)[0]]) / d
    ends = [mid + half * normal, mid - half * normal]
    nose = section.piece("leading_edge", [0.5])[0]
    lead, trail = sorted(ends, key=lambda p: np.linalg.norm(p - nose))
    chord = np.linalg.norm(trail - lead)
    measured_stagger = math.degrees(math.atan2(*(trail - lead)[::-1]))
    midpoint = 0.5 * (lead + trail)
    for centre, radius in circles:
        sagittas.append(np.sign(np.cross([*(trail - lead), 0], [*(midpoint - centre), 0])[2]) * (
            radius - np.linalg.norm(midpoint - centre)))
    assert chord == pytest.approx(spec.chord, rel=1e-9)
    assert measured_stagger == pytest.approx(stagger, abs=1e-7)
    measured_camber = math.degrees(4 * math.atan(2 * np.mean(sagittas) / chord))
    assert measured_camber == pytest.approx(camber, abs=1e-7)
    assert abs(sagittas[0] - sagittas[1]) == pytest.approx(thickness * chord, rel=1e-9)


def test_naca4_mean_line_turns_by_the_camber_angle():
    """The parabolic mean line's end slopes turn by the requested camber angle."""
    spec = SectionSpec("naca4", 0.04, 0.0, 25.0, 0.1, 1e-3, 0.2e-3)
    _, slope = spec.camber(np.array([0.0, 1.0]))
    assert math.degrees(math.atan(slope[0]) - math.atan(slope[1])) == pytest.approx(25.0)
    assert naca4_max_camber(25.0, 0.4) == pytest.approx(
        float(spec.camber(np.array([0.4]))[0][0]))
    assert arc_sagitta(90.0) == pytest.approx(0.5 * (1 - math.cos(math.pi / 4))
                                              / math.sin(math.pi / 4))


@pytest.mark.parametrize("name", list(FAMILY))
def test_edge_circles_have_the_requested_radius_and_touch_both_sides(name):
    """A circle fitted to each edge arc has the requested radius; the sides touch it and stay
    outside it (tangent, no side point inside)."""
    for spec_eta in (0.0, 1.0):
        section = family_blade(name).section(spec_eta)
        spec = section.spec
        grid = piece_grids([section], sag=1e-8)
        sides = np.vstack([section.piece("upper", grid["upper"]),
                           section.piece("lower", grid["lower"])])
        for piece, radius in (("leading_edge", spec.le_radius),
                              ("trailing_edge", spec.te_radius)):
            centre, measured = _circle(section.piece(piece, np.linspace(0.0, 1.0, 50)))
            assert measured == pytest.approx(radius, rel=1e-8)
            gap = np.linalg.norm(sides - centre, axis=1).min() - radius
            assert -1e-9 < gap < 1e-8


@settings(max_examples=6, deadline=None)
@given(name=st.sampled_from(list(FAMILY)), eta=st.floats(0.0, 1.0))
def test_section_polygon_sag_is_below_the_stated_bound(name, eta):
    """Exact points half-way (in parameter) between polygon vertices lie within RING_SAG (10 %
    for the sampled curvature) of the polygon's segments: far below the 1 µm asked for."""
    section = family_blade(name).section(eta)
    grid = piece_grids([section])
    polygon = section.curve(grid)
    mids = {n: 0.5 * (w + np.append(w[1:], 1.0)) for n, w in grid.items()}
    exact = section.curve(mids)
    a, b = polygon, np.roll(polygon, -1, axis=0)
    t = np.clip(np.einsum("ij,ij->i", exact - a, b - a) / np.einsum("ij,ij->i", b - a, b - a),
                0.0, 1.0)
    sag = np.linalg.norm(exact - (a + t[:, None] * (b - a)), axis=1)
    assert sag.max() <= RING_SAG * 1.1 < MESH_SAG
    assert polygon_area(polygon) > 0  # counter-clockwise


def test_bad_sections_are_refused_with_units():
    with pytest.raises(ValueError, match=r"chord 40\.0 m: expected 5–200 mm"):
        SectionSpec("naca4", 40.0, 0.0, 0.0, 0.12, 1e-3, 0.2e-3)
    with pytest.raises(ValueError, match="camber 130"):
        SectionSpec("dca", 0.04, 0.0, 130.0, 0.05, 0.1e-3, 0.1e-3)
    with pytest.raises(ValueError, match=r"leading-edge circle of radius 0\.3 mm"):
        Section(SectionSpec("naca4", 0.04, 0.0, 0.0, 0.12, 0.3e-3, 0.2e-3))


# --- blades --------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(FAMILY))
def test_mesh_is_closed_and_its_volume_is_the_integral_of_the_section_area(name, blades):
    """Watertight, outward; volume = ∫ A(z) dz by 8-point Gauss-Legendre over the exact
    sections (Cavalieri: lean and sweep move sections without changing the volume)."""
    blade = blades[name]
    mesh = blade.mesh
    assert mesh.is_watertight and mesh.is_winding_consistent
    nodes, weights = np.polynomial.legendre.leggauss(8)
    eta = 0.5 * (nodes + 1.0)
    integral = 0.5 * blade.spec.span * sum(
        w * blade.section(float(e)).area(sag=1e-8) for e, w in zip(eta, weights, strict=True))
    assert mesh.volume == pytest.approx(integral, rel=1e-4)
    z = mesh.vertices[:, 2]
    assert z.min() == pytest.approx(blade.spec.hub_radius, abs=1e-12)
    assert z.max() == pytest.approx(blade.spec.hub_radius + blade.spec.span, abs=1e-12)


@pytest.mark.parametrize("name", list(FAMILY))
def test_mesh_is_within_a_micrometre_of_the_exact_surface(name, blades):
    assert blades[name].mesh_sag() <= MESH_SAG


def test_signed_distance_of_known_offsets(blades):
    """Points moved by ±d along the exact normal are ±d away; above the tip cap: the height.
    (A prismatic blade: on a twisted one the surface normal leaves the section plane.)"""
    blade = blades["thick-impulse"]
    rng = np.random.default_rng(1)
    section = blade.section(0.37)
    w = rng.uniform(0.05, 0.95, 300)
    base = section.piece("upper", w)
    tangent = section.piece("upper", w + 1e-6) - base
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])  # upper: counter-clockwise TE→LE
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    z = blade.height(0.37)
    d = rng.uniform(-0.1e-3, 0.5e-3, len(w))  # inward less than the thinnest half thickness
    points = np.column_stack([base + d[:, None] * normal, np.full(len(w), z)])
    assert np.abs(blade.signed_distance(points) - d).max() < MESH_SAG
    top = blade.height(1.0) + 0.3e-3
    centre = blade.section(1.0).piece("upper", [0.5])[0] * 0.5 + blade.section(1.0).piece(
        "lower", [0.5])[0] * 0.5
    assert blade.signed_distance(np.array([[*centre, top]]))[0] == pytest.approx(0.3e-3,
                                                                                 abs=1e-9)


def test_blade_spec_checks_units():
    root = FAMILY["naca-twisted"].root
    with pytest.raises(ValueError, match=r"span 80\.0 m"):
        BladeSpec(root, root, 80.0)


# --- clouds --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def cloud(blades):
    return laser_cloud(blades["naca-twisted"], points=30_000, seed=4)


def test_cloud_noise_outliers_and_holes(cloud, blades):
    blade = blades["naca-twisted"]
    assert len(cloud.points) == 30_000
    assert cloud.outliers.sum() == 300  # 1 %
    distance = blade.signed_distance(cloud.points)
    inliers = distance[~cloud.outliers]
    # σ of 29 700 normal draws: ±1.3 % (2σ of the sample standard deviation)
    assert np.std(inliers) == pytest.approx(0.017e-3, rel=0.02)
    assert abs(np.mean(inliers)) < 0.4e-6
    off = distance[cloud.outliers]
    assert off.min() >= 0.2e-3 - MESH_SAG and off.max() <= 2e-3 + MESH_SAG
    assert len(cloud.hole_centres) == 10
    gaps = np.linalg.norm(cloud.points[~cloud.outliers, None] - cloud.hole_centres[None],
                          axis=2).min(axis=0)
    assert np.all(gaps > cloud.hole_radius - 5 * 0.017e-3)
    # a disc elsewhere holds its share of points: the holes are real
    expected = 30_000 * math.pi * cloud.hole_radius**2 / blade.mesh.area
    assert expected > 10


def test_cloud_is_area_uniform_over_sides_and_caps(cloud, blades):
    """The share of points on the caps is the caps' share of the area (binomial 4σ)."""
    blade = blades["naca-twisted"]
    mesh = blade.mesh
    cap_area = mesh.area_faces[blade.side_faces:].sum()
    share = cap_area / mesh.area
    on_caps = np.abs(cloud.normals[~cloud.outliers, 2]) > 1.0 - 1e-12  # drawn from a cap
    n = int((~cloud.outliers).sum())
    assert on_caps.mean() == pytest.approx(share, abs=4 * math.sqrt(share * (1 - share) / n))
    # and the cap points lie in the cap planes (to the noise)
    z = cloud.points[~cloud.outliers][on_caps, 2]
    plane = np.where(z < blade.height(0.5), blade.height(0.0), blade.height(1.0))
    assert np.abs(z - plane).max() < 6 * 0.017e-3


def test_clouds_are_seeded(blades):
    blade = blades["compressor-dca"]
    a = laser_cloud(blade, points=2_000, seed=7).points
    assert np.array_equal(a, laser_cloud(blade, points=2_000, seed=7).points)
    assert not np.array_equal(a, laser_cloud(blade, points=2_000, seed=8).points)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_random_pose_round_trips(seed):
    points = np.random.default_rng(0).normal(size=(50, 3)) * 0.05
    moved, transform = random_pose(points, seed)
    rotation, translation = transform[:3, :3], transform[:3, 3]
    assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    assert np.linalg.norm(translation) <= 1.0
    assert np.array_equal(transform[3], [0.0, 0.0, 0.0, 1.0])
    back = (np.linalg.inv(transform) @ np.column_stack([moved, np.ones(50)]).T).T[:, :3]
    assert np.allclose(back, points, atol=1e-12)


# --- the current pipeline on the members it handles today ------------------------------------


@pytest.mark.parametrize(("name", "seed"), [("thick-impulse", 1), ("high-camber-turbine", 1)])
def test_reconstruction_meets_the_issue_limits(name, seed, blades):
    """40k points, blade frame: watertight, RMS ≤ 0.02 mm, max ≤ 0.1 mm both ways against the
    exact surface (the issue's limits). Clouds that pass today (bench_foreign_blades: 0.040 and
    0.064 mm max); other members and seeds are listed in the benchmark."""
    blade = blades[name]
    cloud = laser_cloud(blade, points=40_000, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = reconstruct_blade(cloud.points)
    assert trimesh.Trimesh(result.vertices, result.triangles, process=False).is_watertight
    figures = compare_with_exact(blade, result.vertices, result.triangles, seed=seed)
    assert figures["rms"] <= 0.02e-3
    assert figures["max"] <= 0.1e-3
    assert figures["back_max"] <= 0.1e-3
