"""Measurement layer of the virtual plant: true signals → what a DCS historian records.

:func:`measure` turns a frame of true, noise-free canonical signals (SI units: Pa, K, kg/s, W; a
uniformly sampled, usually tz-aware 1-s :class:`~pandas.DatetimeIndex`) into the frame a DCS
historian would store, and returns an exact record of everything injected, so that tests and
realism checks can compare the quality checker's findings (:mod:`steamtwin.dcs.quality`) and the
noise statistics with what was configured.

Effects, applied per signal in this order (all in SI units)
    1. lag: first-order sensor dynamics ``τ·dy/dt + y = x`` (thermowell, transmitter damping),
       discretised exactly with a steady start (``y = x`` before the first sample), see
       :func:`first_order_lag`;
    2. noise: white Gaussian noise of standard deviation ``noise_sigma``;
    3. drift: linear drift ``rate·(t − t₀)`` from the first sample, ``rate`` drawn uniformly within
       ``±drift_per_year`` (a maker's long-term stability bound);
    4. bias: a fixed calibration error ``u·tol(y)``, ``u`` drawn uniformly in [−1, 1] (rectangular
       distribution for a value known only to lie within limits, GUM JCGM 100:2008 §4.3.7) and
       ``tol`` the accuracy class of the instrument at the lagged reading: a fixed offset for
       %-of-span classes, proportional to the reading for %-of-reading classes, and within the
       IEC 60584-1 tolerance at every temperature for thermocouples;
    5. quantisation: rounding to a grid of step ``resolution`` anchored at the lower range value
       (an ADC or the historian's stored resolution);
    6. faults (:class:`FaultConfig`): stuck episodes (the value of a run's first sample held to
       its end), single-sample spikes (quantised too), dropouts (runs of NaN). Events are Poisson
       in time with lognormal durations; an event that would overlap or touch another one of the
       same signal (one free sample between events) is not injected, so every injected event is
       exactly visible in the measured frame and exactly recorded.

Randomness comes only from the ``rng`` argument; each modelled signal gets its own child
generator (:meth:`numpy.random.Generator.spawn`, in column order), and within a signal bias,
drift and noise are drawn before the faults, so switching faults off leaves the rest unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter, lfilter_zi

__all__ = [
    "SECONDS_PER_YEAR",
    "TYPE_K_TOLERANCE",
    "FaultConfig",
    "Injected",
    "Measurement",
    "SensorModel",
    "default_sensor_models",
    "first_order_lag",
    "measure",
    "pressure_transmitter",
    "type_k_thermocouple",
]

SECONDS_PER_YEAR = 365.25 * 86400.0
"""Julian year, s (unit of the drift rates)."""

ZERO_CELSIUS = 273.15
"""0 °C in K."""

#: IEC 60584-1:2013 tolerance of type K thermocouples, class → (± K, ± fraction of |t| in °C),
#: whichever is larger; class 1 valid −40…1000 °C, class 2 −40…1200 °C.
TYPE_K_TOLERANCE: dict[int, tuple[float, float]] = {1: (1.5, 0.004), 2: (2.5, 0.0075)}

Hold = Literal["linear", "zero"]

_FAULT_COLUMNS = ("signal", "kind", "start", "end", "start_row", "end_row", "n_samples",
                  "value", "offset")


@dataclass(frozen=True)
class SensorModel:
    """One instrument and its parameters, all in the signal's SI unit (Pa, K, kg/s, W) and s.

    Accuracy class (the bias limit) at a reading ``x``::

        tol(x) = max(tolerance_abs, tolerance_of_reading·|x − reading_zero|,
                     tolerance_of_span·(span[1] − span[0]))

    ``reading_zero`` is where the instrument's reading is zero (273.15 K for a thermocouple
    whose class is stated in °C). ``span`` is the calibrated range (lower, upper range value);
    the quantisation grid is anchored at its lower value. ``time_constant_s`` is the
    first-order lag τ (0: none), ``noise_sigma`` the white-noise σ, ``drift_per_year`` the
    bound of the linear drift rate per year, ``resolution`` the quantisation step (0: none).
    """

    instrument: str
    span: tuple[float, float]
    tolerance_abs: float = 0.0
    tolerance_of_reading: float = 0.0
    tolerance_of_span: float = 0.0
    reading_zero: float = 0.0
    time_constant_s: float = 0.0
    noise_sigma: float = 0.0
    drift_per_year: float = 0.0
    resolution: float = 0.0
    source: str = ""

    def __post_init__(self) -> None:
        low, high = self.span
        if not (math.isfinite(low) and math.isfinite(high) and high > low):
            raise ValueError(f"{self.instrument}: span must be finite with upper > lower")
        for name in ("tolerance_abs", "tolerance_of_reading", "tolerance_of_span",
                     "time_constant_s", "noise_sigma", "drift_per_year", "resolution"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{self.instrument}: {name} must be finite and ≥ 0")

    @property
    def span_width(self) -> float:
        """Upper minus lower range value (SI)."""
        return self.span[1] - self.span[0]

    def tolerance(self, value: ArrayLike) -> NDArray[np.float64]:
        """Accuracy-class limit (SI, ≥ 0) at the reading(s) ``value`` (SI)."""
        x = np.asarray(value, dtype=np.float64)
        return np.maximum.reduce([
            np.full_like(x, self.tolerance_abs),
            self.tolerance_of_reading * np.abs(x - self.reading_zero),
            np.full_like(x, self.tolerance_of_span * self.span_width),
        ])


def type_k_thermocouple(
    span_degc: tuple[float, float],
    *,
    tolerance_class: int = 1,
    time_constant_s: float,
    noise_sigma: float,
    drift_per_year: float = 0.5,
    bits: int = 16,
    instrument: str = "type K thermocouple",
    source: str = "",
) -> SensorModel:
    """Type K thermocouple of IEC 60584-1:2013 ``tolerance_class`` (1 or 2) on a span in °C.

    ``time_constant_s`` (s), ``noise_sigma`` (K), ``drift_per_year`` (K per year); the reading
    is quantised to ``bits`` over the span.
    """
    absolute, relative = TYPE_K_TOLERANCE[tolerance_class]
    span = (span_degc[0] + ZERO_CELSIUS, span_degc[1] + ZERO_CELSIUS)
    return SensorModel(
        instrument=f"{instrument}, IEC 60584-1 class {tolerance_class}",
        span=span, tolerance_abs=absolute, tolerance_of_reading=relative,
        reading_zero=ZERO_CELSIUS, time_constant_s=time_constant_s, noise_sigma=noise_sigma,
        drift_per_year=drift_per_year, resolution=(span[1] - span[0]) / 2**bits, source=source,
    )


def pressure_transmitter(
    span: tuple[float, float],
    *,
    accuracy_of_span: float = 0.00065,
    noise_of_span: float = 0.0002,
    drift_of_span_per_year: float = 0.00025,
    time_constant_s: float = 0.4,
    bits: int = 16,
    instrument: str = "smart pressure transmitter",
    source: str = "",
) -> SensorModel:
    """Smart transmitter on ``span`` (SI); accuracy, noise σ and drift as fractions of span."""
    width = span[1] - span[0]
    return SensorModel(
        instrument=instrument, span=span, tolerance_of_span=accuracy_of_span,
        time_constant_s=time_constant_s, noise_sigma=noise_of_span * width,
        drift_per_year=drift_of_span_per_year * width, resolution=width / 2**bits, source=source,
    )


def default_sensor_models() -> dict[str, SensorModel]:
    """Instruments of the reference 600 MW unit (16.7 MPa / 538 °C) for the measured signals.

    ``hp_power`` (HP blading power) is not measured by any instrument and has no model.
    """
    # Thermocouples: type K, IEC 60584-1:2013 class 1 (±1.5 K or ±0.004·|t|): ±2.15 K at 538 °C.
    # Noise σ: a TC input card resolves ~0.05 K (≈2 µV at 41 µV/K); the remaining scatter at 1 s
    # is turbulent temperature fluctuation left after the well's filtering, a few tenths of a K
    # in DCS records of main steam → 0.2 K for steam, 0.1 K for a TC peened into casing metal
    # (no fluid fluctuation, electrical noise only). Drift: type K ages at 500–600 °C
    # (short-range ordering); 0.5 K per year is an assumed bound, negligible over a day.
    # Lag: a TC in a thick-walled high-pressure thermowell in superheated steam has τ of tens
    # of seconds (lumped model τ = m·c/(h·A); ASME PTC 19.3 TW-2016 wells; a bare 3 mm
    # sheathed MI TC alone has t0.5 ≈ 23 s in 0.2 m/s air, ≈ 0.2–1.2 s in water): 20 s in
    # dense, fast main steam and at the control stage, 30 s in the thinner HP exhaust steam
    # (lower heat-transfer coefficient). Metal TC in a drilled hole: 5 s (contact resistance);
    # the casing itself changes much more slowly.
    tc_source = "IEC 60584-1:2013 class 1; τ typical for thermowells in steam (assumed)"
    steam_span = (0.0, 650.0)  # °C; covers 538 °C rated with margin for start-ups and trips
    models: dict[str, SensorModel] = {
        "main_steam_temperature": type_k_thermocouple(
            steam_span, time_constant_s=20.0, noise_sigma=0.2, source=tc_source,
            instrument="type K thermocouple in thermowell (main steam)"),
        "control_stage_temperature": type_k_thermocouple(
            steam_span, time_constant_s=20.0, noise_sigma=0.2, source=tc_source,
            instrument="type K thermocouple in thermowell (control stage)"),
        "hp_exhaust_temperature": type_k_thermocouple(
            (0.0, 500.0), time_constant_s=30.0, noise_sigma=0.2, source=tc_source,
            instrument="type K thermocouple in thermowell (HP exhaust)"),
        "hp_inner_casing_temperature": type_k_thermocouple(
            steam_span, time_constant_s=5.0, noise_sigma=0.1, source=tc_source,
            instrument="type K sheathed thermocouple in inner-casing metal"),
    }
    # Pressure: smart transmitter, reference accuracy ±0.065 % of span and long-term stability
    # ±0.125 % of URL per 5 years (Rosemount 3051C, Emerson reference manual 00809-0100-4001;
    # span ≈ URL assumed → 0.025 % of span per year). Damping 0.4 s (dead time 0.1 s, adjustable
    # time constant, same manual family). Noise σ 0.02 % of span (about a third of the accuracy
    # class; 5 kPa on 25 MPa). 16-bit over span (380 Pa on 25 MPa). Spans: 1.5× rated pressure.
    p_source = "Rosemount 3051C: ±0.065 % span, ±0.125 % URL / 5 yr (00809-0100-4001)"
    for name, upper in (("main_steam_pressure", 25.0e6), ("control_stage_pressure", 20.0e6),
                        ("hp_exhaust_pressure", 6.0e6)):
        models[name] = pressure_transmitter((0.0, upper), source=p_source)
    # Main-steam flow: flow nozzle (ISO 5167-3 / ASME PTC 6) with a DP transmitter; ±1.5 % of
    # reading overall (discharge coefficient ~1 % plus transmitter and density compensation).
    # Noise σ 1.5 kg/s (0.3 % of 500 kg/s rated; DP signals are the noisiest of the set);
    # τ 1 s (transmitter damping plus impulse lines). Span 0–700 kg/s.
    models["main_steam_flow"] = SensorModel(
        instrument="flow nozzle + DP transmitter", span=(0.0, 700.0),
        tolerance_of_reading=0.015, time_constant_s=1.0, noise_sigma=1.5,
        drift_per_year=0.001 * 700.0, resolution=700.0 / 2**16,
        source="ISO 5167-3 nozzle; ±1.5 % of reading (assumed overall)",
    )
    # Load: generator active-power transducer, IEC 60688:2012 class 0.2 (±0.2 % of the fiducial
    # value = span 0–700 MW, ±1.4 MW); response time ≤ 0.3–0.4 s → τ 0.2 s; noise σ 0.05 % of
    # span (0.35 MW), drift 0.1 % of span per year (assumed), 16-bit over span.
    models["load"] = SensorModel(
        instrument="active-power transducer (generator terminals)", span=(0.0, 700.0e6),
        tolerance_of_span=0.002, time_constant_s=0.2, noise_sigma=0.35e6,
        drift_per_year=0.7e6, resolution=700.0e6 / 2**16, source="IEC 60688:2012 class 0.2",
    )
    return models


@dataclass(frozen=True)
class FaultConfig:
    """Fault injection: rates per hour per signal, durations in s, sizes relative to σ or span.

    Durations are lognormal (``*_median_s``, log-σ ``*_sigma_ln``), at least one sample and at
    most ``*_max_s``. A spike adds ``±U(lo, hi)`` with ``lo = max(spike_min_sigmas·σ,
    spike_min_span_fraction·span)`` and ``hi = max(lo, spike_max_span_fraction·span)``.
    ``enabled=False`` switches every fault off. Defaults are low (one dropout and one spike per
    signal every ~4 days; no stuck episodes) so that normal data stay normal.
    """

    enabled: bool = True
    dropout_rate_per_h: float = 0.01
    dropout_median_s: float = 20.0
    dropout_sigma_ln: float = 1.0
    dropout_max_s: float = 3600.0
    spike_rate_per_h: float = 0.01
    spike_min_sigmas: float = 8.0
    spike_min_span_fraction: float = 0.002
    spike_max_span_fraction: float = 0.03
    stuck_rate_per_h: float = 0.0
    stuck_median_s: float = 1800.0
    stuck_sigma_ln: float = 0.5
    stuck_max_s: float = 4.0 * 3600.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if name != "enabled" and not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"FaultConfig.{name} must be finite and ≥ 0")

    @classmethod
    def off(cls) -> FaultConfig:
        """No faults at all."""
        return cls(enabled=False)


@dataclass(frozen=True)
class Injected:
    """Exact record of what :func:`measure` injected.

    ``faults``: one row per event — signal, kind (``dropout``/``spike``/``stuck``), start, end
    (timestamps, inclusive), start_row, end_row (0-based positions, inclusive), n_samples, value
    (recorded spike or held value, SI; NaN for dropouts) and offset (spike minus the value it
    replaced, SI; NaN otherwise). ``sensors``: one row per modelled signal (index ``signal``) —
    instrument, bias_fraction ``u``, bias (SI) and tolerance (SI) at the median lagged true
    value, drift_rate (SI/s), drift_per_year (drawn, SI/yr), noise_sigma, time_constant_s,
    resolution. The bias at any reading ``x`` is ``bias_fraction · model.tolerance(x)``.
    """

    faults: pd.DataFrame
    sensors: pd.DataFrame


@dataclass(frozen=True)
class Measurement:
    """The recorded frame (SI, same index and columns as the true frame) and the record."""

    measured: pd.DataFrame
    injected: Injected = field(repr=False)


def first_order_lag(
    values: ArrayLike, dt_s: float, time_constant_s: float, *, hold: Hold = "linear"
) -> NDArray[np.float64]:
    """Exact sampled response of ``τ·dy/dt + y = x`` to samples ``values`` every ``dt_s`` s.

    Exponential discretisation, ``a = exp(−Δt/τ)``, steady start (``y = x[0]`` before the first
    sample). ``hold="linear"`` (first-order hold, default): ``x`` is linear between samples,
    ``y[k] = a·y[k−1] + (1 − a)·x[k−1] + (1 − τ/Δt·(1 − a))·(x[k] − x[k−1])``; exact for
    piecewise-linear input, so a ramp lags by exactly τ. ``hold="zero"`` (zero-order hold):
    ``x`` held at ``x[k−1]`` over the step, ``y[k] = a·y[k−1] + (1 − a)·x[k−1]``; exact for
    piecewise-constant input (a step reaches 63.2 % exactly τ after it), a ramp lags by
    ``Δt/(1 − a) ≈ τ + Δt/2``. ``τ = 0`` returns the input.
    """
    x = np.asarray(values, dtype=np.float64)
    if time_constant_s < 0.0 or dt_s <= 0.0:
        raise ValueError("time constant must be ≥ 0 and the step > 0")
    if time_constant_s == 0.0 or x.size == 0:
        return x.copy()
    ratio = dt_s / time_constant_s
    a = math.exp(-ratio)
    one_minus_a = -math.expm1(-ratio)
    if hold == "linear":
        b0 = 1.0 - one_minus_a / ratio
        b = np.array([b0, one_minus_a - b0])
    elif hold == "zero":
        b = np.array([0.0, one_minus_a])
    else:
        raise ValueError(f"hold must be 'linear' or 'zero', not {hold!r}")
    den = np.array([1.0, -a])
    y, _ = lfilter(b, den, x, zi=lfilter_zi(b, den) * x[0])
    return np.asarray(y, dtype=np.float64)


def measure(
    true_frame: pd.DataFrame,
    models: Mapping[str, SensorModel],
    rng: np.random.Generator,
    *,
    faults: FaultConfig = FaultConfig(),
    hold: Hold = "linear",
    instruments: pd.DataFrame | None = None,
) -> Measurement:
    """Record ``true_frame`` (SI, uniform DatetimeIndex) as the DCS would; see the module doc.

    Columns with a model are measured; other columns are passed through unchanged; models of
    absent columns are ignored. The true signals of modelled columns must be finite. ``hold``
    is the lag discretisation (:func:`first_order_lag`). ``instruments``: the ``sensors``
    record of an earlier measurement (:class:`Injected`) — the same instruments on another day:
    each listed signal keeps that record's ``bias_fraction`` and ``drift_rate`` (its noise and
    faults are drawn anew from ``rng``, which is consumed exactly as without the record).
    """
    if not isinstance(true_frame.index, pd.DatetimeIndex):
        raise TypeError("true_frame needs a DatetimeIndex")
    n = len(true_frame)
    ticks = true_frame.index.asi8  # integer ticks of the index's own unit (ns, us, ...)
    steps = np.diff(ticks)
    if steps.size and (steps[0] <= 0 or np.any(steps != steps[0])):
        raise ValueError("true_frame must be sampled uniformly in increasing time")
    elapsed_s = np.asarray(
        (true_frame.index - true_frame.index[0]) / pd.Timedelta(seconds=1), dtype=np.float64
    ) if n else np.zeros(0)
    dt_s = float(elapsed_s[1]) if n > 1 else 1.0

    measured = true_frame.copy()
    names = [c for c in true_frame.columns if c in models]
    children = rng.spawn(len(names))
    fault_rows: list[dict[str, object]] = []
    sensor_rows: list[dict[str, object]] = []
    for name, child in zip(names, children, strict=True):
        model = models[name]
        x = true_frame[name].to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(x)):
            raise ValueError(f"true signal {name!r} must be finite (no NaN or inf)")
        bias_fraction = float(child.uniform(-1.0, 1.0))
        drift_rate = float(child.uniform(-1.0, 1.0)) * model.drift_per_year / SECONDS_PER_YEAR
        noise = child.standard_normal(n) * model.noise_sigma
        if instruments is not None and name in instruments.index:
            bias_fraction = float(instruments.loc[name, "bias_fraction"])
            drift_rate = float(instruments.loc[name, "drift_rate"])

        lagged = first_order_lag(x, dt_s, model.time_constant_s, hold=hold)
        tolerance = model.tolerance(lagged)
        y = lagged + noise + drift_rate * elapsed_s + bias_fraction * tolerance
        y = _quantise(y, model)

        if faults.enabled and n:
            fault_rows.extend(_inject(y, name, model, faults, dt_s, true_frame.index, child))
        measured[name] = y

        level = float(np.median(lagged)) if n else float("nan")
        level_tol = float(model.tolerance(level))
        sensor_rows.append({
            "signal": name, "instrument": model.instrument, "bias_fraction": bias_fraction,
            "bias": bias_fraction * level_tol, "tolerance": level_tol,
            "drift_rate": drift_rate, "drift_per_year": drift_rate * SECONDS_PER_YEAR,
            "noise_sigma": model.noise_sigma, "time_constant_s": model.time_constant_s,
            "resolution": model.resolution,
        })

    fault_frame = pd.DataFrame(fault_rows, columns=list(_FAULT_COLUMNS))
    for col in ("start_row", "end_row", "n_samples"):
        fault_frame[col] = fault_frame[col].astype(np.int64)
    for col in ("value", "offset"):
        fault_frame[col] = fault_frame[col].astype(np.float64)
    if not fault_rows:
        for col in ("start", "end"):
            fault_frame[col] = pd.Series([], dtype=true_frame.index.dtype)
    fault_frame = fault_frame.sort_values(["signal", "start_row"], kind="stable")
    sensors = pd.DataFrame(sensor_rows).set_index("signal") if sensor_rows else pd.DataFrame(
        index=pd.Index([], name="signal"))
    return Measurement(measured, Injected(fault_frame.reset_index(drop=True), sensors))


# --------------------------------------------------------------------------------------------
# helpers


def _quantise(y: NDArray[np.float64], model: SensorModel) -> NDArray[np.float64]:
    if model.resolution == 0.0:
        return y
    low = model.span[0]
    return low + np.round((y - low) / model.resolution) * model.resolution


def _durations(rng: np.random.Generator, count: int, median_s: float, sigma_ln: float,
               max_s: float, dt_s: float) -> NDArray[np.int64]:
    """Lognormal durations in samples, at least 1, at most ``max_s``."""
    if median_s <= 0.0:
        return np.ones(count, dtype=np.int64)
    seconds = np.minimum(rng.lognormal(math.log(median_s), sigma_ln, count), max_s)
    return np.maximum(np.round(seconds / dt_s), 1).astype(np.int64)


def _inject(y: NDArray[np.float64], name: str, model: SensorModel, cfg: FaultConfig,
            dt_s: float, index: pd.DatetimeIndex,
            rng: np.random.Generator) -> list[dict[str, object]]:
    """Inject faults into ``y`` in place; return the records of those injected."""
    n = y.size
    hours = n * dt_s / 3600.0
    occupied = np.zeros(n + 2, dtype=bool)  # padded by one sample each side
    rows: list[dict[str, object]] = []
    plan = (
        ("stuck", cfg.stuck_rate_per_h, cfg.stuck_median_s, cfg.stuck_sigma_ln, cfg.stuck_max_s),
        ("spike", cfg.spike_rate_per_h, 0.0, 0.0, 0.0),
        ("dropout", cfg.dropout_rate_per_h, cfg.dropout_median_s, cfg.dropout_sigma_ln,
         cfg.dropout_max_s),
    )
    width = model.span_width
    low_amp = max(cfg.spike_min_sigmas * model.noise_sigma, cfg.spike_min_span_fraction * width)
    high_amp = max(low_amp, cfg.spike_max_span_fraction * width)
    for kind, rate, median_s, sigma_ln, max_s in plan:
        count = int(rng.poisson(rate * hours))
        starts = rng.integers(0, n, count)
        lengths = _durations(rng, count, median_s, sigma_ln, max_s, dt_s)
        amplitudes = rng.uniform(low_amp, high_amp, count) * rng.choice([-1.0, 1.0], count)
        for start, length, amplitude in zip(starts, lengths, amplitudes, strict=True):
            start = int(start)
            end = min(start + int(length), n) - 1
            if kind == "stuck" and end == start:
                continue  # a one-sample "stuck" run is no fault
            if occupied[start:end + 3].any():  # event ± one sample, in padded coordinates
                continue
            occupied[start + 1:end + 2] = True
            value, offset = float("nan"), float("nan")
            if kind == "stuck":
                value = float(y[start])
                y[start:end + 1] = value
            elif kind == "spike":
                before = float(y[start])
                value = float(_quantise(np.array([before + amplitude]), model)[0])
                y[start] = value
                offset = value - before
            else:
                y[start:end + 1] = np.nan
            rows.append({
                "signal": name, "kind": kind, "start": index[start], "end": index[end],
                "start_row": start, "end_row": end, "n_samples": end - start + 1,
                "value": value, "offset": offset,
            })
    return rows
