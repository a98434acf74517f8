"""A residual monitor fitted on a healthy history, and its JSON file (``steamtwin monitor fit``,
the service configuration's ``monitor = "monitor.json"``).

:func:`fit_monitor` replays a cleaned history (canonical SI signals, e.g.
:func:`steamtwin.load_history`'s data) through the unit's model at the live parameters, as the
service would — the model run over the samples whose inputs are all good, the others without a
twin value — and fits a :class:`~steamtwin.live.residuals.ResidualMonitor` on the 60-s block
means of measured − twin, with the blocks' load when the history has it. Each sensor's
instrument floor for a block mean is the tag map's white noise averaged over the block's
samples and its resolution's quantisation error, which does not average out:
σ_floor² = σ_noise²/n + Δ²/12 (JCGM 100:2008, GUM, §F.2.2.1); a sensor whose tag map states
neither gets :data:`UNSTATED_FLOOR` (a numerical floor: its σ is then the healthy spread).

The file holds the sensors, their floors, the settings and the fitted state; the fit's history
(first and last sample) and parameters are recorded beside them for provenance.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

import pandas as pd

from steamtwin.dcs.history import load_history
from steamtwin.dcs.tagmap import TagMap
from steamtwin.errors import DataError
from steamtwin.live.residuals import MonitorSettings, ResidualMonitor, block_means
from steamtwin.live.unit_model import unit_model
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.textfile import read_utf8_text

__all__ = ["MONITOR_FORMAT", "UNSTATED_FLOOR", "MonitorFileError", "block_floor", "fit_monitor",
           "fit_monitor_files", "load_monitor", "save_monitor"]

MONITOR_FORMAT = "steamtwin-monitor/1"
#: Block-mean floor (SI) of a sensor whose tag map states neither noise nor resolution:
#: 0.01 K for a temperature, 100 Pa for a pressure — well below any real instrument's, so the
#: healthy spread decides.
UNSTATED_FLOOR = {"temperature": 0.01, "pressure": 100.0}
MIN_HEALTHY_BLOCKS = 30


class MonitorFileError(DataError):
    """A monitor file that cannot be read, or a history that cannot fit one."""


def block_floor(tag_map: TagMap, sensor: str, samples: float) -> float:
    """Instrument floor (SI) of a ``samples``-sample block mean of ``sensor`` (module
    docstring)."""
    spec = tag_map.signals.get(sensor)
    noise = None if spec is None else spec.noise_si
    resolution = None if spec is None else spec.resolution_si
    if noise is None and resolution is None:
        return UNSTATED_FLOOR["pressure" if sensor.endswith("pressure") else "temperature"]
    variance = (noise or 0.0) ** 2 / samples + (resolution or 0.0) ** 2 / 12.0
    return math.sqrt(variance)


def fit_monitor(model: FullOrderModel, params: ModelParameters, history: pd.DataFrame,
                tag_map: TagMap, sensors: Sequence[str] | None = None,
                settings: MonitorSettings | None = None, source: str = "history"
                ) -> ResidualMonitor:
    """A monitor fitted on ``history`` (healthy operation, canonical SI columns, tz-aware
    1-s index; ``load`` in W if present) at ``params``. ``sensors``: default every sensor the
    model computes and the history measures. Raises :class:`MonitorFileError` naming
    ``source`` when an input or sensor is missing or fewer than :data:`MIN_HEALTHY_BLOCKS`
    blocks have every sensor."""
    settings = settings if settings is not None else MonitorSettings()
    missing = [name for name in INPUT_SIGNALS if name not in history.columns]
    if missing:
        raise MonitorFileError(f"{source}: no column for the model input(s) {missing}")
    chosen = list(sensors) if sensors is not None else [
        s for s in model.output_signals if s in history.columns]
    absent = [s for s in chosen if s not in history.columns or s not in model.output_signals]
    if absent or not chosen:
        raise MonitorFileError(f"{source}: sensors {absent or chosen} are not both measured "
                               f"and computed by the model ({list(model.output_signals)})")
    complete = history[list(INPUT_SIGNALS)].notna().all(axis=1)
    twin = model.simulate(history.loc[complete, list(INPUT_SIGNALS)], params)
    residual = history[chosen] - twin[chosen].reindex(history.index)
    if "load" in history.columns:
        residual["load"] = history["load"] / model.spec.design.generator_power
    blocks = block_means(residual, settings.block_s)
    usable = blocks[chosen].notna().all(axis=1)
    if "load" in blocks.columns:
        usable &= blocks["load"].notna()
    if int(usable.sum()) < MIN_HEALTHY_BLOCKS:
        raise MonitorFileError(f"{source}: {int(usable.sum())} blocks of {settings.block_s:g} s "
                               f"have every sensor of {chosen}; at least "
                               f"{MIN_HEALTHY_BLOCKS} are needed")
    floors = {s: block_floor(tag_map, s, settings.block_s) for s in chosen}
    monitor = ResidualMonitor(chosen, floors, settings)
    load = blocks.loc[usable, "load"] if "load" in blocks.columns else None
    return monitor.fit(blocks.loc[usable, chosen], load=load)


def save_monitor(monitor: ResidualMonitor, path: str | Path,
                 provenance: dict[str, object] | None = None) -> Path:
    """Write ``monitor`` (fitted) as JSON; ``provenance``: what it was fitted on."""
    if not hasattr(monitor, "sigma_"):
        raise ValueError("fit the monitor before saving it")
    document = {"format": MONITOR_FORMAT, "sensors": list(monitor.sensors),
                "instrument_sigma": dict(monitor.instrument_sigma),
                "settings": _settings_to_json(monitor.settings),
                "state": monitor.get_state(), "provenance": provenance or {}}
    path = Path(path)
    path.write_text(json.dumps(document, indent=1, default=float) + "\n", encoding="utf-8")
    return path


def load_monitor(path: str | Path) -> ResidualMonitor:
    """The fitted monitor :func:`save_monitor` wrote; :class:`MonitorFileError` naming the
    file and the key otherwise."""
    path = Path(path)
    try:
        document = json.loads(read_utf8_text(path, "monitor file", "JSON", MonitorFileError))
    except json.JSONDecodeError as error:
        raise MonitorFileError(f"{path}: not JSON ({error})") from None
    if not isinstance(document, dict) or document.get("format") != MONITOR_FORMAT:
        raise MonitorFileError(f"{path}: format is not {MONITOR_FORMAT!r}")
    try:
        settings = MonitorSettings(**_settings_from_json(document["settings"]))
        monitor = ResidualMonitor(document["sensors"], document["instrument_sigma"], settings)
        return monitor.set_state(document["state"])
    except (KeyError, TypeError, ValueError) as error:
        raise MonitorFileError(f"{path}: {type(error).__name__}: {error}") from None


def _settings_to_json(settings: MonitorSettings) -> dict[str, object]:
    return {key: (list(value) if isinstance(value, tuple) else value)
            for key, value in asdict(settings).items()}


def _settings_from_json(document: dict[str, object]) -> dict[str, object]:
    defaults = asdict(MonitorSettings())
    return {key: (tuple(value) if isinstance(defaults.get(key), tuple) else value)
            for key, value in document.items()}


def fit_monitor_files(turbine: str | Path, tags: str | Path, data: Sequence[str | Path],
                      out: str | Path, params: str | Path | None = None,
                      settings: MonitorSettings | None = None
                      ) -> tuple[ResidualMonitor, Path]:
    """``steamtwin monitor fit``: the unit's model (``turbine``: "reference" or a spec TOML),
    read through the tag map's sensors and the params file's offsets, at its coefficients
    (default: the design values); the healthy historian export(s) ``data`` cleaned through
    ``tags`` (:func:`~steamtwin.dcs.history.load_history`); the fitted monitor written to
    ``out`` with its provenance. Returns the monitor and the path."""
    setup, model_params = unit_model(turbine, tags, params)
    history = load_history(list(data), setup.tag_map, required=INPUT_SIGNALS)
    source = ", ".join(str(p) for p in data)
    monitor = fit_monitor(setup.model, model_params, history.data, setup.tag_map,
                          settings=settings, source=source)
    index = history.data.index
    provenance = {"data": [str(p) for p in data], "turbine": str(turbine),
                  "params": None if params is None else str(params),
                  "parameters": asdict(model_params), "first": index[0].isoformat(),
                  "last": index[-1].isoformat(), "samples": len(index)}
    return monitor, save_monitor(monitor, out, provenance)
