"""Residual monitoring: tell a failing sensor from a degrading turbine (issue 21, item 5).

Per block of ``block_s`` seconds (60 s by default) the monitor takes the mean residual r
(measured − twin, SI) of each monitored sensor. Block means rather than 1-s samples: the
residuals of a thermowell-lagged temperature are autocorrelated over minutes, and a CUSUM
assumes independent increments; one-minute means of a 1-s stream are nearly so at the
residuals' observed decorrelation (and the ROM/FOM run every second all the same).

Noise model. In a healthy block r ~ N(0, Σ), Σ = diag(σ_s²) with
σ_s = max(instrument floor, healthy scale): the floor is the instrument's own error for a
block mean (noise σ over √n plus resolution, from the tag map), the healthy scale the robust
spread (1.4826·MAD) of the block means the monitor is fitted on (:meth:`fit`: residuals of the
calibrated twin over healthy hours, which carry the model's own error on ramps). The
thresholds therefore follow from the instruments' error and never fall below it.

Hypotheses (structured residuals; Gertler, *Fault Detection and Diagnosis in Engineering
Systems*, 1998, ch. 6; Willsky & Jones, IEEE TAC 21 (1976) 108–112, GLR for a bias):
* ``sensor:<s>`` — sensor s reads off by a bias b_s (signature b_s·e_s: this sensor alone);
* ``degradation:<p>`` — parameter p changed by Δ_p (signature Δ_p·J[:, p], J the twin's
  sensitivity of every sensor to p at the block's operating point).
Each hypothesis h with signature μ_h has a two-sided CUSUM of the log-likelihood ratio of
N(±μ_h, Σ) against N(0, Σ) (Page, Biometrika 41 (1954) 100–115; the multi-hypothesis form of
Nikiforov, IEEE TAC 40 (1995) 1230–1246, and Basseville & Nikiforov, *Detection of Abrupt
Changes*, 1993, §4.3/§7.2):
    g_h ← max(0, g_h + μ_hᵀΣ⁻¹r − ½ μ_hᵀΣ⁻¹μ_h)   (and the same for −μ_h).
An alarm of the hypothesis whose statistic first exceeds the threshold H names its kind and
signal: a bias in one sensor grows only that sensor's CUSUM (the others pay the ½μᵀΣ⁻¹μ
penalty of directions the data do not follow), a parameter change grows the CUSUM whose
signature matches the pattern across sensors. H comes from the mean run length wanted
between false alarms, ``arl0_blocks`` (default 10⁶ blocks ≈ 2 years of minutes), by
Siegmund's approximation for the standardised CUSUM with drift k = ½‖μ‖_Σ:
ARL₀ ≈ (e^{2k(H′)} − 2kH′ − 1)/(2k²), H′ = H/‖μ‖_Σ + 1.166 (Siegmund, *Sequential Analysis*,
1985, §X.2; Montgomery, *Introduction to Statistical Quality Control*, 7th ed., §9.1.3),
divided by the number of hypotheses (Bonferroni). An alarm ends when the reverse CUSUM —
healthy against the fault — crosses the same threshold (Page's test run the other way), so an
alarm is as slow to clear as to raise, and never flickers.

Operating-point baseline and transient σ (optional: :meth:`fit` and :meth:`update` with
``load``). The twin's error is not a constant: it depends on the load (model structure, e.g. the
plant's valve overlap and tip leakage the twin lacks) and on how far the metal lags the load
after a ramp (metal and thermowell transients the twin's lumped metal follows less well). The
metal's load L_f is the block-mean load L through a first-order lag of time constant
``transient_time_s`` (lumped-capacitance response, Incropera & DeWitt, *Fundamentals of Heat
and Mass Transfer*, 6th ed., §5.2; exact discretisation L_f ← L_f + (1 − e^{−Δt/τ})(L − L_f));
the imbalance L − L_f is zero at a steady hold and decays after a ramp. Fitted on healthy data
that include ramps (a calibration day):

* the baseline b_s(L) + β_s·(L − L_f): b_s the median residual of the healthy blocks in each
  band of ``load_band`` (load fraction), linearly interpolated between the bands' median loads
  (held beyond them), β_s the least-squares gain of what is left on the imbalance (alternated
  three times) — the residual's expected value at the operating point, which the monitor
  subtracts instead of one offset (operating-point dependent reference, Isermann,
  *Fault-Diagnosis Systems*, 2006, §7.2, §10.3);
* σ_s = max(floor, √(π/2)·c₀) + √(π/2)·c₁·|L − L_f|, (c₀, c₁) ≥ 0 the least-squares fit of
  the healthy |residual − baseline| on (1, |L − L_f|) (variance function from absolute
  residuals, Davidian & Carroll, JASA 82 (1987) 1079–1091; E|x| = σ√(2/π) for a Gaussian): an
  adaptive threshold (Frank & Ding, J. Process Control 7 (1997) 403–424; Emami-Naeini, Akhter &
  Rock, IEEE TAC 33 (1988) 1106–1115: the model error bounded in proportion to the excitation).
  The thresholds and design shifts stay those of σ at rest: in a transient the standardised
  signatures shrink, the CUSUM steps with them, and the fixed threshold is conservative.

Re-baselining after a known change (:meth:`ResidualMonitor.restart` with ``rebase_after``, at
every swap of the live parameters a degradation alarm caused). The baseline is the healthy
residual of the *old* plant; the degraded plant leaves, after the swap, an offset the twin's
coefficients do not explain and that depends on the load. The control chart's centre is then
estimated again per load band as the new data visit each band, each band self-starting
meanwhile (Montgomery, *SQC* 7th ed., §5.3/§6.2; Hawkins 1987; Quesenberry 1991): the rule, its
justification and its price are in :mod:`steamtwin.live.rebaseline`. σ and the thresholds stay
those of the healthy fit: the instruments did not change.

Partial blocks. σ is that of a full block's mean. A block holding fewer samples — the last,
open bin of a finished stream, the bins around a gap, samples the gate rejected or without a
twin value — has a noisier mean: :meth:`ResidualMonitor.update` takes each sensor's
``coverage`` c (its samples over the block's nominal count) and uses σ/√c. That is an upper
bound of the partial mean's σ whenever the residuals' autocorrelation is non-negative at every
lag (then n·Var(x̄_n) = γ₀ + 2Σ_{k<n}(1 − k/n)γ_k grows with n, so Var(x̄_n) ≤ (N/n)·Var(x̄_N);
Box, Jenkins & Reinsel, *Time Series Analysis*, 4th ed., §2.1.5, variance of a sample mean): a
partial block weighs less in every CUSUM and never raises the false-alarm rate above its
design. (Seen before the rule: the one-sample last bin of a replayed day, judged with the σ of a
60-sample mean, raised a control-stage pressure sensor fault at its end, docs/benchmarks.md.)

Design sizes: ``sensor_shift`` (K for temperatures, Pa for pressures; default
2 × the sensor's σ) and ``parameter_shift`` (per parameter; default 0.01, half a fouling step
of 2 %), the latter capped where its pattern exceeds 2 σ (‖Δ·J‖_Σ ≤ 2, the sensors' size):
a CUSUM is tuned to its design shift (Lorden, Ann. Math. Stat. 42 (1971) 1897–1908) and a
design far above the noise leaves no room for a threshold (H → 0: every block alarms).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import brentq, nnls

from steamtwin.live.rebaseline import BandRebaseline
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import Simulator

__all__ = ["AlarmEvent", "MonitorSettings", "ResidualMonitor", "block_means",
           "model_sensitivity", "siegmund_threshold"]

#: Gaussian consistency constant of the MAD (1/Φ⁻¹(3/4)).
MAD_TO_SIGMA = 1.4826


def siegmund_threshold(arl0: float, drift: float) -> float:
    """Decision interval H (in standardised units) of a one-sided CUSUM with reference drift
    ``drift`` (k, standardised) whose in-control average run length is ``arl0`` samples, by
    Siegmund's approximation ARL₀ ≈ (e^{2k(H+1.166)} − 2k(H+1.166) − 1)/(2k²)."""
    if not (arl0 > 1.0 and drift > 0.0):
        raise ValueError(f"need arl0 > 1 and drift > 0 (got {arl0!r}, {drift!r})")

    def arl(h: float) -> float:
        b = 2.0 * drift * (h + 1.166)
        return (math.expm1(b) - b) / (2.0 * drift**2)

    upper = 1.0
    while arl(upper) < arl0:
        upper *= 2.0
    if arl(0.0) >= arl0:  # a drift so large that any excess is rare enough: H = 0
        return 0.0
    return brentq(lambda h: arl(h) - arl0, 0.0, upper, xtol=1e-9)


