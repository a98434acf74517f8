"""Ramp-rate advisor: the fastest load ramp that keeps the rotor's peak stress within an allowable.

Issue 23, item 5. :meth:`RampAdvisor.fit` tabulates the quasi-steady steam side of the unit's
operating line — one steady full-order run per load from 20 % to rated load, or to the
sliding-pressure line's end if lower (:func:`steamtwin.model.operating.operating_point`; a
one-sample FOM run is its steady state) — and the standing equivalent stress at each load. A
candidate ramp then costs only reduced-order steps: its steam side is the table interpolated
linearly in load along the ramp (quasi-steady: the steam path settles in seconds, the rotor in
tens of minutes; the FOM's own metal storage shifts the stage temperatures by under 1 K,
rotor/steam_side.py), and :meth:`RotorModel.simulate_steam` runs the rotor's transient ROM over
it from the present state (one compiled batch run per candidate).

**Search.** The peak excess of the groove and bore equivalent stresses over their windows
(:mod:`steamtwin.rotor.allowable`) over the ramp and the hold after it, g(rate) (Pa), is expected
to grow with the rate: the surface-to-core temperature difference of a slab under a linearly
changing surface temperature grows in proportion to the rate once the ramp is longer than the
conduction time (Carslaw & Jaeger, *Conduction of Heat in Solids*, 2nd ed., §3.3) and a shorter
ramp of the same size is closer to a step. It need not be strictly so (a short fast ramp may end
before the thermal wave reaches the bore), so the search does not assume it: it halves the rate
from the cap (``max_rate``) until a feasible rate (g ≤ 0) is found, then bisects between that
rate and the infeasible one above it (Press et al., *Numerical Recipes*, 3rd ed., §9.1) to a
relative width ``rate_tolerance``, and returns the feasible end. It therefore never advises a rate
above one it found infeasible. :attr:`RampAdvice.monotone` says whether every rate it evaluated
agreed with monotonicity (no feasible rate above an infeasible one); when not, a faster window may
exist that the advisor does not offer (conservative).

**Start-up / shut-down curve.** :meth:`RampAdvisor.curve` splits a load change into bands
(default 10 % of load) and advises each in turn from the state the previous band's ramp left
(without its hold), each band's check including a hold after it, so the unit may stop at any band
edge within the allowable; where no rate is feasible the unit soaks at the band edge until one
is (the hold points of a start-up curve).

**Margin.** The stress each candidate sees is the ROM's, so the search keeps a share
``margin`` (default :data:`ROM_MARGIN`, 2 %) of each allowed excursion — window edge minus
standing stress — in hand for the ROM's error against the full FEM; the advice then holds in the
FEM whenever the ROM meets its acceptance bound. The life the ramp costs is
:func:`steamtwin.rotor.life.rotor_life` on the predicted run (ramp + hold) at each location.
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from steamtwin.errors import RotorAreaError
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.progress import ProgressCallback, scaled
from steamtwin.rotor.allowable import StressLimit, cycle_limit, user_limit
from steamtwin.rotor.life import rotor_life
from steamtwin.rotor.model import RotorModel, RotorState
from steamtwin.spec.fingerprint import load_spec_and_text
from steamtwin.units import parse_quantity

__all__ = ["LOCATIONS", "AdviceResult", "NoFeasibleRampError", "RampAdvice", "RampAdvisor",
           "RampCurve", "advise_ramp"]

LOCATIONS = ("groove", "bore")
"""The critical points whose equivalent stress the advisor keeps within the allowable."""
LOWEST_LOAD = 0.2
"""Lowest load fraction of the operating line (operating_point's range)."""
HIGHEST_LOAD = 1.0
"""Highest load fraction advised: rated load. The sliding-pressure line may extend past it
(the reference unit's to 1.1), but flows beyond the valves-wide-open point (~1.07 of rated for
the reference unit, model/operating.py) are not steady operating points."""
TABLE_STEP = 0.05
"""Load step of the quasi-steady steam table (fraction of rated load)."""
ROM_MARGIN = 0.02
"""Share of the allowed excursion held back for the ROM's stress error: the ROM's acceptance
bound, groove stress within 2 % of the stress range of the FEM (issue 23, "What must hold";
tests/rotor/test_rotor_model.py checks it on an unseen ramp)."""
STATE_SLACK_K = 5.0
"""Margin (K) over the hottest steam within which a carried state's metal may lie (the ROM's
temperature error is ≤ 1 K, docs/rotor.md)."""


SOAK_STEP_S = 600.0
"""Soak added at a band edge of a start-up/shut-down curve while no rate is feasible (s)."""


class NoFeasibleRampError(RotorAreaError):
    """No ramp rate down to the advisor's ``min_rate`` keeps the rotor within the allowable
    from the given state (the rotor must soak first)."""


def _column(location: str, quantity: str) -> str:
    return f"{location}_{quantity}"


@dataclass(frozen=True)
class RampAdvice:
    """The advised constant-rate ramp and what it costs (SI; rates in fraction of rated load per
    minute)."""

    from_load: float
    to_load: float
    rate_per_min: float
    limited_by: str
    """``"allowable"`` (the stress bound the rate) or ``"max_rate"`` (the cap did)."""
    ramp_s: float
    hold_after_s: float
    peak_pa: dict[str, float]
    """Signed equivalent stress farthest toward its window's edge, per location (Pa)."""
    limits: dict[str, StressLimit]
    fatigue_damage: dict[str, float]
    """Miner's fatigue damage of the predicted run per location (ASME design factors)."""
    creep_damage: dict[str, float]
    """Robinson's creep time fraction of the predicted run per location."""
    run: pd.DataFrame = field(repr=False)
    """The predicted run (ramp + hold): the model's columns plus ``load_fraction``."""
    end_state: RotorState = field(repr=False)
    """The rotor's state at the end of the ramp (before the hold)."""
    evaluations: pd.DataFrame = field(repr=False)
    """Every rate tried: ``rate_per_min``, ``excess_pa`` (peak excess over the window less the
    margin, ≤ 0 is feasible), ``feasible``."""
    monotone: bool

    def summary(self) -> dict[str, object]:
        """Plain numbers for printing or JSON (rates in %/min, stresses in Pa)."""
        return {
            "from_load": self.from_load, "to_load": self.to_load,
            "rate_percent_per_min": 100.0 * self.rate_per_min, "limited_by": self.limited_by,
            "ramp_s": self.ramp_s, "hold_after_s": self.hold_after_s,
            "peak_pa": dict(self.peak_pa),
            "allowable_pa": {loc: [lim.lower_pa, lim.upper_pa] for loc, lim in self.limits.items()},
            "standing_pa": {loc: list(lim.standing_pa) for loc, lim in self.limits.items()},
            "allowable_basis": {loc: lim.basis for loc, lim in self.limits.items()},
            "fatigue_damage": dict(self.fatigue_damage), "creep_damage": dict(self.creep_damage),
            "monotone": self.monotone, "rates_evaluated": len(self.evaluations),
        }


@dataclass(frozen=True)
class RampCurve:
    """A stress-limited start-up or shut-down curve: one advice per load band, and the soak
    (s) at each band's start before it may ramp."""

    bands: list[RampAdvice]
    soaks_s: list[float]

    @property
    def table(self) -> pd.DataFrame:
        """One row per band: from/to load, rate (fraction/min), duration (s), peak stresses
        (Pa), what limited the rate, and the band's fatigue and creep damage per location."""
        return pd.DataFrame([{
            "from_load": b.from_load, "to_load": b.to_load, "soak_s": soak,
            "rate_per_min": b.rate_per_min, "ramp_s": b.ramp_s, "limited_by": b.limited_by,
            **{f"{loc}_peak_pa": b.peak_pa[loc] for loc in b.peak_pa},
            **{f"{loc}_fatigue_damage": b.fatigue_damage[loc] for loc in b.fatigue_damage},
            **{f"{loc}_creep_damage": b.creep_damage[loc] for loc in b.creep_damage},
        } for b, soak in zip(self.bands, self.soaks_s, strict=True)])

    @property
    def duration_s(self) -> float:
        """Time of all the bands' soaks and ramps (s), without the checked holds."""
        return float(sum(b.ramp_s for b in self.bands) + sum(self.soaks_s))


class RampAdvisor:
    """The fastest constant load ramp within an allowable equivalent stress (module docstring).

    ``allowable``: the allowable magnitude of the groove and bore equivalent stress (Pa), or
    ``None`` to derive it from ``cycles`` (design fatigue life per ramp cycle, ASME III factors on
    the steel's strain-life curve; :mod:`steamtwin.rotor.allowable`); exactly one is given.
    ``max_rate`` / ``min_rate``: the fastest rate offered and the slowest tried (fraction of
    rated load per minute); ``step_s``: the ROM step (s); ``rate_tolerance``: relative width of
    the final bisection bracket; ``margin``: the share of each allowed excursion (window edge
    minus standing stress) held back for the ROM's own stress error (default
    :data:`ROM_MARGIN`). The model must be fitted.
    """

    def __init__(self, model: RotorModel, allowable: float | None = None, *,
                 cycles: float | None = None, max_rate: float = 0.10, min_rate: float = 0.002,
                 step_s: float = 10.0, rate_tolerance: float = 0.005,
                 margin: float = ROM_MARGIN, params: ModelParameters | None = None) -> None:
        self.model = model
        self.allowable = allowable
        self.cycles = cycles
        self.max_rate = max_rate
        self.min_rate = min_rate
        self.step_s = step_s
        self.rate_tolerance = rate_tolerance
        self.margin = margin
        self.params = params

    # --- fit ------------------------------------------------------------------------------

    def fit(self, progress: ProgressCallback | None = None) -> RampAdvisor:
        """Tabulate the steady steam side and standing stresses along the operating line."""
        if (self.allowable is None) == (self.cycles is None):
            raise RotorAreaError("give exactly one of allowable (Pa) and cycles (design cycle "
                                 f"count), got allowable={self.allowable!r}, "
                                 f"cycles={self.cycles!r}")
        if not (0.0 < self.min_rate < self.max_rate and np.isfinite(self.max_rate)):
            raise RotorAreaError(f"need 0 < min_rate < max_rate (fraction/min), got "
                                 f"{self.min_rate!r}, {self.max_rate!r}")
        if not (self.step_s > 0.0 and 0.0 < self.rate_tolerance < 0.5):
            raise RotorAreaError(f"step_s must be > 0 s and rate_tolerance in (0, 0.5), got "
                                 f"{self.step_s!r}, {self.rate_tolerance!r}")
        spec = self.model.spec
        low, top = self.operating_range()
        loads = np.unique(np.append(np.arange(low, top, TABLE_STEP), top).round(6))
        rows, standing = [], []
        for k, load in enumerate(loads):
            boundary = operating_point(spec, load)
            inputs = pd.DataFrame({name: [float(v)] for name, v in boundary.items()},
                                  index=pd.to_datetime(["2000-01-01T00:00:00Z"]))
            steam = self.model.steam_side(inputs, self.params)
            rows.append(steam.iloc[0])
            standing.append(self.model.observe(self.model.initial_state(steam)))
            if progress is not None:
                progress((k + 1) / loads.size, f"steady steam side at {load:.0%} load")
        self.loads_ = loads
        self.steam_ = pd.DataFrame(rows).set_axis(pd.Index(loads, name="load_fraction"))
        self.standing_ = pd.DataFrame(standing).set_axis(pd.Index(loads, name="load_fraction"))
        return self

    # --- advice ---------------------------------------------------------------------------

    def advise(self, state: RotorState | None, from_load: float, to_load: float, *,
               hold_after_s: float = 3600.0) -> RampAdvice:
        """The fastest constant ramp ``from_load`` → ``to_load`` (fractions of rated load) whose
        peak groove and bore equivalent stresses over the ramp and ``hold_after_s`` (s) after it
        stay within the allowable; ``state`` is the rotor's present state (``None``: steady at
        ``from_load``). Raises :class:`RotorAreaError` for loads outside the operating line, a
        state of another rotor, an allowable below the standing stress, or when no rate down to
        ``min_rate`` stays within it."""
        self._check_fitted()
        start, end = self.check_load(from_load, "from_load"), self.check_load(to_load, "to_load")
        if start == end:
            raise RotorAreaError(f"from_load and to_load are both {start!r}: nothing to ramp")
        if not (np.isfinite(hold_after_s) and hold_after_s >= 0.0):
            raise RotorAreaError(f"hold_after_s must be ≥ 0 s, got {hold_after_s!r}")
        state = self._start_state(state, start)
        limits = self._limits(start, end)
        checked = {loc: limit.shrunk(self.margin) for loc, limit in limits.items()}
        evaluations: list[tuple[float, float]] = []

        def excess(rate: float) -> float:
            run = self._predict(state, start, end, rate, hold_after_s)
            value = max(float(checked[loc].excess(run[_column(loc, "equivalent")]).max())
                        for loc in LOCATIONS)
            evaluations.append((rate, value))
            return value

        rate, limited_by = self._fastest(excess)
        run = self._predict(state, start, end, rate, hold_after_s)
        end_state = self._end_state(state, start, end, rate)
        frame = pd.DataFrame(evaluations, columns=["rate_per_min", "excess_pa"])
        frame["feasible"] = frame["excess_pa"] <= 0.0
        feasible = frame.sort_values("rate_per_min")["feasible"].to_numpy()
        monotone = not np.any(~feasible[:-1] & feasible[1:])  # no feasible rate above a failed one
        lives = {loc: rotor_life(run, self.model.steel, load=run["load_fraction"], location=loc)
                 for loc in LOCATIONS}
        return RampAdvice(
            from_load=start, to_load=end, rate_per_min=rate, limited_by=limited_by,
            ramp_s=abs(end - start) / rate * 60.0, hold_after_s=float(hold_after_s),
            peak_pa={loc: _peak(run[_column(loc, "equivalent")].to_numpy(), limits[loc])
                     for loc in LOCATIONS},
            limits=limits,
            fatigue_damage={loc: float(life.fatigue_damage) for loc, life in lives.items()},
            creep_damage={loc: float(life.creep_damage) for loc, life in lives.items()},
            run=run, end_state=end_state,
            evaluations=frame, monotone=bool(monotone))

    def curve(self, state: RotorState | None, from_load: float, to_load: float, *,
              band: float = 0.10, hold_after_s: float = 3600.0,
              max_soak_s: float = 4 * 3600.0) -> RampCurve:
        """A stress-limited start-up (or shut-down) curve: the load change in bands of ``band``
        (fraction of rated load), each the fastest ramp from the state the previous band's ramp
        left, checked with a hold of ``hold_after_s`` (s) after it. When no rate is feasible at
        a band edge the unit soaks there (steady steam of that load) in steps of
        :data:`SOAK_STEP_S` until one is, up to ``max_soak_s`` (s) per band — the hold points of
        a start-up curve."""
        self._check_fitted()
        start, end = self.check_load(from_load, "from_load"), self.check_load(to_load, "to_load")
        if not (0.0 < band <= 1.0):
            raise RotorAreaError(f"band must lie in (0, 1] (fraction of rated load), got {band!r}")
        count = max(1, int(np.ceil(abs(end - start) / band - 1e-9)))
        edges = np.linspace(start, end, count + 1)
        state = self._start_state(state, start)
        bands, soaks = [], []
        for a, b in itertools.pairwise(edges):
            soak = 0.0
            while True:
                try:
                    advice = self.advise(state, float(a), float(b), hold_after_s=hold_after_s)
                    break
                except NoFeasibleRampError:
                    if soak + SOAK_STEP_S > max_soak_s:
                        raise
                    state = self._soak(state, float(a), SOAK_STEP_S)
                    soak += SOAK_STEP_S
            bands.append(advice)
            soaks.append(soak)
            state = advice.end_state
        return RampCurve(bands, soaks)

    # --- internals ------------------------------------------------------------------------

    def _check_fitted(self) -> None:
        if not hasattr(self, "steam_"):
            raise RotorAreaError("RampAdvisor is not fitted: call fit() first")

    def operating_range(self) -> tuple[float, float]:
        """The loads the advisor covers (fractions of rated): 20 % to rated load, or to the
        sliding-pressure line's end if lower."""
        return LOWEST_LOAD, min(float(self.model.spec.sliding_pressure.load_fraction[-1]),
                                HIGHEST_LOAD)

    def check_load(self, load: float, name: str) -> float:
        """``load`` (fraction of rated) if inside :meth:`operating_range`, else
        :class:`RotorAreaError` naming ``name`` and the value."""
        low, high = self.operating_range()
        if not (np.isfinite(load) and low <= load <= high):
            raise RotorAreaError(f"{name} = {load!r} ({100 * load:g} % of rated load) is outside "
                                 f"the unit's operating range {100 * low:g}…{100 * high:g} % "
                                 "(the sliding-pressure line up to rated load)")
        return float(load)

    def _steam_at(self, load: np.ndarray | float) -> pd.DataFrame:
        """The quasi-steady steam side at ``load`` (linear in load between table points)."""
        loads = np.atleast_1d(np.asarray(load, dtype=float))
        return pd.DataFrame({name: np.interp(loads, self.loads_, column.to_numpy())
                             for name, column in self.steam_.items()})

    def _start_state(self, state: RotorState | None, load: float) -> RotorState:
        """``state`` checked to be this rotor's, or the steady state at ``load``.

        A state of another model (:meth:`RotorModel.check_state`: another fingerprint) or of
        another number of modes is refused; so is one whose metal at
        the ROM's observed nodes (groove, bore, strain-interpolation nodes) is hotter than the
        hottest steam of the operating line (+ :data:`STATE_SLACK_K`) or below 0 °C: by the
        maximum principle of the heat equation with convective boundaries
        (Carslaw & Jaeger §1.5) the metal cannot exceed the hottest steam it has seen, so such a
        state belongs to another rotor or unit."""
        if state is None:
            return self.model.initial_state(self._steam_at(load).iloc[0])
        self.model.check_state(state)
        modes = self.model.rom_.n_modes_
        coordinates = np.asarray(getattr(getattr(state, "rom", None), "coordinates", None))
        if coordinates.shape != (modes,):
            raise RotorAreaError(f"rotor state has {coordinates.shape} reduced coordinates; "
                                 f"this rotor model's ROM has {modes} modes: the state is "
                                 "from another rotor model")
        temperatures, _ = self.model.rom_.observe(state.rom)  # groove, bore, strain nodes (K)
        hottest = float(self.steam_[[c for c in self.steam_.columns
                                     if c.startswith("steam_temperature:")]].to_numpy().max())
        outside = temperatures[(temperatures < 273.15)
                               | (temperatures > hottest + STATE_SLACK_K)]
        if outside.size:
            raise RotorAreaError(
                f"rotor state: metal temperature {float(outside[0]):.1f} K lies outside "
                f"273.15…{hottest + STATE_SLACK_K:.1f} K (0 °C to the hottest steam of "
                f"turbine {self.model.spec.name!r}): the state is from another rotor")
        return state

    def _limits(self, start: float, end: float) -> dict[str, StressLimit]:
        limits = {}
        for loc in LOCATIONS:
            column = self.standing_[_column(loc, "equivalent")].to_numpy()
            standing = (float(np.interp(start, self.loads_, column)),
                        float(np.interp(end, self.loads_, column)))
            if self.allowable is not None:
                limits[loc] = user_limit(loc, float(self.allowable), standing)
            else:
                temperature = float(np.interp(
                    [start, end], self.loads_,
                    self.standing_[_column(loc, "temperature")].to_numpy()).max())
                limits[loc] = cycle_limit(loc, float(self.cycles), standing, temperature,
                                          self.model.steel)
        return limits

    def ramp_loads(self, from_load: float, to_load: float, rate: float,
                   hold_after_s: float) -> np.ndarray:
        """Load fraction at every ROM step of a ramp at ``rate`` (fraction/min) and its hold:
        samples every ``step_s`` s from the first step after the start; the ramp's last sample
        lands on ``to_load``."""
        ramp_s = abs(to_load - from_load) / rate * 60.0
        times = np.arange(1, int(np.ceil((ramp_s + hold_after_s) / self.step_s - 1e-9)) + 1,
                          dtype=float) * self.step_s
        return from_load + (to_load - from_load) * np.clip(times / ramp_s, 0.0, 1.0)

    def steam_frame(self, from_load: float, to_load: float, rate: float,
                    hold_after_s: float) -> pd.DataFrame:
        """The quasi-steady steam side (:meth:`RotorModel.steam_side`'s columns) of a ramp at
        ``rate`` (fraction/min) and its hold, every ``step_s`` s from the start (first row at
        ``from_load``), with a ``load_fraction`` column — what the advisor runs the ROM over, and
        what :meth:`RotorModel.simulate_steam` (``full_order=True``) takes to check it."""
        loads = np.concatenate([[from_load],
                                self.ramp_loads(from_load, to_load, rate, hold_after_s)])
        steam = self._steam_at(loads).set_axis(
            pd.Timestamp("2000-01-01T00:00:00Z")
            + pd.to_timedelta(np.arange(loads.size) * self.step_s, unit="s"))
        steam["load_fraction"] = loads
        return steam

    def _predict(self, state: RotorState, start: float, end: float, rate: float,
                 hold_after_s: float) -> pd.DataFrame:
        """The ROM's run over the ramp and hold from ``state`` (its first row: ``state`` at
        ``start``), with a ``load_fraction`` column."""
        steam = self.steam_frame(start, end, rate, hold_after_s)
        run = self.model.simulate_steam(steam, state).frame
        run["load_fraction"] = steam["load_fraction"]
        return run

    def _soak(self, state: RotorState, load: float, seconds: float) -> RotorState:
        """The state after ``seconds`` (s) of steady steam at ``load``."""
        steps = int(np.ceil(seconds / self.step_s - 1e-9))
        steam = self._steam_at(np.full(steps + 1, load)).set_axis(
            pd.RangeIndex(steps + 1) * self.step_s)
        return self.model.simulate_steam(steam, state).state

    def _end_state(self, state: RotorState, start: float, end: float, rate: float
                   ) -> RotorState:
        """The rotor's state at the last step of the ramp (no hold)."""
        return self.model.simulate_steam(self.steam_frame(start, end, rate, 0.0), state).state

    def _fastest(self, excess) -> tuple[float, str]:
        """(rate, what limited it): halving from the cap to a feasible rate, then bisection."""
        high = self.max_rate
        if excess(high) <= 0.0:
            return high, "max_rate"
        low = 0.5 * high
        while (value := excess(low)) > 0.0:
            if low <= self.min_rate:
                raise NoFeasibleRampError(
                    f"no ramp rate down to {100 * self.min_rate:.2g} %/min keeps the rotor within "
                    f"the allowable from this state (at that rate the peak stress is "
                    f"{value / 1e6:.1f} MPa past it); wait for the rotor to settle or raise the "
                    "allowable")
            high, low = low, max(0.5 * low, self.min_rate)
        while high - low > self.rate_tolerance * low:
            middle = 0.5 * (low + high)
            if excess(middle) <= 0.0:
                low = middle
            else:
                high = middle
        return low, "allowable"


def _peak(stress: np.ndarray, limit: StressLimit) -> float:
    """The stress of the sample nearest (or farthest past) its window's edge (Pa)."""
    return float(stress[int(np.argmax(limit.excess(stress)))])


DEFAULT_CYCLES = 10_000.0
"""Design cycles per ramp when neither an allowable nor a cycle count is given."""


@dataclass(frozen=True)
class AdviceResult:
    """What :func:`advise_ramp` found: the ramp's advice and, if asked, the band curve."""

    advice: RampAdvice
    curve: RampCurve | None


def advise_ramp(turbine: str | Path, from_load: float, to_load: float, *,
                params_file: Path | None = None, model_file: Path | None = None,
                state_file: Path | None = None, allowable: str | None = None,
                cycles: float | None = None, max_rate: float = 0.10,
                hold_after_s: float = 3600.0, curve: bool = False,
                progress: ProgressCallback | None = None) -> AdviceResult:
    """The advice for a ramp of the unit ``turbine`` ('reference' or a spec TOML) from files:
    the rotor model (``model_file``, else fitted here), its state (JSON of
    ``RotorState.to_dict``, else steady at ``from_load``), the allowable as text with a unit
    ("400 MPa") or a design cycle count (default :data:`DEFAULT_CYCLES`). Loads and
    ``max_rate`` in fractions of rated load (per minute)."""
    if allowable is not None and cycles is not None:
        raise RotorAreaError("give either an allowable stress or a cycle count, not both")
    spec, _ = load_spec_and_text(turbine)
    allowable_pa = None if allowable is None else parse_quantity(allowable, "Pa", "allowable")
    params = ModelParameters.from_json(params_file) if params_file is not None else None
    state = None
    if state_file is not None:
        try:
            state = RotorState.from_dict(json.loads(Path(state_file).read_text(encoding="utf-8")))
        except (ValueError, TypeError, KeyError) as error:
            raise RotorAreaError(f"{state_file}: not a rotor state (JSON of "
                                 f"RotorState.to_dict): {error}") from None
    model = (RotorModel.load(model_file, spec) if model_file is not None
             else RotorModel(spec))
    advisor = RampAdvisor(model, allowable_pa,
                          cycles=None if allowable is not None else (cycles or DEFAULT_CYCLES),
                          max_rate=max_rate, params=params)
    advisor.check_load(from_load, "from_load")
    advisor.check_load(to_load, "to_load")
    if model_file is None:
        model.fit(params, progress=scaled(progress, 0.0, 0.9, "rotor model: "))
    advisor.fit(scaled(progress, 0.9 if model_file is None else 0.0, 1.0, "advisor: "))
    advice = advisor.advise(state, from_load, to_load, hold_after_s=hold_after_s)
    bands = (advisor.curve(state, from_load, to_load, hold_after_s=hold_after_s)
             if curve else None)
    return AdviceResult(advice, bands)
