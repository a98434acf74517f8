"""Where a streamed full-order-model run stands after its last sample (issue 21, item 1).

The live twin advances the model block by block as the samples arrive. Everything a later
block needs to continue exactly as one run over both would is here: the time of the last
sample, the kernel's carried arrays (stage pressures and enthalpies, metal temperatures,
valve-outlet states, the control stage's last outputs, leakage flows, the last sweep's p·v,
the last sample's inputs) and, per lagged sensor, its last reading and last instantaneous
value. :meth:`StreamState.to_dict` / :meth:`StreamState.from_dict` write and read it as JSON
(floats round-trip exactly: Python writes the shortest repr that reads back to the same
double), so the live historian can store it and a restart continue from it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["KERNEL_ARRAYS", "StreamState"]

KERNEL_ARRAYS = ("pressures", "enthalpies", "metal", "throttled", "cs_out", "leak_flow",
                 "inlet_pv", "previous")
"""The kernel's carried arrays, in :func:`steamtwin.model.kernel.run_kernel`'s terms."""


@dataclass(frozen=True)
class StreamState:
    """``time``: the last sample (UTC); ``arrays``: :data:`KERNEL_ARRAYS` (SI); ``sensors``:
    lagged sensor → (last reading, last instantaneous value), K."""

    time: pd.Timestamp
    arrays: Mapping[str, np.ndarray]
    sensors: Mapping[str, tuple[float, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        missing = [name for name in KERNEL_ARRAYS if name not in self.arrays]
        if missing:
            raise ValueError(f"stream state lacks {missing}")
        if pd.Timestamp(self.time).tzinfo is None:
            raise ValueError("stream state time must be time-zone aware")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (exact)."""
        return {"time": pd.Timestamp(self.time).tz_convert("UTC").isoformat(),
                "arrays": {name: {"shape": list(np.shape(self.arrays[name])),
                                  "values": np.ravel(self.arrays[name]).tolist()}
                           for name in KERNEL_ARRAYS},
                "sensors": {name: [float(a), float(b)] for name, (a, b) in self.sensors.items()}}

    @classmethod
    def from_dict(cls, document: Mapping[str, Any]) -> StreamState:
        """The state :meth:`to_dict` wrote (ValueError for a malformed document)."""
        try:
            arrays = {name: np.array(entry["values"], dtype=float).reshape(entry["shape"])
                      for name, entry in document["arrays"].items()}
            sensors = {name: (float(pair[0]), float(pair[1]))
                       for name, pair in document.get("sensors", {}).items()}
            return cls(pd.Timestamp(document["time"]), arrays, sensors)
        except (KeyError, TypeError, ValueError) as error:
            raise ValueError(f"not a stream state: {error}") from None

    def copy(self) -> StreamState:
        """A deep copy (the arrays are the kernel's working arrays while it runs)."""
        return StreamState(self.time, {k: np.array(v, copy=True) for k, v in self.arrays.items()},
                           dict(self.sensors))
