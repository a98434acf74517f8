"""Online use of a ROM: one field, a whole DCS series, VTU files for ParaView.

A series costs one RBF evaluation per sample (all samples at once) plus, for the blade probes,
r multiply-adds per probe; full fields (N values each) are reconstructed only for the samples
asked for. Samples whose inputs are missing or not finite are flagged and predicted as NaN;
samples outside the snapshots' range are flagged with their distance (see
:meth:`PodRbfRom.extrapolation_distance`) and one :class:`ExtrapolationWarning` sums them up.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from steamtwin.blade.mesh import SolidMesh
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.romfile import BladeRom

FLAG_INVALID = "rom_invalid_input"
FLAG_EXTRAPOLATED = "rom_extrapolated"
DISTANCE = "rom_extrapolation_distance"


@dataclass(frozen=True)
class SeriesPrediction:
    """Per-sample predictions (SI) and flags, plus fields (K) at the requested samples.

    ``sensors`` columns: the ROM's steam-path sensors, the blade probes, ``rom_invalid_input``,
    ``rom_extrapolated`` and ``rom_extrapolation_distance``. ``fields`` maps sample positions
    to nodal temperature arrays.
    """

    sensors: pd.DataFrame
    fields: dict[int, np.ndarray]


def predict_field(bundle: BladeRom, condition: dict[str, float] | np.ndarray) -> np.ndarray:
    """The nodal temperature field (N,) K at one condition (SI, the ROM's inputs)."""
    rom = bundle.rom
    if isinstance(condition, dict):
        missing = [name for name in rom.input_names_ if name not in condition]
        if missing:
            raise ValueError(f"condition lacks input(s) {missing}")
        condition = np.array([condition[name] for name in rom.input_names_], dtype=float)
    return rom.predict(np.asarray(condition, dtype=float))


def predict_series(bundle: BladeRom, signals: pd.DataFrame, fields_every: int | None = None,
                   progress: Callable[[float], None] | None = None) -> SeriesPrediction:
    """Sensor and probe predictions for every row of ``signals`` (canonical names, SI).

    ``fields_every`` = n also reconstructs the full field at every n-th valid sample.
    """
    rom = bundle.rom
    missing = [name for name in rom.input_names_ if name not in signals.columns]
    if missing:
        raise ValueError(f"the data lack the ROM input signal(s) {missing} (SI units)")
    if fields_every is not None and fields_every < 1:
        raise ValueError(f"fields_every must be ≥ 1, got {fields_every}")
    inputs = signals[list(rom.input_names_)].apply(pd.to_numeric, errors="coerce").to_numpy(
        dtype=float)
    valid = np.all(np.isfinite(inputs), axis=1)
    n = len(signals)
    reduced = np.full((n, rom.n_modes_ + len(rom.sensor_names_)), np.nan)
    distance = np.full(n, np.nan)
    if np.any(valid):
        reduced[valid] = rom.predict_reduced(inputs[valid], warn=False)
        distance[valid] = rom.extrapolation_distance(inputs[valid])
    coefficients = reduced[:, : rom.n_modes_]
    names = list(bundle.probes)
    nodes = np.array([bundle.probes[name] for name in names], dtype=np.int64)
    probes = rom.mean_[nodes] + coefficients @ rom.modes_[:, nodes]
    table = pd.DataFrame(reduced[:, rom.n_modes_:], index=signals.index,
                         columns=list(rom.sensor_names_))
    for j, name in enumerate(names):
        table[name] = probes[:, j]
    table[FLAG_INVALID] = ~valid
    table[FLAG_EXTRAPOLATED] = valid & (distance > 0.0)
    table[DISTANCE] = distance
    outside = int(table[FLAG_EXTRAPOLATED].sum())
    if outside:
        worst = int(np.nanargmax(distance))
        warnings.warn(f"{outside} of {n} samples lie outside the snapshots' range (farthest "
                      f"{distance[worst]:.3f} scaled units, at {signals.index[worst]}); their "
                      "predictions are extrapolated and flagged", ExtrapolationWarning,
                      stacklevel=2)
    fields: dict[int, np.ndarray] = {}
    if fields_every is not None:
        chosen = np.flatnonzero(valid)[::fields_every]
        for k, row in enumerate(chosen):
            fields[int(row)] = rom.reconstruct(coefficients[row])[0]
            if progress is not None:
                progress((k + 1) / chosen.size)
    return SeriesPrediction(table, fields)


def write_vtu(mesh: SolidMesh, fields: dict[str, np.ndarray], path: str | Path) -> Path:
    """Write nodal fields (K) on the tetrahedral mesh to a ``.vtu`` file for ParaView."""
    n = mesh.points.shape[0]
    data = {}
    for name, values in fields.items():
        array = np.asarray(values, dtype=float)
        if array.shape != (n,):
            raise ValueError(f"field {name!r} has shape {array.shape}, expected ({n},)")
        data[name] = array
    path = Path(path)
    meshio.write(path, meshio.Mesh(mesh.points, [("tetra", mesh.tetrahedra)], point_data=data))
    return path
