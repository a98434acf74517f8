"""Errors of a POD–RBF ROM, split into projection and interpolation parts.

For a reference field x (the FOM's) at condition c, with modes Φ (rows orthonormal) and mean x̄:

* projection error   e_P = x − (x̄ + Φᵀ·Φ·(x − x̄))   — what the kept modes cannot represent;
* interpolation error e_I = Φᵀ·(a_RBF(c) − Φ·(x − x̄)) — what the RBF map gets wrong in the modes;
* total error         e = x − x̂(c) = e_P − e_I, and since e_P ⊥ the modes, ‖e‖₂² = ‖e_P‖₂² +
  ‖e_I‖₂²; in the max norm max|e| ≤ max|e_P| + max|e_I|.

Each is reported as the maximum absolute nodal error (K) and as a **relative error**: the max
absolute error divided by the temperature range of the field, max(x) − min(x) over all nodes of
all training snapshots (``PodRbfRom.field_range_``, the span the ROM must cover). The same error
over the reference field's own range (max − min of x at that condition) is reported too
(``relative_to_own_range``).

Leave-one-out: for each snapshot, a ROM with the same hyper-parameters is fitted to the others and
tested on the one left out (its conditions may then lie outside the others' hull — corner points
of the design — which the report flags).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from steamtwin.rom.estimator import ExtrapolationWarning, PodRbfRom


@dataclass(frozen=True)
class ErrorReport:
    """Per reference field (rows): max abs errors (K) and relative errors (see module doc)."""

    table: pd.DataFrame

    def summary(self) -> dict[str, float]:
        """Maximum over the fields of each column, plus the mean of the total relative error."""
        numeric = self.table.select_dtypes("number")
        out = {f"max_{name}": float(numeric[name].max()) for name in numeric.columns}
        out["mean_relative_total"] = float(self.table["relative_total"].mean())
        return out


def rom_errors(rom: PodRbfRom, fields: np.ndarray, conditions: np.ndarray) -> ErrorReport:
    """Projection, interpolation and total errors of ``rom`` on reference ``fields`` (n, N) K."""
    x = np.atleast_2d(np.asarray(fields, dtype=float))
    c = np.atleast_2d(np.asarray(conditions, dtype=float))
    if x.shape[0] != c.shape[0] or x.shape[1] != rom.mean_.size:
        raise ValueError(f"fields must have shape ({c.shape[0]}, {rom.mean_.size}), "
                         f"got {x.shape}")
    projected = rom.project(x)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        interpolated = rom.predict_coefficients(c)
    projection = x - rom.reconstruct(projected)
    interpolation = (interpolated - projected) @ rom.modes_
    total = x - rom.reconstruct(interpolated)
    own_range = x.max(axis=1) - x.min(axis=1)
    table = pd.DataFrame({
        "projection": np.abs(projection).max(axis=1),
        "interpolation": np.abs(interpolation).max(axis=1),
        "total": np.abs(total).max(axis=1),
        "rms_total": np.sqrt(np.mean(total**2, axis=1)),
    })
    for name in ("projection", "interpolation", "total"):
        table[f"relative_{name}"] = table[name] / rom.field_range_
    table["relative_to_own_range"] = table["total"] / np.where(own_range > 0, own_range, np.nan)
    table["extrapolation_distance"] = rom.extrapolation_distance(c)
    return ErrorReport(table)


def leave_one_out(rom: PodRbfRom, snapshots: np.ndarray, conditions: np.ndarray,
                  input_names: tuple[str, ...] | None = None) -> ErrorReport:
    """Leave-one-out errors: refit ``rom``'s hyper-parameters without each snapshot in turn."""
    x = np.asarray(snapshots, dtype=float)
    c = np.asarray(conditions, dtype=float)
    names = input_names or getattr(rom, "input_names_", None) or tuple(
        f"input_{i}" for i in range(c.shape[1]))
    rows = []
    for i in range(x.shape[0]):
        keep = np.arange(x.shape[0]) != i
        model = PodRbfRom(**rom.get_params()).fit(x[keep], c[keep], input_names=names)
        report = rom_errors(model, x[i:i + 1], c[i:i + 1]).table
        rows.append(report.assign(snapshot=i))
    return ErrorReport(pd.concat(rows, ignore_index=True))
