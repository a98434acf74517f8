"""The ``Simulator`` protocol: what calibration, the ROM and monitoring need from a model.

Any object with these attributes and this ``simulate`` method can stand in for the built-in
full-order model — for example a wrapper that writes the inputs to files, runs an external CFD
or 1-D code and reads its results back (see docs/architecture.md, "Plugging in a solver").
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import pandas as pd

from steamtwin.model.parameters import ModelParameters

INPUT_SIGNALS = (
    "main_steam_pressure",
    "main_steam_temperature",
    "main_steam_flow",
    "hp_exhaust_pressure",
)
"""Boundary conditions the built-in model takes, canonical names, SI units (Pa, K, kg/s)."""


@runtime_checkable
class Simulator(Protocol):
    """A model mapping a time series of DCS boundary conditions to sensor predictions.

    ``simulate(inputs, params)`` takes a DataFrame indexed by time (a DatetimeIndex, or seconds)
    with the columns ``input_signals`` in SI units and returns a DataFrame on the same index with
    the columns ``output_signals`` in SI units (Pa, K, W). It must raise ``ValueError`` naming the
    column and row for inputs it cannot handle, never return NaN silently.

    Optional fast path for calibration (see ``calibration.objective.predict_window``):
    ``check_inputs(inputs)`` checks a series once and ``simulate_checked(checked, params,
    signals)`` returns the ``signals`` as an array (samples, signals; SI).
    """

    input_signals: tuple[str, ...]
    output_signals: tuple[str, ...]

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters) -> pd.DataFrame:
        """Simulate the series; SI units in and out."""
        ...
