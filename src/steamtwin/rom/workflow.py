"""The ROM's two steps from files, as ``steamtwin rom build`` and ``rom predict`` run them.

:func:`build_rom_from_files` reads a turbine spec, a parameter file, a blade mesh (or meshes
the spec's control-stage rotor, row hp1) and optionally a historian export the snapshots must
cover, then calls :func:`~steamtwin.rom.build.build_rom`. :func:`predict_history` loads a ROM
file, checks that a given spec and parameter file are the ROM's own
(:mod:`steamtwin.rom.provenance`), reads a historian export through its quality gate
(:func:`~steamtwin.dcs.history.load_history`) and predicts every sample
(:func:`~steamtwin.rom.reconstruction.predict_series`), optionally as the DCS reads the
temperature sensors (:func:`~steamtwin.rom.reconstruction.read_through`). Values SI; the
wire table of :meth:`HistoryPrediction.in_wire_units` in °C, MPa and MW.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.dcs.history import load_history
from steamtwin.geometry.meshing import blade_volume_mesh
from steamtwin.geometry.volume_mesh import read_volume_mesh
from steamtwin.model.parameters import ModelParameters, sensor_offsets_from_json
from steamtwin.model.sensor_setup import sensor_setup
from steamtwin.progress import ProgressCallback
from steamtwin.rom.build import build_rom
from steamtwin.rom.envelope import parse_parameter_interval
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.provenance import check_parameters, resolve_spec
from steamtwin.rom.reconstruction import (
    DISTANCE,
    FLAG_EXTRAPOLATED,
    FLAG_INVALID,
    FLAG_OUT_OF_DOMAIN,
    MAX_EXTRAPOLATION,
    predict_series,
    read_through,
    write_vtu,
)
from steamtwin.rom.romfile import BladeRom, load_rom
from steamtwin.rom.snapshots import ROM_INPUTS
from steamtwin.spec import load_spec
from steamtwin.spec.fingerprint import load_spec_and_text

__all__ = ["HistoryPrediction", "build_rom_from_files", "predict_history", "wire_unit"]

_KELVIN = 273.15
_FLAGS = (FLAG_INVALID, FLAG_OUT_OF_DOMAIN, FLAG_EXTRAPOLATED, DISTANCE)
_WIRE: dict[str, tuple[str, Callable[[Any], Any]]] = {
    "K": ("degC", lambda v: v - _KELVIN), "Pa": ("MPa", lambda v: v / 1e6),
    "W": ("MW", lambda v: v / 1e6)}


def wire_unit(name: str) -> tuple[str, Callable[[Any], Any]]:
    """The wire unit of a ROM input or output ``name`` (``degC``, ``MPa`` or ``MW``) and the
    conversion from its SI value (K, Pa, W), told by the name: ``…pressure`` is a pressure,
    ``…power`` and ``load`` a power, anything else a temperature."""
    if name.endswith("pressure"):
        return _WIRE["Pa"]
    if name.endswith("power") or name == "load":
        return _WIRE["W"]
    return _WIRE["K"]


def build_rom_from_files(turbine: str | Path = "reference", *,
                         params_file: str | Path | None = None,
                         mesh_file: str | Path | None = None,
                         element_size: float | None = None,
                         history_file: str | Path | None = None,
                         tag_map_file: str | Path | None = None,
                         accept_quality_errors: bool = False,
                         parameter_intervals: Sequence[str] = (),
                         progress: ProgressCallback | None = None,
                         **build_options: Any) -> BladeRom:
    """A ROM built from files: ``turbine`` ('reference' or a spec TOML), ``params_file``
    (parameter JSON; default: empirical), ``mesh_file`` (.msh/.vtu; default: the spec's hp1
    blade meshed at ``element_size``, m), ``history_file`` with ``tag_map_file`` (a historian
    export whose main-steam p, T and control-stage pressure the snapshots must cover; it
    passes the quality gate unless ``accept_quality_errors``), ``parameter_intervals``
    (``"NAME=LOW:HIGH"`` texts, SI). ``build_options`` go to
    :func:`~steamtwin.rom.build.build_rom` (``n_snapshots``, ``energy``, ``random_state``, …).
    Raises ``ValueError`` when only one of ``history_file`` and ``tag_map_file`` is given.
    """
    if (history_file is None) != (tag_map_file is None):
        raise ValueError("history_file and tag_map_file go together")
    spec, spec_toml = load_spec_and_text(turbine)
    parameters = ModelParameters.from_json(params_file) if params_file else ModelParameters()
    intervals = dict(parse_parameter_interval(text) for text in parameter_intervals)
    observed = None
    if history_file is not None and tag_map_file is not None:
        observed = load_history(history_file, tag_map_file, required=list(ROM_INPUTS),
                                accept_errors=accept_quality_errors).data
    if progress is not None:
        progress(0.0, "meshing the control-stage blade")
    volume = (read_volume_mesh(mesh_file) if mesh_file is not None
              else blade_volume_mesh(spec, "hp1", element_size=element_size))
    bundle, _ = build_rom(spec, volume, parameters, progress=progress,
                          spec_toml=spec_toml, params_file=params_file,
                          parameter_intervals=intervals or None, observed=observed,
                          **build_options)
    return bundle


@dataclass(frozen=True)
class HistoryPrediction:
    """What :func:`predict_history` found.

    ``bundle``: the ROM file's content; ``table``: per sample, the sensors (as read, or the
    ROM's steady values) and probes (SI) with the flags of
    :class:`~steamtwin.rom.reconstruction.SeriesPrediction`; ``fields``: sample position →
    nodal temperature (K); ``excluded``: samples the quality gate excluded per signal (only
    those with some); ``warnings``: the extrapolation warnings; ``sensors_as_read``: one line
    per sensor model applied (empty for steady values).
    """

    bundle: BladeRom
    table: pd.DataFrame
    fields: dict[int, np.ndarray]
    excluded: dict[str, int]
    warnings: list[str]
    sensors_as_read: list[str]

    def in_wire_units(self) -> pd.DataFrame:
        """:attr:`table` with each value column in its wire unit (``"<name> [degC]"``, MPa,
        MW; :func:`wire_unit`), the flags as they are, the index named ``time``."""
        wire = pd.DataFrame(index=self.table.index)
        for name in self.table.columns:
            if name in _FLAGS:
                wire[name] = self.table[name]
                continue
            unit, convert = wire_unit(name)
            wire[f"{name} [{unit}]"] = convert(self.table[name])
        wire.index.name = "time"
        return wire

    def write_fields(self, folder: str | Path) -> list[Path]:
        """Write each field as ``field_<row>_<YYYYmmddTHHMMSS>.vtu`` (ParaView) into
        ``folder``; returns the paths."""
        paths = []
        for row, field in self.fields.items():
            stamp = pd.Timestamp(self.table.index[row]).strftime("%Y%m%dT%H%M%S")
            paths.append(write_vtu(self.bundle.mesh, {"temperature_K": field},
                                   Path(folder) / f"field_{row:06d}_{stamp}.vtu"))
        return paths


def predict_history(rom_file: str | Path, history_file: str | Path,
                    tag_map_file: str | Path, *, turbine: str | Path | None = None,
                    params_file: str | Path | None = None, fields_every: int | None = None,
                    max_extrapolation: float = MAX_EXTRAPOLATION,
                    accept_quality_errors: bool = False,
                    readings: bool = True) -> HistoryPrediction:
    """Predict steam-path sensors and blade temperatures for every sample of a historian export.

    ``turbine`` and ``params_file``, when given, must be the ROM's own (else
    :class:`~steamtwin.rom.provenance.ProvenanceError`). The export passes the quality gate
    (``DataQualityError`` on error-level findings unless ``accept_quality_errors``).
    ``fields_every`` = n also reconstructs the field at every n-th valid sample;
    ``max_extrapolation`` as in :func:`~steamtwin.rom.reconstruction.predict_series`.
    ``readings``: the temperature sensors as the DCS reads them (each thermocouple's lag from
    the tag map, else typical, and the sensor offsets a joint calibration wrote into
    ``params_file``); False: the ROM's steady values.
    """
    bundle = load_rom(rom_file)
    spec = resolve_spec(bundle, None if turbine is None else load_spec(turbine),
                        f"--turbine {turbine}", rom_file)
    offsets: dict[str, float] = {}
    if params_file is not None:
        check_parameters(bundle, ModelParameters.from_json(params_file),
                         f"--params {params_file}", rom_file)
        offsets = sensor_offsets_from_json(params_file)
    history = load_history(history_file, tag_map_file,
                           required=[str(n) for n in bundle.rom.input_names_],
                           accept_errors=accept_quality_errors)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        result = predict_series(bundle, history.data, fields_every=fields_every,
                                max_extrapolation=max_extrapolation)
    setup = dataclasses.replace(sensor_setup(spec, history.historian.tag_map), offsets=offsets)
    table = read_through(result.sensors, setup) if readings else result.sensors
    return HistoryPrediction(
        bundle=bundle, table=table, fields=result.fields,
        excluded={name: n for name, n in history.excluded.items() if n},
        warnings=[str(warning.message) for warning in caught],
        sensors_as_read=setup.describe() if readings else [])
