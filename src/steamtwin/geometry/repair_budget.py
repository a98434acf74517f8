"""CPU budget of the guard's repair refits: a reconstruction that will be refused stops early.

Each repair of :func:`~steamtwin.geometry.reconstruct.guarded` is a whole adaptive fit of the
side, its triangulation and a new two-way check (at 80k points 5–15 s of CPU each). Before the
budget, a cloud refused after its repairs cost up to 58 s of CPU (docs/benchmarks.md, "Blades we
did not design"), while issue 19 asks for ≤ 30 s per 80k-point cloud. The rule: a repair is
started only when the CPU time already spent plus the cost of one more refit stays within the
budget, the cost of a refit estimated by :data:`REFIT_MARGIN` × the dearest one measured so far
(the first fit from the segmented cloud to its guard report, then every repair) — the next
refit repeats the same steps on the same points with more penalty (the adaptive fit's rounds
are bounded, ``AdaptiveSurfaceFit.max_rounds``), but its rounds may fold and be refitted. A
cloud that passes at its first fit never meets the budget; one whose repair passes keeps it as
long as the first fit takes less than 1 / (1 + REFIT_MARGIN) of the budget (12 s of 30).

CPU time is the process's (``time.process_time``, all threads), so that a machine shared with
other work does not change which repairs are tried; the reconstruction runs with one BLAS
thread (``reconstruct.BLAS_THREADS``), whose default threads would otherwise count their
spinning while they wait for a core of a loaded machine.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

#: A repair is started only when the time spent plus this multiple of the dearest refit so far
#: fits the budget: a repair's adaptive fit took 1.3 × the first fit's (compressor-dca 80k
#: seed 0, random pose: 33.9 s of CPU against a 30 s budget with a margin of 1).
REFIT_MARGIN = 1.5


@dataclass
class RepairBudget:
    """CPU seconds of one reconstruction: ``seconds`` the budget (None: unlimited), ``started``
    the process time at its start, ``refit_seconds`` the dearest refit measured and ``since``
    the process time at which the current one began (s; default: ``started``)."""

    seconds: float | None
    started: float
    refit_seconds: float = 0.0
    since: float | None = None

    @classmethod
    def start(cls, seconds: float | None) -> RepairBudget:
        """A budget of ``seconds`` of CPU (None: unlimited) counted from now."""
        return cls(seconds=seconds, started=time.process_time())

    def mark(self) -> None:
        """A refit (or the first fit, from the segmented cloud) begins now."""
        self.since = time.process_time()

    @property
    def spent(self) -> float:
        """CPU seconds since the start."""
        return time.process_time() - self.started

    def measure(self) -> None:
        """Record the refit that began at the last :meth:`mark` (or the start) and ends now."""
        since = self.started if self.since is None else self.since
        self.refit_seconds = max(self.refit_seconds, time.process_time() - since)

    def allows_refit(self) -> bool:
        """Whether one more refit, costing :data:`REFIT_MARGIN` × the dearest measured so far,
        fits in the budget."""
        return (self.seconds is None
                or self.spent + REFIT_MARGIN * self.refit_seconds <= self.seconds)
