"""The rotor stress and life report: files, figures and tables of ``steamtwin rotor stress``.

:func:`rotor_stress` is the command's one library call: it fits a
:class:`~steamtwin.rotor.model.RotorModel` to the turbine spec (with the twin's parameters),
runs its transient ROM over each cleaned historian record (the metal starting in equilibrium
with the first sample; a record that follows the previous one within :data:`CONTIGUOUS_GAP_S`
carries its state on), counts the life with :func:`~steamtwin.rotor.life.rotor_life` and writes
(:func:`write_rotor_report`):

* ``rotor_stress.parquet`` and ``rotor_stress.csv``: the run's time series (SI: K, Pa), one row
  per input sample;
* ``rotor_cycles.csv``: the rainflow cycles at the groove with their damage;
* ``rotor_life.json``: the life summary, per ramp and per day;
* ``report.html`` (+ ``report.json`` and one CSV per table, :class:`ValidationReport`): the
  summary (peak groove stress against the allowable), the life table, then the figures —
  stress vs time with the allowable, groove/bore and steam temperature, the rainflow matrix
  (range × mean, cycles counted), life consumed per ramp.

**Allowable.** Given by the user (``allowable_pa``), it bounds the peak von Mises stress at
the groove root. Without one it is :func:`default_allowable`: 3·S_m, the limit on the range of
primary-plus-secondary stress intensity of ASME BPVC Section III, Division 1, NB-3222.2, with
S_m = R_m(T)/3 (the tensile-strength criterion of ASME BPVC II-D, Mandatory Appendix 2, which
governs for a yield ratio R_p0.2/R_m above 1/2, as for the quenched-and-tempered CrMoV forging,
R_p0.2 ≥ 585 MPa at R_m ≤ 860 MPa: docs/rotor.md "Steel data") at the groove's highest
temperature of the record — 3·S_m = R_m(T_max). No yield table of the grade at temperature is
stored, so the yield criterion is not applied; a plant's own allowable (EN 12952-3, TRD 301)
goes in ``--allowable``.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from steamtwin.dcs.history import History
from steamtwin.errors import RotorAreaError
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.progress import ProgressCallback, scaled
from steamtwin.rotor.conduction import steam_temperature_column
from steamtwin.rotor.geometry import rotor_geometry
from steamtwin.rotor.life import rotor_life
from steamtwin.rotor.model import LOCATIONS, RotorModel
from steamtwin.rotor.steel import TabulatedSteel
from steamtwin.spec import TurbineSpec
from steamtwin.units import convert
from steamtwin.validation.html import ValidationReport
from steamtwin.validation.render import json_value
from steamtwin.validation.summary import Headline

__all__ = ["CONTIGUOUS_GAP_S", "RotorLifeResult", "checked_allowable", "default_allowable",
           "groove_steam_group", "life_table", "rainflow_matrix", "rainflow_matrix_figure",
           "ramp_life_figure", "rotor_headlines", "rotor_stress", "stress_figure",
           "temperature_figure", "write_rotor_report"]

MPA = 1e6
"""Pa per MPa."""
CONTIGUOUS_GAP_S = 60.0
"""s: a record starting at most this long after the previous one ends carries its rotor state
on (files of one historian that follow each other); after a longer gap the metal starts in
equilibrium with the record's first sample again."""
MATRIX_BINS = 12
"""Bins of the rainflow matrix along each axis (range and mean)."""


def default_allowable(steel: TabulatedSteel, groove_temperature_k: ArrayLike) -> float:
    """3·S_m = R_m(T_max) (Pa) at the highest groove temperature (K) of the record (module
    docstring: ASME III NB-3222.2 with S_m = R_m/3, ASME II-D Mandatory Appendix 2)."""
    hottest = float(np.nanmax(np.asarray(groove_temperature_k, dtype=float)))
    return float(steel.tensile_strength(hottest))


def checked_allowable(allowable_pa: float, where: str = "--allowable") -> float:
    """The allowable (Pa) if finite and positive, else :class:`RotorAreaError` naming ``where``."""
    value = float(allowable_pa)
    if not (math.isfinite(value) and value > 0.0):
        raise RotorAreaError(f"{where} {value / MPA:g} MPa: the allowable stress must be a "
                             "positive stress, e.g. '450 MPa'")
    return value


