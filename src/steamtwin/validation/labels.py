"""Readable names, units and rounding of the report's columns — in one place.

The tables keep machine-friendly column names (``rmse_calibrated_K``,
``main_steam_pressure_MPa_mean``: the CSV and JSON files carry them); the HTML shows each as
"Readable name [unit]" (:func:`column_label`): first from :data:`COLUMN_LABELS`, else by rule —
a canonical signal's name becomes its readable name (:data:`SIGNAL_NAMES`, units from the data
contract :data:`steamtwin.dcs.signals.SIGNALS`), a trailing unit token (``_K``, ``_degC``,
``_MPa``, ``_t_per_h``, ``_pct``, …, see :data:`UNIT_TOKENS`) becomes the bracketed unit, a
trailing ``_mean``/``_min``/``_max`` a statistic, and the remaining words are spelled out
(:data:`WORDS`). No underscore survives.

**Rounding rule** (:func:`round_digits`): a figure is shown with 3 significant figures (4 from
1000 up, so that whole numbers up to 9999 stay whole; none beyond 4), never finer than its
unit's resolution (:data:`RESOLUTION`: about a tenth of the instrument class the quantity is
measured with — thermocouples ±1.5 K, IEC 60584-1 class 1, shown to 0.1 °C; pressure
transmitters ±0.1 % of a 16-MPa span ≈ 16 kPa, IEC 60770-1, shown to 0.001 MPa; deviations to
0.01 K, the resolution of the twin's comparison; run times to 0.1 s).
"""

from __future__ import annotations

import math
import re

from steamtwin.dcs.signals import SIGNALS

__all__ = ["COLUMN_LABELS", "GA_SETTINGS", "LABEL_COLUMNS", "RESOLUTION", "ROW_UNIT_COLUMNS",
           "SIGNAL_NAMES", "UNIT_TOKENS", "WORDS", "column_label", "header_text", "round_digits",
           "unit_text", "value_label"]

SIGNAL_NAMES: dict[str, str] = {
    "main_steam_pressure": "Main-steam pressure",
    "main_steam_temperature": "Main-steam temperature",
    "main_steam_flow": "Main-steam flow",
    "control_stage_pressure": "Control-stage pressure",
    "control_stage_temperature": "Control-stage temperature",
    "hp_exhaust_pressure": "HP-exhaust pressure",
    "hp_exhaust_temperature": "HP-exhaust temperature",
    "hp_inner_casing_temperature": "Inner-casing metal temperature",
    "load": "Load",
    "hp_power": "HP power",
}
"""Readable name of every canonical signal (the order of the data contract)."""

PARAMETER_NAMES: dict[str, str] = {
    "flow_coefficient": "Flow coefficient",
    "friction_coefficient": "Friction coefficient",
    "heat_transfer_coefficient": "Heat-transfer coefficient",
}
"""Readable names of the calibrated parameters (multipliers, no unit)."""

UNIT_TOKENS: dict[str, str] = {
    "t_per_h": "t/h", "kg_per_s": "kg/s", "degC": "°C", "MPa": "MPa", "kPa": "kPa", "Pa": "Pa",
    "pct": "%", "mm": "mm", "cm3": "cm³", "MW": "MW", "W": "W", "K": "K", "s": "s", "min": "min",
    "h": "h", "deg": "°",
}
"""Unit tokens that end a column name (before an optional statistic) → the unit shown."""

RESOLUTION: dict[str, float] = {
    "°C": 0.1, "K": 0.01, "MPa": 0.001, "kPa": 1.0, "t/h": 1.0, "kg/s": 0.1, "MW": 0.1,
    "%": 0.01, "mm": 0.001, "cm³": 0.001, "s": 0.1, "min": 0.1, "h": 0.01, "°": 0.1,
}
"""The finest step a figure in this unit is shown with (see the module's rounding rule)."""

WORDS: dict[str, str] = {
    "hp": "HP", "ip": "IP", "rmse": "RMSE", "rom": "ROM", "fom": "FOM", "rms": "RMS",
    "abs": "abs.", "n": "N", "std": "σ", "p95": "95th percentile", "pct": "%",
    "conf": "95 % interval", "ga": "GA", "dcs": "DCS", "stl": "STL",
}
"""Words spelled out (or upper-cased) when a column name is turned into a label by rule."""

_STATISTICS = {"mean": "mean", "min": "min", "max": "max"}
_PREFIXES = {"empirical": ("{name} RMSE, empirical constants", "K"),
             "calibrated": ("{name} RMSE, calibrated", "K"),
             "delivered": ("{name} RMSE, calibrated, sensor offsets applied", "K"),
             "corr": ("Correlation with {lower}", "")}
