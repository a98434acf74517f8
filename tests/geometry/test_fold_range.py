"""Folds are judged where the side surface is used, between the cap planes (issue 19, lean-sweep
80k seed 5 in a random pose): the side's fit looped at the thin trailing edge only at the top of
its z knots, 0.12 mm beyond the tip plane and 0.2 mm beyond the last point — no part of the
triangulation —, was stiffened 100-fold for it and cut the tip's leading edge 0.27 mm inside
(max 0.31 mm, refused by the guard); judged between the cap planes it passes (0.039 mm)."""

from __future__ import annotations

import numpy as np
from foreign_blades import family_blade, laser_cloud

from steamtwin.geometry import reconstruct
from steamtwin.geometry.bspline import AdaptiveSurfaceFit, PeriodicSurface, clamped_knots


def _looping_at_the_top() -> PeriodicSurface:
    """A periodic surface over z ∈ [0, 1] (m): circles (radius 1) below, a figure eight (a
    section crossing itself) as the top row of coefficients, reached only at z = 1."""
    breaks = np.linspace(0.0, 1.0, 16, endpoint=False)
    t = 2.0 * np.pi * breaks
    circle = np.column_stack([np.cos(t), np.sin(t)])
    eight = np.column_stack([np.sin(t), 0.5 * np.sin(2.0 * t)])
    coefficients = np.stack([circle, circle, circle, eight], axis=1)  # (m, nz, 2)
    return PeriodicSurface(breaks, clamped_knots(0.0, 1.0, 0), coefficients)


def test_a_loop_beyond_the_range_judged_is_no_fold() -> None:
    """The figure eight at the top is a fold over the whole knot range, not below z = 0.5 (the
    section there is 7/8 circle, 1/8 eight by the cubic basis weights)."""
    surface = _looping_at_the_top()
    assert surface.folds()
    assert surface.folds(z_range=(0.9, 1.0))
    assert not surface.folds(z_range=(0.0, 0.5))


def test_the_side_fit_judges_folds_between_the_cap_planes(monkeypatch) -> None:
    """reconstruct_blade hands the fit the span between the cap planes over the side points as
    the range where folds count, inside the knots' margin."""
    seen = {}
    fit = AdaptiveSurfaceFit.fit

    def spy(self, s, z, xy, breaks, z_knots):
        seen["range"], seen["knots"], seen["z"] = self.fold_range, z_knots, z
        return fit(self, s, z, xy, breaks, z_knots)

    monkeypatch.setattr(AdaptiveSurfaceFit, "fit", spy)
    cloud = laser_cloud(family_blade("thick-impulse"), points=20_000, seed=0).points
    result = reconstruct.reconstruct_blade(cloud, reconstruct.ReconstructionSettings(guard=None))
    low, high = seen["range"]
    knots = seen["knots"]
    assert knots[0] < low <= seen["z"].min() and seen["z"].max() <= high < knots[-1]
    # the triangulation's ends (the rims on the tilted cap planes) within 10 µm of the range
    bottom, top = result.vertices[:, 2].min(), result.vertices[:, 2].max()
    assert abs(bottom - low) < 1e-5 and abs(top - high) < 1e-5
