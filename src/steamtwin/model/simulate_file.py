"""The full-order model over a CSV of boundary conditions, as ``steamtwin simulate`` runs it.

The inputs file is a canonical CSV (:mod:`steamtwin.dcs.canonical_csv`: ``time`` and the
model's inputs in MPa, °C, t/h); the result is the model's outputs in SI (Pa, K, W) on the same
index. An input the model refuses is reported in the file's terms (:func:`in_file_terms`): the
file, the column, the data row (1-based, the header not counted) with its line in the file
(data row + 1), and values and limits in the file's units.
"""

from __future__ import annotations

import math
from datetime import tzinfo
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.dcs.canonical_csv import CsvFormatError, read_canonical_csv
from steamtwin.dcs.signals import SIGNALS
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.progress import ProgressCallback
from steamtwin.spec import load_spec
from steamtwin.units import convert

__all__ = ["in_file_terms", "simulate_csv"]

_DISPLAY_UNITS = {"degC": "°C"}


def simulate_csv(inputs: str | Path, *, turbine: str | Path = "reference",
                 params_file: str | Path | None = None, time_zone: tzinfo | None = None,
                 progress: ProgressCallback | None = None) -> pd.DataFrame:
    """The model of ``turbine`` ('reference' or a spec TOML) with the parameters of
    ``params_file`` (JSON; default: empirical) over the boundary conditions of ``inputs``.

    ``time_zone``: the zone of timestamps written without a UTC offset (None: such timestamps
    are refused). Returns the model's outputs (SI) on the inputs' time index. Raises the spec's
    and the parameter file's errors, and :class:`~steamtwin.dcs.canonical_csv.CsvFormatError`
    naming the file, column and row for a malformed file or an input the model refuses; every
    input is checked before the model is prepared (the first run compiles it, ~20 s).
    """
    spec = load_spec(turbine)
    parameters = ModelParameters.from_json(params_file) if params_file else ModelParameters()
    frame = read_canonical_csv(inputs, required=INPUT_SIGNALS, time_zone=time_zone)
    model = FullOrderModel(spec)
    try:
        checked = model.check_inputs(frame)  # before the model is prepared: bad rows fail fast
        if progress is not None:
            progress(0.0, "preparing the model (the first run compiles it, ~20 s)")
        _ = model.design_
        if progress is not None:
            progress(0.5, f"simulating {len(frame)} samples")
        outputs = pd.DataFrame(model.simulate_checked(checked, parameters), index=frame.index,
                               columns=list(model.output_signals))
    except InputError as error:
        raise CsvFormatError(in_file_terms(error, Path(inputs))) from error
    if progress is not None:
        progress(1.0, "done")
    return outputs


def in_file_terms(error: InputError, path: Path) -> str:
    """The model's input error re-worded for the CSV it came from: the file, the column, the
    data row (1-based) with its line (data row + 1) and, for a range error, the value and the
    limits in the file's units (MPa, °C, t/h)."""
    if error.row is None:
        return f"{path}: {error}"
    where = f"column {error.column!r} " if error.column else ""
    where += f"data row {error.row + 1} (line {error.row + 2})"
    signal = SIGNALS.get(error.column or "")
    if error.limits is None or error.value is None or signal is None:
        return f"{path}: {where}: {error.reason}"
    value, low, high = convert(np.array([error.value, *error.limits]), signal.si_unit,
                               signal.wire_unit)
    unit = _DISPLAY_UNITS.get(signal.wire_unit, signal.wire_unit)
    shown = "an empty cell" if math.isnan(value) else f"{value:g} {unit}"
    rows = "1 bad row" if error.count == 1 else f"{error.count} bad rows"
    return (f"{path}: {where}: {shown} is not a number within [{low:g}, {high:g}] {unit} "
            f"({rows})")
