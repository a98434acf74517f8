"""Data-quality check and cleaning of DCS (historian) data in canonical SI signals.

Rule: **nothing is dropped or invented silently.** :func:`check_quality` finds problems in a frame
as read (possibly unsorted, with duplicate timestamps and gaps); :func:`clean` repairs or rejects
what it safely can and flags and counts every sample it touched. Cleaning never interpolates and
never fills a gap; resampling is a later, separate, explicit step.

Each finding names the source, the signal and its historian tag, the first offending row with
its timestamp, and the expected unit or range. Messages and the printed table count data rows
from 1 in the frame as read (the header not counted); ``Finding.first_row`` and the JSON's
``first_row`` keep the 0-based position for programs.

Severity policy
    error: a required signal is missing or entirely NaN; a signal's level is explained by a common
    unit confusion (bar/MPa, kPa/MPa, °C/K, t/h/kg/s, kW/MW); duplicate timestamps with
    conflicting values (which value is true is unknown); more than ``out_of_range_error_fraction``
    (default 1 %) of a signal's samples outside its physical range, or marked bad by the
    historian's quality column.
    warning: everything that is repairable without guessing or that affects only a few samples:
    unsorted timestamps, identical duplicate rows, gaps, NaN, spikes, stuck runs, a constant
    signal, a few out-of-range values, a level outside the typical range that no unit confusion
    explains (e.g. the unit was shut down), non-numeric columns.

Detectors (all on the time-sorted frame with duplicate timestamps reduced to their first row;
samples that are NaN, out of range or marked bad by the historian take no part)
    gaps: steps longer than ``gap_factor`` (3) × the nominal step (median step unless given).
    noise σ and quantum q of each signal (overridable with ``noise_si``/``resolution_si``):
    q is the historian's resolution, the largest step of which (nearly) all non-zero
    differences between consecutive values are whole multiples (:func:`estimate_resolution`);
    σ is the white-noise standard deviation from the second differences
    ``(x[i−1] − 2·x[i] + x[i+1])/√6`` (variance σ² for white noise; a linear trend cancels)
    [Gasser, Sroka & Jennen-Steinmetz 1986, Biometrika 73(3) 625–633], taken as the standard
    deviation of the central 99 % of them divided by 0.9616 (the truncated-normal factor), then
    Sheppard-corrected for quantisation (σ² − q²/12) (:func:`estimate_noise_sigma`). A MAD
    estimate is not used because it collapses to 0 once half the differences are 0, i.e. on
    any signal quantised at about its noise level. σ is estimated again without the samples of
    stuck runs found in a first pass.
    stuck: a run of n exactly repeated values is stuck when chance explains it less than
    :data:`STUCK_CHANCE_RUNS_PER_DAY` (0.1) times per signal-day, i.e. when
    ``(86400 s / step) · P < 0.1`` with ``P = ∏ p_i`` over n − 1 of its samples, and it lasts at
    least ``stuck_min_duration_s`` (30 s). ``p_i`` is the probability that a sample falls into
    the held value's quantisation cell: ``Φ((q/2 − δ_i)/σ) − Φ((−q/2 − δ_i)/σ)`` with
    ``δ_i`` the offset of the local trend (the slope between the medians of up to 30 valid
    samples before and after the run) from the run's centre. ``p_i`` is never taken below the
    signal's observed persistence: the largest chance, estimated from its own runs of equal
    values (capped at the floor, censored there; runs that white noise of σ cannot explain are
    left out), that a run of m = 1, 2, 4, … samples goes on by one more. So a legitimately flat,
    coarsely quantised or slowly wandering (coloured) signal is not called stuck. Pairs of
    equal samples are treated as independent. Without trend and persistence
    ``P = p^(n−1)``, ``p = 2Φ(q/2σ) − 1``; for σ = 0.5 K and q = 0.1 K, p = 0.08 and 7
    equal samples at 1 s are already improbable, so the duration floor decides. A signal
    constant over the whole record is reported once as ``constant`` instead, since it cannot
    be told from a legitimately constant one.
    spikes: the local trend is the rolling median over ``spike_window`` (61) valid samples; a
    sample is a spike when its departure from the trend exceeds both ``spike_n_sigmas`` (k)
    × the noise scale and the signal's physical rate limit × the longer of its two time steps
    (:data:`MAX_RATES`, overridable with ``max_rate_si``), and the excursion returns: at most
    :data:`SPIKE_MAX_SAMPLES` (3) consecutive departures of one sign with a non-departing
    valid sample on each side. A step, however fast, does not return and is never a spike.
    The noise scale is the larger of √(σ² + q²/12) and the spread of the departures
    themselves (std of their central 99 % / 0.9616), so coloured noise or process
    fluctuations that the second differences do not see do not raise false spikes.
    k = 4.5 from the false-alarm budget of ≤ 1 false spike per signal-day at 1 s: for white
    Gaussian noise the expected number is 86400 · 2·(1 − Φ(4.5)) = 0.59 per day (0.63
    measured on the virtual plant). The price is the Neyman–Pearson limit for a single
    sample: a spike of A·σ is found with probability Φ(A/1.013 − 4.5) (1.013 = √(1 + π/122):
    the 61-sample median's own variance πσ²/(2·61) [Kendall & Stuart, sample median]),
    0.67 at 5σ, 0.92 at 6σ, 95 % at about 6.2σ; measured 0.675, 0.923 and 0.988 at 7σ over
    10 instrument draws of the virtual plant (``benchmarks/bench_quality_detection.py``;
    docs/benchmarks.md).
    historian quality: samples the historian's quality column marked bad or uncertain
    (``bad_quality`` masks, one per signal in the frame-as-read row order); a warning, an
    error when more than ``out_of_range_error_fraction`` of the signal's samples.
    unit: the median is compared with :data:`TYPICAL_RANGES`; main-steam flow is also compared
    with the load (steam rate 2.5–4.0 kg/kWh) when the load looks right, since the t/h vs kg/s
    factor 3.6 is smaller than the flow range itself.

Flag codes (:class:`Flag`, a bitmask per sample in ``CleaningResult.flags``, uint16)
    1 MISSING (NaN as read, left NaN), 2 SPIKE, 4 OUT_OF_RANGE, 8 STUCK (part of a stuck run),
    16 DUPLICATE (the row's timestamp had other rows, which were dropped; the first kept),
    32 DUPLICATE_CONFLICT (those dropped rows held a different value of this signal),
    64 OUT_OF_ORDER (the row came after a later timestamp in the file and was moved),
    128 REMOVED (cleaning replaced the value by NaN), 256 BAD_QUALITY (the historian's quality
    column marked the sample bad or uncertain). A value is changed iff REMOVED is set.
    :func:`clean` removes spikes, out-of-range, stuck and bad-quality samples, and every sample
    of a signal with an error-level unit finding (a unit mix-up never feeds a model).
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from enum import IntFlag
from typing import Any, Literal

import numpy as np
import pandas as pd
from scipy.ndimage import median_filter
from scipy.special import ndtr

from steamtwin.dcs.signals import SIGNALS
from steamtwin.units import convert

__all__ = [
    "MAX_RATES",
    "SPIKE_MAX_SAMPLES",
    "STUCK_CHANCE_RUNS_PER_DAY",
    "TYPICAL_RANGES",
    "CleaningResult",
    "Finding",
    "Flag",
    "QualityReport",
    "check_quality",
    "clean",
    "estimate_noise_sigma",
    "estimate_resolution",
]

Severity = Literal["error", "warning"]
Action = Literal["detected", "repaired", "rejected"]

INDEX = "(index)"
"""Pseudo-signal under which index findings (order, duplicates, gaps) are counted."""

SECONDS_PER_DAY = 86400.0

STUCK_CHANCE_RUNS_PER_DAY = 0.1
"""A run is stuck when chance would produce fewer such runs per signal-day than this."""

SPIKE_MAX_SAMPLES = 3
"""Longest excursion (consecutive samples) that counts as a spike; longer ones are steps."""

_TRIM = 0.99
"""Share of the central values kept by the trimmed standard deviation."""
#: std of N(0, 1) truncated to its central 99 % (|z| ≤ 2.5758):
#: sqrt(1 − 2·c·φ(c)/(2Φ(c) − 1)) [Johnson, Kotz & Balakrishnan 1994, ch. 13, truncated normal].
_TRIMMED_STD_FACTOR = 0.96164

#: Typical operating range of each canonical signal in SI, for a 600 MW subcritical unit
#: (16.7 MPa / 538 °C, sliding pressure, nozzle governing) between 30 and 100 % load, with
#: margin. Used only to spot a wrong unit; physical validity limits are the caller's ``ranges``.
TYPICAL_RANGES: dict[str, tuple[float, float]] = {
    # 16.7 MPa rated, ~8 MPa at 30 % on sliding pressure; 20 MPa is above any subcritical rating.
    "main_steam_pressure": (2.0e6, 20.0e6),
    # 538 °C rated; 430–500 °C during starts and deep part load: 427–607 °C.
    "main_steam_temperature": (700.0, 880.0),
    # 500 kg/s (1800 t/h) rated, ~150 kg/s at 30 %, ~560 kg/s at valves wide open.
    "main_steam_flow": (50.0, 700.0),
    # 13 MPa rated, ~proportional to flow (Stodola), ~4 MPa at 30 %.
    "control_stage_pressure": (1.0e6, 16.0e6),
    # ~490 °C rated, ~430 °C with throttled nozzle groups at part load: 327–577 °C.
    "control_stage_temperature": (600.0, 850.0),
    # 3.9 MPa rated (cold reheat), ~1.2 MPa at 30 %.
    "hp_exhaust_pressure": (0.5e6, 5.0e6),
    # 327 °C rated, 280–380 °C over the load range: 227–447 °C.
    "hp_exhaust_temperature": (500.0, 720.0),
    # In service the governing-stage inner wall follows the control-stage steam; 277–577 °C.
    "hp_inner_casing_temperature": (550.0, 850.0),
    # 180–600 MW at 30–100 % load.
    "load": (50.0e6, 700.0e6),
    # ~177 MW at rated, ~50 MW at 30 %.
    "hp_power": (20.0e6, 250.0e6),
}

#: Physical rate limit of each canonical signal in SI per second (Pa/s, K/s, kg/s², W/s): the
#: fastest the *measured* signal genuinely moves in operation (load ramps up to 5 %/min, boiler-
#: limited pressure ramps, sensor lag, metal heat-up limits). A departure from the local trend
#: that returns within a few samples needs at least departure/step in and out; below this
#: limit × step it may be real. Trips, load rejections and valve steps are faster but are
#: monotone steps, which never count as spikes whatever their rate.
MAX_RATES: dict[str, float] = {
    # Sliding pressure 0.45–1.0 × 16.7 MPa: 7.7 kPa/s at a 5 %/min ramp; drum saturation-
    # temperature limits of a few K/min (EN 12952-3) at dTsat/dp ≈ 5 K/MPa near 16.7 MPa allow
    # ~1 MPa/min = 17 kPa/s → 20 kPa/s (1.2 MPa/min).
    "main_steam_pressure": 20.0e3,
    # Steam-temperature ramps are held to a few K/min (turbine thermal stress; the plant's
    # firing/spray dip is ~1.2 K per %/min through 300 s); a 20-s thermowell passes at most
    # ΔT/τ → 0.1 K/s (6 K/min).
    "main_steam_temperature": 0.1,
    # 500 kg/s rated: 10 %/min = 0.83 kg/s² → 1 kg/s per s.
    "main_steam_flow": 1.0,
    # ∝ flow (Stodola), 13 MPa rated: 5 %/min = 10.8 kPa/s → 15 kPa/s (7 %/min).
    "control_stage_pressure": 15.0e3,
    # Nozzle throttling: ~30 K over a 30–100 % ramp, at 5 %/min 0.08 K/s → 0.2 K/s.
    "control_stage_temperature": 0.2,
    # ∝ flow, 3.9 MPa rated: 5 %/min = 3.3 kPa/s → 5 kPa/s.
    "hp_exhaust_pressure": 5.0e3,
    # ~100 K over the load range through a 30-s well: 0.1 K/s.
    "hp_exhaust_temperature": 0.1,
    # Casing-metal heat-up limits of start-up curves, 1.5–5 K/min (thermal stress) → 0.05 K/s.
    "hp_inner_casing_temperature": 0.05,
    # 600 MW: 10 %/min = 1 MW/s (coordinated-control ramps ≤ 5 %/min, primary response faster).
    "load": 1.0e6,
    # ~177 MW HP share: 10 %/min ≈ 0.3 MW/s.
    "hp_power": 0.3e6,
}

#: Units a value of each SI kind is commonly (mis)declared in; the unit check tries each.
_CANDIDATE_UNITS: dict[str, tuple[str, ...]] = {
    "Pa": ("Pa", "kPa", "bar", "MPa"),
    "K": ("K", "degC"),
    "kg/s": ("kg/s", "t/h", "kg/h"),
    "W": ("W", "kW", "MW"),
}

#: Steam rate band of a reheat unit, kg/s per W (2.5–4.0 kg/kWh; ~3.0 at rated [Cotton ch. 2]).
_STEAM_RATE = (2.5 / 3.6e6, 4.0 / 3.6e6)


class Flag(IntFlag):
    """Per-sample cleaning codes (bitmask); see the module docstring."""

    MISSING = 1
    SPIKE = 2
    OUT_OF_RANGE = 4
    STUCK = 8
    DUPLICATE = 16
    DUPLICATE_CONFLICT = 32
    OUT_OF_ORDER = 64
    REMOVED = 128
    BAD_QUALITY = 256


@dataclass(frozen=True)
class Finding:
    """One data-quality finding; ``first_row`` is the 0-based position in the frame as read."""

    kind: str
    severity: Severity
    signal: str | None
    tag: str | None
    count: int
    first_row: int | None
    first_time: pd.Timestamp | float | None
    message: str
    action: Action = "detected"
    details: tuple[tuple[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form (timestamps as ISO 8601, index times in s)."""
        return {
            "kind": self.kind,
            "severity": self.severity,
            "action": self.action,
            "signal": self.signal,
            "tag": self.tag,
            "count": int(self.count),
            "first_row": None if self.first_row is None else int(self.first_row),
            "first_time": _json_time(self.first_time),
            "message": self.message,
            "details": {key: _json_value(value) for key, value in self.details},
        }


