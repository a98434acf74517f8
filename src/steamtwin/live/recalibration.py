"""Online recalibration inside the live twin: a filter that always runs, parameters that change
only on schedule or on a degradation alarm.

:class:`LiveRecalibration` feeds every good sample to a
:class:`~steamtwin.calibration.tracking.ParameterTracker` (iterated EKF on the coefficients,
10-minute steps by default, each step a Gauss–Newton MAP over its own data: a fraction of a
second of model runs). The tracker's estimate becomes the *live* parameters only

* **on schedule**: every ``every_s`` seconds of data time (default 24 h), so slow wear is
  followed without the twin chasing each step's noise; and
* **on a degradation alarm** of the residual monitor: the alarmed coefficient's variance is
  reset to its prior's (covariance resetting, Goodwin & Sin 1984, §3.3.2) so the next steps
  follow the change at the rate the data allow, and while the alarm is active — and for
  ``settle_steps`` steps after it ends, as the estimate gathers the data of the new state — every
  step's estimate of the alarmed coefficient is swapped in (the others stay as they are).

Swapping only then keeps the residuals the monitor judges anchored to one parameter set: a twin
that re-fitted itself every ten minutes would absorb the very change the monitor is there to
flag. A swap happens between two blocks of samples (the model's state carries on; the new set
applies from the next sample), and each swap is returned for the historian with its reason.
The tracker's state is part of the service's saved state.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace

import pandas as pd

from steamtwin.calibration.tracking import ParameterTracker
from steamtwin.model.parameters import DEFAULT_PRIORS, ModelParameters, ParameterPrior

__all__ = ["LiveRecalibration", "ParameterSwap", "centred_priors", "swap_values"]


@dataclass(frozen=True)
class ParameterSwap:
    """A change of the live parameters: ``time`` (the end of the data it rests on, UTC),
    the new ``params``, the ``reason`` ("schedule" or "degradation:<parameter>") and
    ``intervals``: name → the filter's 95 % interval (low, high) of each value it took from
    the filter (the flow coefficient's widened by the flow meter's uncertainty,
    :class:`~steamtwin.calibration.tracking.ParameterTracker`)."""

    time: pd.Timestamp
    params: ModelParameters
    reason: str
    intervals: Mapping[str, tuple[float, float]] = field(default_factory=dict)


class LiveRecalibration:
    """Recalibration of one live unit (module docstring).

    ``tracker``: the configured filter (its ``priors`` are the calibration's posterior, its
    ``sigma`` the instruments' error); ``every_s``: scheduled swap interval, s of data time;
    ``settle_steps``: tracker steps still swapped in after a degradation alarm ends (the first
    estimates rest on one step's data; each further step narrows them).
    """

    def __init__(self, tracker: ParameterTracker, every_s: float = 86_400.0,
                 settle_steps: int = 3) -> None:
        if not (isinstance(every_s, int | float) and math.isfinite(every_s) and every_s > 0):
            raise ValueError(f"every_s must be a positive number of seconds (got {every_s!r})")
        if isinstance(settle_steps, bool) or not isinstance(settle_steps, int) or settle_steps < 0:
            raise ValueError(f"settle_steps must be a whole number ≥ 0 (got {settle_steps!r})")
        self.tracker = tracker
        self.every_s = float(every_s)
        self.settle_steps = settle_steps
        self._last_swap: pd.Timestamp | None = None
        self._degraded: dict[str, pd.Timestamp] = {}
        self._settling: dict[str, int] = {}

    def start(self) -> LiveRecalibration:
        """Start the filter from its priors; returns self."""
        self.tracker.start()
        return self

    def feed(self, data: pd.DataFrame, live: ModelParameters) -> list[ParameterSwap]:
        """Take the good samples of a block (canonical SI signals; bad samples NaN) and the
        ``live`` parameters; return the swaps due: while a degradation alarm is active, one per
        tracker step with the alarmed coefficients replaced by the filter's estimate (the
        others stay live: a step's data pull the others about in transients, and the monitor's
        baseline holds for them); else, when the schedule comes due, the whole estimate."""
        if data.empty:
            return []
        if self._last_swap is None:
            self._last_swap = data.index[0]
        steps = self.tracker.update(data)
        swaps = []
        for end, row in steps.iterrows():
            if row["error"]:
                continue
            following = sorted({p for p, since in self._degraded.items() if end > since}
                               | set(self._settling))
            if following:
                live = replace(live, **{p: getattr(self.tracker.params_, p) for p in following})
                swaps.append(ParameterSwap(end, live,
                                           ",".join(f"degradation:{p}" for p in following),
                                           _intervals(row, following)))
                self._last_swap = end
            self._settling = {p: n - 1 for p, n in self._settling.items() if n > 1}
        last = data.index[-1]
        if not swaps and last - self._last_swap >= pd.Timedelta(seconds=self.every_s):
            # the steps that gave an estimate (a block without a step has no columns)
            estimated = steps[~steps["error"].astype(bool)] if len(steps) else steps
            intervals = (_intervals(estimated.iloc[-1], self.tracker.tracked)
                         if len(estimated) else {})
            swaps.append(ParameterSwap(last, self.tracker.params_, "schedule", intervals))
            self._last_swap = last
        return swaps

    def on_alarm(self, kind: str, signal: str, time: pd.Timestamp, ended: bool) -> None:
        """A residual alarm started or ended at ``time``; a degradation of a tracked parameter
        resets its variance and makes the estimate of every step whose data reach past the
        alarm's start live until the alarm ends (then ``settle_steps`` more)."""
        if kind != "degradation" or signal not in self.tracker.tracked:
            return
        if ended:
            self._degraded.pop(signal, None)
            if self.settle_steps:
                self._settling[signal] = self.settle_steps
            return
        self.tracker.reset([signal])
        self._degraded[signal] = pd.Timestamp(time)
        self._settling.pop(signal, None)

    @property
    def estimate(self) -> ModelParameters:
        """The filter's current estimate (not necessarily live)."""
        return self.tracker.params_

    def get_state(self) -> dict[str, object]:
        """JSON-ready state: the filter's, the last swap and the active degradations."""
        return {"tracker": self.tracker.get_state(),
                "last_swap": None if self._last_swap is None else self._last_swap.isoformat(),
                "degraded": {p: t.isoformat() for p, t in self._degraded.items()},
                "settling": dict(self._settling)}

    def set_state(self, state: Mapping[str, object]) -> LiveRecalibration:
        """Restore :meth:`get_state`'s output exactly."""
        self.tracker.set_state(state["tracker"])
        last = state.get("last_swap")
        self._last_swap = None if last is None else pd.Timestamp(last)
        self._degraded = {str(p): pd.Timestamp(t) for p, t in state.get("degraded", {}).items()}
        self._settling = {str(k): int(v) for k, v in state.get("settling", {}).items()}
        return self


def _intervals(row: pd.Series, names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """The 95 % intervals a tracker step's row gives for ``names``."""
    return {name: (float(row[f"{name}_low"]), float(row[f"{name}_high"])) for name in names}


def swap_values(swap: ParameterSwap) -> dict[str, float]:
    """The swap's parameters as name → value, for the historian's ``parameters`` table."""
    return {name: float(value) for name, value in asdict(swap.params).items()}


def centred_priors(params: ModelParameters,
                   base: Mapping[str, ParameterPrior] | None = None) -> dict[str, ParameterPrior]:
    """``base``'s priors (default :data:`~steamtwin.model.parameters.DEFAULT_PRIORS`) moved to
    centre on ``params``: the tracker starts at the live (calibrated) coefficients with the
    design spread, so its first estimate is the live set, not the design one."""
    priors = dict(base or DEFAULT_PRIORS)
    return {name: replace(prior, center=float(getattr(params, name)))
            for name, prior in priors.items()}
