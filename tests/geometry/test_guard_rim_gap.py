"""The guard at a cap rim where the fit trimmed the points under a bulge (issue 19).

naca-twisted 80k seed 6 in a random pose, with session 23's section order: the side fit folded
at every penalty in its first round and the 100-fold stiff fit was kept; it bulged 0.15–0.20 mm
at the leading edge next to the tip rim, where the fit trimmed the edge's own points as off the
surface. Read only against the kept points — 0.5–1.2 mm round the nose, their arc drop up to
0.36 mm — the bulge read 0.10–0.135 mm against 0.149 mm and the STL was written watertight.
The trimmed points count too, unless they lie among kept points of a face turned the other
way: slender 80k seed 2's 0.15-mm trailing edge at the tip has points of the opposite face
placed on this one (their k-NN normals turned with it), which read a clean fit 0.17 mm off.
Since session 24's section order both clouds' first fits are different (naca-twisted s6 within
0.05 mm, slender s2 folding at the tip), so the bulge is put on naca-twisted s6's clean fit —
0.2 mm at the leading edge, fading over 0.4 mm along the span from the tip rim, the points
under it trimmed — and the clean thin-edged tip is slender 80k seed 4's."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from foreign_blades import compare_with_exact, family_blade, laser_cloud, random_pose

from steamtwin.geometry.fit_guard import guard_surface
from steamtwin.geometry.frame import reconstruct_in_any_pose
from steamtwin.geometry.reconstruct import ReconstructionSettings


def _first_fit(member: str, seed: int):
    """The unguarded reconstruction of the family cloud, and its largest deviation from the
    exact blade both ways (m)."""
    blade = family_blade(member)
    cloud = laser_cloud(blade, points=80_000, seed=seed)
    scan, pose = random_pose(cloud.points, seed + 1000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result, frame = reconstruct_in_any_pose(scan, ReconstructionSettings(guard=None))
    vertices = (frame.to_scan(result.vertices) - pose[:3, 3]) @ pose[:3, :3]
    truth = compare_with_exact(blade, vertices, result.triangles, seed=seed)
    return result, max(truth["max"], truth["back_max"])


def _bulged_at_the_tip_rim(result, height: float = 0.2e-3):
    """``result`` with its side bulged outward at the leading edge next to the tip rim by up
    to ``height`` (m; Gaussian, 1 mm of arc round the section and 0.4 mm along the span) and
    the cloud's side points under the bulge trimmed, as a fit that stands off them trims them."""
    columns = len(result.ring_parameters)
    s = np.tile(result.ring_parameters, len(result.vertices) // columns)
    z = result.vertices[:, 2]
    top = float(z.max())
    centre = 0.5 * (result.boundaries["suction_side|leading_edge"]
                    + result.boundaries["leading_edge|pressure_side"])
    perimeter = float(np.median(result.segmentation.perimeter[
        np.isfinite(result.segmentation.perimeter)]))

    def arc(parameters: np.ndarray) -> np.ndarray:
        return (np.mod(parameters - centre + 0.5, 1.0) - 0.5) * perimeter

    weight = np.exp(-(arc(s) / 1e-3) ** 2 - ((top - z) / 0.4e-3) ** 2)
    vertices = result.vertices.copy()
    vertices[:, :2] += (height * weight)[:, None] * result.surface.outward_normals(s, z)
    placed = np.isfinite(result.parameters)
    under = np.zeros(len(result.points), dtype=bool)
    under[placed] = ((np.abs(arc(result.parameters[placed])) < 1.5e-3)
                     & (result.points[placed, 2] > top - 0.8e-3))
    return replace(result, vertices=vertices, inliers=result.inliers & ~under)


@pytest.mark.parametrize(("member", "seed", "bulged"), [("naca-twisted", 6, True),
                                                        ("slender", 4, False)])
def test_the_rim_is_read_against_the_trimmed_points_of_its_own_face(member, seed, bulged):
    result, deviation = _first_fit(member, seed)
    assert deviation < 0.1e-3  # measured 0.042 and 0.068 mm
    if bulged:
        result = _bulged_at_the_tip_rim(result)
    report = guard_surface(result, ReconstructionSettings().guard)
    assert report.failed is bulged
    if bulged:  # the bulge at the rim: 0.23 mm read over 16 vertices
        assert report.worst > 0.15e-3