@dataclass(frozen=True)
class QualityReport:
    """Findings of a quality check (and of a cleaning, with ``action`` repaired/rejected)."""

    findings: tuple[Finding, ...]
    source: str = ""
    n_rows: int = 0
    signals: tuple[str, ...] = ()

    @property
    def errors(self) -> tuple[Finding, ...]:
        """Findings of severity ``error``."""
        return tuple(f for f in self.findings if f.severity == "error")

    @property
    def warnings(self) -> tuple[Finding, ...]:
        """Findings of severity ``warning``."""
        return tuple(f for f in self.findings if f.severity == "warning")

    @property
    def ok(self) -> bool:
        """True when there is no error (warnings allowed)."""
        return not self.errors

    def counts(self, action: Action = "detected") -> pd.DataFrame:
        """Counts as a DataFrame: signal (``"(index)"`` for the time index) × kind."""
        rows: dict[tuple[str, str], int] = {}
        for f in self.findings:
            if f.action == action:
                key = (f.signal or INDEX, f.kind)
                rows[key] = rows.get(key, 0) + int(f.count)
        if not rows:
            return pd.DataFrame(dtype="int64")
        series = pd.Series(rows, dtype="int64")
        return series.unstack(fill_value=0).astype("int64")

    def to_dict(self) -> dict[str, Any]:
        """Machine-readable, JSON-serialisable form."""
        counts: dict[str, dict[str, dict[str, int]]] = {}
        for action in ("detected", "repaired", "rejected"):
            table = self.counts(action)  # type: ignore[arg-type]
            if not table.empty:
                counts[action] = {
                    str(signal): {str(k): int(v) for k, v in row.items() if v}
                    for signal, row in table.iterrows()
                }
        return {
            "source": self.source,
            "rows": int(self.n_rows),
            "signals": list(self.signals),
            "ok": self.ok,
            "errors": len(self.errors),
            "warnings": len(self.warnings),
            "counts": counts,
            "findings": [f.to_dict() for f in self.findings],
        }

    def to_text(self) -> str:
        """Printable aligned table, one line per finding, message last."""
        head = (
            f"Data quality{' of ' + self.source if self.source else ''}: {self.n_rows} rows, "
            f"{len(self.signals)} signals — {len(self.errors)} error(s), "
            f"{len(self.warnings)} warning(s)"
        )
        if not self.findings:
            return head + "\nno findings"
        columns = ("severity", "action", "kind", "signal", "tag", "count", "row", "message")
        table = [
            (
                f.severity, f.action, f.kind, f.signal or INDEX, f.tag or "", str(f.count),
                "" if f.first_row is None else str(f.first_row + 1), f.message,
            )
            for f in self.findings
        ]
        widths = [max(len(columns[i]), *(len(r[i]) for r in table)) for i in range(7)]
        right = {5, 6}

        def line(cells: tuple[str, ...]) -> str:
            padded = [
                cells[i].rjust(widths[i]) if i in right else cells[i].ljust(widths[i])
                for i in range(7)
            ]
            return "  ".join([*padded, cells[7]]).rstrip()

        return "\n".join([head, line(columns), *(line(r) for r in table)])

    def __str__(self) -> str:
        return self.to_text()


