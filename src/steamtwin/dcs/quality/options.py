"""The settings of one data-quality check (:class:`QualityOptions`, validated once)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from steamtwin.dcs.quality.limits import MAX_RATES


@dataclass(frozen=True)
class QualityOptions:
    """Every setting of one check, validated once by :meth:`make` from the keyword arguments
    of :func:`~steamtwin.dcs.quality.check_quality` / :func:`~steamtwin.dcs.quality.clean`
    (their docstrings give the meaning and unit of each): SI ranges, declared units, tags,
    the nominal step (s), the gap factor, the spike window (samples) and k, the shortest stuck
    run (s), the out-of-range error share, per-signal noise, resolution and rate limit (SI),
    and the historian's bad-quality masks."""

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
             bad) -> QualityOptions:  # type: ignore[no-untyped-def]
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