"""``<prefix>:<name>`` columns (Table 6's per-sensor RMSEs, the identifiability correlations)."""

LABEL_COLUMNS = frozenset({"item", "setting", "metric", "statistic"})
"""Columns whose text cells are names, spelled out as column names are (:func:`header_text`)."""

GA_SETTINGS: dict[str, str] = {
    "population": "Population", "generations": "Generations",
    "crossover_probability": "Crossover probability",
    "mutation_probability": "Mutation probability",
}
"""Readable names of the GA's settings (Table 7)."""

COLUMN_LABELS: dict[str, tuple[str, str]] = {
    # Table 5 and the time columns
    "window": ("Window", ""), "start": ("Start", ""), "end": ("End", ""),
    "samples": ("Samples", ""), "time": ("Time", ""),
    # Table 8 (the deviation unit is the row's: K or MPa)
    "signal": ("Signal", ""), "unit": ("Unit", ""),
    "n_samples": ("Samples", ""), "n_used": ("Used", ""),
    "n_skipped_missing": ("Skipped: missing", ""),
    "n_skipped_rom_invalid": ("Skipped: ROM input invalid", ""),
    "n_extrapolated": ("Extrapolated", ""),
    "mean_deviation": ("Mean d (bias)", ""), "mean_abs_deviation": ("Mean |d|", ""),
    "max_abs_deviation": ("Max |d|", ""), "rmse": ("RMSE", ""),
    "mean_measured": ("Mean measured", ""), "measured_unit": ("Unit of measured", ""),
    "mean_deviation_pct": ("Mean d", "%"), "relative_error_pct": ("Mean |d| / measured", "%"),
    "rmse_pct": ("RMSE / measured", "%"),
    "max_relative_error_pct": ("Max relative error", "%"),
    # Table 6, calibrated parameters, Table 7
    "condition": ("Condition", ""), "rmse_empirical_K": ("RMSE, empirical constants", "K"),
    "rmse_calibrated_K": ("RMSE, calibrated", "K"), "reduction_pct": ("Reduction", "%"),
    "instrument_error_K": ("Instrument error", "K"),
    "calibrated_over_instrument": ("Calibrated RMSE / instrument error", ""),
    "rmse_delivered_K": ("RMSE, calibrated, sensor offsets applied", "K"),
    "delivered_over_instrument": ("RMSE with the offsets / instrument error", ""),
    "parameter": ("Parameter", ""), "calibrated": ("Calibrated", ""),
    "low_95": ("95 % interval, low", ""), "high_95": ("95 % interval, high", ""),
    "prior_low_95": ("Prior 95 %, low", ""), "prior_high_95": ("Prior 95 %, high", ""),
    "identifiable": ("Identifiable", ""), "detectable_rise": ("Detectable rise", ""),
    "std_error": ("Standard error", ""),
    "setting": ("GA setting", ""), "value": ("Value", ""), "rmse_K": ("RMSE", "K"),
    "evaluations": ("Model runs", ""),
    # Sobol' indices and noise propagation
    "output": ("Output", ""), "statistic": ("Statistic", ""),
    "S1": ("First-order index S1", ""), "S1_conf": ("S1, 95 % interval ±", ""),
    "ST": ("Total index ST", ""), "ST_conf": ("ST, 95 % interval ±", ""),
    "std": ("Output σ", ""),
    "sigma_K": ("Noise σ", "K"), "rms_deviation": ("RMS deviation", ""),
    "gain": ("Gain (RMS deviation / σ)", ""),
    # geometry
    "step": ("Step", ""), "result": ("Result", ""), "section": ("Section", ""),
    "mean_mm": ("Mean deviation", "mm"), "rms_mm": ("RMS deviation", "mm"),
    "p95_mm": ("95th percentile", "mm"), "max_mm": ("Max deviation", "mm"),
    "hausdorff_mm": ("Hausdorff distance", "mm"), "row": ("Row", ""),
    "bound_mm": ("Scan error bound ±", "mm"),
    "throat_area_ratio_min": ("Throat area ratio, min", ""),
    "throat_area_ratio_max": ("Throat area ratio, max", ""),
    "throat_area_ratio_std": ("Throat area ratio, σ", ""),
    "hp_exhaust_temperature_spread_K": ("HP-exhaust spread (max − min)", "K"),
    "hp_exhaust_temperature_max_deviation_K": ("Largest HP-exhaust deviation", "K"),
    "hp_exhaust_temperature_std_K": ("HP-exhaust σ", "K"),
    "nominal_hp_exhaust_temperature_degC": ("Nominal HP-exhaust temperature", "°C"),
    # Figure 9 errors, model checks, the live twin, provenance, data quality
    "max_abs_error_K": ("Max |ROM − FOM|", "K"), "mean_abs_error_K": ("Mean |ROM − FOM|", "K"),
    "quantity": ("Quantity", ""), "spec": ("Spec", ""), "model": ("Model", ""),
    "difference": ("Model − spec", ""), "load_fraction": ("Load fraction", ""),
    "control_stage_efficiency": ("Control-stage efficiency", ""),
    "active_admission_arc": ("Active admission arc", ""),
    "item": ("Item", ""), "severity": ("Severity", ""), "action": ("Action", ""),
    "kind": ("Kind", ""), "tag": ("Tag", ""), "count": ("Count", ""),
    "first_row": ("First row", ""), "message": ("Message", ""),
}
"""Column name → (readable name, unit; "" when the column has none or its unit is per row)."""

