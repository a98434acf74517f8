"""The recent past of a streamed model, kept so a parameter swap can recompute its state.

A live recalibration estimates the parameters from the last step's data (10 min by default);
the model's carried state at the swap — metal temperatures, thermocouple lags — grew under the
old parameters over those same minutes. :class:`RewindBuffer` keeps checkpoints of the state
(one per minute of data at most) and the model inputs since the oldest one, over a horizon of
two recalibration steps, so :meth:`RewindBuffer.replay` can run the model again from the
checkpoint at the start of the estimate's data with the new parameters: the state then is the
one the new parameters would have produced, as an offline recalibration over the same data
would have it. The buffer is part of the service's saved state.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from steamtwin.jsonframe import frame_from_json, frame_to_json
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.stream_state import StreamState

__all__ = ["CHECKPOINT_EVERY_S", "RewindBuffer"]

#: Seconds of data between two kept checkpoints of the model state.
CHECKPOINT_EVERY_S = 60.0


class RewindBuffer:
    """Checkpoints of a streamed model's state and the inputs since (module docstring)."""

    def __init__(self) -> None:
        self._checkpoints: list[tuple[int, StreamState | None]] = []
        self._inputs = pd.DataFrame()

    def keep(self, state: StreamState | None, inputs: pd.DataFrame, horizon_s: float) -> None:
        """Record the state a block of complete ``inputs`` (SI, tz-aware index) starts from,
        then the inputs; forget what lies more than ``horizon_s`` seconds behind them."""
        if inputs.empty:
            return
        first = int(inputs.index[:1].as_unit("ns").asi8[0])
        checkpoint = first - 1 if state is None else _ns(state.time)
        step = round(CHECKPOINT_EVERY_S * 1e9)
        if not self._checkpoints or checkpoint - self._checkpoints[-1][0] >= step:
            self._checkpoints.append((checkpoint, state))
        self._inputs = inputs.copy() if self._inputs.empty else pd.concat([self._inputs, inputs])
        cutoff = int(inputs.index[-1:].as_unit("ns").asi8[0]) - round(horizon_s * 1e9)
        while len(self._checkpoints) > 1 and self._checkpoints[1][0] <= cutoff:
            self._checkpoints.pop(0)
        oldest = self._checkpoints[0][0]
        self._inputs = self._inputs[self._inputs.index.as_unit("ns").asi8 > oldest]

    def replay(self, model: FullOrderModel, params: ModelParameters, since: pd.Timestamp
               ) -> StreamState | None:
        """The state after every kept input, run again with ``params`` from the newest
        checkpoint at or before ``since`` (the oldest if none is); None if nothing is kept."""
        if not self._checkpoints or self._inputs.empty:
            return None
        limit = _ns(since)
        start, state = self._checkpoints[0]
        for time, kept in self._checkpoints:
            if time <= limit:
                start, state = time, kept
        inputs = self._inputs[self._inputs.index.as_unit("ns").asi8 > start]
        if inputs.empty:
            return None
        _, replayed = model.simulate_stream(inputs, params, state)
        return replayed

    def get_state(self) -> dict[str, object]:
        """JSON-ready checkpoints and inputs."""
        return {"checkpoints": [[time, None if state is None else state.to_dict()]
                                for time, state in self._checkpoints],
                "inputs": frame_to_json(self._inputs)}

    def set_state(self, state: Mapping[str, object]) -> RewindBuffer:
        """Restore :meth:`get_state`'s output exactly."""
        self._checkpoints = [(int(time), None if kept is None else StreamState.from_dict(kept))
                             for time, kept in state.get("checkpoints", [])]
        self._inputs = frame_from_json(state.get("inputs", {}))
        return self


def _ns(time: object) -> int:
    stamp = pd.Timestamp(time)
    if stamp.tzinfo is None:
        stamp = stamp.tz_localize("UTC")
    return int(stamp.tz_convert("UTC").as_unit("ns").value)
