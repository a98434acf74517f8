"""The data-quality check and cleaning of a frame: :func:`check_quality` and :func:`clean`."""

from __future__ import annotations

from collections.abc import Collection, Mapping

import numpy as np
import pandas as pd

from steamtwin.dcs.quality.detectors import analyse
from steamtwin.dcs.quality.messages import Where, detection_findings, unit_findings
from steamtwin.dcs.quality.options import QualityOptions
from steamtwin.dcs.quality.report import CleaningResult, Finding, Flag, QualityReport


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
    options = QualityOptions.make(
        required, ranges, declared_units, tag_names, source, nominal_step_s, gap_factor,
        spike_window, spike_n_sigmas, stuck_min_duration_s, out_of_range_error_fraction,
        noise_si, resolution_si, max_rate_si, bad_quality,
    )
    analysis = analyse(frame, options)
    return QualityReport(
        tuple(detection_findings(analysis, options)), source, len(frame), analysis.signals
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
    options = QualityOptions.make(
        required, ranges, declared_units, tag_names, source, nominal_step_s, gap_factor,
        spike_window, spike_n_sigmas, stuck_min_duration_s, out_of_range_error_fraction,
        noise_si, resolution_si, max_rate_si, bad_quality,
    )
    analysis = analyse(frame, options)
    if report is not None and report.n_rows != len(frame):
        raise ValueError(
            f"{source or 'clean'}: the report is for {report.n_rows} rows, the frame has "
            f"{len(frame)}; pass the report of this frame or none"
        )
    detected = (
        list(report.findings) if report is not None else detection_findings(analysis, options)
    )
    unit_errors = {f.signal for f in unit_findings(analysis, options)
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
        where = Where(a, options, name)
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
    index_where = Where(a, options, None)
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