ROW_UNIT_COLUMNS: dict[str, str] = {
    "mean_deviation": "unit", "mean_abs_deviation": "unit", "max_abs_deviation": "unit",
    "rmse": "unit", "mean_measured": "measured_unit",
}
"""Columns whose unit is given per row, by another column (Table 8: K or MPa) → that column;
their figures are rounded for the row's unit."""


def column_label(name: object) -> tuple[str, str]:
    """(readable name, unit) of a report column; by :data:`COLUMN_LABELS`, else by rule."""
    text = str(name)
    if text in COLUMN_LABELS:
        return COLUMN_LABELS[text]
    if ":" in text:  # "<prefix>:<name>", e.g. Table 6's per-sensor RMSEs "calibrated:<sensor>"
        head, _, tail = text.partition(":")
        tail_label = column_label(tail)[0]
        if head in _PREFIXES:
            label, unit = _PREFIXES[head]
            lower = (tail_label if tail_label[1:2].isupper()  # an acronym such as "HP" stays
                     else tail_label[:1].lower() + tail_label[1:])
            return label.format(name=tail_label, lower=lower), unit
        return f"{tail_label}, {_words(head)}", ""
    statistic = ""
    stem, _, last = text.rpartition("_")
    if stem and last in _STATISTICS:
        text, statistic = stem, _STATISTICS[last]
    unit = ""
    for token, shown in UNIT_TOKENS.items():
        if text.endswith(f"_{token}"):
            text, unit = text[: -len(token) - 1], shown
            break
    if not unit and text in SIGNALS:  # a bare signal: its wire unit (data contract)
        unit = UNIT_TOKENS.get(SIGNALS[text].wire_unit.replace("/", "_per_"), "")
    label = _words(text)
    return (f"{label}, {statistic}" if statistic else label), unit


def header_text(name: object) -> str:
    """"Readable name [unit]" (or the name alone) of a report column."""
    label, unit = column_label(name)
    return f"{label} [{unit}]" if unit else label


def value_label(value: str) -> str:
    """A canonical signal or parameter name or a unit token (``degC``, ``t_per_h``) in a table
    cell as its readable name or unit; other text as it is."""
    return (SIGNAL_NAMES.get(value) or PARAMETER_NAMES.get(value) or GA_SETTINGS.get(value)
            or UNIT_TOKENS.get(value) or value)


def unit_text(unit: object) -> str:
    """A unit as the data give it (``"degC"``, ``"t/h"``, ``"K"``) as shown (``"°C"``)."""
    text = str(unit)
    return UNIT_TOKENS.get(text.replace("/", "_per_"), text)


def round_digits(value: float, unit: str = "") -> int:
    """Decimals to show ``value`` in ``unit`` with, by the module's rounding rule; negative
    for rounding left of the point (e.g. −1: to tens). ``value`` must be finite and non-zero.
    """
    exponent = math.floor(math.log10(abs(value)))
    rounded = round(value, 2 - exponent)
    if rounded and math.floor(math.log10(abs(rounded))) > exponent:  # 0.9996 → 1.00, not 1.000
        exponent += 1
    significant = 4 if exponent >= 3 else 3
    decimals = significant - 1 - exponent
    resolution = RESOLUTION.get(unit)
    if resolution is not None:
        decimals = min(decimals, -math.floor(math.log10(resolution)))
    return decimals


def _words(text: str) -> str:
    """Snake case spelled out: signal and parameter names whole, then word by word."""
    for name, label in (SIGNAL_NAMES | PARAMETER_NAMES).items():
        text = re.sub(rf"(^|_){name}(_|$)", lambda m, label=label: f"{m[1]}{label}{m[2]}",
                      text)
    words = [WORDS.get(word.lower(), word) for word in re.split(r"[_.]+", text) if word]
    if not words:
        return text
    label = " ".join(words)
    return label[0].upper() + label[1:] if label[0].isascii() else label