@dataclass(frozen=True)
class CleaningResult:
    """Cleaned data (time-sorted, unique index), per-sample :class:`Flag` codes and the report.

    ``rows`` gives, for each output row, its 0-based position in the frame as read.
    """

    data: pd.DataFrame
    flags: pd.DataFrame
    report: QualityReport
    rows: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))


# --------------------------------------------------------------------------------------------
# public functions


def check_quality(
    frame: pd.DataFrame,
    *,
    required: Collection[str] = (),
    ranges: Mapping[str, tuple[float, float]] | None = None,
    declared_units: Mapping[str, str] | None = None,
    tag_names: Mapping[str, str] | None = None,
    source: str = "",
    nominal_step_s: float | None = None,
    gap_factor: float = 3.0,
    spike_window: int = 61,
    spike_n_sigmas: float = 4.5,
    stuck_min_duration_s: float = 30.0,
    out_of_range_error_fraction: float = 0.01,
    noise_si: Mapping[str, float] | None = None,
    resolution_si: Mapping[str, float] | None = None,
    max_rate_si: Mapping[str, float] | None = None,
    bad_quality: Mapping[str, np.ndarray] | None = None,
) -> QualityReport:
    """Check DCS data in SI units on a time index; nothing is changed.

    ``ranges`` are physical validity limits in SI (Pa, K, kg/s, W); ``declared_units`` the units
    the historian declared (e.g. ``{"main_steam_pressure": "MPa"}``; SI assumed if absent);
    ``tag_names`` map signal → historian tag for the messages. ``nominal_step_s`` is the
    sampling step in s (median step if None). ``spike_window`` (odd, samples) and
    ``spike_n_sigmas`` (k) set the spike detector; ``stuck_min_duration_s`` (s) is the shortest
    run reported as stuck. ``noise_si``: white-noise σ per signal (SI, before quantisation;
    estimated when absent); ``resolution_si``: quantum per signal (SI; estimated when absent);
    ``max_rate_si``: physical rate limit per signal (SI per s; overrides :data:`MAX_RATES`);
    ``bad_quality``: per signal, a boolean mask over the frame's rows as read of samples the
    historian's quality column marked bad or uncertain. See the module docstring.
    """
    options = _Options.make(
        required, ranges, declared_units, tag_names, source, nominal_step_s, gap_factor,
        spike_window, spike_n_sigmas, stuck_min_duration_s, out_of_range_error_fraction,
        noise_si, resolution_si, max_rate_si, bad_quality,
    )
    analysis = _analyse(frame, options)
    return QualityReport(
        tuple(_detection_findings(analysis, options)), source, len(frame), analysis.signals
    )


