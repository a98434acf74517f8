"""Calibration windows from one or several historian files, weighted so that no load dominates.

Which windows (:func:`find_calibration_windows`; the rule is
:func:`steamtwin.dcs.windows.find_windows`, the same for validation, with each window then cut
around input dropouts a calibration cannot fill, :func:`split_at_input_dropouts`)
    *Steady* windows: every steady-load span of at least ``min_steady_s`` (default 1 h;
    :func:`steamtwin.dcs.windows.find_steady_windows`), at every load, cut to its last
    ``max_steady_s`` (default 2 h; the start of a hold still carries the ramp's transient,
    which the ramp windows hold). They see the flow and friction coefficients.
    *Ramp* windows: every stretch between two steady spans (or before the first / after the
    last) in which the load moves by at least ``ramp_min_change`` of rated (default 5 %),
    widened by ``ramp_before_s`` (600 s) before and ``ramp_after_s`` (1800 s) after. While the
    steam temperature changes, the metal lags it by its storage time constant m·c/(h·A), and
    only then does the heat-transfer coefficient show in the casing-metal and steam
    temperatures (Incropera & DeWitt, lumped capacitance, §5.2); the half hour after the ramp
    holds the metal's settling, a few of the HP casing's time constants.

How they are weighted (:meth:`WindowSet.sample_weights`)
    Windows fall into *bands*: steady windows by load, ``band_width`` (10 % of rated) wide,
    every ramp window into one band "ramps". Each band together weighs the same, as much as one
    window of average length (n_ref = the mean over bands of the band's mean window length):
    each sample of a window in band b weighs ω = n_ref / N_b, N_b the band's samples. Reasons:
    a twin's residual at one load is dominated by its model bias there, which repeats in every
    window at that load — ten windows at 50 % are not ten times the evidence, and unweighted
    they would make the fit hide the 50 % bias at the other loads' expense (the issue's
    friction coefficient bent to 0.9 by part load). Counting each band as one window keeps the
    likelihood from treating a repeated bias as independent evidence, and duplicating a band's
    windows changes nothing (N_b doubles with the same residuals; n_ref stays). With one
    window per band of equal length every ω is 1: the plain Gaussian likelihood.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from steamtwin.calibration.settings import MAX_INPUT_GAP_S, MIN_WINDOW_SAMPLES
from steamtwin.dcs.windows import find_windows, load_fraction, select_window
from steamtwin.model.simulator import INPUT_SIGNALS

__all__ = [
    "RAMP_BAND",
    "CalibrationWindow",
    "WindowSet",
    "WindowSource",
    "find_calibration_windows",
    "given_windows",
    "joint_window_set",
    "measurement_sigma",
    "split_at_input_dropouts",
]

RAMP_BAND = "ramps"
"""Band label of every ramp window."""


@dataclass(frozen=True)
class CalibrationWindow:
    """One window: ``data`` (canonical SI signals on a time index), ``kind`` ("steady",
    "ramp" or "given"), ``load_fraction`` (mean load / rated, NaN without load), ``source``
    (the file it came from) and ``sigma`` (measurement error per sensor in K, from that file's
    tag map; None = the calibration's default)."""

    data: pd.DataFrame
    kind: str = "given"
    load_fraction: float = float("nan")
    source: str = ""
    sigma: Mapping[str, float] | None = None

    @property
    def name(self) -> str:
        """Human label: source, kind, load and time span (names the file in errors)."""
        load = "" if np.isnan(self.load_fraction) else f" {100 * self.load_fraction:.0f} %"
        where = f"{self.source}: " if self.source else ""
        index = self.data.index
        span = f" {index[0]} … {index[-1]}" if len(index) else ""
        return f"{where}{self.kind}{load}{span}"


@dataclass(frozen=True)
class WindowSet:
    """Windows of one joint calibration and their load-band weights (module docstring).

    Iterates over its :class:`CalibrationWindow` s; ``band_width``: steady-load band width
    (fraction of rated).
    """

    windows: tuple[CalibrationWindow, ...]
    band_width: float = 0.10

    def __post_init__(self) -> None:
        if not self.windows:
            raise ValueError("a window set needs at least one window")
        if not 0.0 < self.band_width <= 1.0:
            raise ValueError(f"band_width must be a fraction of rated in (0, 1] "
                             f"(got {self.band_width!r})")

    def __iter__(self) -> Iterator[CalibrationWindow]:
        return iter(self.windows)

    def __len__(self) -> int:
        return len(self.windows)

    def bands(self) -> list[str]:
        """Band label of each window: "ramps", "<lo>–<hi> %" of rated, or "no load"."""
        labels = []
        for window in self.windows:
            if window.kind == "ramp":
                labels.append(RAMP_BAND)
            elif np.isnan(window.load_fraction):
                labels.append("no load")
            else:
                k = int(np.floor(window.load_fraction / self.band_width + 1e-9))
                labels.append(f"{100 * k * self.band_width:.0f}–"
                              f"{100 * (k + 1) * self.band_width:.0f} %")
        return labels

    def sample_weights(self) -> np.ndarray:
        """Weight ω of each sample, per window (dimensionless; module docstring)."""
        labels = self.bands()
        lengths = np.array([len(w.data) for w in self.windows], dtype=float)
        totals = {b: lengths[[lab == b for lab in labels]].sum() for b in set(labels)}
        counts = {b: labels.count(b) for b in set(labels)}
        reference = float(np.mean([totals[b] / counts[b] for b in totals]))
        return np.array([reference / totals[lab] for lab in labels])

    def summary(self) -> pd.DataFrame:
        """One row per window: name, kind, band, load (%), samples, weight per sample."""
        return pd.DataFrame({
            "window": [w.name for w in self.windows], "kind": [w.kind for w in self.windows],
            "band": self.bands(), "load_pct": [100 * w.load_fraction for w in self.windows],
            "samples": [len(w.data) for w in self.windows], "weight": self.sample_weights()})


def given_windows(frames: Sequence[pd.DataFrame], rated_load_w: float, *, source: str = "",
                  sigma: Mapping[str, float] | None = None) -> list[CalibrationWindow]:
    """Windows chosen by hand (kind "given"), banded by their mean load."""
    return [CalibrationWindow(f, "given", load_fraction(f, rated_load_w), source, sigma)
            for f in frames]


def find_calibration_windows(
    data: pd.DataFrame, rated_load_w: float, *, source: str = "",
    sigma: Mapping[str, float] | None = None, min_steady_s: float = 3600.0,
    max_steady_s: float = 7200.0, tolerance: float = 0.02, ramp_min_change: float = 0.05,
    ramp_before_s: float = 600.0, ramp_after_s: float = 1800.0,
) -> list[CalibrationWindow]:
    """Steady windows at every load and ramp windows of one file (module docstring), in time
    order. ``data``: canonical SI signals with ``load`` (W) on a DatetimeIndex;
    ``rated_load_w`` (W); durations in s; ``tolerance`` and ``ramp_min_change`` fractions of
    rated. ValueError naming ``source`` if the data have no load signal."""
    result = []
    for window in find_windows(data, rated_load_w, min_steady_s=min_steady_s,
                               max_steady_s=max_steady_s, tolerance=tolerance,
                               ramp_min_change=ramp_min_change, ramp_before_s=ramp_before_s,
                               ramp_after_s=ramp_after_s, source=source):
        result.extend(CalibrationWindow(
            piece, window.kind, window.load_fraction if window.kind == "steady"
            else load_fraction(piece, rated_load_w), source, sigma)
            for piece in split_at_input_dropouts(window.data))
    return sorted(result, key=lambda w: w.data.index[0])


def split_at_input_dropouts(frame: pd.DataFrame, max_gap_s: float = MAX_INPUT_GAP_S,
                            min_samples: int = MIN_WINDOW_SAMPLES) -> list[pd.DataFrame]:
    """``frame`` cut around every stretch in which a model input (the quality gate's NaN) is
    missing for longer than ``max_gap_s`` (s) — what a calibration cannot fill forward
    (:data:`~steamtwin.calibration.objective.MAX_INPUT_GAP_S`) — keeping the pieces of at
    least ``min_samples`` rows (a calibration window's least); shorter dropouts stay for the
    calibration to fill and count. A frame without such a dropout comes back whole."""
    inputs = [name for name in INPUT_SIGNALS if name in frame.columns]
    if frame.empty or not inputs:
        return [frame]
    missing = frame[inputs].isna().any(axis=1).to_numpy()
    seconds = (frame.index - frame.index[0]) / pd.Timedelta(seconds=1)
    seconds = np.asarray(seconds, dtype=float)
    cut = np.zeros(len(frame), dtype=bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], missing.astype(np.int8), [0]])))
    for first, stop in zip(edges[0::2], edges[1::2], strict=True):
        # as the calibration measures a dropout: its last row against the last valid one
        # (leading missing rows the calibration drops itself, and counts)
        if first > 0 and seconds[stop - 1] - seconds[first - 1] > max_gap_s:
            cut[first:stop] = True
    if not cut.any():
        return [frame]
    pieces = []
    labels = np.cumsum(np.diff(np.concatenate([[True], cut])) != 0)
    for label in np.unique(labels[~cut]):
        piece = frame.iloc[np.flatnonzero((labels == label) & ~cut)]
        if len(piece) >= min_samples:
            pieces.append(piece)
    return pieces


