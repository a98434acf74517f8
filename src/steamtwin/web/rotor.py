"""The HP rotor for the HTTP service (issue 23, item 6, the Rotor page): the latest stored
rotor values of a unit whose live twin runs a rotor model (``rotor`` in its ``[[units]]``
table; :mod:`steamtwin.live.rotor_stream` stores them as twin signals), the allowable stress
when configured (``rotor_allowable_mpa``), and the life consumed over a stored range —
:func:`~steamtwin.rotor.life.rotor_life` (rainflow/Neuber/Manson–Coffin–Basquin fatigue with
the ASME design factors, Larson–Miller creep) on the stored equivalent-stress and temperature
series at the groove root and the bore, with the unit's measured load for the ramps.

The life needs only the rotor steel of the unit's spec (``[rotor]`` section's material), not
the rotor model file, so it works the same for ``rotor = "fit"``. Its answers are cached per
(unit, range, last stored sample): a range that ends before the last sample never changes,
and a page polling the current range recomputes only when a sample was stored.

The ramp advice (:class:`~steamtwin.rotor.advisor.RampAdvisor`: the fastest constant ramp to a
target load within the allowable, and what it costs) starts from the rotor state of the live
twin's last saved state (the ``states`` table: saved every ``snapshot_every_s``, 10 min by
default, so up to that old) at the load measured then; it needs the rotor model file and
the allowable (the advisor is fitted once per unit, on first use: a steady FOM run per 5 % of
load along the operating line).
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.errors import SteamtwinError
from steamtwin.live.config import ServiceConfig
from steamtwin.live.rotor_stream import ROTOR_SIGNALS
from steamtwin.rotor.advisor import RampAdvisor
from steamtwin.rotor.geometry import rotor_geometry
from steamtwin.rotor.life import rotor_life
from steamtwin.rotor.model import LOCATIONS, RotorModel, RotorState
from steamtwin.rotor.steel import TabulatedSteel, steel
from steamtwin.spec import TurbineSpec, load_spec
from steamtwin.web.queries import HistorianReader, SeriesQuery

__all__ = ["CACHE_ENTRIES", "NoRotorError", "RotorViews"]

CACHE_ENTRIES = 64
"""Life answers kept (least recently used dropped first)."""


class NoRotorError(SteamtwinError, LookupError):
    """The unit has no rotor model configured (the message says where to add it)."""


class NoAdviceError(SteamtwinError, LookupError):
    """The unit's configuration or stored state cannot give ramp advice (the message says why
    and what to add)."""


@dataclass(frozen=True)
class _RotorUnit:
    turbine: str
    allowable: float | None
    model: Path | None

    @cached_property
    def spec(self) -> TurbineSpec:
        return load_spec(self.turbine)

    @cached_property
    def steel(self) -> TabulatedSteel:
        return steel(rotor_geometry(self.spec).section.material)


def _json_table(frame: pd.DataFrame, columns: list[str]) -> list[dict[str, object]]:
    """Rows of ``frame[columns]`` as JSON-ready dicts (times ISO 8601 UTC, NaN → None)."""
    rows = []
    for record in frame[columns].to_dict("records"):
        row: dict[str, object] = {}
        for key, value in record.items():
            if isinstance(value, pd.Timestamp):
                row[key] = value.isoformat()
            elif isinstance(value, float | np.floating):
                row[key] = float(value) if np.isfinite(value) else None
            elif isinstance(value, np.integer):
                row[key] = int(value)
            else:
                row[key] = value
        rows.append(row)
    return rows


class RotorViews:
    """The rotor answers of the units of ``config`` that run a rotor model (None: none)."""

    def __init__(self, config: ServiceConfig | None) -> None:
        self._units = {} if config is None else {
            unit.name: _RotorUnit(unit.turbine, unit.rotor_allowable,
                                  None if unit.rotor == "fit" else unit.rotor)
            for unit in config.units if unit.rotor is not None}
        self._cache: OrderedDict[tuple, dict[str, object]] = OrderedDict()
        self._lock = threading.Lock()
        self._advisors: dict[str, RampAdvisor] = {}
        self._advisor_lock = threading.Lock()

    def _unit(self, unit: str) -> _RotorUnit:
        found = self._units.get(unit)
        if found is None:
            raise NoRotorError(f"unit {unit!r} has no rotor model: add rotor = \"rotor.npz\" "
                               "(RotorModel.save) or rotor = \"fit\" to its [[units]] table in "
                               "the serve configuration")
        return found

    def allowable(self, unit: str) -> float | None:
        """The configured allowable stress (Pa), None if not configured."""
        return self._unit(unit).allowable

    def latest(self, reader: HistorianReader, unit: str, at: pd.Timestamp
               ) -> dict[str, object]:
        """The rotor signals (SI) of the last stored twin sample at or before ``at``."""
        self._unit(unit)
        found = reader.sample_at(unit, at, source="twin")
        if found is None:
            return {"time": None, "values": dict.fromkeys(ROTOR_SIGNALS)}
        stamp, values = found
        return {"time": stamp.isoformat(),
                "values": {name: values.get(name) for name in ROTOR_SIGNALS}}

    def life(self, reader: HistorianReader, unit: str, start: pd.Timestamp,
             end: pd.Timestamp, last: pd.Timestamp | None) -> dict[str, object]:
        """Fatigue and creep damage (dimensionless; 1 = crack initiation or rupture) at each
        location over the stored samples in [``start``, ``end``] (module docstring); ``last``:
        the unit's last stored sample (the cache key's freshness)."""
        entry = self._unit(unit)
        key = (unit, start, end, None if last is None or last > end else last)
        with self._lock:
            if key in self._cache:
                self._cache.move_to_end(key)
                return self._cache[key]
        answer = self._life(reader, unit, entry, start, end)
        with self._lock:
            self._cache[key] = answer
            while len(self._cache) > CACHE_ENTRIES:
                self._cache.popitem(last=False)
        return answer

    def _life(self, reader: HistorianReader, unit: str, entry: _RotorUnit,
              start: pd.Timestamp, end: pd.Timestamp) -> dict[str, object]:
        wanted = {f"{location}_{quantity}": f"rotor_{location}_{name}"
                  for location in LOCATIONS
                  for quantity, name in (("equivalent", "stress"),
                                         ("temperature", "temperature"))}
        columns = {}
        for column, signal in wanted.items():
            raw = reader.raw(SeriesQuery(unit, "twin", signal, start, end))
            columns[column] = pd.Series(raw["value"].to_numpy(dtype=float),
                                        index=pd.DatetimeIndex(raw["time"]))
        frame = pd.DataFrame(columns).dropna()  # samples without a twin value: no rotor step
        rated = entry.spec.design.generator_power
        answer: dict[str, object] = {"start": start.isoformat(), "end": end.isoformat(),
                                     "samples": len(frame), "rated_load_w": rated,
                                     "locations": {}}
        if len(frame) < 2:
            answer["note"] = "fewer than 2 rotor samples stored in the range"
            return answer
        measured = reader.raw(SeriesQuery(unit, "measured", "load", start, end))
        load = None
        if len(measured):
            series = pd.Series(measured["value"].to_numpy(dtype=float),
                               index=pd.DatetimeIndex(measured["time"])).dropna()
            if len(series):
                load = series.reindex(series.index.union(frame.index)).interpolate(
                    method="time").ffill().bfill().reindex(frame.index)
        for location in LOCATIONS:
            life = rotor_life(frame, entry.steel, load=load, location=location,
                              rated_load=rated)
            answer["locations"][location] = {  # type: ignore[index]
                **life.summary(),
                "per_day": _json_table(life.per_day, ["day", "fatigue_damage", "creep_damage",
                                                      "damage"]),
                "per_ramp": _json_table(life.per_ramp, ["start", "end", "from_load", "to_load",
                                                        "rate_per_min", "damage"])}
        return answer

    def _advisor(self, unit: str, entry: _RotorUnit) -> RampAdvisor:
        if entry.model is None or entry.allowable is None:
            raise NoAdviceError(
                f"unit {unit!r}: ramp advice needs the rotor model file and the allowable: set "
                "rotor = \"rotor.npz\" (RotorModel.save; a model fitted at start is not "
                "shared with the HTTP service) and rotor_allowable_mpa in its [[units]] table")
        with self._advisor_lock:  # one fit per unit, however many requests arrive at once
            if unit not in self._advisors:
                model = RotorModel.load(entry.model, entry.spec)
                self._advisors[unit] = RampAdvisor(model, entry.allowable).fit()
            return self._advisors[unit]

    def advice(self, reader: HistorianReader, unit: str, to_load: float,
               hold_after_s: float) -> dict[str, object]:
        """The fastest ramp from the last saved rotor state to ``to_load`` (fraction of rated
        load) within the allowable, with a hold of ``hold_after_s`` (s) after it
        (:meth:`RampAdvisor.advise`; rates in %/min, stresses in Pa, damages dimensionless).
        Raises :class:`~steamtwin.errors.RotorAreaError` for a load the advisor refuses."""
        entry = self._unit(unit)
        advisor = self._advisor(unit, entry)
        with reader.connection() as connection:
            row = connection.execute("SELECT time, state FROM states WHERE unit = ? ORDER BY "
                                     "time DESC LIMIT 1", [unit]).fetchone()
        document = None if row is None else json.loads(row[1]).get("rotor")
        if document is None:
            raise NoAdviceError(f"unit {unit!r} has no saved rotor state yet (the live twin "
                                "saves one every 10 min of data)")
        saved = pd.Timestamp(row[0]).tz_convert("UTC")
        state = RotorState.from_dict(document["state"])
        found = reader.sample_at(unit, saved)
        load = None if found is None else found[1].get("load")
        if load is None:
            raise NoAdviceError(f"unit {unit!r}: no measured load at the saved rotor state's "
                                f"time {saved.isoformat()}")
        from_load = float(load) / entry.spec.design.generator_power
        advice = advisor.advise(state, from_load, to_load, hold_after_s=hold_after_s)
        return {"unit": unit, "state_time": saved.isoformat(), **advice.summary()}
