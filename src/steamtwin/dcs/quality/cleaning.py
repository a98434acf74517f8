"""The data-quality check and cleaning of a frame: :func:`check_quality` and :func:`clean`."""

from __future__ import annotations

import numpy as np
import pandas as pd

from steamtwin.dcs.quality.detectors import Analysis, analyse
from steamtwin.dcs.quality.messages import Where, detection_findings, unit_findings
from steamtwin.dcs.quality.options import QualityOptions
from steamtwin.dcs.quality.report import CleaningResult, Finding, Flag, QualityReport


def check_quality(frame: pd.DataFrame, options: QualityOptions | None = None) -> QualityReport:
    """Check DCS data in SI units on a time index; nothing is changed.

    ``frame``: one column per canonical signal (SI: Pa, K, kg/s, W) on a time index, as read
    (possibly unsorted, with duplicate timestamps and gaps). ``options``: the ranges, units,
    tags and detector settings (:class:`QualityOptions`; None: the defaults). See the module
    docstring of :mod:`steamtwin.dcs.quality` for what is found and why.
    """
    options = _options_or_default(options)
    analysis = analyse(frame, options)
    return QualityReport(
        tuple(detection_findings(analysis, options)), options.source, len(frame),
        analysis.signals,
    )


def clean(frame: pd.DataFrame, options: QualityOptions | None = None, *,
          report: QualityReport | None = None, reject_stuck: bool = True) -> CleaningResult:
    """Sort, de-duplicate and reject bad samples (→ NaN), flagging and counting every change.

    Exact duplicate rows are removed; of conflicting duplicates the first row as read is kept.
    Spikes, out-of-range values, samples the historian marked bad (``options.bad_quality``) and
    stuck runs (unless ``reject_stuck=False``) become NaN, and so does every sample of a signal
    with an error-level unit finding. Nothing is interpolated. ``frame`` and ``options`` as in
    :func:`check_quality`. ``report``: a :func:`check_quality` report of this same frame,
    carried into the result instead of rebuilding the detection findings (the per-sample masks
    are always recomputed with ``options``).
    """
    options = _options_or_default(options)
    analysis = analyse(frame, options)
    if report is not None and report.n_rows != len(frame):
        raise ValueError(
            f"{options.source or 'clean'}: the report is for {report.n_rows} rows, the frame "
            f"has {len(frame)}; pass the report of this frame or none"
        )
    detected = (
        list(report.findings) if report is not None else detection_findings(analysis, options)
    )
    a = analysis
    flags, removed = _flag_codes(a, frame.columns, options, reject_stuck)
    data = frame.iloc[a.rows].copy()
    actions: list[Finding] = []
    for name, col in a.columns.items():
        remove, stuck, unit = removed[name]
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
    full = QualityReport(tuple(detected + actions), options.source, len(frame), a.signals)
    return CleaningResult(data, flags_frame, full, a.rows.copy())


def clean_flags(frame: pd.DataFrame, options: QualityOptions, *, reject_stuck: bool = True
                ) -> tuple[np.ndarray, np.ndarray]:
    """What :func:`clean` does to each sample, without its findings: the as-read positions of
    the rows kept (sorted, de-duplicated) and their :class:`Flag` bits (rows × columns,
    uint16; ``Flag.REMOVED`` where :func:`clean` writes NaN). For a caller that builds its own
    findings (the live gate, :mod:`steamtwin.live.gate`) and needs the masks only."""
    options = _options_or_default(options)
    analysis = analyse(frame, options)
    flags, _ = _flag_codes(analysis, frame.columns, options, reject_stuck)
    return analysis.rows.copy(), flags


def _flag_codes(a: Analysis, columns: pd.Index, options: QualityOptions, reject_stuck: bool
                ) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Flag bits per kept row and column, and per checked signal its (removed, stuck
    rejected, unit rejected) masks: spikes, out-of-range values, bad statuses, stuck runs
    (unless ``reject_stuck`` is False) and every sample of a signal with an error-level unit
    finding are removed."""
    unit_errors = {f.signal for f in unit_findings(a, options)
                   if f.kind == "unit" and f.severity == "error"}
    flags = np.zeros((len(a.rows), len(columns)), dtype=np.uint16)
    common = (a.kept_has_dup.astype(np.uint16) * np.uint16(Flag.DUPLICATE)) | (
        a.kept_late.astype(np.uint16) * np.uint16(Flag.OUT_OF_ORDER)
    )
    position = {name: j for j, name in enumerate(columns)}
    for name in columns:
        flags[:, position[name]] |= common
    removed = {}
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
        removed[name] = (remove, stuck, unit)
    return flags, removed


def _options_or_default(options: QualityOptions | None) -> QualityOptions:
    if options is None:
        return QualityOptions()
    if not isinstance(options, QualityOptions):
        raise TypeError("options must be a steamtwin.dcs.quality.QualityOptions (got "
                        f"{type(options).__name__}); build it with QualityOptions(ranges=…, …)")
    return options
