"""The guard judges the cap rims (geometry/fit_guard.py: rim_excursion, issue 19).

Next to a cap the side's points end; a bulge of the side's spline on the rim ring (thick-impulse
80k seed 0: 0.33 mm at the tip rim) stood beyond the cap outline and the side's points, but the
rim zone was measured and not judged. Now the rim vertices are checked in their own section
against the side's points and the cap's (plane and outline).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from test_fit_guard import foreign_blade, noisy_cloud

from steamtwin.geometry.fit_guard import guard_surface, rim_excursion
from steamtwin.geometry.reconstruct import ReconstructionSettings, reconstruct_blade


def _capped_cylinder(radius: float, height: float, count: int, seed: int) -> np.ndarray:
    """Points area-uniform on a closed circular cylinder (side and top cap, m), σ 0.01 mm."""
    rng = np.random.default_rng(seed)
    side_area, cap_area = 2 * math.pi * radius * height, math.pi * radius**2
    n_side = round(count * side_area / (side_area + cap_area))
    angle = rng.uniform(0.0, 2 * math.pi, n_side)
    r = radius + rng.normal(0.0, 0.01e-3, n_side)
    side = np.column_stack([r * np.cos(angle), r * np.sin(angle),
                            rng.uniform(0.0, height, n_side)])
    n_cap = count - n_side
    rho, phi = radius * np.sqrt(rng.uniform(0.0, 1.0, n_cap)), rng.uniform(0, 2 * math.pi, n_cap)
    cap = np.column_stack([rho * np.cos(phi), rho * np.sin(phi),
                           height + rng.normal(0.0, 0.01e-3, n_cap)])
    return np.vstack([side, cap])


def test_rim_excursion_is_the_distance_beyond_the_cap_outline() -> None:
    """A 3-mm cylinder with its top cap (0.1-mm spacing): rim samples on the top circle lie
    within 0.03 mm of the data; pushed out by 0.3 mm they stand 0.25–0.33 mm outside it —
    the side's points below and the cap's outline both inside."""
    radius, height = 3e-3, 2e-3
    points = _capped_cylinder(radius, height, 12_000, seed=0)
    normals = np.column_stack([points[:, :2] / np.linalg.norm(points[:, :2], axis=1)[:, None],
                               np.zeros(len(points))])
    turn = np.linspace(0.0, 2 * math.pi, 90, endpoint=False)
    outward = np.column_stack([np.cos(turn), np.sin(turn), np.zeros(len(turn))])
    for push, lo, hi in ((0.0, 0.0, 0.03e-3), (0.3e-3, 0.25e-3, 0.33e-3)):
        samples = (radius + push) * outward + np.array([0.0, 0.0, height])
        on_cap = points[:, 2] > height - 0.05e-3
        excursion = rim_excursion(samples, outward, [(points[~on_cap], normals[~on_cap]),
                                                     (points[on_cap], normals[on_cap])])
        assert lo <= excursion.min() and excursion.max() <= hi, push


@pytest.fixture(scope="module")
def blade_fit():
    """A tapered, twisted NACA blade (30 mm span) from 20k noisy points, fitted unguarded."""
    vertices, triangles = foreign_blade(0.03, 0.03, 0.022, (30.0, 45.0), 0.4e-3)
    cloud = noisy_cloud(vertices, triangles, 20_000, 0.01e-3, seed=1)
    return reconstruct_blade(cloud, ReconstructionSettings(guard=None))


def _tip_rim_bulge(reconstruction, size: float, half_width: int = 8):
    """The fit with the suction side's vertices of the tip ring pushed out along the
    surface normal, ``size`` (m) at the patch's middle column, a cosine taper over
    ``half_width`` columns either side: the tip-rim bulge of issue 19."""
    s = reconstruction.ring_parameters
    columns = len(s)
    boundaries = reconstruction.boundaries
    lo = next(v for key, v in boundaries.items() if key.endswith("|suction_side"))
    hi = next(v for key, v in boundaries.items() if key.startswith("suction_side|"))
    middle = np.mod(lo + 0.5 * np.mod(hi - lo, 1.0), 1.0)
    centre = int(np.argmin(np.abs(np.mod(s - middle + 0.5, 1.0) - 0.5)))
    vertices = reconstruction.vertices.copy()
    tip_ring = len(vertices) - columns
    for step in range(-half_width, half_width + 1):
        column = (centre + step) % columns
        at = tip_ring + column
        normal = reconstruction.surface.outward_normals(s[column:column + 1],
                                                        vertices[at:at + 1, 2])[0]
        weight = 0.5 * (1.0 + math.cos(math.pi * step / (half_width + 1)))
        vertices[at, :2] += weight * size * normal
    return dataclasses.replace(reconstruction, vertices=vertices)


def test_a_clean_rim_passes_the_guard(blade_fit) -> None:
    """The unguarded fit of the synthetic blade passes the guard, its rims included: no false
    alarm on a clean rim, and every vertex is held to the limit."""
    assert len(blade_fit.vertices) % len(blade_fit.ring_parameters) == 0  # rings only
    clean = guard_surface(blade_fit)
    assert not clean.failed, [d.describe() for d in clean.defects]
    assert bool(np.all(clean.judged))


def test_a_tip_rim_bulge_is_a_defect(blade_fit) -> None:
    """With a 0.3-mm bulge on its tip rim the fit fails the guard with a defect at 100 % span
    of at least 0.25 mm — the finding the reconstruction repairs or refuses."""
    bulged = guard_surface(_tip_rim_bulge(blade_fit, 0.3e-3))
    assert bulged.failed
    worst = bulged.defects[0]
    assert worst.span_to == pytest.approx(1.0, abs=1e-3) and worst.size >= 0.25e-3
    assert worst.region in {"tip", "suction_side"} and worst.vertices >= 3


def test_rim_excursion_refuses_more_reaches_than_sets_of_points():
    """A near-line reach per set of points: one more than the sets is a mistake, not ignored."""
    samples = np.array([[1e-3, 0.0, 0.0]])
    outward = np.array([[1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="2 near-line reaches for 1 sets"):
        rim_excursion(samples, outward, [(samples, outward)], near=(1e-4, 1e-4))
