"""Calibration results as files: the method's Table 6, Table 7, Figure 7 and Figure 8 (CSV + PNG).

* Table 6 — RMSE (K) per condition with the empirical constants (1, 1, 1) and with the calibrated
  parameters, and the reduction in %; for a joint calibration per load band, against the
  instruments' own error (:func:`band_rmse_table`), and the parameters' MAP with 95 % posterior
  and prior intervals (:func:`parameter_table`).
* Table 7 — sensitivity of the calibrated RMSE to the GA's settings: population P, crossover
  probability p_c and mutation probability p_m, one varied at a time around the base run.
* Figure 7 — convergence: best and mean RMSE (and fitness 1/(RMSE+ε)) per generation.
* Figure 8 — predicted vs measured temperatures over a window, before and after calibration.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from steamtwin.calibration.objective import window_rmse
from steamtwin.calibration.posterior import Posterior
from steamtwin.calibration.settings import DEFAULT_SENSORS, ObjectiveSettings
from steamtwin.calibration.windowset import WindowSet
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator

__all__ = ["band_rmse_table", "convergence_figure", "ga_sensitivity_table", "parameter_table",
           "rmse_table", "temperature_comparison_figure", "trajectory_figure", "write_trajectory"]

_LABELS = {"control_stage_temperature": "control-stage steam",
           "hp_exhaust_temperature": "HP-exhaust steam",
           "hp_inner_casing_temperature": "inner-casing metal"}


def rmse_table(simulator: Simulator, conditions: Mapping[str, Sequence[pd.DataFrame]],
               params: ModelParameters, *, sensors: Sequence[str] = DEFAULT_SENSORS,
               min_samples: int = 60, delivered: Simulator | None = None) -> pd.DataFrame:
    """Table 6: per condition, RMSE (K) with empirical constants and calibrated, reduction (%).

    ``conditions`` maps a name (e.g. "30 % load") to its windows; per-sensor RMSEs follow.
    ``delivered``: the calibrated model as ``validate`` and ``predict`` read it (the sensor
    offsets the calibration estimated applied, :attr:`steamtwin.Twin.delivered_model`) — adds
    ``rmse_delivered_K`` and ``delivered:<sensor>`` (K) at ``params``; the raw
    ``rmse_calibrated_K`` scores the readings without the offsets.
    """
    settings = ObjectiveSettings(sensors=sensors, min_samples=min_samples)
    rows = []
    for name, windows in conditions.items():
        before = window_rmse(simulator, windows, ModelParameters(), settings)
        after = window_rmse(simulator, windows, params, settings)
        row: dict[str, object] = {"condition": name, "samples": int(after["samples"].sum())}
        row["rmse_empirical_K"] = _pooled(before, "rmse")
        row["rmse_calibrated_K"] = _pooled(after, "rmse")
        row["reduction_pct"] = 100.0 * (1.0 - row["rmse_calibrated_K"] / row["rmse_empirical_K"])
        for sensor in sensors:
            row[f"empirical:{sensor}"] = _pooled(before, f"rmse:{sensor}")
            row[f"calibrated:{sensor}"] = _pooled(after, f"rmse:{sensor}")
        if delivered is not None:
            as_delivered = window_rmse(delivered, windows, params, settings)
            row["rmse_delivered_K"] = _pooled(as_delivered, "rmse")
            for sensor in sensors:
                row[f"delivered:{sensor}"] = _pooled(as_delivered, f"rmse:{sensor}")
        rows.append(row)
    return pd.DataFrame(rows).set_index("condition")


def band_rmse_table(simulator: Simulator, window_set: WindowSet, params: ModelParameters, *,
                    sensors: Sequence[str] = DEFAULT_SENSORS, min_samples: int = 60,
                    delivered: Simulator | None = None) -> pd.DataFrame:
    """Table 6 of a joint calibration: :func:`rmse_table` per load band of ``window_set``
    plus ``instrument_error_K`` (root mean square of the sensors' measurement σ in K over the
    band's windows whose tag map gives it; NaN where none does) and
    ``calibrated_over_instrument`` (the calibrated RMSE as a multiple of it); with
    ``delivered`` also ``delivered_over_instrument`` — the acceptance figure (issue 18: ≤ 1.5,
    the calibrated twin as it is delivered, its sensor offsets applied)."""
    bands = window_set.bands()
    conditions: dict[str, list[pd.DataFrame]] = {}
    sigmas: dict[str, list[float]] = {}
    for band, window in zip(bands, window_set, strict=True):
        conditions.setdefault(band, []).append(window.data)
        given = window.sigma or {}
        sigmas.setdefault(band, []).extend(
            float(given[s]) if s in given else np.nan for s in sensors)
    table = rmse_table(simulator, conditions, params, sensors=sensors, min_samples=min_samples,
                       delivered=delivered)
    table["instrument_error_K"] = [
        float(np.sqrt(np.nanmean(np.square(sigmas[b])))) if np.isfinite(sigmas[b]).any()
        else np.nan for b in table.index]
    table["calibrated_over_instrument"] = (table["rmse_calibrated_K"]
                                           / table["instrument_error_K"])
    if delivered is not None:
        table["delivered_over_instrument"] = (table["rmse_delivered_K"]
                                              / table["instrument_error_K"])
    return table


def parameter_table(posterior: Posterior) -> pd.DataFrame:
    """Table 6, parameters: per parameter the MAP, the 95 % posterior interval and the method
    that made it (the wider of the Laplace and, over a joint calibration's load bands, the
    cluster-robust interval; both given), its prior's centre and 95 % interval, the shrinkage
    (posterior σ / prior σ) and the posterior correlations
    (:meth:`~steamtwin.calibration.posterior.Posterior.table`)."""
    return posterior.table()


def _pooled(table: pd.DataFrame, column: str) -> float:
    """Sample-weighted pooled RMSE over a window_rmse table's rows."""
    weights = table["samples"].to_numpy(dtype=float)
    return float(np.sqrt(np.sum(weights * table[column].to_numpy() ** 2) / weights.sum()))


def ga_sensitivity_table(fit: Callable[[dict[str, object]], object],
                         base: Mapping[str, object],
                         variations: Mapping[str, Sequence[object]] | None = None
                         ) -> pd.DataFrame:
    """Table 7: the calibrated RMSE for each GA setting varied alone around ``base``.

    ``fit(settings)`` runs one calibration and returns a fitted calibrator (``rmse_``,
    ``params_``, ``n_evaluations_``); default variations: P ∈ {30, 50, 80}, p_c ∈ {0.6, 0.8,
    0.9}, p_m ∈ {0.1, 1/3, 0.5}, as in the method's Table 7.
    """
    variations = variations or {"population": (30, 50, 80),
                                "crossover_probability": (0.6, 0.8, 0.9),
                                "mutation_probability": (0.1, 1.0 / 3.0, 0.5)}
    rows = []
    for setting, values in variations.items():
        for value in values:
            fitted = fit({**base, setting: value})
            p = fitted.params_
            rows.append({"setting": setting, "value": value, "rmse_K": fitted.rmse_,
                         "evaluations": fitted.n_evaluations_,
                         "flow_coefficient": p.flow_coefficient,
                         "friction_coefficient": p.friction_coefficient,
                         "heat_transfer_coefficient": p.heat_transfer_coefficient})
    return pd.DataFrame(rows)


def convergence_figure(history: pd.DataFrame, path: str | Path) -> Path:
    """Figure 7: best and mean RMSE (K, left) and fitness (1/K, right) per generation."""
    path = Path(path)
    figure = Figure(figsize=(10, 4))
    left, right = figure.subplots(1, 2)
    generation = history.index.to_numpy()
    left.plot(generation, history["best_rmse"], label="best")
    left.plot(generation, history["mean_rmse"], label="population mean")
    left.set(xlabel="generation", ylabel="RMSE (K)", yscale="log", title="RMSE")
    right.plot(generation, history["best_fitness"], label="best")
    right.plot(generation, history["mean_fitness"], label="population mean")
    right.set(xlabel="generation", ylabel="fitness 1/(RMSE + ε) (1/K)", title="fitness")
    for axes in (left, right):
        axes.grid(alpha=0.3)
        axes.legend()
    figure.suptitle("GA convergence (Figure 7)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    return path


def temperature_comparison_figure(simulator: Simulator, window: pd.DataFrame,
                                  params: ModelParameters, path: str | Path, *,
                                  sensors: Sequence[str] = DEFAULT_SENSORS,
                                  title: str = "") -> Path:
    """Figure 8: measured vs predicted temperatures (°C) with empirical and calibrated
    parameters, one panel per sensor, over ``window`` (canonical SI signals)."""
    path = Path(path)
    inputs = window[list(simulator.input_signals)].ffill().bfill()
    before = simulator.simulate(inputs, ModelParameters())
    after = simulator.simulate(inputs, params)
    hours = (window.index - window.index[0]).total_seconds() / 3600.0
    figure = Figure(figsize=(10, 2.8 * len(sensors)))
    axes = figure.subplots(len(sensors), 1, sharex=True)
    for ax, sensor in zip(np.atleast_1d(axes), sensors, strict=True):
        ax.plot(hours, window[sensor] - 273.15, color="0.5", lw=0.6, label="measured")
        ax.plot(hours, before[sensor] - 273.15, lw=1.2, label="empirical constants")
        ax.plot(hours, after[sensor] - 273.15, lw=1.2, label="calibrated")
        ax.set(ylabel=f"{_LABELS.get(sensor, sensor)} (°C)")
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[0].legend(loc="best", fontsize=8)
    np.atleast_1d(axes)[-1].set(xlabel="time (h)")
    figure.suptitle(title or "Predicted vs measured temperatures (Figure 8)")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    return path


def write_trajectory(trajectory: pd.DataFrame, folder: str | Path,
                     time_zone: str | None = None) -> tuple[Path, Path]:
    """An online calibration's trajectory as ``trajectory.csv`` and ``trajectory.png``
    (:func:`trajectory_figure`) in ``folder``, its times converted to ``time_zone`` (the
    data's own, e.g. the tag map's ``historian.time_zone``; None: as they are); returns both
    paths."""
    folder = Path(folder)
    if time_zone:
        trajectory = trajectory.set_axis(trajectory.index.tz_convert(time_zone))
    table = folder / "trajectory.csv"
    trajectory.to_csv(table)
    return table, trajectory_figure(trajectory, folder / "trajectory.png")


def trajectory_figure(trajectory: pd.DataFrame, path: str | Path,
                      truth: pd.DataFrame | None = None) -> Path:
    """Online calibration: each parameter (with its 95 % band where the trajectory has
    ``<name>_low``/``_high``, as the tracker's does) and the RMSE per update (where given) over
    time (``truth``, if given, holds true parameter columns on a time index to draw
    alongside)."""
    path = Path(path)
    names = [name for name in ("flow_coefficient", "friction_coefficient",
                               "heat_transfer_coefficient", "rmse") if name in trajectory]
    figure = Figure(figsize=(10, 2 * len(names)))
    axes = np.atleast_1d(figure.subplots(len(names), 1, sharex=True))
    for ax, name in zip(axes, names, strict=True):
        ax.plot(trajectory.index, trajectory[name], marker="o", lw=1, label="online")
        if f"{name}_low" in trajectory and f"{name}_high" in trajectory:
            ax.fill_between(trajectory.index, trajectory[f"{name}_low"],
                            trajectory[f"{name}_high"], alpha=0.2, label="95 % interval")
        if truth is not None and name in truth.columns:
            ax.plot(truth.index, truth[name], color="0.4", lw=1, label="truth")
            ax.legend(fontsize=8)
        ax.set(ylabel=name.replace("_", " ") + (" (K)" if name == "rmse" else ""))
        ax.grid(alpha=0.3)
    axes[-1].set(xlabel="time (window end)")
    figure.suptitle("Online calibration: parameter trajectory")
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    return path
