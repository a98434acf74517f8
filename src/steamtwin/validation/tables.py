"""The validation report's tables: operating conditions (Table 5), deviations (Table 8), ROM.

Inputs are canonical SI frames (K, Pa, kg/s, W) on a time index; the tables are in the wire
units of :data:`steamtwin.dcs.signals.SIGNALS` (°C, MPa, t/h, MW), the unit in each column name.

**Table 8 metrics** (per compared signal — steam-path temperatures and measured pressures —
and window; d_i = monitored_i − measured_i over the n used samples, i.e. those where both values
are finite and the ROM did not flag its input invalid). ``unit`` is the unit of the deviations:
K for temperatures, MPa for pressures; ``measured_unit`` that of ``mean_measured`` (°C, MPa):

* ``mean_deviation`` = Σ d_i / n (bias); ``mean_abs_deviation`` = Σ |d_i| / n;
  ``max_abs_deviation`` = max |d_i|; ``rmse`` = sqrt(Σ d_i² / n); ``mean_measured`` = mean of
  the used measured values;
* in % of the measured value: ``mean_deviation_pct`` = 100 · mean_deviation / mean_measured,
  ``relative_error_pct`` = 100 · mean_abs_deviation / mean_measured, ``rmse_pct`` = 100 · rmse /
  mean_measured, ``max_relative_error_pct`` = 100 · max_i |d_i| / measured_i. Temperatures are
  taken **in °C** there (the °C scale, as the validation literature quotes it; on the K scale
  the same deviation is a smaller percentage by the factor T[°C] / T[K]); pressures are
  absolute (MPa).

Samples not used are counted, never dropped silently: ``n_skipped_rom_invalid`` (the ROM
flagged its input missing/invalid, ``rom_invalid_input``), ``n_skipped_missing`` (otherwise
measured or monitored not finite, e.g. a dropout or a rejected spike); ``n_used +
n_skipped_missing + n_skipped_rom_invalid = n_samples``. ``n_extrapolated`` counts used samples
the ROM flagged as outside its snapshots' range.

**Per-sample series** (:func:`series_frame`): for one window, per compared signal the measured
value, the twin's and the residual (twin − measured) at every sample, in the same units
(``<signal>_measured_degC``, ``<signal>_twin_degC``, ``<signal>_residual_K``; pressures in
MPa), ``<signal>_used`` (the sample counts in Table 8) and the ROM's flags.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from steamtwin.dcs.quality import QualityReport
from steamtwin.dcs.signals import SIGNALS
from steamtwin.rom.reconstruction import FLAG_EXTRAPOLATED, FLAG_INVALID
from steamtwin.rom.romfile import FORMAT_VERSION, BladeRom
from steamtwin.units import convert
from steamtwin.validation.html import NotesSection, Section, TableSection

__all__ = ["DEVIATION_UNITS", "OPERATING_SIGNALS", "deviation_table", "operating_table",
           "quality_section", "rom_provenance_table", "series_frame", "unit_label"]

OPERATING_SIGNALS = (
    "load",
    "main_steam_pressure",
    "main_steam_temperature",
    "main_steam_flow",
    "control_stage_pressure",
    "hp_exhaust_pressure",
    "hp_exhaust_temperature",
    "hp_inner_casing_temperature",
)
"""Signals of Table 5, in this order (those absent from every window are left out)."""


def unit_label(unit: str) -> str:
    """A wire unit as used in column names: ``"t/h"`` → ``"t_per_h"`` (a pint unit name too)."""
    return unit.replace("/", "_per_")


def operating_table(windows: Mapping[str, pd.DataFrame],
                    signals: Sequence[str] = OPERATING_SIGNALS) -> pd.DataFrame:
    """Table 5: per window (rows, index ``window``) the main operating parameters.

    Columns: ``start`` and ``end`` (first and last sample time), ``samples`` (rows), then for
    each signal present in at least one window ``<signal>_<unit>_mean``, ``_min`` and ``_max``
    over its finite samples, in the signal's wire unit (e.g. ``main_steam_pressure_MPa_mean``,
    ``main_steam_flow_t_per_h_max``); NaN where a window lacks the signal.
    """
    unknown = [name for name in signals if name not in SIGNALS]
    if unknown:
        raise ValueError(f"not canonical signals: {unknown}")
    if not windows:
        raise ValueError("no windows given")
    present = [name for name in signals if any(name in w.columns for w in windows.values())]
    rows = []
    for window_name, frame in windows.items():
        if frame.empty:
            raise ValueError(f"window {window_name!r} holds no sample")
        row: dict[str, object] = {"window": window_name, "start": frame.index[0],
                                  "end": frame.index[-1], "samples": len(frame)}
        for name in present:
            signal = SIGNALS[name]
            prefix = f"{name}_{unit_label(signal.wire_unit)}"
            values = np.full(len(frame), np.nan)
            if name in frame.columns:
                values = convert(frame[name].to_numpy(dtype=float), signal.si_unit,
                                 signal.wire_unit)
            finite = values[np.isfinite(values)]
            empty = finite.size == 0
            row[f"{prefix}_mean"] = np.nan if empty else float(finite.mean())
            row[f"{prefix}_min"] = np.nan if empty else float(finite.min())
            row[f"{prefix}_max"] = np.nan if empty else float(finite.max())
        rows.append(row)
    return pd.DataFrame(rows).set_index("window")


DEVIATION_UNITS = {"K": ("K", "degC"), "Pa": ("MPa", "MPa")}
"""SI unit of a compared signal → (unit of its deviations, unit of its measured values)."""

_METRICS = ("mean_deviation", "mean_abs_deviation", "max_abs_deviation", "rmse",
            "mean_measured", "mean_deviation_pct", "relative_error_pct", "rmse_pct",
            "max_relative_error_pct")


def _units(name: str) -> tuple[str, str, str]:
    """(SI unit, deviation unit, measured unit) of a compared signal; ValueError otherwise."""
    signal = SIGNALS.get(name)
    if signal is None or signal.si_unit not in DEVIATION_UNITS:
        raise ValueError(f"{name!r} is not a canonical temperature (K) or pressure (Pa) signal")
    return (signal.si_unit, *DEVIATION_UNITS[signal.si_unit])


def deviation_table(pairs: Mapping[str, tuple[pd.DataFrame, pd.DataFrame]],
                    signals: Sequence[str]) -> pd.DataFrame:
    """Table 8: deviation of monitored from measured values per signal and window.

    ``pairs`` maps a window name to (measured, monitored): canonical SI frames on the same
    index, the monitored one as from :func:`steamtwin.rom.reconstruction.predict_series` (its
    ``rom_invalid_input`` / ``rom_extrapolated`` flags are used when present). ``signals`` are
    temperature (K) or pressure (Pa) signals present in both frames. One row per (signal,
    window), signals outer; metrics and counts as defined in the module docstring (K or MPa,
    %, counts).
    """
    for name in signals:
        _units(name)
    rows = []
    for name in signals:
        for window_name, (measured, monitored) in pairs.items():
            rows.append(_deviation_row(name, window_name, measured, monitored))
    columns = ["signal", "window", "unit", "n_samples", "n_used", "n_skipped_missing",
               "n_skipped_rom_invalid", "n_extrapolated", *_METRICS[:5], "measured_unit",
               *_METRICS[5:]]
    return pd.DataFrame(rows, columns=columns)


def _compared(name: str, window_name: str, measured: pd.DataFrame, monitored: pd.DataFrame
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Measured and monitored values in the table's units, the used mask and the invalid flag."""
    for label, frame in (("measured", measured), ("monitored", monitored)):
        if name not in frame.columns:
            raise ValueError(f"window {window_name!r}: the {label} data lack {name!r}")
    if not measured.index.equals(monitored.index):
        raise ValueError(f"window {window_name!r}: measured and monitored data are not on the "
                         "same time index")
    si_unit, _, measured_unit = _units(name)
    truth = convert(measured[name].to_numpy(dtype=float), si_unit, measured_unit)
    model = convert(monitored[name].to_numpy(dtype=float), si_unit, measured_unit)
    invalid = _flag(monitored, FLAG_INVALID, truth.size)
    used = np.isfinite(truth) & np.isfinite(model) & ~invalid
    return np.asarray(truth, dtype=float), np.asarray(model, dtype=float), used, invalid


