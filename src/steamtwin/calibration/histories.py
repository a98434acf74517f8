"""From historian files to a joint calibration's windows and fitted sensors.

:func:`load_histories` reads several historian exports through the quality gate
(:func:`~steamtwin.dcs.history.load_history`), each with its tag map, naming the file in any
error; :func:`calibration_window_set` turns cleaned histories into the
:class:`~steamtwin.calibration.windowset.WindowSet` of a joint calibration — each file's σ per
sensor from its tag map (noise² + resolution²/12,
:func:`~steamtwin.calibration.windowset.measurement_sigma`), the control-stage pressure as the
flow coefficient's witness (Stodola's cone law) when every file maps it, and the windows given
or found (:func:`~steamtwin.calibration.windowset.joint_window_set`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from steamtwin.calibration.settings import DEFAULT_SENSORS
from steamtwin.calibration.tracking import TYPICAL_INSTRUMENT_ERROR
from steamtwin.calibration.windowset import (
    WindowSet,
    WindowSource,
    joint_window_set,
    measurement_sigma,
)
from steamtwin.dcs.history import DataQualityError, History, load_history
from steamtwin.dcs.readers import HistorianFormatError
from steamtwin.dcs.tagmap import TagMapError
from steamtwin.dcs.windows import parse_window
from steamtwin.model.simulator import INPUT_SIGNALS

__all__ = ["PRESSURE_WITNESS", "calibration_window_set", "load_histories"]

PRESSURE_WITNESS = "control_stage_pressure"
"""The pressure a calibration adds to the fitted temperatures when every file maps it."""


def load_histories(data: Sequence[str | Path], tags: Sequence[str | Path], *,
                   accept_errors: bool = False) -> list[History]:
    """Every ``data`` file through the quality gate with its tag map: one ``tags`` for all
    files or one per file in the same order; the model's inputs are required.

    Errors of a file (its tag map, format, columns) are a ``ValueError`` naming the file and
    its tag map; error-level quality findings raise
    :class:`~steamtwin.dcs.history.DataQualityError` unless ``accept_errors``.
    """
    if not data:
        raise ValueError("give at least one historian file")
    if len(tags) not in (1, len(data)):
        raise ValueError(f"give one --tags for all {len(data)} --data files or one per file "
                         f"in the same order (got {len(tags)})")
    result = []
    for k, path in enumerate(data):
        tag_path = tags[0] if len(tags) == 1 else tags[k]
        try:
            result.append(load_history(path, tag_path, required=INPUT_SIGNALS,
                                       accept_errors=accept_errors))
        except DataQualityError:
            raise
        except (TagMapError, HistorianFormatError, ValueError, KeyError) as error:
            raise ValueError(f"--data {path} (with --tags {tag_path}): {error}") from None
    return result


def calibration_window_set(histories: Sequence[History], rated_power_w: float, *,
                           windows: Sequence[str | tuple[pd.Timestamp, pd.Timestamp]] = (),
                           ramps: bool = True, min_steady_s: float = 3600.0,
                           max_steady_s: float = 7200.0, pressure_witness: bool | None = None
                           ) -> tuple[WindowSet, tuple[str, ...]]:
    """The joint window set of ``histories`` and the sensors to fit.

    ``windows``: spans (ISO 8601 START/END or timestamp pairs) taken from every history
    covering them; else the steady holds of ≥ ``min_steady_s`` (s; the last ``max_steady_s``)
    at every load and, with ``ramps``, the load ramps, load bands relative to
    ``rated_power_w`` (W). ``pressure_witness``: also fit :data:`PRESSURE_WITNESS` (σ from
    the tag map, else the typical transmitter's); None: when every history maps it; True with
    a history lacking it is a ``ValueError`` naming the file and its tag map.
    """
    sources = []
    for item in histories:
        signals = item.tag_map.signals.values()
        sigma = measurement_sigma({s.signal: s.noise_si for s in signals},
                                  {s.signal: s.resolution_si for s in signals})
        sources.append(WindowSource(item.historian.source, item.data, sigma or None))
    if pressure_witness is None:
        pressure_witness = all(PRESSURE_WITNESS in s.data.columns for s in sources)
    sensors: tuple[str, ...] = DEFAULT_SENSORS
    if pressure_witness:
        for item, source in zip(histories, sources, strict=True):
            if PRESSURE_WITNESS not in source.data.columns:
                raise ValueError(f"--pressure-witness: {source.name} has no "
                                 f"{PRESSURE_WITNESS} (map it in {item.tag_map.source})")
        typical = {PRESSURE_WITNESS: TYPICAL_INSTRUMENT_ERROR[PRESSURE_WITNESS]}
        sensors = (*DEFAULT_SENSORS, PRESSURE_WITNESS)
        sources = [dataclasses.replace(s, sigma={**typical, **(s.sigma or {})})
                   for s in sources]
    given = [parse_window(w) if isinstance(w, str) else w for w in windows]
    window_set = joint_window_set(sources, rated_power_w, given=given, ramps=ramps,
                                  min_steady_s=min_steady_s,
                                  max_steady_s=max(max_steady_s, min_steady_s))
    return window_set, sensors
