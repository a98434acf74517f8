"""The findings of the data-quality check as messages naming source, signal, tag, first row
and time, and the expected unit or range."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from steamtwin.dcs.quality.detectors import Analysis, Column, segments
from steamtwin.dcs.quality.limits import (
    CANDIDATE_UNITS,
    SPIKE_MAX_SAMPLES,
    STEAM_RATE,
    STUCK_CHANCE_RUNS_PER_DAY,
    TYPICAL_RANGES,
    Action,
    Severity,
)
from steamtwin.dcs.quality.options import QualityOptions
from steamtwin.dcs.quality.report import Finding, time_label, time_text
from steamtwin.dcs.signals import SIGNALS
from steamtwin.units import convert


def _unit_of(signal: str | None, options: QualityOptions) -> tuple[str, str]:
    """(display unit, SI unit) of a signal; display = declared, else wire unit, else none."""
    if signal in SIGNALS:
        si = SIGNALS[signal].si_unit
        return options.declared_units.get(signal, SIGNALS[signal].wire_unit), si
    return "", ""

def _show(value: float, signal: str | None, options: QualityOptions, *, delta: bool = False) -> str:
    """A SI value as text in the signal's display unit (e.g. ``16.7 MPa``).

    ``delta``: the value is a difference (a 0.5 K step is 0.5 °C, not −272.65 °C).
    """
    unit, si = _unit_of(signal, options)
    if not unit or not math.isfinite(value):
        return f"{value:.4g}"
    try:
        shown = float(convert(value, si, unit))
        if delta:
            shown -= float(convert(0.0, si, unit))
    except Exception:  # unknown declared unit: show SI
        return f"{value:.4g} {si}"
    return f"{shown:.4g} {unit}"

class Where:
    """Builds findings for one signal (or the index) with source, tag, row and time."""

    def __init__(self, a: Analysis, options: QualityOptions, signal: str | None) -> None:
        self.a, self.options, self.signal = a, options, signal
        self.tag = options.tag_names.get(signal) if signal is not None else None

    @property
    def label(self) -> str:
        """``signal (tag T)``, or ``time index``."""
        if self.signal is None:
            return "time index"
        return f"{self.signal} ({f'tag {self.tag}' if self.tag else 'no tag given'})"

    @property
    def name(self) -> str:
        """The label with the source in front."""
        return f"{self.options.source}: {self.label}" if self.options.source else self.label

    def make(self, kind: str, severity: Severity, count: int, row: int | None, time: Any,
             text: str, action: Action = "detected", *, counted: bool = True,
             **details: Any) -> Finding:
        at = "" if row is None else f"; first at data row {row + 1} ({time_text(time)})"
        message = f"{self.name}: {f'{count} ' if counted else ''}{text}{at}"
        return Finding(kind, severity, self.signal, self.tag, int(count), row, time, message,
                       action, tuple(details.items()))

    def first(self, mask: np.ndarray) -> tuple[int | None, Any]:
        """First (in time) masked kept row: its as-read position and time."""
        if not mask.any():
            return None, None
        i = int(np.argmax(mask))
        return int(self.a.rows[i]), time_label(self.a.labels[i], self.a.is_datetime)

    def finding(self, kind: str, severity: Severity, mask: np.ndarray, text: str,
                action: Action = "detected", **details: Any) -> Finding:
        return self.make(kind, severity, int(mask.sum()), *self.first(mask), text, action,
                         **details)

def detection_findings(a: Analysis, options: QualityOptions) -> list[Finding]:
    out: list[Finding] = []
    index = Where(a, options, None)
    for name in a.missing_required:
        where = Where(a, options, name)
        unit = (f"{SIGNALS[name].wire_unit} (SI {SIGNALS[name].si_unit})"
                if name in SIGNALS else "its unit")
        out.append(where.make(
            "missing_signal", "error", 1, None, None,
            f"required signal is missing from the data (expected a column in {unit})",
            counted=False,
        ))
    for name in a.non_numeric:
        out.append(Where(a, options, name).make(
            "not_numeric", "warning", a.n, None, None,
            "value(s) are not numeric; column not checked",
        ))
    if a.backwards:
        row = a.first_backwards
        out.append(index.make(
            "unsorted", "warning", a.backwards, row,
            time_label(a.raw_labels[row], a.is_datetime),
            "backwards time step(s) (timestamps not sorted)",
        ))
    if a.n_dup_identical:
        out.append(index.make(
            "duplicate", "warning", a.n_dup_identical, *a.first_dup_identical,
            "duplicate timestamp row(s) with identical values",
        ))
    if a.n_dup_conflict:
        out.append(index.make(
            "duplicate_conflict", "error", a.n_dup_conflict, *a.first_dup_conflict,
            "duplicate timestamp row(s) with conflicting values in "
            + ", ".join(Where(a, options, name).label for name in a.conflict_signals),
            signals=a.conflict_signals,
        ))
    if a.gaps.size:
        largest = int(np.argmax(a.gap_steps_s))
        i = int(a.gaps[largest])
        missing_s = float((a.gap_steps_s - a.step_s).sum())
        start = time_label(a.labels[i], a.is_datetime)
        mask = np.zeros(len(a.rows), dtype=bool)
        mask[a.gaps] = True
        out.append(index.finding(
            "gap", "warning", mask,
            f"gap(s) longer than {options.gap_factor:g} × the {a.step_s:g} s step, "
            f"{missing_s:g} s missing in total; largest {a.gap_steps_s[largest]:g} s from "
            f"{time_text(start)} (data row {int(a.rows[i]) + 1})",
            missing_s=missing_s, largest_gap_s=float(a.gap_steps_s[largest]),
            largest_gap_start=start, step_s=a.step_s,
        ))
    for name, col in a.columns.items():
        out.extend(_signal_findings(a, options, name, col))
    out.extend(unit_findings(a, options))
    return out

def _signal_findings(a: Analysis, options: QualityOptions, name: str, col: Column) -> list[Finding]:
    out: list[Finding] = []
    where = Where(a, options, name)
    n_valid = int((~col.nan).sum())
    if col.nan.any():
        starts, ends, _ = segments(np.r_[False, col.nan[1:] & col.nan[:-1]])
        lengths = np.where(col.nan[starts], ends - starts + 1, 0)
        longest = int(lengths.max())
        everything = n_valid == 0
        severity: Severity = "error" if everything and name in options.required else "warning"
        text = "NaN value(s)" + (" — the signal has no value at all" if everything else "")
        out.append(where.finding("nan", severity, col.nan, f"{text}; longest run {longest} "
                                 "sample(s)", longest_run=longest))
    if col.out_of_range.any():
        lo, hi = options.ranges[name]
        bad = col.values[col.out_of_range]
        fraction = bad.size / max(n_valid, 1)
        severity = "error" if fraction > options.out_of_range_error_fraction else "warning"
        out.append(where.finding(
            "out_of_range", severity, col.out_of_range,
            f"value(s) ({fraction:.2%}) outside the physical range {_show(lo, name, options)} "
            f"… {_show(hi, name, options)}; seen {_show(float(bad.min()), name, options)} … "
            f"{_show(float(bad.max()), name, options)}",
            low=lo, high=hi, min=float(bad.min()), max=float(bad.max()), fraction=fraction,
        ))
    if col.bad.any():
        fraction = int(col.bad.sum()) / max(col.values.size, 1)
        severity = "error" if fraction > options.out_of_range_error_fraction else "warning"
        out.append(where.finding(
            "historian_quality", severity, col.bad,
            f"sample(s) ({fraction:.2%}) marked bad or uncertain by the historian's quality "
            "column", fraction=fraction,
        ))
    grid = (f"quantum {_show(col.quantum, name, options, delta=True)}" if col.quantum > 0.0
            else "no quantum")
    noise = f"noise σ {_show(col.sigma, name, options, delta=True)}, {grid}"
    if col.spike.any():
        i = int(np.argmax(col.spike))
        out.append(where.finding(
            "spike", "warning", col.spike,
            f"spike(s): excursion(s) of ≤ {SPIKE_MAX_SAMPLES} sample(s) that return, beyond "
            f"{options.spike_n_sigmas:g} × {_show(col.spike_scale, name, options, delta=True)} "
            f"(noise scale) and beyond the physical rate limit "
            f"{_show(col.max_rate, name, options, delta=True)}/s × step from the "
            f"{options.spike_window}-sample rolling median; first value "
            f"{_show(float(col.values[i]), name, options)}",
            noise_scale=col.spike_scale, n_sigmas=options.spike_n_sigmas, max_rate=col.max_rate,
        ))
    if col.stuck.any():
        out.append(where.finding(
            "stuck", "warning", col.stuck,
            f"sample(s) in {col.stuck_runs} stuck run(s) (value exactly repeated for at least "
            f"{options.stuck_min_duration_s:g} s, fewer than {STUCK_CHANCE_RUNS_PER_DAY:g} such "
            f"runs per day expected by chance with {noise}), {col.stuck_duration_s:g} s in total",
            runs=col.stuck_runs, duration_s=col.stuck_duration_s, sigma=col.sigma,
            quantum=col.quantum,
        ))
    if col.constant:
        value = float(col.values[~col.nan][0])
        out.append(where.make(
            "constant", "warning", n_valid, *where.first(~col.nan),
            f"sample(s) all equal to {_show(value, name, options)} over the whole record "
            "(stuck sensor or a legitimately constant signal?)",
        ))
    return out

def unit_findings(a: Analysis, options: QualityOptions) -> list[Finding]:
    out: list[Finding] = []
    medians = {
        name: float(np.median(col.values[~col.nan]))
        for name, col in a.columns.items()
        if name in TYPICAL_RANGES and (~col.nan).any()
    }
    plausible: set[str] = set()
    for name, median in medians.items():
        finding = _unit_check(a, options, name, median, TYPICAL_RANGES[name], "typical")
        if finding is None:
            plausible.add(name)
        else:
            out.append(finding)
    if "main_steam_flow" in plausible and "load" in plausible and medians["load"] > 0:
        band = (STEAM_RATE[0] * medians["load"], STEAM_RATE[1] * medians["load"])
        finding = _unit_check(a, options, "main_steam_flow", medians["main_steam_flow"], band,
                              f"steam-rate (2.5–4.0 kg/kWh × load {medians['load'] / 1e6:.4g} MW)")
        if finding is not None and finding.kind == "unit":
            out.append(finding)
    return out

def _unit_check(a: Analysis, options: QualityOptions, name: str, median: float,
                band: tuple[float, float], label: str) -> Finding | None:
    lo, hi = band
    if lo <= median <= hi:
        return None
    si = SIGNALS[name].si_unit
    declared = options.declared_units.get(name, si)
    where = Where(a, options, name)
    expected = f"{_show(lo, name, options)} … {_show(hi, name, options)}"
    try:
        raw = float(convert(median, si, declared))
    except Exception:
        raw, declared = median, si
    centre = math.sqrt(lo * hi)
    best: tuple[float, str, float] | None = None
    for unit in CANDIDATE_UNITS.get(si, ()):
        if unit == declared:
            continue
        value = float(convert(raw, unit, si))
        if lo <= value <= hi:
            distance = abs(math.log(value / centre))
            if best is None or distance < best[0]:
                best = (distance, unit, value)
    if best is None:
        side = "below" if median < lo else "above"
        return where.make(
            "atypical_level", "warning", 1, None, None,
            f"median {median:.3g} {si} is {side} the {label} range {expected}; declared "
            f"{declared}; no common unit confusion explains it (unit shut down?)",
            counted=False, median=median, declared_unit=declared, low=lo, high=hi,
        )
    if si == "K":
        off = median - best[2]
        relation = f"{abs(off):.4g} K {'above' if off > 0 else 'below'}"
    else:
        factor = median / best[2]
        relation = f"{factor:.3g}× above" if factor > 1 else f"{1 / factor:.3g}× below"
    return where.make(
        "unit", "error", 1, None, None,
        f"probably wrong unit: median {median:.3g} {si} — {relation} the {label} range "
        f"{expected}; declared {declared}, the data look like {best[1]} "
        f"(median would be {_show(best[2], name, options)})",
        counted=False, median=median, declared_unit=declared, probable_unit=best[1],
        low=lo, high=hi,
    )