def _deviation_row(name: str, window_name: str, measured: pd.DataFrame,
                   monitored: pd.DataFrame) -> dict[str, object]:
    truth, model, used, invalid = _compared(name, window_name, measured, monitored)
    _, unit, measured_unit = _units(name)
    n = truth.size
    finite = np.isfinite(truth) & np.isfinite(model)
    deviation = model[used] - truth[used]  # a K difference equals a °C difference
    row: dict[str, object] = {
        "signal": name, "window": window_name, "unit": unit, "n_samples": n,
        "n_used": int(used.sum()), "n_skipped_missing": int((~finite & ~invalid).sum()),
        "n_skipped_rom_invalid": int(invalid.sum()),
        "n_extrapolated": int((_flag(monitored, FLAG_EXTRAPOLATED, n) & used).sum()),
        "measured_unit": measured_unit,
    }
    if deviation.size == 0:
        return row | dict.fromkeys(_METRICS, np.nan)
    absolute = np.abs(deviation)
    mean_measured = float(truth[used].mean())
    rmse = float(np.sqrt(np.mean(deviation**2)))
    return row | {
        "mean_deviation": float(deviation.mean()),
        "mean_abs_deviation": float(absolute.mean()),
        "max_abs_deviation": float(absolute.max()),
        "rmse": rmse,
        "mean_measured": mean_measured,
        "mean_deviation_pct": 100.0 * float(deviation.mean()) / mean_measured,
        "relative_error_pct": 100.0 * float(absolute.mean()) / mean_measured,
        "rmse_pct": 100.0 * rmse / mean_measured,
        "max_relative_error_pct": 100.0 * float(np.max(absolute / truth[used])),
    }


