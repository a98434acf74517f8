"""Constants of the data-quality check: typical ranges and rate limits of the canonical
signals, the stuck and spike detectors' budgets, the unit candidates (sources in the
package docstring and beside each value)."""

from __future__ import annotations

from typing import Literal

Severity = Literal["error", "warning"]

Action = Literal["detected", "repaired", "rejected"]

INDEX = "(index)"
"""Pseudo-signal under which index findings (order, duplicates, gaps) are counted."""

SECONDS_PER_DAY = 86400.0

STUCK_CHANCE_RUNS_PER_DAY = 0.1
"""A run is stuck when chance would produce fewer such runs per signal-day than this."""

SPIKE_MAX_SAMPLES = 3
"""Longest excursion (consecutive samples) that counts as a spike; longer ones are steps."""

TRIM_SHARE = 0.99
"""Share of the central values kept by the trimmed standard deviation."""

#: std of N(0, 1) truncated to its central 99 % (|z| ≤ 2.5758):
#: sqrt(1 − 2·c·φ(c)/(2Φ(c) − 1)) [Johnson, Kotz & Balakrishnan 1994, ch. 13, truncated normal].
TRIMMED_STD_FACTOR = 0.96164

#: Typical operating range of each canonical signal in SI, for a 600 MW subcritical unit
#: (16.7 MPa / 538 °C, sliding pressure, nozzle governing) between 30 and 100 % load, with
#: margin. Used only to spot a wrong unit; physical validity limits are the caller's ``ranges``.
TYPICAL_RANGES: dict[str, tuple[float, float]] = {
    # 16.7 MPa rated, ~8 MPa at 30 % on sliding pressure; 20 MPa is above any subcritical rating.
    "main_steam_pressure": (2.0e6, 20.0e6),
    # 538 °C rated; 430–500 °C during starts and deep part load: 427–607 °C.
    "main_steam_temperature": (700.0, 880.0),
    # 500 kg/s (1800 t/h) rated, ~150 kg/s at 30 %, ~560 kg/s at valves wide open.
    "main_steam_flow": (50.0, 700.0),
    # 13 MPa rated, ~proportional to flow (Stodola), ~4 MPa at 30 %.
    "control_stage_pressure": (1.0e6, 16.0e6),
    # ~490 °C rated, ~430 °C with throttled nozzle groups at part load: 327–577 °C.
    "control_stage_temperature": (600.0, 850.0),
    # 3.9 MPa rated (cold reheat), ~1.2 MPa at 30 %.
    "hp_exhaust_pressure": (0.5e6, 5.0e6),
    # 327 °C rated, 280–380 °C over the load range: 227–447 °C.
    "hp_exhaust_temperature": (500.0, 720.0),
    # In service the governing-stage inner wall follows the control-stage steam; 277–577 °C.
    "hp_inner_casing_temperature": (550.0, 850.0),
    # 180–600 MW at 30–100 % load.
    "load": (50.0e6, 700.0e6),
    # ~177 MW at rated, ~50 MW at 30 %.
    "hp_power": (20.0e6, 250.0e6),
}

#: Physical rate limit of each canonical signal in SI per second (Pa/s, K/s, kg/s², W/s): the
#: fastest the *measured* signal genuinely moves in operation (load ramps up to 5 %/min, boiler-
#: limited pressure ramps, sensor lag, metal heat-up limits). A departure from the local trend
#: that returns within a few samples needs at least departure/step in and out; below this
#: limit × step it may be real. Trips, load rejections and valve steps are faster but are
#: monotone steps, which never count as spikes whatever their rate.
MAX_RATES: dict[str, float] = {
    # Sliding pressure 0.45–1.0 × 16.7 MPa: 7.7 kPa/s at a 5 %/min ramp; drum saturation-
    # temperature limits of a few K/min (EN 12952-3) at dTsat/dp ≈ 5 K/MPa near 16.7 MPa allow
    # ~1 MPa/min = 17 kPa/s → 20 kPa/s (1.2 MPa/min).
    "main_steam_pressure": 20.0e3,
    # Steam-temperature ramps are held to a few K/min (turbine thermal stress; the plant's
    # firing/spray dip is ~1.2 K per %/min through 300 s); a 20-s thermowell passes at most
    # ΔT/τ → 0.1 K/s (6 K/min).
    "main_steam_temperature": 0.1,
    # 500 kg/s rated: 10 %/min = 0.83 kg/s² → 1 kg/s per s.
    "main_steam_flow": 1.0,
    # ∝ flow (Stodola), 13 MPa rated: 5 %/min = 10.8 kPa/s → 15 kPa/s (7 %/min).
    "control_stage_pressure": 15.0e3,
    # Nozzle throttling: ~30 K over a 30–100 % ramp, at 5 %/min 0.08 K/s → 0.2 K/s.
    "control_stage_temperature": 0.2,
    # ∝ flow, 3.9 MPa rated: 5 %/min = 3.3 kPa/s → 5 kPa/s.
    "hp_exhaust_pressure": 5.0e3,
    # ~100 K over the load range through a 30-s well: 0.1 K/s.
    "hp_exhaust_temperature": 0.1,
    # Casing-metal heat-up limits of start-up curves, 1.5–5 K/min (thermal stress) → 0.05 K/s.
    "hp_inner_casing_temperature": 0.05,
    # 600 MW: 10 %/min = 1 MW/s (coordinated-control ramps ≤ 5 %/min, primary response faster).
    "load": 1.0e6,
    # ~177 MW HP share: 10 %/min ≈ 0.3 MW/s.
    "hp_power": 0.3e6,
}

#: Units a value of each SI kind is commonly (mis)declared in; the unit check tries each.
CANDIDATE_UNITS: dict[str, tuple[str, ...]] = {
    "Pa": ("Pa", "kPa", "bar", "MPa"),
    "K": ("K", "degC"),
    "kg/s": ("kg/s", "t/h", "kg/h"),
    "W": ("W", "kW", "MW"),
}

#: Steam rate band of a reheat unit, kg/s per W (2.5–4.0 kg/kWh; ~3.0 at rated [Cotton ch. 2]).
STEAM_RATE = (2.5 / 3.6e6, 4.0 / 3.6e6)