def clean(
    frame: pd.DataFrame,
    report: QualityReport | None = None,
    *,
    required: Collection[str] = (),
    ranges: Mapping[str, tuple[float, float]] | None = None,
    declared_units: Mapping[str, str] | None = None,
    tag_names: Mapping[str, str] | None = None,
    source: str = "",
    nominal_step_s: float | None = None,
    gap_factor: float = 3.0,
    spike_window: int = 61,
    spike_n_sigmas: float = 4.5,
    stuck_min_duration_s: float = 30.0,
    out_of_range_error_fraction: float = 0.01,
    noise_si: Mapping[str, float] | None = None,
    resolution_si: Mapping[str, float] | None = None,
    max_rate_si: Mapping[str, float] | None = None,
    bad_quality: Mapping[str, np.ndarray] | None = None,
    reject_stuck: bool = True,
) -> CleaningResult:
    """Sort, de-duplicate and reject bad samples (→ NaN), flagging and counting every change.

    Exact duplicate rows are removed; of conflicting duplicates the first row as read is kept.
    Spikes, out-of-range values, samples the historian marked bad (``bad_quality``) and stuck
    runs (unless ``reject_stuck=False``) become NaN, and so does every sample of a signal with
    an error-level unit finding. Nothing is interpolated. ``report``: a :func:`check_quality`
    report of this same frame, carried into the result instead of rebuilding the detection
    findings (the per-sample masks are always recomputed with the options given here). Other
    options as in :func:`check_quality`.
    """
    options = _Options.make(
        required, ranges, declared_units, tag_names, source, nominal_step_s, gap_factor,
        spike_window, spike_n_sigmas, stuck_min_duration_s, out_of_range_error_fraction,
        noise_si, resolution_si, max_rate_si, bad_quality,
    )
    analysis = _analyse(frame, options)
    if report is not None and report.n_rows != len(frame):
        raise ValueError(
            f"{source or 'clean'}: the report is for {report.n_rows} rows, the frame has "
            f"{len(frame)}; pass the report of this frame or none"
        )
    detected = (
        list(report.findings) if report is not None else _detection_findings(analysis, options)
    )
    unit_errors = {f.signal for f in _unit_findings(analysis, options)
                   if f.kind == "unit" and f.severity == "error"}

    a = analysis
    data = frame.iloc[a.rows].copy()
    flags = np.zeros((len(a.rows), frame.shape[1]), dtype=np.uint16)
    actions: list[Finding] = []
    common = (a.kept_has_dup.astype(np.uint16) * np.uint16(Flag.DUPLICATE)) | (
        a.kept_late.astype(np.uint16) * np.uint16(Flag.OUT_OF_ORDER)
    )
    position = {name: j for j, name in enumerate(frame.columns)}
    for name in frame.columns:
        flags[:, position[name]] |= common
    for name, col in a.columns.items():
        f = flags[:, position[name]]
        for bit, mask in ((Flag.MISSING, col.nan), (Flag.SPIKE, col.spike),
                          (Flag.OUT_OF_RANGE, col.out_of_range), (Flag.STUCK, col.stuck),
                          (Flag.DUPLICATE_CONFLICT, col.conflict),
                          (Flag.BAD_QUALITY, col.bad)):
            f[mask] |= np.uint16(bit)
        stuck = col.stuck & ~col.nan if reject_stuck else np.zeros_like(col.nan)
        unit = ~col.nan if name in unit_errors else np.zeros_like(col.nan)
        remove = col.spike | col.out_of_range | (col.bad & ~col.nan) | stuck | unit
        f[remove] |= np.uint16(Flag.REMOVED)
        if remove.any():
            values = col.values.copy()
            values[remove] = np.nan
            data[name] = values
        where = _Where(a, options, name)
        for kind, mask, what in (
            ("duplicate_conflict", col.conflict, "conflicting duplicate values dropped, "
             "first row as read kept"),
            ("spike", col.spike, "spike(s) replaced by NaN"),
            ("out_of_range", col.out_of_range, "out-of-range value(s) replaced by NaN"),
            ("historian_quality", col.bad & ~col.nan,
             "value(s) marked bad/uncertain by the historian replaced by NaN"),
            ("stuck", stuck, "stuck value(s) replaced by NaN"),
            ("unit", unit, "value(s) replaced by NaN: the signal's unit is probably wrong "
             "(unit error), so none of it may feed a model"),
        ):
            if mask.any():
                actions.append(where.finding(kind, "warning", mask, f"{what}", "rejected"))
    index_where = _Where(a, options, None)
    if a.kept_late.any():
        actions.append(index_where.finding(
            "unsorted", "warning", a.kept_late,
            "row(s) that came after a later timestamp moved into time order", "repaired",
        ))
    if a.n_dup_identical:
        actions.append(index_where.make(
            "duplicate", "warning", a.n_dup_identical, *a.first_dup_identical,
            "exact duplicate row(s) removed", "repaired",
        ))
    if a.n_dup_conflict:
        actions.append(index_where.make(
            "duplicate_conflict", "error", a.n_dup_conflict, *a.first_dup_conflict,
            "row(s) with conflicting values at a repeated timestamp dropped, first kept",
            "rejected",
        ))
    flags_frame = pd.DataFrame(flags, index=data.index, columns=frame.columns)
    full = QualityReport(tuple(detected + actions), source, len(frame), a.signals)
    return CleaningResult(data, flags_frame, full, a.rows.copy())


# --------------------------------------------------------------------------------------------
# analysis shared by check and clean