MODEL_FILE = "rotor-model.npz"
"""The fitted :class:`RotorModel` :func:`rotor_stress` saves beside its report."""


@dataclass
class RotorLifeResult:
    """What :func:`write_rotor_report` wrote: the run ``frame`` (SI), the ``life``
    (:class:`~steamtwin.rotor.life.RotorLife`), the allowable (Pa) and where it came from, and
    the files by name."""

    frame: pd.DataFrame
    life: object
    allowable_pa: float
    allowable_source: str
    files: dict[str, Path] = field(default_factory=dict)


# ------------------------------------------------------------------------------------------
# figures (bare matplotlib Figures on the Agg canvas, no pyplot state, as validation.figures)


def _hours(index: pd.Index) -> np.ndarray:
    if isinstance(index, pd.DatetimeIndex):
        return np.asarray((index - index[0]).total_seconds(), dtype=float) / 3600.0
    return np.arange(len(index), dtype=float) / 3600.0


def stress_figure(frame: pd.DataFrame, allowable_pa: float, path: str | Path) -> Path:
    """Von Mises stress at the groove and the bore (MPa) against hours from the first sample,
    with the allowable as a dashed line; the signed equivalent stress fatigue counts below."""
    hours = _hours(frame.index)
    figure = Figure(figsize=(10, 6.5))
    top, bottom = figure.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": (3, 2)})
    for location, colour in zip(LOCATIONS, ("tab:red", "tab:blue"), strict=True):
        top.plot(hours, frame[f"{location}_von_mises"] / MPA, color=colour, lw=1.0,
                 label=f"{location}: von Mises")
        bottom.plot(hours, frame[f"{location}_equivalent"] / MPA, color=colour, lw=1.0,
                    label=f"{location}: signed equivalent")
    top.axhline(allowable_pa / MPA, color="black", ls="--", lw=1.0,
                label=f"allowable {allowable_pa / MPA:.0f} MPa")
    peak = float(frame["groove_von_mises"].max())
    top.set_title(f"peak at the groove {peak / MPA:.0f} MPa "
                  f"({100.0 * peak / allowable_pa:.0f} % of the allowable)", fontsize=9)
    top.set(ylabel="von Mises stress (MPa)")
    bottom.axhline(0.0, color="black", lw=0.6)
    bottom.set(xlabel="time (h)", ylabel="equivalent stress (MPa)")
    top.set_ylim(0.0, 1.15 * max(peak, allowable_pa) / MPA)  # the allowable line in view
    for axis in (top, bottom):
        axis.grid(alpha=0.3)
        axis.legend(loc="lower right", fontsize=8)
    return _saved(figure, "Rotor thermal and centrifugal stress", path)


def temperature_figure(frame: pd.DataFrame, path: str | Path,
                       steam_temperature: pd.Series | None = None,
                       steam_label: str = "steam") -> Path:
    """Groove-root and bore metal temperature (°C) and, when given, the steam temperature
    wetting the groove (K in the frames), against hours from the first sample."""
    hours = _hours(frame.index)
    figure = Figure(figsize=(10, 4.5))
    axis = figure.subplots()
    if steam_temperature is not None:
        axis.plot(hours, convert(steam_temperature.to_numpy(dtype=float), "K", "degC"),
                  color="0.5", lw=0.8, label=steam_label)
    for location, colour in zip(LOCATIONS, ("tab:red", "tab:blue"), strict=True):
        axis.plot(hours, convert(frame[f"{location}_temperature"].to_numpy(dtype=float), "K",
                                 "degC"), color=colour, lw=1.2, label=f"{location} metal")
    axis.set(xlabel="time (h)", ylabel="temperature (°C)")
    axis.grid(alpha=0.3)
    axis.legend(loc="best", fontsize=8)
    return _saved(figure, "Rotor metal temperature at the critical points and the steam", path)


