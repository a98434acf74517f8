"""Re-baselining per load band after a degradation swap (issue 21, item 5).

:class:`~steamtwin.live.residuals.ResidualMonitor` subtracts the residual a healthy plant shows
at each operating point (band medians over the load plus a transient term, fitted on a
calibration day). After a degradation alarm the live parameters are swapped; the twin's
coefficients then follow the degraded plant only along the pattern its J describes, and the
plant's own answer to its fouling (valve overlap, tip leakage, metal: structure the twin lacks)
leaves a residual offset *that depends on the load*, as the healthy one does (operating-point
dependent reference, Isermann, *Fault-Diagnosis Systems*, 2006, §7.2, §10.3). A single constant
learned at the load of the swap does not hold at the other loads the day visits: there the
sensors part together, a pattern neither one sensor nor J explains, which the sensor
hypotheses read as one fault after another (docs/benchmarks.md, "Re-baselining after a
degradation swap": ≈ 19 sensor-hours of false sensor faults on the virtual plant's ``day``).

Rule. At every swap a degradation alarm caused, the control chart's centre is estimated again
from data of the changed process (Montgomery, *Introduction to Statistical Quality Control*,
7th ed., §5.3 and §6.2) — per load band, as the new data visit each band. The band is that of
the *lagged* load, ⌊L_f,1/``load_band``⌋, L_f,1 the block-mean load through the monitor's
shortest first-order lag (``transient_times_s[0]``, 300 s by default; lumped-capacitance
response, Incropera & DeWitt, 6th ed., §5.2): the degraded plant's offset reaches the
thermocouples through their thermowells and the metal, minutes after the load (on the virtual
plant it settled over ≈ 5 min at each new hold). Keyed by the load itself, a hold's first,
still-settling blocks enter the hold's band and its settled blocks then read as a shift from
them (on the ``day``: three false sensor-fault alarms, ≈ 1.9 sensor-hours, at the holds at
76 % and 56 %);
keyed by the lagged load, the settling blocks fall in the bands the lag is still crossing and
the hold's band learns from settled blocks. For sensor s in band b, the k-th block wholly
after the swap with residual r_k (against the band's current centre) enters the CUSUMs as the
self-starting innovation

    u_k = (r_k − r̄_{k−1}) · √((k − 1)/k),   r̄_{k−1} the mean of the band's earlier k − 1 blocks,

(Hawkins, The Statistician 36 (1987) 299–316; Quesenberry, J. Quality Technology 23 (1991)
213–223): with σ known and the band's new centre constant, u_2, u_3, … are independent
N(0, σ²) whatever that centre is, so the thresholds keep their false-alarm rate and monitoring
never pauses — not even in a band the new data reach for the first time (its first block,
u_1 = 0, is spent on the centre). Innovations of different bands are functions of disjoint
sets of independent blocks, hence independent of each other too. Once a band has held
``blocks`` blocks, its centre moves by their mean (error σ/√``blocks``; the mean, not the
median, because the innovations' distribution rests on it) and its plain residuals resume.
A further degradation swap reopens every band (the twin changed at every load); the centres
learned so far stay the reference against which the new windows' means are added.

Why per band and not a "common shift" hypothesis: the classifier's sensor hypotheses are
single-sensor GLRs (signature b·e_s, Willsky & Jones, IEEE TAC 21 (1976) 108–112); a shared
offset of all sensors that follows the load is an unmodelled process change, not evidence for
any e_s. Learning that offset per band removes it from every hypothesis's evidence at the
source instead of suppressing alarms of a pattern class, which would also hide two sensors
failing at once.

Price: when the offset follows the load faster than the key's lag, a ramp's first blocks are
judged in the band just left (re-learned at the previous hold) with part of the next load's
offset — the synthetic test's seed 42 of 31–42 raises one false sensor fault there. A fault
present in a band from its first blocks after the swap is taken into that band's
centre, and a fault that starts while the load runs through bands not yet visited is seen with
the weight √((k − 1)/k) of each band's k-th block (none for the first). A fault starting in a
band already learned, or with a few blocks in its window, is seen at (nearly) full size.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

__all__ = ["BandRebaseline"]


class BandRebaseline:
    """Per sensor and load band: the centre shift learned after degradation swaps
    (``shift_``, SI, sensor → band → shift) and the self-starting window of each band since the
    last swap (``window_``, sensor → band → [blocks, sum of residuals (SI)]; None before the
    first swap). ``blocks``: blocks whose mean re-bases a band (module docstring)."""

    def __init__(self, sensors: Sequence[str], blocks: int) -> None:
        self.sensors = tuple(sensors)
        self.blocks = blocks
        self.shift_: dict[str, dict[str, float]] = {s: {} for s in self.sensors}
        self.window_: dict[str, dict[str, list]] | None = None
        self.after_: pd.Timestamp | None = None

    def open(self, after: pd.Timestamp) -> None:
        """A degradation swap made the samples after ``after`` (UTC): every band relearns."""
        self.window_ = {s: {} for s in self.sensors}
        self.after_ = pd.Timestamp(after)

    def shift(self, band: str) -> np.ndarray:
        """The learned centre shift of every sensor in ``band`` (SI; 0 where none)."""
        return np.array([self.shift_[s].get(band, 0.0) for s in self.sensors])

    def innovations(self, start: pd.Timestamp, band: str, residual: np.ndarray) -> np.ndarray:
        """The block starting at ``start`` in ``band`` with ``residual`` (per sensor, against
        the band's current centre; NaN: out of the block): the self-starting innovation of
        each sensor whose band is still learning, the residual itself elsewhere; the window
        learns the block and a full window moves its band's centre."""
        if self.window_ is None or pd.Timestamp(start) < self.after_:
            return residual  # no swap yet, or a block (partly) before it: the centre holds
        out = residual.copy()
        for j, sensor in enumerate(self.sensors):
            value = float(residual[j])
            count, total = self.window_[sensor].get(band, (0, 0.0))
            if not math.isfinite(value) or count >= self.blocks:
                continue
            out[j] = (value - (total / count if count else 0.0)) * math.sqrt(count / (count + 1))
            count, total = count + 1, total + value
            self.window_[sensor][band] = [count, total]
            if count == self.blocks:
                self.shift_[sensor][band] = self.shift_[sensor].get(band, 0.0) + total / count
        return out

    def get_state(self) -> dict:
        """JSON-ready state (learned shifts, windows, the last swap's time)."""
        return {"shift": {s: dict(bands) for s, bands in self.shift_.items()},
                "window": (None if self.window_ is None else
                           {s: {b: [int(n), float(t)] for b, (n, t) in bands.items()}
                            for s, bands in self.window_.items()}),
                "after": None if self.after_ is None else self.after_.isoformat()}

    def set_state(self, state: Mapping[str, object]) -> BandRebaseline:
        """Restore :meth:`get_state`'s output exactly."""
        shift, window = state["shift"], state["window"]
        self.shift_ = {s: {b: float(v) for b, v in shift.get(s, {}).items()}
                       for s in self.sensors}
        self.window_ = None if window is None else {
            s: {b: [int(n), float(t)] for b, (n, t) in window.get(s, {}).items()}
            for s in self.sensors}
        after = state["after"]
        self.after_ = None if after is None else pd.Timestamp(after)
        return self