def block_means(residuals: pd.DataFrame, block_s: float = 60.0) -> pd.DataFrame:
    """Mean of each column over consecutive blocks of ``block_s`` seconds (labelled by the
    block's end), with ``n_<column>`` the number of finite samples in it."""
    if not isinstance(residuals.index, pd.DatetimeIndex):
        raise ValueError("residuals need a DatetimeIndex")
    grouped = residuals.resample(pd.Timedelta(seconds=block_s), label="right", closed="left")
    means = grouped.mean()
    counts = grouped.count().add_prefix("n_")
    return means.join(counts)


def model_sensitivity(simulator: Simulator, inputs: pd.DataFrame, params: ModelParameters,
                      sensors: Sequence[str], parameters: Sequence[str] = ("flow_coefficient",),
                      relative_step: float = 1e-3) -> pd.DataFrame:
    """J (sensors × parameters): the change of each sensor's block-mean output per unit change
    of each parameter at ``params`` over ``inputs`` (central differences, step
    ``relative_step`` × the value)."""
    columns = {}
    for name in parameters:
        value = getattr(params, name)
        step = relative_step * abs(value)
        up = simulator.simulate(inputs, _with(params, name, value + step))
        down = simulator.simulate(inputs, _with(params, name, value - step))
        columns[name] = [(up[s].mean() - down[s].mean()) / (2.0 * step) for s in sensors]
    return pd.DataFrame(columns, index=list(sensors))


