"""Reconstruction of the strongly cambered IP stator rows, whose suction side bulges upstream
of the leading edge: the faces are not graphs over the chord line, so the start parameters come
from arc length round the section (``segmentation.section_turn``)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from steamtwin.geometry.fidelity import sample_triangles, truth_section
from steamtwin.geometry.profile import Blade, make_blade, reference_surface
from steamtwin.geometry.reconstruct import initial_parameters, reconstruct_blade
from steamtwin.geometry.reconstruction_report import reconstruction_fidelity
from steamtwin.geometry.segmentation import segment_blade
from steamtwin.geometry.volume_mesh import REGIONS
from steamtwin.spec import TurbineSpec

pytestmark = pytest.mark.slow  # 27 s of the full suite (2026-11-27): not in the quick loop

SIDE = [REGIONS.index(name) for name in ("pressure_side", "suction_side", "leading_edge",
                                         "trailing_edge")]


@pytest.fixture(scope="module")
def ip1_blade(reference_spec: TurbineSpec) -> Blade:
    return make_blade(reference_spec, "ip1")


def noisy_samples(blade: Blade, count: int, noise: float, seed: int = 2
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Points spread uniformly over the exact surface, moved along the normal by uniform noise
    ±``noise`` (m), and the region each was drawn from."""
    vertices, triangles, regions = reference_surface(blade)
    rng = np.random.default_rng(seed)
    points, pick, normals = sample_triangles(vertices, triangles, count, rng)
    return points + normals * rng.uniform(-noise, noise, count)[:, None], regions[pick]


def test_start_parameter_is_monotone_round_an_ip_section(ip1_blade) -> None:
    """On exact points of ip1 the start parameter follows arc length round every section: in
    slabs across the span, sorted by the exact arc position, s steps back by less than 2 mm of
    arc (measured: at most 0.8 mm, graph-distance noise) and stays within 5 mm of the exact
    position (measured: 3.1 mm) — the chordwise turn fraction put the bulge of the suction side
    tens of mm off, onto the other face."""
    points, truth = noisy_samples(ip1_blade, 40_000, noise=0.0)
    segmentation = segment_blade(points)
    # measured: 97.2 % of the points on the right patch (the chordwise labelling: 82 %)
    assert np.mean(segmentation.labels == truth) > 0.95
    side = np.isin(segmentation.labels, SIDE)
    s, perimeter = initial_parameters(points, segmentation, side)
    hub, span = ip1_blade.design.hub_radius, ip1_blade.design.span
    for fraction in (0.1, 0.5, 0.9):
        height = hub + fraction * span
        section = truth_section(ip1_blade, height)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(section, axis=0),
                                                             axis=1))])
        slab = side & (np.abs(points[:, 2] - height) < 0.5e-3)
        nearest = np.argmin(np.linalg.norm(points[slab, None, :2] - section[None], axis=2),
                            axis=1)
        # exact arc position, anticlockwise from the most downstream point like s
        exact = np.mod(arc[nearest] - arc[np.argmax(section[:, 0])], arc[-1]) / arc[-1]
        if np.corrcoef(exact, s[slab])[0, 1] < 0.0:  # the section's own orientation
            exact = np.mod(-exact, 1.0)
        order = np.argsort(exact)
        steps = np.mod(np.diff(s[slab][order]) + 0.5, 1.0) - 0.5
        assert steps.min() * perimeter > -2e-3
        error = np.mod(s[slab] - exact + 0.5, 1.0) - 0.5
        assert np.abs(error).max() * perimeter < 5e-3


def test_ip_stator_reconstructs_watertight_and_close(ip1_blade) -> None:
    """ip1 from 100k noisy points (±0.05 mm along the normal, mean spacing ~0.5 mm like the
    80k-point fused benchmark scans): the chordwise start parameters left 27 % of the side out
    and the reconstruction was refused; now a watertight surface within the issue's bounds.
    (At 40k random points, spacing ~0.8 mm against the 0.82 mm trailing-edge radius, the
    result depends on the sample: chord errors up to 1.5 mm.)"""
    points, _ = noisy_samples(ip1_blade, 100_000, noise=0.05e-3)
    result = reconstruct_blade(points)
    mesh = trimesh.Trimesh(result.vertices, result.triangles, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.0
    assert not result.surface.folds()
    assert result.volume == pytest.approx(ip1_blade.volume, rel=1e-3)  # measured −0.003 %
    assert np.mean(~result.inliers[np.isin(result.segmentation.labels, SIDE)]) < 0.05
    report = reconstruction_fidelity(ip1_blade, result.vertices, result.triangles,
                                     samples=5_000)
    # measured (samples seeded 2, 3, 4): RMS 0.0058/0.0066/0.0062 mm, max 0.055/0.057/0.061
    # mm, worst chord error 0.024/0.038/0.031 mm, worst stagger error 0.010/0.029/0.022°
    assert report.deviation.rms < 0.02e-3
    assert report.deviation.max < 0.1e-3
    for section in report.extra["sections"]:
        errors = {row["metric"]: row["error"] for row in section["metrics"]}
        assert abs(errors["chord"]) < 0.05
        assert abs(errors["stagger"]) < 0.1