@dataclass(frozen=True)
class _Options:
    required: tuple[str, ...]
    ranges: dict[str, tuple[float, float]]
    declared: dict[str, str]
    tags: dict[str, str]
    source: str
    nominal_step_s: float | None
    gap_factor: float
    window: int
    n_sigmas: float
    stuck_s: float
    oor_error_fraction: float
    noise: dict[str, float]
    resolution: dict[str, float]
    max_rate: dict[str, float]
    bad: dict[str, np.ndarray]

    @classmethod
    def make(cls, required, ranges, declared, tags, source, nominal, gap_factor, window,
             n_sigmas, stuck_s, oor_fraction, noise, resolution, max_rate,
             bad) -> _Options:  # type: ignore[no-untyped-def]
        where = source or "quality check"
        if window < 3 or window % 2 == 0:
            raise ValueError(f"spike_window must be an odd number ≥ 3 of samples, got {window}")
        if n_sigmas <= 0 or gap_factor <= 1 or stuck_s <= 0:
            raise ValueError("spike_n_sigmas > 0, gap_factor > 1, stuck_min_duration_s > 0")
        if nominal is not None and not nominal > 0:
            raise ValueError(f"nominal_step_s must be > 0 s, got {nominal}")
        per_signal: list[dict[str, float]] = []
        for option, mapping in (("noise_si", noise), ("resolution_si", resolution),
                                ("max_rate_si", max_rate)):
            checked: dict[str, float] = {}
            for name, value in dict(mapping or {}).items():
                number = float(value)
                if not (math.isfinite(number) and number >= 0.0):
                    raise ValueError(f"{where}: {option}[{name!r}] must be a finite number ≥ 0 "
                                     f"in SI units, got {value!r}")
                checked[str(name)] = number
            per_signal.append(checked)
        masks: dict[str, np.ndarray] = {}
        for name, mask in dict(bad or {}).items():
            array = np.asarray(mask)
            if array.ndim != 1 or array.dtype != np.bool_:
                raise ValueError(f"{where}: bad_quality[{name!r}] must be a 1-D boolean mask "
                                 f"over the rows as read, got dtype {array.dtype}, "
                                 f"shape {array.shape}")
            masks[str(name)] = array
        return cls(tuple(required), dict(ranges or {}), dict(declared or {}), dict(tags or {}),
                   source, nominal, gap_factor, int(window), float(n_sigmas), float(stuck_s),
                   float(oor_fraction), per_signal[0], per_signal[1],
                   {**MAX_RATES, **per_signal[2]}, masks)


@dataclass
class _Column:
    values: np.ndarray
    nan: np.ndarray
    out_of_range: np.ndarray
    bad: np.ndarray
    spike: np.ndarray
    stuck: np.ndarray
    conflict: np.ndarray
    sigma: float = math.nan  # white-noise σ before quantisation, SI
    quantum: float = 0.0  # historian resolution, SI (0: none found)
    spike_scale: float = math.nan  # noise scale of the spike test, SI
    max_rate: float = 0.0  # SI per s
    stuck_runs: int = 0
    stuck_duration_s: float = 0.0
    constant: bool = False


@dataclass
class _Analysis:
    n: int
    signals: tuple[str, ...]
    missing_required: list[str]
    non_numeric: list[str]
    is_datetime: bool
    rows: np.ndarray  # as-read position of each kept (sorted, unique) row
    times_ns: np.ndarray  # kept rows, int64 ns
    labels: pd.Index  # kept rows' index labels
    backwards: int
    first_backwards: int | None
    kept_late: np.ndarray
    kept_has_dup: np.ndarray
    n_dup_identical: int
    first_dup_identical: tuple[int | None, Any]
    n_dup_conflict: int
    first_dup_conflict: tuple[int | None, Any]
    conflict_signals: list[str]
    step_s: float
    gaps: np.ndarray  # kept-row positions i where step i → i+1 is a gap
    gap_steps_s: np.ndarray
    columns: dict[str, _Column]
    raw_labels: pd.Index


def _times_ns(index: pd.Index, source: str) -> tuple[np.ndarray, bool]:
    if isinstance(index, pd.DatetimeIndex):
        if index.hasnans:
            row = int(np.flatnonzero(index.isna())[0])
            raise ValueError(f"{source or 'frame'}: row {row} has no timestamp (NaT)")
        return index.as_unit("ns").asi8, True
    if pd.api.types.is_numeric_dtype(index.dtype):
        seconds = np.asarray(index, dtype=float)
        if not np.isfinite(seconds).all():
            row = int(np.flatnonzero(~np.isfinite(seconds))[0])
            raise ValueError(f"{source or 'frame'}: row {row} has no valid time (s)")
        return np.round(seconds * 1e9).astype(np.int64), False
    raise TypeError(
        f"{source or 'frame'}: expected a DatetimeIndex (or time in s), got {type(index).__name__}"
    )


def _analyse(frame: pd.DataFrame, options: _Options) -> _Analysis:
    n = len(frame)
    t_raw, is_datetime = _times_ns(frame.index, options.source)
    numeric = [c for c in frame.columns if pd.api.types.is_numeric_dtype(frame[c].dtype)]
    non_numeric = [str(c) for c in frame.columns if c not in numeric]
    missing = [name for name in options.required if name not in frame.columns]

    steps = np.diff(t_raw)
    backwards = int((steps < 0).sum())
    first_backwards = int(np.argmax(steps < 0)) + 1 if backwards else None
    late_raw = np.zeros(n, dtype=bool)
    if n > 1:
        late_raw[1:] = t_raw[1:] < np.maximum.accumulate(t_raw)[:-1]

    order = np.argsort(t_raw, kind="stable")
    ts = t_raw[order]
    dup = np.zeros(n, dtype=bool)
    dup[1:] = ts[1:] == ts[:-1]
    kept = ~dup
    rows = order[kept]
    group = np.cumsum(kept) - 1
    firsts = np.flatnonzero(kept)
    values = (
        frame[numeric].to_numpy(dtype=float)[order] if numeric else np.empty((n, 0), dtype=float)
    )
    dup_rows = np.flatnonzero(dup)
    first_of_dup = firsts[group[dup_rows]]
    a, b = values[dup_rows], values[first_of_dup]
    differ = ~((a == b) | (np.isnan(a) & np.isnan(b)))
    row_conflict = differ.any(axis=1)
    n_groups = len(firsts)
    conflict = np.zeros((n_groups, len(numeric)), dtype=bool)
    if dup_rows.size:
        np.logical_or.at(conflict, group[dup_rows], differ)
    has_dup = np.zeros(n_groups, dtype=bool)
    has_dup[group[dup_rows]] = True

    def first_of(mask: np.ndarray) -> tuple[int | None, Any]:
        if not mask.any():
            return None, None
        row = int(order[dup_rows[mask]].min())  # earliest duplicate row as read
        return row, _time_label(frame.index[row], is_datetime)

    kept_values = values[kept]
    times = ts[kept]
    dts = np.diff(times) / 1e9
    if options.nominal_step_s is not None:
        step = float(options.nominal_step_s)
    else:
        step = float(np.median(dts)) if dts.size else math.nan
    gaps = np.flatnonzero(dts > options.gap_factor * step) if dts.size else np.zeros(0, int)

    columns: dict[str, _Column] = {}
    where = options.source or "quality check"
    for name, mask in options.bad.items():
        if name not in frame.columns:  # a non-numeric column is reported, not checked
            raise ValueError(f"{where}: bad_quality has a mask for {name!r}, which is not a "
                             "column of the data")
        if mask.size != n:
            raise ValueError(f"{where}: bad_quality[{name!r}] has {mask.size} entries, the data "
                             f"have {n} rows (one entry per row as read)")
    seconds = (times - times[0]) / 1e9 if times.size else np.zeros(0)
    step_s = step if math.isfinite(step) and step > 0 else 1.0
    for j, name in enumerate(numeric):
        key = str(name)
        x = np.ascontiguousarray(kept_values[:, j])
        nan = np.isnan(x)
        oor = np.zeros_like(nan)
        if name in options.ranges:
            lo, hi = options.ranges[name]
            with np.errstate(invalid="ignore"):
                oor = ~nan & ((x < lo) | (x > hi))
        bad = options.bad[key][rows] if key in options.bad else np.zeros_like(nan)
        col = _Column(x, nan, oor, bad, np.zeros_like(nan), np.zeros_like(nan),
                      conflict[:, j].copy())
        _detect(col, seconds, step_s, options, key)
        if (~nan).sum() > 1 and np.nanmin(x) == np.nanmax(x):
            col.constant = True
            col.stuck[:] = False
            col.stuck_runs, col.stuck_duration_s = 0, 0.0
        columns[key] = col

    return _Analysis(
        n=n, signals=tuple(str(c) for c in numeric), missing_required=missing,
        non_numeric=non_numeric, is_datetime=is_datetime, rows=rows, times_ns=times,
        labels=frame.index[rows], backwards=backwards, first_backwards=first_backwards,
        kept_late=late_raw[rows], kept_has_dup=has_dup,
        n_dup_identical=int((~row_conflict).sum()), first_dup_identical=first_of(~row_conflict),
        n_dup_conflict=int(row_conflict.sum()), first_dup_conflict=first_of(row_conflict),
        conflict_signals=[str(numeric[j]) for j in np.flatnonzero(differ.any(axis=0))],
        step_s=step, gaps=gaps, gap_steps_s=dts[gaps], columns=columns, raw_labels=frame.index,
    )


