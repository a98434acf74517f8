"""Boundary conditions along the unit's operating line (sliding pressure), for off-design runs.

At a load fraction L of the rated point:

* main-steam pressure from the spec's sliding-pressure line (linear between its points);
* main-steam temperature from the spec's ``[temperature_schedule]`` (linear between its points,
  held flat outside them), else at its design value. The boiler's superheat and reheat
  temperature controls (spray attemperation, burner tilt, gas recirculation) hold rated steam
  temperatures down to a control point, below which they fall with load; the DEH/CCS
  steam-temperature setpoint follows that schedule (Cotton, *Evaluating and Improving Steam
  Turbine Performance*, 1998, ch. 2 on part-load steam temperatures);
* main-steam flow m = L·m_design — steam rate taken constant (within ~3 % over 30–100 % load for
  reheat units, Cotton 1998 ch. 2);
* HP-exhaust pressure p = p_design·(m/m_design)·sqrt(T_rh/T_rh,rated): the reheater, IP and LP
  sections downstream swallow steam by Stodola's cone law with a large pressure ratio,
  m·sqrt(T)/p = const at their inlet (Stodola 1927; Cooke 1985), so their inlet pressure is
  proportional to flow times the square root of the hot-reheat temperature; without a scheduled
  reheat temperature it is held at its rated value and p ∝ m.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from steamtwin.spec import TurbineSpec


def operating_point(spec: TurbineSpec, load_fraction: float | np.ndarray) -> dict[str, np.ndarray]:
    """Canonical boundary conditions (SI) at ``load_fraction`` of rated load.

    From 0.2 up to the last point of the spec's sliding-pressure line; near the top, flows above
    what the valves wide open pass (~1.07 of rated for the reference unit) are the model's to
    refuse.
    """
    load = np.asarray(load_fraction, dtype=float)
    line = spec.sliding_pressure
    if np.any(~np.isfinite(load)) or np.any(load < 0.2) or np.any(load > line.load_fraction[-1]):
        raise ValueError(
            f"load_fraction must lie within 0.2…{line.load_fraction[-1]} (got {load_fraction!r})"
        )
    flow = load * spec.design.main_steam_flow
    return {
        "main_steam_pressure": np.interp(load, line.load_fraction, line.pressure),
        "main_steam_temperature": main_steam_temperature(spec, load),
        "main_steam_flow": flow,
        "hp_exhaust_pressure": hp_exhaust_pressure(spec, flow, load),
    }


def main_steam_temperature(spec: TurbineSpec, load_fraction: float | np.ndarray) -> np.ndarray:
    """Main-steam temperature (K) at ``load_fraction`` of rated load: the spec's temperature
    schedule, linear between its points and flat outside them; without one, the design value."""
    load = np.asarray(load_fraction, dtype=float)
    schedule = spec.temperature_schedule
    if schedule is None:
        return np.full_like(load, spec.design.main_steam_temperature)
    return np.interp(load, schedule.load_fraction, schedule.main_steam_temperature)


def hp_exhaust_pressure(spec: TurbineSpec, flow: float | np.ndarray,
                        load_fraction: float | np.ndarray) -> np.ndarray:
    """HP-exhaust pressure (Pa) at main-steam ``flow`` (kg/s) and ``load_fraction``.

    p = p_design·(m/m_design)·sqrt(T_rh(L)/T_rh(1)) with the schedule's hot-reheat temperature
    T_rh (cone law of the IP section, Stodola 1927; Cooke 1985); p ∝ m when it is not scheduled.
    """
    design = spec.design
    pressure = design.hp_exhaust_pressure * np.asarray(flow, dtype=float) / design.main_steam_flow
    schedule = spec.temperature_schedule
    if schedule is None or schedule.reheat_temperature is None:
        return pressure
    reheat = np.interp(np.asarray(load_fraction, dtype=float), schedule.load_fraction,
                       schedule.reheat_temperature)
    rated = np.interp(1.0, schedule.load_fraction, schedule.reheat_temperature)
    return pressure * np.sqrt(reheat / rated)


def load_profile_inputs(spec: TurbineSpec, load_fraction: np.ndarray, step_seconds: float = 1.0,
                        start: str = "2026-01-01T00:00:00Z") -> pd.DataFrame:
    """An input frame following a load profile (one value per sample) on the operating line."""
    load = np.asarray(load_fraction, dtype=float)
    index = pd.date_range(start, periods=load.size, freq=pd.Timedelta(seconds=step_seconds))
    return pd.DataFrame(operating_point(spec, load), index=index)


def ramp_profile(start_load: float, end_load: float, rate_per_minute: float,
                 hold_before_s: float, hold_after_s: float, step_seconds: float = 1.0
                 ) -> np.ndarray:
    """Load fractions: a hold, a linear ramp at ``rate_per_minute`` (fraction/min), a hold."""
    if rate_per_minute <= 0.0 or step_seconds <= 0.0:
        raise ValueError("rate_per_minute and step_seconds must be positive")
    ramp_s = abs(end_load - start_load) / rate_per_minute * 60.0
    times = np.arange(0.0, hold_before_s + ramp_s + hold_after_s + step_seconds / 2, step_seconds)
    progress = (np.clip((times - hold_before_s) / ramp_s, 0.0, 1.0) if ramp_s > 0
                else np.ones_like(times))
    return start_load + (end_load - start_load) * progress
