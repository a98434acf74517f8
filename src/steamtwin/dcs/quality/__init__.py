"""Data-quality check and cleaning of DCS (historian) data in canonical SI signals.

Rule: **nothing is dropped or invented silently.** :func:`check_quality` finds problems in a frame
as read (possibly unsorted, with duplicate timestamps and gaps); :func:`clean` repairs or rejects
what it safely can and flags and counts every sample it touched. Cleaning never interpolates and
never fills a gap; resampling is a later, separate, explicit step.

Every setting named below (ranges, units, tags, detector parameters) is a field of one
:class:`QualityOptions`, built and validated once and passed to both functions.

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

from steamtwin.dcs.quality.cleaning import check_quality, clean
from steamtwin.dcs.quality.detectors import estimate_noise_sigma, estimate_resolution
from steamtwin.dcs.quality.limits import (
    MAX_RATES,
    SPIKE_MAX_SAMPLES,
    STUCK_CHANCE_RUNS_PER_DAY,
    TYPICAL_RANGES,
)
from steamtwin.dcs.quality.options import QualityOptions
from steamtwin.dcs.quality.report import CleaningResult, Finding, Flag, QualityReport

__all__ = [
    "MAX_RATES",
    "SPIKE_MAX_SAMPLES",
    "STUCK_CHANCE_RUNS_PER_DAY",
    "TYPICAL_RANGES",
    "CleaningResult",
    "Finding",
    "Flag",
    "QualityOptions",
    "QualityReport",
    "check_quality",
    "clean",
    "estimate_noise_sigma",
    "estimate_resolution",
]
