"""The HP rotor in the live twin (issue 23, item 6): each sample the twin accepted advances the
rotor's reduced-order model (:class:`~steamtwin.rotor.model.RotorModel`) by one step.

The steam side of a sample — each metal group's steam temperature (K) and rotor heat-transfer
coefficient (W/(m²·K)) — comes from the streamed full-order model's own stage states of that
sample (:meth:`~steamtwin.model.fom.FullOrderModel.simulate_stream_detailed`, then
:func:`~steamtwin.rotor.steam_side.steam_side` with that run, at the twin's live parameters),
so the rotor sees the same steam path the sensors' twin values come from. The rotor state is
carried from sample to sample; the step's length is the time since the previous accepted
sample (a sample with a missing input gets no twin value and does not step the rotor; the next
one steps over the gap, as the FOM does). The first accepted sample puts the metal in
equilibrium with its steam (:meth:`RotorModel.initial_state`).

The rotor's carried state is part of the live twin's saved state (:meth:`LiveRotor.get_state`,
exact through JSON), so a restart continues it exactly. A parameter swap changes the rotor's
htc from the next sample on; the rotor state is not recomputed from the estimate's start as the
FOM's metal is (its htc multiplier enters the rotor only through the steam side, and the
rotor's time constant, ~30 min, is far shorter than the days the estimate rests on).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from steamtwin.model.fom import FullOrderModel, SimulationResult
from steamtwin.model.parameters import ModelParameters
from steamtwin.rotor.model import RotorModel, RotorState
from steamtwin.rotor.steam_side import steam_side

__all__ = ["ROTOR_SIGNALS", "LiveRotor"]

ROTOR_SIGNALS: dict[str, str] = {
    "rotor_groove_temperature": "groove_temperature",
    "rotor_bore_temperature": "bore_temperature",
    "rotor_groove_stress": "groove_equivalent",
    "rotor_bore_stress": "bore_equivalent",
    "rotor_groove_von_mises": "groove_von_mises",
    "rotor_bore_von_mises": "bore_von_mises",
    "rotor_mean_temperature": "mean_temperature",
}
"""Twin signal stored in the historian → :class:`RotorModel` run-frame column (SI: K, Pa;
``*_stress`` is the signed equivalent stress the life module counts)."""


class LiveRotor:
    """``model``: a fitted :class:`RotorModel` of the unit's spec; its state is carried over the
    samples given to :meth:`advance`."""

    def __init__(self, model: RotorModel) -> None:
        self.model = model
        self._state: RotorState | None = None
        self._time: pd.Timestamp | None = None

    def advance(self, fom: FullOrderModel, inputs: pd.DataFrame, run: SimulationResult,
                params: ModelParameters) -> np.ndarray:
        """Step the rotor over the samples of ``inputs`` (the FOM's SI inputs, the samples the
        twin accepted) with ``run`` (the FOM's detailed stream run over them); returns
        (samples, :data:`ROTOR_SIGNALS`) values in SI.

        One step per sample; the samples go to :meth:`RotorModel.simulate_steam` in runs of
        equal spacing (its compiled kernel steps exactly as :meth:`RotorModel.step` does, and
        its states are bit-identical — tested in tests/rotor; stepping one sample at a time
        through :meth:`RotorModel.step` cost 2.4 times as much: docs/benchmarks.md)."""
        steam = steam_side(fom, inputs, params, groups=list(self.model.groups_), run=run)
        columns = list(ROTOR_SIGNALS.values())
        values = np.empty((len(steam), len(columns)))
        for first, stop in _equal_steps(steam.index, self._time):
            part = steam.iloc[first:stop]
            if self._state is None:
                result = self.model.simulate_steam(part)
                frame = result.frame
            else:  # a leading row at the state's time: its values are not used, only its time
                lead = part.iloc[:1].set_axis(pd.DatetimeIndex([self._time]))
                result = self.model.simulate_steam(pd.concat([lead, part]), self._state)
                frame = result.frame.iloc[1:]
            values[first:stop] = frame[columns].to_numpy(dtype=float)
            self._state, self._time = result.state, steam.index[stop - 1]
        return values

    def get_state(self) -> dict[str, object] | None:
        """The carried state (JSON-ready, exact), None before the first sample."""
        if self._state is None or self._time is None:
            return None
        return {"time": self._time.isoformat(), "state": self._state.to_dict()}

    def set_state(self, document: Mapping[str, object] | None) -> LiveRotor:
        """Restore :meth:`get_state`'s output (None: start afresh)."""
        if document is None:
            self._state, self._time = None, None
        else:
            self._state = RotorState.from_dict(document["state"])  # type: ignore[arg-type]
            self._time = pd.Timestamp(str(document["time"]))
        return self


def _equal_steps(index: pd.DatetimeIndex, last: pd.Timestamp | None
                 ) -> list[tuple[int, int]]:
    """[first, stop) row ranges of ``index`` whose steps — from ``last`` (the rotor state's
    time) for the first row — are equal (to 1e-6 relative, the rotor model's own check)."""
    seconds = (index - index[0]).total_seconds().to_numpy(dtype=float)
    before = [] if last is None else [(last - index[0]).total_seconds()]
    steps = np.diff(np.concatenate([before, seconds]))
    ranges, first = [], 0
    offset = len(before)  # steps[k] ends at row k + 1 - offset
    for k in range(1, steps.size):
        if abs(steps[k] - steps[k - 1]) > 1e-6 * steps[k - 1]:
            stop = k + 1 - offset
            ranges.append((first, stop))
            first = stop
    ranges.append((first, len(index)))
    return ranges
