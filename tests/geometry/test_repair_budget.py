"""The CPU budget of the guard's repairs (issue 19: ≤ 30 s per 80k-point cloud): a repair
refit starts only when it fits in the budget, a passing first fit never meets it, and the
refusal still names the defect. The guard and the refit are stand-ins, so that the rule is
tested without a whole reconstruction."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
import pytest

import steamtwin.geometry.reconstruct as reconstruct
from steamtwin.geometry.blade_cloud import ReconstructionError
from steamtwin.geometry.fit_guard import Defect, GuardReport, GuardSettings
from steamtwin.geometry.repair_budget import RepairBudget


@dataclass(frozen=True)
class _Fit:
    """What :func:`reconstruct.guarded` reads of a reconstruction besides the guard's input."""

    points: np.ndarray
    segmentation: object
    penalty: float
    guard: object = None


def _report(size_mm: float) -> GuardReport:
    defects = [] if size_mm <= 0.0 else [Defect("trailing_edge", 0.4, 0.5, size_mm * 1e-3, 9)]
    return GuardReport(excursion=np.zeros(3), limit=0.1e-3, noise=0.017e-3, spacing=0.2e-3,
                       defects=defects)


@pytest.fixture
def stand_ins(monkeypatch):
    """Refits recorded by their penalty factor, each burning ``cost`` s of CPU; the guard
    finds a defect of ``sizes[penalty]`` mm (0: passes)."""
    calls: list[float] = []
    state = {"cost": 0.0, "sizes": {1.0: 0.7, 10.0: 0.4, 100.0: 0.0}}

    def refit(points, settings, segmentation):
        calls.append(settings.penalty_factor)
        end = time.process_time() + state["cost"]
        while time.process_time() < end:
            pass
        return _Fit(points, segmentation, settings.penalty_factor)

    monkeypatch.setattr(reconstruct, "_reconstruct", refit)
    monkeypatch.setattr(reconstruct, "guard_surface",
                        lambda fit, settings: _report(state["sizes"][fit.penalty]))
    monkeypatch.setattr(reconstruct, "remnants", lambda fit, report, earlier: [])
    monkeypatch.setattr(reconstruct, "refusal_message",
                        lambda report, points, segmentation: report.defects[0].describe())
    return calls, state


def _settings(budget: float | None) -> reconstruct.ReconstructionSettings:
    return reconstruct.ReconstructionSettings(guard=GuardSettings(cpu_budget=budget))


def test_repairs_run_while_they_fit_in_the_budget(stand_ins) -> None:
    """Unlimited (and ample) budget: both repairs are tried and the second one passes."""
    calls, _ = stand_ins
    for budget in (None, RepairBudget.start(30.0)):
        calls.clear()
        seconds = None if budget is None else 30.0
        result = reconstruct.guarded(_Fit(np.zeros((1, 3)), None, 1.0), _settings(seconds),
                                     budget)
        assert calls == [10.0, 100.0]
        assert result.penalty == 100.0 and result.guard.repairs == 100.0


def test_no_repair_starts_that_would_overrun_the_budget(stand_ins) -> None:
    """9 s spent of 10 and a first fit that cost 2 s: no refit, refused at once with the
    first fit's defect (without the budget the same cloud is refitted twice)."""
    calls, _ = stand_ins
    budget = RepairBudget(seconds=10.0, started=time.process_time() - 9.0,
                          since=time.process_time() - 2.0)
    with pytest.raises(ReconstructionError, match=r"0\.70 mm at the trailing edge"):
        reconstruct.guarded(_Fit(np.zeros((1, 3)), None, 1.0), _settings(10.0), budget)
    assert calls == []


def test_the_dearest_refit_measured_bounds_the_next(stand_ins) -> None:
    """A first repair that costs more than the time left stops the chain after it: a budget
    of 0.2 s of CPU, a fit measured at ~0 s and a repair that burns 0.1 s (the next one, with
    the margin, would need 0.15 s more)."""
    calls, state = stand_ins
    state["cost"] = 0.1
    with pytest.raises(ReconstructionError, match=r"0\.70 mm"):
        reconstruct.guarded(_Fit(np.zeros((1, 3)), None, 1.0), _settings(0.2),
                            RepairBudget.start(0.2))
    assert calls == [10.0]


def test_a_passing_first_fit_is_returned_whatever_the_budget(stand_ins) -> None:
    calls, state = stand_ins
    state["sizes"] = {1.0: 0.0}
    budget = RepairBudget(seconds=1.0, started=time.process_time() - 5.0)
    result = reconstruct.guarded(_Fit(np.zeros((1, 3)), None, 1.0), _settings(1.0), budget)
    assert calls == [] and result.guard.repairs == 1.0


def test_the_budget_measures_the_process_cpu_time() -> None:
    budget = RepairBudget.start(1.0)
    budget.mark()
    end = time.process_time() + 0.05
    while time.process_time() < end:
        pass
    budget.measure()
    assert 0.04 <= budget.refit_seconds <= 0.5 and budget.spent >= 0.05
    assert budget.allows_refit() and not replace(budget, seconds=0.06).allows_refit()
    # the margin: 0.05 s spent and 0.05 s for a refit do not fit 0.11 s (1.5 × 0.05 = 0.075)
    assert not replace(budget, seconds=budget.spent + 1.2 * budget.refit_seconds).allows_refit()