def rainflow_matrix(cycles: pd.DataFrame, bins: int = MATRIX_BINS
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Counts of the rainflow cycles (half cycles count ½) in a range × mean grid:
    (counts[range bin, mean bin], range edges Pa, mean edges Pa); the counts sum to the
    cycles' total count."""
    ranges = cycles["range_pa"].to_numpy(dtype=float)
    means = cycles["mean_pa"].to_numpy(dtype=float)
    range_edges = np.linspace(0.0, max(float(ranges.max(initial=0.0)), 1.0), bins + 1)
    low, high = float(means.min(initial=0.0)), float(means.max(initial=0.0))
    if high - low < 1.0:
        low, high = low - 0.5, high + 0.5
    mean_edges = np.linspace(low, high, bins + 1)
    counts, _, _ = np.histogram2d(ranges, means, bins=(range_edges, mean_edges),
                                  weights=cycles["count"].to_numpy(dtype=float))
    return counts, range_edges, mean_edges


def rainflow_matrix_figure(cycles: pd.DataFrame, path: str | Path) -> Path:
    """The rainflow matrix of :func:`rainflow_matrix` as a colour map (MPa axes), each
    non-empty cell labelled with its count."""
    counts, range_edges, mean_edges = rainflow_matrix(cycles)
    figure = Figure(figsize=(7.5, 6))
    axis = figure.subplots()
    shown = np.ma.masked_equal(counts.T, 0.0)
    # logarithmic colours: a record's many small (noise) cycles and its few ramp cycles
    norm = LogNorm(vmin=0.5, vmax=max(float(counts.max()), 1.0))
    image = axis.pcolormesh(range_edges / MPA, mean_edges / MPA, shown, cmap="viridis",
                            norm=norm)
    figure.colorbar(image, ax=axis, label="cycles (half cycles count ½)")
    for i, j in zip(*np.nonzero(counts), strict=True):
        count = counts[i, j]
        axis.text(0.5 * (range_edges[i] + range_edges[i + 1]) / MPA,
                  0.5 * (mean_edges[j] + mean_edges[j + 1]) / MPA,
                  f"{count:,.0f}" if count >= 10 else f"{count:g}", ha="center", va="center",
                  fontsize=7, color="white" if count < 0.3 * counts.max() else "black")
    axis.set(xlabel="stress range (MPa)", ylabel="mean stress (MPa)")
    axis.set_title(f"{cycles['count'].sum():,g} cycles at the groove (ASTM E1049 rainflow)",
                   fontsize=9)
    return _saved(figure, "Rainflow matrix: range × mean", path)


def ramp_life_figure(per_ramp: pd.DataFrame, path: str | Path) -> Path:
    """Life consumed per load ramp (fraction of the life, fatigue and creep stacked), one bar
    per ramp labelled with its start time and loads."""
    figure = Figure(figsize=(max(6.0, 0.6 * len(per_ramp) + 3.0), 4.5))
    axis = figure.subplots()
    positions = np.arange(len(per_ramp))
    fatigue = per_ramp["fatigue_damage"].to_numpy(dtype=float)
    creep = per_ramp["creep_damage"].to_numpy(dtype=float)
    axis.bar(positions, fatigue, color="tab:red", label="fatigue")
    axis.bar(positions, creep, bottom=fatigue, color="tab:orange", label="creep")
    labels = [f"{_clock(row.start)}\n{100 * row.from_load:.0f}→{100 * row.to_load:.0f} %"
              for row in per_ramp.itertuples(index=False)]
    axis.set_xticks(positions, labels, fontsize=7)
    axis.set(ylabel="life consumed (fraction)", xlabel="ramp (start, load from → to)")
    axis.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    axis.grid(alpha=0.3, axis="y")
    axis.legend(loc="best", fontsize=8)
    return _saved(figure, "Life consumed per load ramp", path)


def _saved(figure: Figure, title: str, path: str | Path) -> Path:
    """``figure`` titled and written to ``path`` (PNG)."""
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    return Path(path)


def _clock(value: object) -> str:
    return value.strftime("%m-%d %H:%M") if isinstance(value, pd.Timestamp) else str(value)


# ------------------------------------------------------------------------------------------
# tables and the summary


def life_table(life: object) -> pd.DataFrame:
    """Life consumed (fraction of the life; 1 = crack initiation or rupture) by fatigue,
    creep and both: over the record, per day (the mean over the record's days) and the worst
    day."""
    per_day = life.per_day
    days = max(len(per_day), 1)
    rows = []
    for name, fatigue, creep in (
            ("whole record", life.fatigue_damage, life.creep_damage),
            ("per day, mean", life.fatigue_damage / days, life.creep_damage / days),
            ("worst day", float(per_day["fatigue_damage"].max()),
             float(per_day["creep_damage"].max()))):
        rows.append({"item": name, "fatigue_damage": float(fatigue),
                     "creep_damage": float(creep), "total_damage": float(fatigue + creep)})
    return pd.DataFrame(rows)


def rotor_headlines(frame: pd.DataFrame, allowable_pa: float, source: str) -> list[Headline]:
    """The report's summary: the peak von Mises stress at the groove root and at the bore,
    each against the allowable (MPa)."""
    return [Headline(f"Peak von Mises stress at the {location}",
                     float(frame[f"{location}_von_mises"].max()) / MPA, "MPa",
                     allowable_pa / MPA, "–", source) for location in LOCATIONS]


# ------------------------------------------------------------------------------------------
# files


def write_rotor_report(directory: str | Path, frame: pd.DataFrame, life: object, *,
                       allowable_pa: float, allowable_source: str,
                       steam_temperature: pd.Series | None = None, steam_label: str = "steam",
                       title: str = "Rotor thermal stress and life",
                       settings: Mapping[str, object] | None = None,
                       timings: Mapping[str, float] | None = None) -> RotorLifeResult:
    """Write the stress series, the cycles, the life JSON and the HTML report into
    ``directory`` (module docstring); returns them with their paths.

    ``frame``: the run frame (:class:`~steamtwin.rotor.model.RotorRun` ``.frame``, SI);
    ``life``: its :class:`~steamtwin.rotor.life.RotorLife`; ``allowable_pa`` (Pa, > 0) and
    where it comes from; ``steam_temperature`` (K, on the frame's index): the steam wetting
    the groove, drawn with the metal temperatures.
    """
    allowable_pa = checked_allowable(allowable_pa)
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    clock = time.perf_counter()
    files = {"rotor_stress.parquet": directory / "rotor_stress.parquet",
             "rotor_stress.csv": directory / "rotor_stress.csv",
             "rotor_cycles.csv": directory / "rotor_cycles.csv",
             "rotor_life.json": directory / "rotor_life.json"}
    frame.to_parquet(files["rotor_stress.parquet"])
    frame.to_csv(files["rotor_stress.csv"])
    life.cycles.to_csv(files["rotor_cycles.csv"], index=False)
    document = {"allowable_pa": allowable_pa, "allowable_source": allowable_source,
                "peak_groove_von_mises_pa": float(frame["groove_von_mises"].max()),
                "summary": life.summary(),
                "per_ramp": life.per_ramp.to_dict(orient="records"),
                "per_day": life.per_day.to_dict(orient="records")}
    files["rotor_life.json"].write_text(json.dumps(
        json_value(document), indent=2, ensure_ascii=False, allow_nan=False) + "\n",
        encoding="utf-8")
    report = ValidationReport(title, settings=dict(settings or {}),
                              timings=dict(timings or {}),
                              headlines=rotor_headlines(frame, allowable_pa, allowable_source))
    report.add_table("rotor_life_summary", life_table(life),
                     "Life consumed (fraction of the life: 1 = crack initiation by fatigue, "
                     "Miner's sum; rupture by creep, Robinson's time fraction)")
    report.add_figure(stress_figure(frame, allowable_pa, directory / "rotor_stress.png"),
                      f"Stress at the groove root and the bore, allowable "
                      f"{allowable_pa / MPA:.0f} MPa ({allowable_source})")
    report.add_figure(temperature_figure(frame, directory / "rotor_temperature.png",
                                         steam_temperature, steam_label),
                      "Metal temperature at the groove root and the bore, and the steam")
    if len(life.cycles):
        report.add_figure(rainflow_matrix_figure(life.cycles, directory / "rotor_rainflow.png"),
                          "Rainflow matrix of the groove's equivalent stress")
    if len(life.per_ramp):
        report.add_figure(ramp_life_figure(life.per_ramp, directory / "rotor_ramps.png"),
                          "Life consumed per load ramp")
        report.add_table("rotor_life_per_ramp", life.per_ramp, "Life consumed per load ramp")
    report.add_table("rotor_life_per_day", life.per_day, "Life consumed per day")
    report.add_files("Data files", [
        (files["rotor_stress.parquet"], "the stress and temperature series (SI: K, Pa), one "
         "row per input sample; rotor_stress.csv the same as text"),
        (files["rotor_cycles.csv"], "rainflow cycles at the groove with their damage"),
        (files["rotor_life.json"], "life summary, per ramp and per day")])
    report.timings["write the report"] = time.perf_counter() - clock
    files["report.html"] = report.write(directory)
    return RotorLifeResult(frame, life, allowable_pa, allowable_source, files)


# ------------------------------------------------------------------------------------------
# the command's library call


def groove_steam_group(spec: TurbineSpec) -> str:
    """The metal group whose steam wets the rotor surface at the groove's axial position
    (the spec's ``[[rotor.steam]]`` intervals)."""
    section = spec.rotor
    for steam in section.steam:
        if steam.start <= section.groove_position <= steam.end:
            return steam.group
    raise RotorAreaError(f"turbine spec {spec.name!r}: no [[rotor.steam]] interval covers the "
                         f"groove at rotor.groove_position = {section.groove_position:g} m")


def rotor_stress(histories: Sequence[History], spec: TurbineSpec, directory: str | Path, *,
                 params: ModelParameters | None = None, allowable_pa: float | None = None,
                 mesh_size: float | None = None, settings: Mapping[str, object] | None = None,
                 progress: ProgressCallback | None = None) -> RotorLifeResult:
    """Stress and life of ``spec``'s HP rotor over cleaned historian records, written into
    ``directory`` by :func:`write_rotor_report` (module docstring).

    ``histories``: records in time order (e.g. of
    :func:`~steamtwin.calibration.histories.load_histories`); samples the quality gate
    excluded hold the input's last good value. ``params``: the twin's parameters (its
    heat-transfer multiplier scales the rotor's htc); ``allowable_pa`` (Pa, > 0): the limit of
    the groove's peak von Mises stress, None for :func:`default_allowable`. Raises
    :class:`RotorAreaError` for a spec without ``[rotor]`` (saying what to add) or a
    non-positive allowable, before any work.
    """
    if allowable_pa is not None:
        allowable_pa = checked_allowable(allowable_pa)
    if not histories:
        raise ValueError("give at least one historian record")
    rotor_geometry(spec)  # a spec without [rotor] or an undrawable one: refused, saying why
    group = groove_steam_group(spec)
    timings: dict[str, float] = {}
    clock = time.perf_counter()
    model = RotorModel(spec, mesh_size=mesh_size).fit(
        params, progress=scaled(progress, 0.0, 0.6, "fit the rotor model: "))
    timings["fit the rotor model"] = time.perf_counter() - clock
    clock = time.perf_counter()
    frames, steam, loads, state, last = [], [], [], None, None
    for k, history in enumerate(histories):
        inputs = history.data[list(INPUT_SIGNALS)].ffill().bfill()
        if last is not None and (inputs.index[0] - last).total_seconds() > CONTIGUOUS_GAP_S:
            state = None
        boundary = model.steam_side(inputs, params)  # one FOM run: for the ROM and the figure
        run = model.simulate_steam(boundary, state)
        frames.append(run.frame)
        state, last = run.state, inputs.index[-1]
        steam.append(boundary[steam_temperature_column(group)])
        if "load" in history.data.columns:  # W → fraction of the rated generator output
            loads.append(history.data["load"].ffill().bfill() / spec.design.generator_power)
        if progress is not None:
            progress(0.6 + 0.3 * (k + 1) / len(histories), f"record {k + 1} of {len(histories)}")
    frame = pd.concat(frames)
    timings["run the rotor ROM"] = time.perf_counter() - clock
    clock = time.perf_counter()
    life = rotor_life(frame, model.steel,
                      load=pd.concat(loads) if len(loads) == len(frames) else None)
    timings["count the life"] = time.perf_counter() - clock
    if allowable_pa is None:
        allowable_pa = default_allowable(model.steel, frame["groove_temperature"])
        source = "3 S_m = R_m(T_max), ASME III NB-3222.2"
    else:
        source = "user (--allowable)"
    result = write_rotor_report(
        directory, frame, life, allowable_pa=allowable_pa, allowable_source=source,
        steam_temperature=pd.concat(steam), steam_label=f"steam, {group}",
        title=f"Rotor thermal stress and life: {spec.name}", settings=settings,
        timings=timings)
    # the fitted model beside its report: `serve` (`rotor = ".../rotor-model.npz"`) and
    # `rotor advise --model` take it without fitting again
    result.files["rotor-model.npz"] = model.save(Path(directory) / MODEL_FILE)
    if progress is not None:
        progress(1.0, "report written")
    return result