def measurement_sigma(noise: Mapping[str, float | None], resolution: Mapping[str, float | None]
                      ) -> dict[str, float]:
    """Measurement error σ (K) per signal from a tag map's white noise σ and resolution Δ (K):
    ``σ² = noise² + Δ²/12`` (rounding to Δ adds uniform noise of variance Δ²/12; Widrow &
    Kollár 2008, *Quantization Noise*, ch. 4). Signals with neither are left out (the
    calibration's default applies)."""
    result = {}
    for name in set(noise) | set(resolution):
        n, d = noise.get(name), resolution.get(name)
        if n is None and d is None:
            continue
        result[name] = float(np.sqrt((n or 0.0) ** 2 + (d or 0.0) ** 2 / 12.0))
    return {name: value for name, value in result.items() if value > 0}


@dataclass(frozen=True)
class WindowSource:
    """One historian file of a joint calibration: ``name`` (its path, for messages), ``data``
    (cleaned canonical SI signals) and ``sigma`` (measurement error per sensor in K, or None)."""

    name: str
    data: pd.DataFrame
    sigma: Mapping[str, float] | None = None


def joint_window_set(sources: Sequence[WindowSource], rated_load_w: float, *,
                     given: Sequence[tuple[pd.Timestamp, pd.Timestamp]] = (),
                     ramps: bool = True, band_width: float = 0.10,
                     **search: float) -> WindowSet:
    """The windows of several files as one :class:`WindowSet`.

    ``given`` (START, END) windows are taken from every file that covers them (ValueError
    naming the window and each file's span if none does); without them every file is searched
    (:func:`find_calibration_windows` with ``search``'s durations/tolerances), ramps dropped
    when ``ramps`` is False. ValueError naming the file when a file yields no window.
    """
    if not sources:
        raise ValueError("no historian file given")
    windows: list[CalibrationWindow] = []
    for start, end in given:
        found = [s for s in sources if len(s.data) and s.data.index[0] <= start
                 and end <= s.data.index[-1] + pd.Timedelta(seconds=1)]
        if not found:
            spans = "; ".join(f"{s.name}: {s.data.index[0]} … {s.data.index[-1]}"
                              for s in sources)
            raise ValueError(f"window {start}/{end} lies in none of the files ({spans})")
        for source in found:
            frame = select_window(source.data, start, end)
            windows.extend(given_windows([frame], rated_load_w, source=source.name,
                                         sigma=source.sigma))
    if not given:
        for source in sources:
            found = find_calibration_windows(source.data, rated_load_w, source=source.name,
                                             sigma=source.sigma, **search)
            if not ramps:
                found = [w for w in found if w.kind != "ramp"]
            if not found:
                raise ValueError(
                    f"{source.name}: no steady window of at least "
                    f"{search.get('min_steady_s', 3600.0) / 60:g} min and no load ramp found; "
                    "pass --window START/END or a shorter --min-steady-minutes")
            windows.extend(found)
    return WindowSet(tuple(windows), band_width)