def estimate_noise_sigma(values: np.ndarray, resolution: float = 0.0) -> float:
    """White-noise σ of evenly sampled ``values`` (SI; NaN breaks the series), before quantisation.

    From the second differences ``(x[i−1] − 2·x[i] + x[i+1])/√6`` (variance σ² for white
    noise, a linear trend cancels) [Gasser, Sroka & Jennen-Steinmetz 1986, Biometrika 73(3)]:
    the standard deviation of their central 99 % / 0.9616 (truncated normal), robust to < 1 %
    of steps and spikes and, unlike a MAD, not collapsing on quantised data; then corrected
    for the quantisation noise ``resolution²/12`` (Sheppard 1898). NaN with fewer than 3
    triples of finite values.
    """
    x = np.asarray(values, dtype=float)
    if x.size < 3:
        return math.nan
    second = x[:-2] - 2.0 * x[1:-1] + x[2:]
    second = second[np.isfinite(second)]
    if second.size < 3:
        return math.nan
    total = _trimmed_std(second) / math.sqrt(6.0)
    return math.sqrt(max(total**2 - resolution**2 / 12.0, 0.0))


def estimate_resolution(values: np.ndarray) -> float:
    """Quantum (SI) of a historian signal: its values' grid step; 0 when no grid is found.

    Non-zero absolute differences of consecutive finite values (ignoring float noise below
    1e-9 of the largest magnitude) are tried against the smallest one divided by 1 … 8; the
    first candidate of which ≥ 99.9 % of the differences are whole multiples (within 1 %) is
    taken, refined as the median difference per step. Fewer than 10 non-zero differences:
    0 (no evidence of a grid).
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return 0.0
    tolerance = 1e-9 * float(np.max(np.abs(x))) + 1e-300
    steps = np.abs(np.diff(x))
    steps = steps[steps > tolerance]
    if steps.size < 10:
        return 0.0
    smallest = float(steps.min())
    for divisor in range(1, 9):
        candidate = smallest / divisor
        multiples = steps / candidate
        whole = np.round(multiples)
        if np.mean(np.abs(multiples - whole) <= 0.01) >= 0.999:
            return float(np.median(steps / whole))
    return 0.0


def _trimmed_std(v: np.ndarray) -> float:
    """Std about the median of the central 99 % of ``v``, scaled to σ for a normal sample."""
    deviation = np.abs(v - np.median(v))
    central = deviation[deviation <= np.quantile(deviation, _TRIM)]
    return float(np.sqrt(np.mean(central**2)) / _TRIMMED_STD_FACTOR)


def _detect(col: _Column, seconds: np.ndarray, step_s: float, options: _Options,
            name: str) -> None:
    """Noise, quantum, stuck runs and spikes of one column (sets the fields of ``col``)."""
    usable = ~col.nan & ~col.out_of_range & ~col.bad
    x = np.where(usable, col.values, np.nan)
    quantum = options.resolution.get(name)
    col.quantum = estimate_resolution(x) if quantum is None else quantum
    col.max_rate = options.max_rate.get(name, 0.0)
    given = options.noise.get(name)
    sigma = given if given is not None else estimate_noise_sigma(x, col.quantum)
    stuck = _stuck(x, seconds, sigma, col.quantum, step_s, options.stuck_s)
    if given is None and stuck.any():  # again without the stuck runs' zero differences
        sigma = estimate_noise_sigma(np.where(stuck, np.nan, x), col.quantum)
        stuck = _stuck(x, seconds, sigma, col.quantum, step_s, options.stuck_s)
    col.sigma, col.stuck = sigma, stuck
    if stuck.any():
        starts, ends, _ = _segments(np.r_[False, stuck[1:] & stuck[:-1]])
        runs = stuck[starts]
        col.stuck_runs = int(runs.sum())
        col.stuck_duration_s = float((seconds[ends] - seconds[starts])[runs].sum())
    col.spike, col.spike_scale = _spikes(x, seconds, usable & ~stuck, col, options)


def _cell_probability(offset: np.ndarray, sigma: float, quantum: float) -> np.ndarray:
    """Probability that a sample with noise σ, ``offset`` from a cell's centre, falls in it."""
    if not math.isfinite(sigma):
        return np.ones_like(offset)
    if quantum == 0.0:
        return np.full_like(offset, 0.0 if sigma > 0.0 else 1.0)
    if sigma == 0.0:
        return (offset < quantum / 2.0).astype(float)
    half = quantum / 2.0
    return ndtr((half - offset) / sigma) - ndtr((-half - offset) / sigma)


