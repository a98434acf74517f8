"""The twin's sensitivity J to its parameters, per load band, for the degradation hypotheses.

The residual monitor tells a parameter change from a sensor fault by the pattern Δp·J[:, p] it
leaves across the sensors (:mod:`~steamtwin.live.residuals`). J moves with the operating point
(the control-stage pressure's sensitivity to the flow coefficient scales with the flow, Stodola's
cone law) but little within a few per cent of load, so :class:`SensitivityCache` computes it by
central differences (:func:`~steamtwin.live.residuals.model_sensitivity`) over the first block
seen in each load band and reuses it there until the live parameters change. The cache is part
of the service's saved state, so a restarted service uses the same J as an uninterrupted one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from steamtwin.live.residuals import model_sensitivity
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS, Simulator

__all__ = ["SensitivityCache"]


class SensitivityCache:
    """J (sensors × ``parameters``) per load band of width ``band`` (load fraction), computed
    with ``simulator`` over a block's inputs (SI, canonical names) at the live parameters."""

    def __init__(self, simulator: Simulator, sensors: Sequence[str],
                 parameters: Sequence[str] = ("flow_coefficient",), band: float = 0.05) -> None:
        if not (math.isfinite(band) and 0.0 < band <= 1.0):
            raise ValueError(f"band must be a load fraction in (0, 1] (got {band!r})")
        self.simulator = simulator
        self.sensors = tuple(sensors)
        self.parameters = tuple(parameters)
        self.band = float(band)
        self._bands: dict[int, pd.DataFrame] = {}

    def get(self, load: float, inputs: pd.DataFrame, params: ModelParameters
            ) -> pd.DataFrame | None:
        """J at load fraction ``load``; computed over ``inputs`` (the block's model inputs, gaps
        carried from the nearest sample) the first time the band is seen. None when the load
        is unknown or the block has no complete input row."""
        if load is None or not math.isfinite(load):
            return None
        key = round(load / self.band)
        if key not in self._bands:
            window = inputs[list(INPUT_SIGNALS)].ffill().bfill()
            if window.empty or not np.isfinite(window.to_numpy(dtype=float)).all():
                return None
            self._bands[key] = model_sensitivity(self.simulator, window, params, self.sensors,
                                                 self.parameters)
        return self._bands[key]

    def clear(self) -> None:
        """Forget every band (the live parameters changed)."""
        self._bands.clear()

    def get_state(self) -> dict[str, object]:
        """JSON-ready J per band."""
        return {str(key): {column: [float(x) for x in frame[column]] for column in frame}
                for key, frame in self._bands.items()}

    def set_state(self, state: Mapping[str, Mapping[str, Sequence[float]]]) -> SensitivityCache:
        """Restore :meth:`get_state`'s output exactly."""
        self._bands = {int(key): pd.DataFrame({c: list(v) for c, v in columns.items()},
                                              index=list(self.sensors))
                       for key, columns in state.items()}
        return self
