"""The settings of one data-quality check (:class:`QualityOptions`, validated once)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from steamtwin.dcs.quality.limits import MAX_RATES


@dataclass(frozen=True, eq=False)
class QualityOptions:
    """Every setting of one :func:`~steamtwin.dcs.quality.check_quality` /
    :func:`~steamtwin.dcs.quality.clean`, validated when built (``ValueError`` naming the
    option, the source and the expected unit). The defaults are the method's (module docstring
    of :mod:`steamtwin.dcs.quality`); change one with :func:`dataclasses.replace`.

    ``required``: signals that must be present and not all NaN (an error otherwise).
    ``ranges``: physical validity limits per signal in SI (Pa, K, kg/s, W).
    ``declared_units``: the units the historian declared (e.g. ``{"main_steam_pressure":
    "MPa"}``; SI assumed if absent). ``tag_names``: signal → historian tag, for the messages.
    ``source``: the file or stream named in every message.
    ``nominal_step_s``: the sampling step (s; None: the median step). ``gap_factor``: a step
    longer than this × the nominal step is a gap (> 1). ``spike_window`` (odd, ≥ 3 samples)
    and ``spike_n_sigmas`` (k > 0) set the spike detector; ``stuck_min_duration_s`` (s, > 0)
    is the shortest run reported as stuck. ``out_of_range_error_fraction``: the share of a
    signal's samples out of range or marked bad above which that is an error, not a warning.
    ``noise_si``: white-noise σ per signal (SI, before quantisation; estimated when absent);
    ``resolution_si``: quantum per signal (SI; estimated when absent); ``max_rate_si``:
    physical rate limit per signal (SI per s; overrides :data:`~steamtwin.dcs.quality.MAX_RATES`
    in :attr:`rate_limits`). ``bad_quality``: per signal, a 1-D boolean mask over the frame's
    rows as read of samples the historian's quality column marked bad or uncertain.

    Compared by identity (``eq=False``): the masks are arrays.
    """

    required: tuple[str, ...] = ()
    ranges: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    declared_units: Mapping[str, str] = field(default_factory=dict)
    tag_names: Mapping[str, str] = field(default_factory=dict)
    source: str = ""
    nominal_step_s: float | None = None
    gap_factor: float = 3.0
    spike_window: int = 61
    spike_n_sigmas: float = 4.5
    stuck_min_duration_s: float = 30.0
    out_of_range_error_fraction: float = 0.01
    noise_si: Mapping[str, float] = field(default_factory=dict)
    resolution_si: Mapping[str, float] = field(default_factory=dict)
    max_rate_si: Mapping[str, float] = field(default_factory=dict)
    bad_quality: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = self.source or "quality check"
        window = self.spike_window
        if int(window) != window or window < 3 or window % 2 == 0:
            raise ValueError(f"{where}: spike_window must be an odd number ≥ 3 of samples, "
                             f"got {window}")
        if not (self.spike_n_sigmas > 0 and self.gap_factor > 1
                and self.stuck_min_duration_s > 0):
            raise ValueError(f"{where}: spike_n_sigmas must be > 0, gap_factor > 1 and "
                             "stuck_min_duration_s > 0 s (got "
                             f"{self.spike_n_sigmas}, {self.gap_factor}, "
                             f"{self.stuck_min_duration_s})")
        if self.nominal_step_s is not None and not self.nominal_step_s > 0:
            raise ValueError(f"{where}: nominal_step_s must be > 0 s, got {self.nominal_step_s}")
        if not 0.0 <= self.out_of_range_error_fraction <= 1.0:
            raise ValueError(f"{where}: out_of_range_error_fraction must lie within [0, 1], "
                             f"got {self.out_of_range_error_fraction}")
        per_signal = {option: _checked_numbers(where, option, getattr(self, option))
                      for option in ("noise_si", "resolution_si", "max_rate_si")}
        masks: dict[str, np.ndarray] = {}
        for name, mask in dict(self.bad_quality or {}).items():
            array = np.asarray(mask)
            if array.ndim != 1 or array.dtype != np.bool_:
                raise ValueError(f"{where}: bad_quality[{name!r}] must be a 1-D boolean mask "
                                 f"over the rows as read, got dtype {array.dtype}, "
                                 f"shape {array.shape}")
            masks[str(name)] = array
        normalised = {
            "required": tuple(self.required), "ranges": dict(self.ranges or {}),
            "declared_units": dict(self.declared_units or {}),
            "tag_names": dict(self.tag_names or {}), "spike_window": int(window),
            "spike_n_sigmas": float(self.spike_n_sigmas),
            "stuck_min_duration_s": float(self.stuck_min_duration_s),
            "out_of_range_error_fraction": float(self.out_of_range_error_fraction),
            "bad_quality": masks, **per_signal}
        for name, value in normalised.items():
            object.__setattr__(self, name, value)

    @property
    def rate_limits(self) -> dict[str, float]:
        """Physical rate limit per signal (SI per s): :data:`MAX_RATES` with ``max_rate_si``."""
        return {**MAX_RATES, **self.max_rate_si}


def _checked_numbers(where: str, option: str, mapping: Mapping[str, float] | None
                     ) -> dict[str, float]:
    checked: dict[str, float] = {}
    for name, value in dict(mapping or {}).items():
        number = float(value)
        if not (math.isfinite(number) and number >= 0.0):
            raise ValueError(f"{where}: {option}[{name!r}] must be a finite number ≥ 0 in SI "
                             f"units, got {value!r}")
        checked[str(name)] = number
    return checked