def _stuck(x: np.ndarray, seconds: np.ndarray, sigma: float, quantum: float, step_s: float,
           min_duration_s: float) -> np.ndarray:
    """Stuck mask: runs of equal values too improbable for noise σ and quantum (module doc)."""
    out = np.zeros(x.size, dtype=bool)
    if x.size < 2:
        return out
    same = np.zeros(x.size, dtype=bool)
    same[1:] = x[1:] == x[:-1]
    starts, ends, _ = _segments(same)
    duration = seconds[ends] - seconds[starts]
    real = np.isfinite(x[starts])
    long = np.flatnonzero((ends > starts) & (duration >= min_duration_s) & real)
    limit = math.log(STUCK_CHANCE_RUNS_PER_DAY * step_s / SECONDS_PER_DAY)
    cells: list[np.ndarray] = []
    for s, e in zip(starts[long], ends[long], strict=True):
        slope = _slope_around(x, seconds, int(s), int(e))
        offset = abs(slope) * np.abs(seconds[s:e + 1] - 0.5 * (seconds[s] + seconds[e]))
        cells.append(_cell_probability(offset, sigma, quantum))
    # runs that white noise alone (without trend) cannot explain take no part in the persistence
    flat = float(_cell_probability(np.zeros(1), sigma, quantum)[0])
    impossible = np.array([_log_run(np.full(p.size, flat)) < limit for p in cells], dtype=bool)
    keep = real.copy()
    keep[long[impossible]] = False
    cap = max(round(min_duration_s / step_s), 2)
    observed = _persistence(np.minimum(ends - starts + 1, cap)[keep], cap)
    for run, p in zip(long, cells, strict=True):
        if _log_run(np.maximum(p, observed)) < limit:
            out[starts[run]:ends[run] + 1] = True
    return out


def _log_run(p: np.ndarray) -> float:
    """log of the product of the n − 1 smallest of ``p`` (the first sample of a run is free)."""
    with np.errstate(divide="ignore"):
        return float(np.sort(np.log(p))[:-1].sum())


def _persistence(lengths: np.ndarray, cap: int, least_runs: int = 20) -> float:
    """Largest observed chance that a run of equal values goes on one more sample.

    ``lengths``: run lengths (samples) capped at ``cap`` (runs that reach it are censored).
    For m = 1, 2, 4, … < cap with at least ``least_runs`` runs reaching m, the geometric
    estimate Σ(c − m) / Σ(c − m + [c < cap]) over those runs; the largest is returned (0 with
    no data). Coloured noise or a slowly wandering level makes runs persist longer than white
    noise would; this floor keeps such legitimate runs from being called stuck.
    """
    best, m = 0.0, 1
    while m < cap:
        reach = lengths[lengths >= m]
        if reach.size < least_runs:
            break
        trials = float((reach - m).sum() + (reach < cap).sum())
        if trials > 0.0:
            best = max(best, float((reach - m).sum()) / trials)
        m *= 2
    return best


def _slope_around(x: np.ndarray, seconds: np.ndarray, start: int, end: int,
                  reach: int = 30, least: int = 10) -> float:
    """Local trend (SI/s) across a run: medians of ≤ ``reach`` finite samples either side."""
    before = slice(max(start - reach, 0), start)
    after = slice(end + 1, end + 1 + reach)
    xb, xa = x[before], x[after]
    fb, fa = np.isfinite(xb), np.isfinite(xa)
    if fb.sum() < least or fa.sum() < least:
        return 0.0
    tb, ta = float(np.median(seconds[before][fb])), float(np.median(seconds[after][fa]))
    return float((np.median(xa[fa]) - np.median(xb[fb])) / (ta - tb))


def _spikes(x: np.ndarray, seconds: np.ndarray, valid: np.ndarray, col: _Column,
            options: _Options) -> tuple[np.ndarray, float]:
    """Spike mask (module doc) and the noise scale used (SI)."""
    out = np.zeros(x.size, dtype=bool)
    index = np.flatnonzero(valid)
    if index.size < 3:
        return out, math.nan
    xv, tv = x[index], seconds[index]
    residual = xv - _rolling_median(xv, options.window)
    noise = math.sqrt(col.sigma**2 + col.quantum**2 / 12.0) if math.isfinite(col.sigma) else 0.0
    scale = max(noise, _trimmed_std(residual))
    dt = np.diff(tv)
    longer_step = np.maximum(np.r_[dt[0], dt], np.r_[dt, dt[-1]])
    threshold = np.maximum(options.n_sigmas * scale, col.max_rate * longer_step)
    candidate = (threshold > 0.0) & (np.abs(residual) > threshold)
    sign = np.sign(residual)
    joined = np.zeros(index.size, dtype=bool)
    joined[1:] = candidate[1:] & candidate[:-1] & (sign[1:] == sign[:-1])
    starts, ends, ids = _segments(joined)
    last = index.size - 1
    returns = (candidate[starts] & (ends - starts + 1 <= SPIKE_MAX_SAMPLES)
               & (starts > 0) & (ends < last)
               & ~candidate[np.maximum(starts - 1, 0)] & ~candidate[np.minimum(ends + 1, last)])
    out[index] = returns[ids] & candidate
    return out, scale


