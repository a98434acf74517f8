"""Figure 10 analogue: monitored vs measured HP-exhaust temperature over validation windows.

One column per window: the upper panel shows measured and monitored temperature (°C), the
lower one the deviation monitored − measured (K), against minutes from the window's first
sample; each column is titled with the window's name and its start and end in the time zone of
its index (the data's own, see :func:`window_label`). Samples the ROM could not predict (NaN)
leave gaps. Drawn on a bare :class:`matplotlib.figure.Figure` (Agg canvas, no pyplot state),
written as PNG.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from steamtwin.units import convert

__all__ = ["exhaust_tracking_figure", "window_label"]

_LABELS = {"hp_exhaust_temperature": "HP-exhaust steam temperature",
           "control_stage_temperature": "control-stage steam temperature",
           "hp_inner_casing_temperature": "inner-casing metal temperature"}


def window_label(name: str, index: pd.Index) -> str:
    """``"<name>, <start> … <end>"`` with ISO times in the index's own zone (e.g. +08:00)."""
    if not isinstance(index, pd.DatetimeIndex) or len(index) == 0:
        return name
    start, end = index[0], index[-1]
    end_text = (end.strftime("%H:%M") if end.date() == start.date()
                else end.isoformat(timespec="minutes"))
    return f"{name}, {start.isoformat(timespec='minutes')} … {end_text}"


def exhaust_tracking_figure(measured: Mapping[str, pd.DataFrame],
                            monitored: Mapping[str, pd.DataFrame], path: str | Path,
                            title: str = "", *,
                            signal: str = "hp_exhaust_temperature") -> Path:
    """Write the tracking figure of ``signal`` (K in the frames) for each window to ``path``.

    ``measured`` and ``monitored`` map the same window names (e.g. "30 % load", "50 % load")
    to canonical SI frames on the same time index.
    """
    if not measured:
        raise ValueError("no windows given")
    if list(measured) != list(monitored):
        raise ValueError(f"measured windows {list(measured)} and monitored windows "
                         f"{list(monitored)} differ")
    path = Path(path)
    figure = Figure(figsize=(5.5 * len(measured), 6.0))
    axes = figure.subplots(2, len(measured), sharex="col", squeeze=False,
                           gridspec_kw={"height_ratios": (2, 1)})
    label = _LABELS.get(signal, signal.replace("_", " "))
    for column, (name, truth) in enumerate(measured.items()):
        model = monitored[name]
        for kind, frame in (("measured", truth), ("monitored", model)):
            if signal not in frame.columns:
                raise ValueError(f"window {name!r}: the {kind} data lack {signal!r}")
        if len(truth) == 0:
            raise ValueError(f"window {name!r} holds no sample")
        if not truth.index.equals(model.index):
            raise ValueError(f"window {name!r}: measured and monitored data are not on the "
                             "same time index")
        minutes = (truth.index - truth.index[0]).total_seconds() / 60.0
        measured_degc = convert(truth[signal].to_numpy(dtype=float), "K", "degC")
        monitored_degc = convert(model[signal].to_numpy(dtype=float), "K", "degC")
        deviation = monitored_degc - measured_degc
        top, bottom = axes[0, column], axes[1, column]
        top.plot(minutes, measured_degc, color="0.45", lw=0.7, label="measured (DCS)")
        top.plot(minutes, monitored_degc, color="tab:red", lw=1.2, label="monitored (twin)")
        top.set_title(window_label(name, truth.index), fontsize=9)
        top.set(ylabel=f"{label} (°C)")
        top.legend(loc="best", fontsize=8)
        bottom.plot(minutes, deviation, color="tab:blue", lw=0.8)
        bottom.axhline(0.0, color="black", lw=0.6)
        finite = np.abs(deviation[np.isfinite(deviation)])
        if finite.size:
            bottom.set_title(f"mean |Δ| {finite.mean():.2f} K, max |Δ| {finite.max():.2f} K",
                             fontsize=9)
        bottom.set(xlabel="time (min)", ylabel="monitored − measured (K)")
        for axis in (top, bottom):
            axis.grid(alpha=0.3)
    figure.suptitle(title or f"Monitored vs measured {label} (Figure 10)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    return path
