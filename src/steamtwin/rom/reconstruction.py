"""Online use of a ROM: one field, a whole DCS series, VTU files for ParaView.

A series costs one RBF evaluation per sample (all samples at once) plus, for the blade probes,
r multiply-adds per probe; full fields (N values each) are reconstructed only for the samples
asked for. Samples whose inputs are missing or not finite, or outside the physical domain, are
flagged ``rom_invalid_input`` and predicted as NaN — a ROM is a fit, and a fit evaluated far from
its data returns numbers that only look like results (a wet "main steam", or a pressure ten times
the snapshots', once gave −101 MW and 1862 MW). Outside the domain means: main steam not
superheated (at or below the IF97 region-2 boundary, saturation or B23 line, at its pressure),
control-stage pressure not below main-steam pressure, or farther than ``max_extrapolation``
outside the snapshots (:meth:`PodRbfRom.extrapolation_distance`, in units of each input's
snapshot span). Those samples are also flagged ``rom_out_of_domain``; samples outside the
snapshots' range but within the limit are predicted, flagged ``rom_extrapolated`` with their
distance, and one :class:`ExtrapolationWarning` sums them up.

The ROM is quasi-steady: its steam-path sensors are the steam's (or metal's) steady values.
:func:`read_through` gives what the DCS reads of them — each thermocouple's first-order lag
(:func:`steamtwin.model.measurement.lag`, the discretisation the full-order model's readings
use) and the offset a joint calibration estimated for it — from the same
:class:`~steamtwin.model.sensor_setup.SensorSetup` that calibrate and validate use (issue 18,
item 3). A run of invalid samples interrupts a reading: the sensor restarts steady after it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from steamtwin.blade.mesh import SolidMesh
from steamtwin.model.measurement import check_time_constants, lag
from steamtwin.model.sensor_setup import SensorSetup
from steamtwin.progress import ProgressCallback
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.romfile import BladeRom
from steamtwin.steam.tables import lower_boundary_temperature

IF97_PRESSURE_RANGE = (611.657, 100.0e6)
"""Pa; IAPWS-IF97's triple-point pressure and upper limit (IAPWS R7-97(2012), §4–5)."""

FLAG_INVALID = "rom_invalid_input"
FLAG_OUT_OF_DOMAIN = "rom_out_of_domain"
FLAG_EXTRAPOLATED = "rom_extrapolated"
DISTANCE = "rom_extrapolation_distance"
MAX_EXTRAPOLATION = 1.0
"""Default limit of :func:`predict_series`: a sample may lie at most one whole snapshot span
(of each input, Euclidean over the inputs) outside the snapshots; farther, the fit has no data
nearer than the width of everything it was fitted on."""