def series_frame(measured: pd.DataFrame, monitored: pd.DataFrame, signals: Sequence[str],
                 window_name: str = "") -> pd.DataFrame:
    """Per-sample measured, twin and residual values of ``signals`` over one window.

    Frames as for :func:`deviation_table`; columns as in the module docstring, on the
    window's time index (its time zone kept). ``attrs["units"]`` maps each value column to
    its unit.
    """
    columns: dict[str, object] = {}
    units: dict[str, str] = {}
    for name in signals:
        truth, model, used, _ = _compared(name, window_name, measured, monitored)
        _, unit, measured_unit = _units(name)
        for suffix, values, label in (("measured", truth, measured_unit),
                                      ("twin", model, measured_unit),
                                      ("residual", model - truth, unit)):
            column = f"{name}_{suffix}_{label}"
            columns[column] = values
            units[column] = label
        columns[f"{name}_used"] = used
    n = len(measured)
    columns[FLAG_INVALID] = _flag(monitored, FLAG_INVALID, n)
    columns[FLAG_EXTRAPOLATED] = _flag(monitored, FLAG_EXTRAPOLATED, n)
    frame = pd.DataFrame(columns, index=measured.index)
    frame.index.name = "time"
    frame.attrs["units"] = units
    return frame


def _flag(frame: pd.DataFrame, column: str, n: int) -> np.ndarray:
    if column not in frame.columns:
        return np.zeros(n, dtype=bool)
    return frame[column].fillna(False).to_numpy(dtype=bool)


def rom_provenance_table(bundle: BladeRom) -> pd.DataFrame:
    """What the ROM is and how it was built: one row per item (``item``, ``value``).

    The fitted model's own figures (format version, snapshots, modes, energy, kernel, inputs,
    sensors, mesh, field range) followed by the file's provenance, nested keys joined by dots
    (e.g. ``model_parameters.flow_coefficient``).
    """
    rom = bundle.rom
    items: dict[str, object] = {
        "format_version": FORMAT_VERSION,
        "snapshots": int(rom.centres_.shape[0]),
        "modes": int(rom.n_modes_),
        "energy_threshold": float(rom.energy),
        "energy_captured": float(rom.energy_captured_),
        "kernel": rom.kernel,
        "input_scaling": rom.input_scaling,
        "inputs": ", ".join(rom.input_names_),
        "sensors": ", ".join(rom.sensor_names_),
        "blade_probes": ", ".join(bundle.probes),
        "mesh_nodes": int(bundle.mesh.points.shape[0]),
        "mesh_tetrahedra": int(bundle.mesh.tetrahedra.shape[0]),
        "field_range_K": float(rom.field_range_),
    }
    items |= {f"provenance.{key}": value for key, value in _flatten(bundle.provenance).items()}
    return pd.DataFrame({"item": list(items), "value": [_scalar(v) for v in items.values()]})


def _flatten(document: Mapping[str, object], prefix: str = "") -> dict[str, object]:
    flat: dict[str, object] = {}
    for key, value in document.items():
        if isinstance(value, Mapping):
            flat |= _flatten(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _scalar(value: object) -> object:
    """Lists as comma-separated text, everything else as it is."""
    if isinstance(value, list | tuple):
        return ", ".join(str(v) for v in value)
    return value


def quality_section(quality: QualityReport, caption: str, name: str = "data_quality"
                    ) -> Section:
    """The DCS cleaning's findings (what was rejected, where, how many) as a report table, or a
    note saying there were none."""
    if not quality.findings:
        return NotesSection(caption, ("no findings",))
    columns = ("severity", "action", "kind", "signal", "tag", "count", "first_row", "message")
    frame = pd.DataFrame([f.to_dict() for f in quality.findings], columns=list(columns))
    return TableSection(name, frame, f"{caption}: {len(quality.errors)} error(s), "
                        f"{len(quality.warnings)} warning(s)")