def _with(params: ModelParameters, name: str, value: float) -> ModelParameters:
    import dataclasses

    return dataclasses.replace(params, **{name: value})


def _long_run_factor(deviation: np.ndarray) -> float:
    """√((1 + ρ)/(1 − ρ)), ρ ∈ [0, 0.95] the lag-1 autocorrelation of consecutive healthy
    deviations: the long-run σ of an AR(1) series over its marginal σ, by which a CUSUM that
    assumes independent blocks must widen σ to keep its false-alarm rate on correlated model
    error (Montgomery, *Introduction to Statistical Quality Control*, 7th ed., §10.4;
    Box, Jenkins & Reinsel, *Time Series Analysis*, 4th ed., §3.2)."""
    centred = deviation - np.mean(deviation)
    denominator = float(centred @ centred)
    rho = float(centred[1:] @ centred[:-1]) / denominator if denominator > 0.0 else 0.0
    rho = min(max(rho, 0.0), 0.95)
    return math.sqrt((1.0 + rho) / (1.0 - rho))


@dataclass(frozen=True)
class MonitorSettings:
    """``block_s``: residual block length (s); ``arl0_blocks``: wanted mean number of blocks
    between false alarms over all hypotheses; ``sensor_shift``: design bias per sensor (SI;
    missing: 2 σ); ``parameter_shift``: design change per parameter (default 0.01 each);
    ``load_band``: width of the baseline's load bands (load fraction); ``transient_times_s``:
    the time constants (s) of the load lags behind the imbalances; ``rebase_blocks``: blocks
    per load band whose mean re-bases that band after a degradation swap
    (:mod:`steamtwin.live.rebaseline`)."""

    block_s: float = 60.0
    arl0_blocks: float = 1.0e6
    sensor_shift: Mapping[str, float] = field(default_factory=dict)
    parameter_shift: Mapping[str, float] = field(default_factory=dict)
    load_band: float = 0.02
    transient_times_s: tuple[float, ...] = (300.0, 1200.0, 3600.0)
    rebase_blocks: int = 30

    def __post_init__(self) -> None:
        if (isinstance(self.rebase_blocks, bool) or not isinstance(self.rebase_blocks, int)
                or self.rebase_blocks < 1):
            raise ValueError(f"rebase_blocks must be a whole number ≥ 1 (got "
                             f"{self.rebase_blocks!r})")
        if not (self.load_band > 0.0 and self.transient_times_s
                and all(t > 0.0 for t in self.transient_times_s)):
            raise ValueError(f"load_band and transient_times_s must be positive (got "
                             f"{self.load_band!r}, {self.transient_times_s!r})")
        if not self.block_s > 0.0:
            raise ValueError(f"block_s must be positive (got {self.block_s!r})")
        if not self.arl0_blocks > 1.0:
            raise ValueError(f"arl0_blocks must exceed 1 (got {self.arl0_blocks!r})")
        for name, value in {**self.sensor_shift, **self.parameter_shift}.items():
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"design shift of {name} must be positive (got {value!r})")


