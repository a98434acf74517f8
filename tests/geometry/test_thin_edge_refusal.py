"""Which edge a guard finding belongs to (issue 19: a refusal at a thin edge says how many points
per millimetre the edge needs and where): a gap at the end of the chord is at that edge, also
when the segmentation labelled its points a side."""

from __future__ import annotations

from steamtwin.geometry.fit_guard import CoverageGap, Defect, GuardReport, at_edges


def _report(*findings) -> GuardReport:
    import numpy as np

    return GuardReport(excursion=np.zeros(1), limit=0.1e-3, noise=0.017e-3, spacing=0.2e-3,
                       defects=[f for f in findings if isinstance(f, Defect)],
                       gaps=[f for f in findings if isinstance(f, CoverageGap)])


def test_a_side_gap_at_the_end_of_the_chord_is_at_that_edge() -> None:
    """The slender blade's refusal (80k, seed 0): gaps 1.45–1.81 mm on the suction side at
    99–100 % chord — the trailing edge, which the message did not name, so it gave no density
    for it."""
    rear = CoverageGap("suction_side", 0.25, 0.43, 0.99, 1.0, 1.81e-3, 739)
    front = CoverageGap("pressure_side", 0.1, 0.2, 0.0, 0.01, 0.3e-3, 20)
    middle = CoverageGap("pressure_side", 0.5, 0.6, 0.4, 0.6, 0.3e-3, 40)
    edge = Defect("leading_edge", 0.9, 0.95, 0.4e-3, 5)
    side = Defect("suction_side", 0.3, 0.4, 0.4e-3, 5)
    found = at_edges(_report(rear, front, middle, edge, side))
    assert found["trailing_edge"] == [rear]
    assert found["leading_edge"] == [edge, front]


def test_a_folding_side_is_refused_with_the_edge_density_it_needs(monkeypatch) -> None:
    """A side that folds (the slender blade's refusal at 80k points) is refused with the
    density note of the sparse edges, asked for only when it is refused."""
    import numpy as np
    import pytest

    from steamtwin.geometry.blade_cloud import ReconstructionError
    from steamtwin.geometry.reconstruct import check_side_fit

    class Folding:
        inliers_ = np.ones(10, dtype=bool)
        outlier_distance = 0.1e-3
        fold_range = None

        class surface_:
            @staticmethod
            def folds(z_range=None) -> bool:
                return True

    asked = []

    def note() -> str:
        asked.append(True)
        return "; too few points on the edge: trailing edge at 80–100 % span: 2.1 per mm"

    with pytest.raises(ReconstructionError, match=r"folds over itself.*trailing edge at 80–100"):
        check_side_fit(Folding(), note)
    Folding.surface_.folds = staticmethod(lambda z_range=None: False)
    check_side_fit(Folding(), note)
    assert len(asked) == 1