@dataclass(frozen=True)
class SeriesPrediction:
    """Per-sample predictions (SI) and flags, plus fields (K) at the requested samples.

    ``sensors`` columns: the ROM's steam-path sensors, the blade probes, ``rom_invalid_input``,
    ``rom_out_of_domain``, ``rom_extrapolated`` and ``rom_extrapolation_distance``.
    ``fields`` maps sample positions to nodal temperature arrays.
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
                   progress: ProgressCallback | None = None,
                   max_extrapolation: float = MAX_EXTRAPOLATION) -> SeriesPrediction:
    """Sensor and probe predictions for every row of ``signals`` (canonical names, SI).

    ``fields_every`` = n also reconstructs the full field at every n-th valid sample.
    ``max_extrapolation``: the farthest a sample may lie outside the snapshots and still be
    predicted, in units of each input's snapshot span (see the module docstring).
    """
    rom = bundle.rom
    missing = [name for name in rom.input_names_ if name not in signals.columns]
    if missing:
        raise ValueError(f"the data lack the ROM input signal(s) {missing} (SI units)")
    if fields_every is not None and fields_every < 1:
        raise ValueError(f"fields_every must be ≥ 1, got {fields_every}")
    if not max_extrapolation >= 0.0:
        raise ValueError(f"max_extrapolation must be ≥ 0 (snapshot spans), got "
                         f"{max_extrapolation!r}")
    inputs = signals[list(rom.input_names_)].apply(pd.to_numeric, errors="coerce").to_numpy(
        dtype=float)
    finite = np.all(np.isfinite(inputs), axis=1)
    n = len(signals)
    distance = np.full(n, np.nan)
    if np.any(finite):
        distance[finite] = rom.extrapolation_distance(inputs[finite])
    out_of_domain = finite & (~_physical(rom.input_names_, inputs)
                              | (distance > max_extrapolation))
    valid = finite & ~out_of_domain
    reduced = np.full((n, rom.n_modes_ + len(rom.sensor_names_)), np.nan)
    if np.any(valid):
        reduced[valid] = rom.predict_reduced(inputs[valid], warn=False)
    coefficients = reduced[:, : rom.n_modes_]
    names = list(bundle.probes)
    nodes = np.array([bundle.probes[name] for name in names], dtype=np.int64)
    probes = rom.mean_[nodes] + coefficients @ rom.modes_[:, nodes]
    table = pd.DataFrame(reduced[:, rom.n_modes_:], index=signals.index,
                         columns=list(rom.sensor_names_))
    for j, name in enumerate(names):
        table[name] = probes[:, j]
    table[FLAG_INVALID] = ~valid
    table[FLAG_OUT_OF_DOMAIN] = out_of_domain
    table[FLAG_EXTRAPOLATED] = valid & (distance > 0.0)
    table[DISTANCE] = distance
    outside = int(table[FLAG_EXTRAPOLATED].sum())
    if outside:
        worst = int(np.nanargmax(np.where(table[FLAG_EXTRAPOLATED], distance, np.nan)))
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
                progress((k + 1) / chosen.size, f"field {k + 1}/{chosen.size}")
    return SeriesPrediction(table, fields)


def read_through(sensors: pd.DataFrame, setup: SensorSetup) -> pd.DataFrame:
    """``sensors`` (a :attr:`SeriesPrediction.sensors` table, SI, on a time index) as the DCS
    reads them: each column in ``setup.time_constants`` (τ in s) lagged over every run of
    finite values, from a steady start at the run's first sample, then ``setup.offsets`` (K)
    added. Columns not named in ``setup`` (pressures, power, blade probes, flags) are left as
    they are. ValueError for a time constant or offset of a signal the table does not hold,
    or for a table whose index is not increasing time."""
    names = tuple(str(name) for name in sensors.columns)
    lags = check_time_constants(
        {name: tau for name, tau in setup.time_constants.items() if name in names}, names)
    unknown = sorted(set(setup.offsets) - set(names))
    if unknown:
        raise ValueError(f"sensor offsets for {unknown}, which the ROM does not predict (it "
                         f"predicts {list(names)})")
    if not lags and not setup.offsets:
        return sensors.copy()
    if not isinstance(sensors.index, pd.DatetimeIndex) or not (
            sensors.index.is_monotonic_increasing and sensors.index.is_unique):
        raise ValueError("the sensors' index must be increasing, unique timestamps to lag "
                         "the readings")
    seconds = (sensors.index - sensors.index[0]).total_seconds().to_numpy(dtype=float)
    steps = np.diff(seconds, prepend=seconds[:1])
    read = sensors.copy()
    for name, tau in lags.items():
        values = sensors[name].to_numpy(dtype=float)
        reading = np.full_like(values, np.nan)
        for start, stop in _finite_runs(values):
            reading[start:stop] = lag(values[start:stop], steps[start:stop], tau)
        read[name] = reading
    for name, offset in setup.offsets.items():
        read[name] = read[name] + float(offset)
    return read


def _finite_runs(values: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of consecutive finite values."""
    finite = np.concatenate(([False], np.isfinite(values), [False]))
    edges = np.flatnonzero(np.diff(finite.astype(np.int8)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def _physical(names: tuple[str, ...], inputs: np.ndarray) -> np.ndarray:
    """Rows whose inputs a steam turbine can see: superheated main steam, p_cs < p0 (finite
    rows only; other rows are True and judged elsewhere)."""
    ok = np.ones(inputs.shape[0], dtype=bool)
    column = {name: j for j, name in enumerate(names)}
    finite = np.all(np.isfinite(inputs), axis=1)
    if "main_steam_pressure" in column:
        p0 = inputs[:, column["main_steam_pressure"]]
        low, high = IF97_PRESSURE_RANGE
        in_tables = finite & (p0 >= low) & (p0 <= high)
        ok[finite & ~in_tables] = False
        if "main_steam_temperature" in column and in_tables.any():
            t0 = inputs[in_tables, column["main_steam_temperature"]]
            ok[in_tables] &= t0 > lower_boundary_temperature(p0[in_tables])
        if "control_stage_pressure" in column:
            p1 = inputs[:, column["control_stage_pressure"]]
            ok[finite] &= (p1[finite] > 0.0) & (p1[finite] < p0[finite])
    return ok


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