@dataclass(frozen=True)
class AlarmEvent:
    """An alarm starting (``end`` None) or ending: ``kind`` "sensor_fault" or "degradation",
    ``signal`` (the sensor or the parameter), ``time`` (block end), the statistic, the
    threshold and the block's standardised residuals as evidence."""

    kind: str
    signal: str
    time: pd.Timestamp
    ended: bool
    statistic: float
    threshold: float
    evidence: dict[str, float]


class ResidualMonitor:
    """Multi-hypothesis CUSUM on block-mean residuals (see the module docstring).

    ``sensors``: monitored sensors (canonical names); ``instrument_sigma``: each one's
    instrument error for a block mean (SI), the floor of its σ. :meth:`fit` learns the healthy
    spread; :meth:`update` takes one block and returns the alarms it starts or ends.
    """

    def __init__(self, sensors: Sequence[str], instrument_sigma: Mapping[str, float],
                 settings: MonitorSettings = MonitorSettings()) -> None:
        self.sensors = tuple(sensors)
        self.instrument_sigma = dict(instrument_sigma)
        self.settings = settings

    def fit(self, healthy_blocks: pd.DataFrame, load: pd.Series | None = None
            ) -> ResidualMonitor:
        """Learn σ per sensor from block means of healthy residuals (columns ``sensors``):
        max(instrument floor, 1.4826·MAD about the median); the median is the offset
        ``offset_`` the monitor subtracts (a sensor's calibration residual).

        With ``load`` (each block's mean load fraction, same index; the healthy blocks should
        then include ramps) the offset becomes the operating-point baseline of the module
        docstring — band medians ``baseline_`` plus ``transient_gain_``·(L − L_f) — and σ
        grows with |L − L_f| by ``transient_sigma_`` (σ per unit imbalance)."""
        missing = [s for s in self.sensors if s not in self.instrument_sigma]
        if missing:
            raise ValueError(f"instrument_sigma lacks {missing}")
        for sensor in self.sensors:
            if not (math.isfinite(self.instrument_sigma[sensor])
                    and self.instrument_sigma[sensor] > 0.0):
                raise ValueError(f"instrument_sigma of {sensor} must be positive")
        loads = imbalance = None
        self.filtered_load_: list[float] | None = None
        self.last_time_: pd.Timestamp | None = None
        if load is not None:
            if not load.index.equals(healthy_blocks.index):
                raise ValueError(f"fit: load must have the healthy blocks' index ({len(load)} "
                                 f"values against {len(healthy_blocks)} blocks)")
            loads = load.to_numpy(dtype=float)
            imbalance = np.array([self._advance(stamp, value) for stamp, value in
                                  zip(healthy_blocks.index, loads, strict=True)])
            imbalance = imbalance.reshape(len(loads), len(self.settings.transient_times_s))
        sigma, offset, baseline, gain, growth = {}, {}, {}, {}, {}
        for sensor in self.sensors:
            column = healthy_blocks[sensor].to_numpy(dtype=float)
            usable = np.isfinite(column)
            if loads is not None:
                usable &= np.isfinite(loads) & np.isfinite(imbalance).all(axis=1)
            values = column[usable]
            if values.size < 10:
                raise ValueError(f"fit needs at least 10 healthy blocks of {sensor} (got "
                                 f"{values.size})")
            centre = float(np.median(values))
            offset[sensor] = centre
            if loads is None:
                spread = MAD_TO_SIGMA * float(np.median(np.abs(values - centre)))
            else:
                at, off = loads[usable], imbalance[usable]
                beta = np.zeros(off.shape[1])
                for _ in range(3):  # alternate: band medians given the gains, gains given them
                    baseline[sensor] = self._bands(at, values - off @ beta)
                    rest = values - np.interp(at, *baseline[sensor])
                    beta = np.linalg.lstsq(off, rest, rcond=None)[0]
                gain[sensor] = [float(b) for b in beta]
                deviation = rest - off @ beta
                # E|x| = σ√(2/π): least squares of |deviation| on (1, |L − L_f,k|), all ≥ 0
                design = np.column_stack([np.ones(values.size), np.abs(off)])
                coefficients, _ = nnls(design, np.abs(deviation))
                factor = math.sqrt(math.pi / 2.0) * _long_run_factor(deviation)
                spread = factor * float(coefficients[0])
                growth[sensor] = [factor * float(c) for c in coefficients[1:]]
            sigma[sensor] = max(self.instrument_sigma[sensor], spread)
        self.sigma_ = sigma
        self.offset_ = offset
        self.baseline_ = baseline
        self.transient_gain_ = gain
        self.transient_sigma_ = growth
        self.filtered_load_ = None
        self.last_time_ = None
        self.statistics_: dict[str, float] = {}
        self.active_: dict[str, pd.Timestamp] = {}
        self.rebaseline_ = BandRebaseline(self.sensors, self.settings.rebase_blocks)
        return self

    def _bands(self, loads: np.ndarray, values: np.ndarray) -> tuple[list[float], list[float]]:
        """(median load, median residual) of each load band holding ≥ 3 blocks, by load."""
        bands = np.floor(loads / self.settings.load_band)
        centres, medians = [], []
        for band in np.unique(bands):
            inside = bands == band
            if inside.sum() >= 3:
                centres.append(float(np.median(loads[inside])))
                medians.append(float(np.median(values[inside])))
        if not centres:
            raise ValueError("fit: no load band holds 3 healthy blocks")
        return centres, medians

    def _advance(self, time: pd.Timestamp, load: float) -> list[float]:
        """Advance the lagged loads L_f,k by one block of load ``load`` (first-order lags of
        time constants ``transient_times_s``; NaN: held) and return the imbalances L − L_f,k."""
        count = len(self.settings.transient_times_s)
        if not math.isfinite(load):
            return [math.nan] * count
        if self.filtered_load_ is None:
            self.filtered_load_ = [float(load)] * count  # the stream starts in equilibrium
        else:
            elapsed = max((pd.Timestamp(time) - self.last_time_).total_seconds(), 0.0)
            for k, tau in enumerate(self.settings.transient_times_s):
                share = -math.expm1(-elapsed / tau)
                self.filtered_load_[k] += share * (float(load) - self.filtered_load_[k])
        self.last_time_ = pd.Timestamp(time)
        return [float(load) - lagged for lagged in self.filtered_load_]

    def _hypotheses(self, sensitivity: pd.DataFrame | None) -> dict[str, tuple[str, str,
                                                                               np.ndarray]]:
        hypotheses = {}
        sigma = np.array([self.sigma_[s] for s in self.sensors])
        for j, sensor in enumerate(self.sensors):
            shift = self.settings.sensor_shift.get(sensor, 2.0 * self.sigma_[sensor])
            direction = np.zeros(len(self.sensors))
            direction[j] = shift
            hypotheses[f"sensor:{sensor}"] = ("sensor_fault", sensor, direction)
        if sensitivity is not None:
            for parameter in sensitivity.columns:
                column = sensitivity[parameter].reindex(list(self.sensors)).to_numpy(float)
                shift = self.settings.parameter_shift.get(parameter, 0.01)
                norm = float(np.linalg.norm(np.nan_to_num(column) / sigma))
                if norm > 0.0:  # no larger than a 2-σ pattern (the sensors' design size)
                    shift = min(shift, 2.0 / norm)
                hypotheses[f"degradation:{parameter}"] = ("degradation", parameter,
                                                          shift * column)
        return hypotheses

    def threshold(self, direction: np.ndarray, hypotheses: int) -> float:
        """H of one hypothesis with signature ``direction`` among ``hypotheses`` (two-sided
        each): the log-likelihood-ratio threshold for the wanted false-alarm rate."""
        sigma = np.array([self.sigma_[s] for s in self.sensors])
        norm = float(np.linalg.norm(direction / sigma))
        standard = siegmund_threshold(self.settings.arl0_blocks * 2 * hypotheses, 0.5 * norm)
        return standard * norm  # the LLR CUSUM is the standardised one scaled by ‖μ‖_Σ

    def update(self, time: pd.Timestamp, block: Mapping[str, float],
               sensitivity: pd.DataFrame | None = None,
               load: float | None = None,
               coverage: Mapping[str, float] | None = None) -> list[AlarmEvent]:
        """Advance every CUSUM by one block of mean residuals (sensor → SI; NaN: sensor out
        of this block) with the twin's ``sensitivity`` J there (sensors × parameters); return
        the alarms that start or end. ``load`` (the block's mean load fraction) selects the
        operating-point baseline and σ of a monitor fitted with loads (module docstring).
        ``coverage``: per sensor, the share of the block's nominal samples its mean rests on
        (0–1, dimensionless; missing or None: a full block); σ of a partial block's mean is
        σ/√coverage (module docstring, "Partial blocks").

        Isolation (Gertler 1998, §6; accommodation): an active sensor fault takes its sensor
        out of the other hypotheses' evidence, an active degradation removes its pattern (the
        block's projection on its signature) — so a fault explained once does not raise the
        hypotheses it also moves. When several hypotheses cross their thresholds in the same
        block, the one whose signature explains most of the block's standardised residual (the
        GLR of the block, (dᵀz)²/dᵀd signed by the direction, Willsky & Jones 1976; ties: the
        one furthest past its threshold) is raised and the others' statistics restart: the
        same evidence, explained by the raised one.
        """
        if not hasattr(self, "sigma_"):
            raise RuntimeError("fit the monitor on healthy residuals first")
        baseline = getattr(self, "baseline_", {})
        at_load = bool(baseline) and load is not None and math.isfinite(load)
        imbalance = np.array(self._advance(time, float(load)) if at_load
                             else [0.0] * len(self.settings.transient_times_s))
        growth = getattr(self, "transient_sigma_", {})
        sigma = np.array([self.sigma_[s] + float(np.abs(imbalance) @ growth[s]) if s in growth
                          else self.sigma_[s] for s in self.sensors])
        if coverage is not None:
            share = np.array([float(coverage.get(s, 1.0)) for s in self.sensors])
            if np.any(share < 0.0):
                raise ValueError(f"coverage must be a share of the block's samples in 0–1 "
                                 f"(got {dict(coverage)})")
            with np.errstate(divide="ignore"):  # no sample: σ = ∞, the sensor out of the block
                sigma = sigma / np.sqrt(np.minimum(share, 1.0))
        band = (str(math.floor(self.filtered_load_[0] / self.settings.load_band)) if at_load
                else "offset")  # the band of the lagged load (steamtwin.live.rebaseline)
        r = np.array([float(block.get(s, math.nan))
                      - (float(np.interp(load, *baseline[s]))
                         + float(imbalance @ self.transient_gain_[s]) if at_load
                         else self.offset_[s]) for s in self.sensors])
        r = self.rebaseline_.innovations(  # re-based per band after a degradation swap
            pd.Timestamp(time) - pd.Timedelta(seconds=self.settings.block_s), band,
            r - self.rebaseline_.shift(band))
        present = np.isfinite(r)
        z_raw = np.where(present, r / sigma, 0.0)
        hypotheses = self._hypotheses(sensitivity)
        active = {name[:-1] for name in self.active_}
        explained = present.copy()
        for key in active:
            if key.startswith("sensor:"):
                explained[self.sensors.index(key.split(":", 1)[1])] = False
        z = np.where(explained, z_raw, 0.0)
        for key in active:
            if key.startswith("degradation:") and key in hypotheses:
                d = np.where(explained, hypotheses[key][2] / sigma, 0.0)
                if d @ d > 0.0:
                    z = z - (d @ z) / (d @ d) * d
        events, crossing = [], []
        evidence = {s: float(v) for s, v in zip(self.sensors, z_raw, strict=True)}
        for key, (kind, signal, direction) in hypotheses.items():
            own = key in active  # an active alarm follows its own, unadjusted evidence
            mask = present if own else explained
            d = np.where(mask, direction / sigma, 0.0)
            gain = float(d @ (z_raw if own else z))
            penalty = 0.5 * float(d @ d)
            limit = self.threshold(direction, len(hypotheses))
            for sign, suffix in ((1.0, "+"), (-1.0, "-")):
                name = key + suffix
                step = sign * gain - penalty  # log-likelihood ratio, fault against healthy
                if name in self.active_:  # the return: healthy against fault
                    value = max(0.0, self.statistics_.get(name, 0.0) - step)
                    self.statistics_[name] = value
                    if value > limit:
                        del self.active_[name]
                        self.statistics_[name] = 0.0
                        events.append(AlarmEvent(kind, signal, time, True, value, limit,
                                                 evidence))
                    continue
                value = max(0.0, self.statistics_.get(name, 0.0) + step)
                self.statistics_[name] = value
                if key not in active and value > limit:
                    explains = sign * gain * abs(gain) / penalty if penalty > 0.0 else 0.0
                    crossing.append((explains, value / limit if limit > 0.0 else math.inf,
                                     name, kind,
                                     signal, value, limit))
        if crossing:
            _, _, name, kind, signal, value, limit = max(crossing)
            self.active_[name] = time
            events.append(AlarmEvent(kind, signal, time, False, value, limit, evidence))
            for _, _, other, *_ in crossing:
                self.statistics_[other] = 0.0  # the raised one's return CUSUM starts at 0
        return events

    def restart(self, rebase_after: pd.Timestamp | None = None) -> None:
        """Zero the statistics of every hypothesis not in alarm (the active ones keep their
        return statistic): after the twin's parameters change, evidence gathered against the
        old set no longer speaks for the new one, and a CUSUM restarts from zero after the
        model it tests is re-identified (Basseville & Nikiforov, *Detection of Abrupt
        Changes*, 1993, §2.2 and §8.1). ``rebase_after`` (UTC; None: no re-basing): the change
        follows a known change of the plant (a degradation alarm's swap) and applies to the
        samples after this time: every load band relearns its centre from the blocks that
        start after it, ``settings.rebase_blocks`` per band, self-starting meanwhile
        (:mod:`steamtwin.live.rebaseline`)."""
        if not hasattr(self, "statistics_"):
            raise RuntimeError("fit the monitor on healthy residuals first")
        self.statistics_ = {name: (value if name in self.active_ else 0.0)
                            for name, value in self.statistics_.items()}
        if rebase_after is not None:
            self.rebaseline_.open(rebase_after)

    def get_state(self) -> dict:
        """JSON-ready state (fitted σ, offsets, load baselines, ramp σ and activity, statistics,
        active alarms, the per-band re-baselining) to restart from."""
        return {"sigma": self.sigma_, "offset": self.offset_, "statistics": self.statistics_,
                "active": {k: v.isoformat() for k, v in self.active_.items()},
                "baseline": {k: [list(c), list(m)] for k, (c, m) in
                             getattr(self, "baseline_", {}).items()},
                "transient_gain": dict(getattr(self, "transient_gain_", {})),
                "transient_sigma": dict(getattr(self, "transient_sigma_", {})),
                "filtered_load": (None if getattr(self, "filtered_load_", None) is None
                                  else list(self.filtered_load_)),
                "last_time": (None if getattr(self, "last_time_", None) is None
                              else self.last_time_.isoformat()),
                "rebaseline": self.rebaseline_.get_state()}

    def set_state(self, state: Mapping[str, object]) -> ResidualMonitor:
        """Restore :meth:`get_state`'s output exactly."""
        self.sigma_ = {k: float(v) for k, v in state["sigma"].items()}
        self.offset_ = {k: float(v) for k, v in state["offset"].items()}
        self.statistics_ = {k: float(v) for k, v in state["statistics"].items()}
        self.active_ = {k: pd.Timestamp(v) for k, v in state["active"].items()}
        self.baseline_ = {k: ([float(x) for x in c], [float(x) for x in m])
                          for k, (c, m) in state.get("baseline", {}).items()}
        self.transient_gain_ = {k: [float(x) for x in v]
                                for k, v in state.get("transient_gain", {}).items()}
        self.transient_sigma_ = {k: [float(x) for x in v]
                                 for k, v in state.get("transient_sigma", {}).items()}
        filtered = state.get("filtered_load")
        self.filtered_load_ = None if filtered is None else [float(x) for x in filtered]
        last = state.get("last_time")
        self.last_time_ = None if last is None else pd.Timestamp(last)
        if state.get("shift") or state.get("rebasing") is not None:
            raise ValueError("monitor state: a one-constant re-baselining ('shift', "
                             "'rebasing') from before the per-band rule; refit the monitor")
        self.rebaseline_ = BandRebaseline(self.sensors, self.settings.rebase_blocks)
        if state.get("rebaseline") is not None:
            self.rebaseline_.set_state(state["rebaseline"])
        return self