def _rolling_median(x: np.ndarray, window: int) -> np.ndarray:
    """Centred rolling median over ``window`` samples, windows truncated at the ends."""
    trend = median_filter(x, size=window, mode="nearest")
    half = min(window // 2, x.size)
    edges = np.unique(np.r_[np.arange(half), np.arange(x.size - half, x.size)])
    padded = np.concatenate([np.full(window // 2, np.nan), x, np.full(window // 2, np.nan)])
    trend[edges] = np.nanmedian(padded[edges[:, None] + np.arange(window)], axis=1)
    return trend


def _segments(mask_continue: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments of samples where ``mask_continue[i]`` says i continues i − 1's segment."""
    starts = np.flatnonzero(~mask_continue)
    ends = np.r_[starts[1:] - 1, mask_continue.size - 1]
    ids = np.cumsum(~mask_continue) - 1
    return starts, ends, ids


# --------------------------------------------------------------------------------------------
# findings


def _time_label(label: Any, is_datetime: bool) -> Any:
    return pd.Timestamp(label) if is_datetime else float(label)


def _time_text(value: Any) -> str:
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    return f"t = {value:g} s"


def _json_time(value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    return float(value)


def _json_value(value: Any) -> Any:
    if isinstance(value, pd.Timestamp):
        return value.isoformat()
    if isinstance(value, np.integer | bool | np.bool_):
        return value.item() if not isinstance(value, bool) else value
    if isinstance(value, float | np.floating):
        return None if not math.isfinite(float(value)) else float(value)
    if isinstance(value, list | tuple):
        return [_json_value(v) for v in value]
    return value


def _unit_of(signal: str | None, options: _Options) -> tuple[str, str]:
    """(display unit, SI unit) of a signal; display = declared, else wire unit, else none."""
    if signal in SIGNALS:
        si = SIGNALS[signal].si_unit
        return options.declared.get(signal, SIGNALS[signal].wire_unit), si
    return "", ""


def _show(value: float, signal: str | None, options: _Options, *, delta: bool = False) -> str:
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


class _Where:
    """Builds findings for one signal (or the index) with source, tag, row and time."""

    def __init__(self, a: _Analysis, options: _Options, signal: str | None) -> None:
        self.a, self.options, self.signal = a, options, signal
        self.tag = options.tags.get(signal) if signal is not None else None

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
        at = "" if row is None else f"; first at data row {row + 1} ({_time_text(time)})"
        message = f"{self.name}: {f'{count} ' if counted else ''}{text}{at}"
        return Finding(kind, severity, self.signal, self.tag, int(count), row, time, message,
                       action, tuple(details.items()))

    def first(self, mask: np.ndarray) -> tuple[int | None, Any]:
        """First (in time) masked kept row: its as-read position and time."""
        if not mask.any():
            return None, None
        i = int(np.argmax(mask))
        return int(self.a.rows[i]), _time_label(self.a.labels[i], self.a.is_datetime)

    def finding(self, kind: str, severity: Severity, mask: np.ndarray, text: str,
                action: Action = "detected", **details: Any) -> Finding:
        return self.make(kind, severity, int(mask.sum()), *self.first(mask), text, action,
                         **details)


def _detection_findings(a: _Analysis, options: _Options) -> list[Finding]:
    out: list[Finding] = []
    index = _Where(a, options, None)
    for name in a.missing_required:
        where = _Where(a, options, name)
        unit = (f"{SIGNALS[name].wire_unit} (SI {SIGNALS[name].si_unit})"
                if name in SIGNALS else "its unit")
        out.append(where.make(
            "missing_signal", "error", 1, None, None,
            f"required signal is missing from the data (expected a column in {unit})",
            counted=False,
        ))
    for name in a.non_numeric:
        out.append(_Where(a, options, name).make(
            "not_numeric", "warning", a.n, None, None,
            "value(s) are not numeric; column not checked",
        ))
    if a.backwards:
        row = a.first_backwards
        out.append(index.make(
            "unsorted", "warning", a.backwards, row,
            _time_label(a.raw_labels[row], a.is_datetime),
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
            + ", ".join(_Where(a, options, name).label for name in a.conflict_signals),
            signals=a.conflict_signals,
        ))
    if a.gaps.size:
        largest = int(np.argmax(a.gap_steps_s))
        i = int(a.gaps[largest])
        missing_s = float((a.gap_steps_s - a.step_s).sum())
        start = _time_label(a.labels[i], a.is_datetime)
        mask = np.zeros(len(a.rows), dtype=bool)
        mask[a.gaps] = True
        out.append(index.finding(
            "gap", "warning", mask,
            f"gap(s) longer than {options.gap_factor:g} × the {a.step_s:g} s step, "
            f"{missing_s:g} s missing in total; largest {a.gap_steps_s[largest]:g} s from "
            f"{_time_text(start)} (data row {int(a.rows[i]) + 1})",
            missing_s=missing_s, largest_gap_s=float(a.gap_steps_s[largest]),
            largest_gap_start=start, step_s=a.step_s,
        ))
    for name, col in a.columns.items():
        out.extend(_signal_findings(a, options, name, col))
    out.extend(_unit_findings(a, options))
    return out


def _signal_findings(a: _Analysis, options: _Options, name: str, col: _Column) -> list[Finding]:
    out: list[Finding] = []
    where = _Where(a, options, name)
    n_valid = int((~col.nan).sum())
    if col.nan.any():
        starts, ends, _ = _segments(np.r_[False, col.nan[1:] & col.nan[:-1]])
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
        severity = "error" if fraction > options.oor_error_fraction else "warning"
        out.append(where.finding(
            "out_of_range", severity, col.out_of_range,
            f"value(s) ({fraction:.2%}) outside the physical range {_show(lo, name, options)} "
            f"… {_show(hi, name, options)}; seen {_show(float(bad.min()), name, options)} … "
            f"{_show(float(bad.max()), name, options)}",
            low=lo, high=hi, min=float(bad.min()), max=float(bad.max()), fraction=fraction,
        ))
    if col.bad.any():
        fraction = int(col.bad.sum()) / max(col.values.size, 1)
        severity = "error" if fraction > options.oor_error_fraction else "warning"
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
            f"{options.n_sigmas:g} × {_show(col.spike_scale, name, options, delta=True)} "
            f"(noise scale) and beyond the physical rate limit "
            f"{_show(col.max_rate, name, options, delta=True)}/s × step from the "
            f"{options.window}-sample rolling median; first value "
            f"{_show(float(col.values[i]), name, options)}",
            noise_scale=col.spike_scale, n_sigmas=options.n_sigmas, max_rate=col.max_rate,
        ))
    if col.stuck.any():
        out.append(where.finding(
            "stuck", "warning", col.stuck,
            f"sample(s) in {col.stuck_runs} stuck run(s) (value exactly repeated for at least "
            f"{options.stuck_s:g} s, fewer than {STUCK_CHANCE_RUNS_PER_DAY:g} such runs per day "
            f"expected by chance with {noise}), {col.stuck_duration_s:g} s in total",
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


def _unit_findings(a: _Analysis, options: _Options) -> list[Finding]:
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
        band = (_STEAM_RATE[0] * medians["load"], _STEAM_RATE[1] * medians["load"])
        finding = _unit_check(a, options, "main_steam_flow", medians["main_steam_flow"], band,
                              f"steam-rate (2.5–4.0 kg/kWh × load {medians['load'] / 1e6:.4g} MW)")
        if finding is not None and finding.kind == "unit":
            out.append(finding)
    return out


def _unit_check(a: _Analysis, options: _Options, name: str, median: float,
                band: tuple[float, float], label: str) -> Finding | None:
    lo, hi = band
    if lo <= median <= hi:
        return None
    si = SIGNALS[name].si_unit
    declared = options.declared.get(name, si)
    where = _Where(a, options, name)
    expected = f"{_show(lo, name, options)} … {_show(hi, name, options)}"
    try:
        raw = float(convert(median, si, declared))
    except Exception:
        raw, declared = median, si
    centre = math.sqrt(lo * hi)
    best: tuple[float, str, float] | None = None
    for unit in _CANDIDATE_UNITS.get(si, ()):
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
