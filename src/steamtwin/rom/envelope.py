"""The operating envelope a ROM's snapshots must cover, and snapshot conditions the model can run.

Kept as one module because the envelope and the feasible snapshot conditions share the same
steady model runs along the operating line (one-sample runs, flow bisection against the valves'
capacity, errors naming the parameter).

The ROM maps the DCS signals (main-steam pressure p0, temperature T0, control-stage pressure p1)
to the blade field; a sample outside its snapshots is extrapolated or refused
(:mod:`steamtwin.rom.reconstruction`). The envelope says, per load level, which p0, T0 and flow
the snapshots span, as a box about the unit's operating line at that level
(:func:`steamtwin.model.operating.operating_point`: sliding pressure, temperature schedule):

* **Operating line** — p0 × (1 ± 5 %), T0 ± 10 K, flow ± 4 % (``steamtwin.rom.snapshots``).
* **Valve points** — the loads at which a group of governing valves reaches full lift on the
  model's operating line (the governing-stage efficiency kinks there: Cotton, *Evaluating and
  Improving Steam Turbine Performance*, 1998, ch. 6); each gets a snapshot on the line.
* **Parameter intervals** — the ROM is built with the calibrated parameters, but a plant whose
  parameters lie anywhere in their interval shows another p1 at the same flow. The model is run
  along the line at each interval end; at fixed parameters p1 ∝ flow (Stodola's cone law with
  the HP-exhaust pressure ∝ flow: p1² − p2² ∝ m², p2 ∝ m ⇒ p1 ∝ m; Stodola 1927, Cooke 1985),
  so the flow box is widened by the ratio of those p1 to the calibrated model's.
* **Observed inputs** — a historian's p0, T0, p1 (after the quality gate): each sample's load
  from its main-steam flow, else from p1 along the calibrated line; per load band, its p0 and T0
  offsets from the line widen that level's box, plus the instruments' margins; the outer
  levels' flow boxes reach the samples' p1 (as the load whose line p1 it is, p1 ∝ flow), and
  samples below the lowest level's box add a level.

:func:`feasible_conditions` then runs the model once per snapshot condition (steady, no FEM):
a condition above what the wide-open valves pass is replaced by the same (p0, T0) at the highest
flow they pass (plus one row at its flow and the lowest throttle pressure that passes it), any
other failure by the farthest feasible point on the segment from its level's operating-line
point; replacements are counted. When the operating line itself cannot be run,
:class:`EnvelopeError` names the parameter and the plant limit. :func:`observed_anchors` adds
snapshots about observed samples the planned ones leave outside their hull.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from steamtwin.errors import RomError
from steamtwin.model.design_check import valve_openings
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.operating import hp_exhaust_pressure, operating_point
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters, ParameterError
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.spec import TurbineSpec

__all__ = [
    "EnvelopeError",
    "LevelBox",
    "OperatingEnvelope",
    "feasible_conditions",
    "line_box",
    "observed_anchors",
    "operating_envelope",
    "operating_line",
    "parse_parameter_interval",
    "valve_points",
]

MINIMUM_LOAD = 0.2  # lowest load of the sliding-pressure line helper (operating_point)
LINE_STEP = 0.005  # load resolution of the operating-line run that finds the valve points
FULL_LIFT = 1.0 - 1e-6  # a valve group at this lift or above counts as wide open
# Margins added to the observed inputs' range: a pressure transmitter's accuracy class
# (±0.5 % of reading, IEC 60770-1 class 0.5) and a class-1 thermocouple's tolerance
# (±1.5 K up to 375 °C, ±0.004·t above: ±2.2 K at 550 °C, IEC 60584-1:2013 Table 2).
OBSERVED_PRESSURE_MARGIN = 0.005
OBSERVED_TEMPERATURE_MARGIN = 2.2
OBSERVED_LOAD_MARGIN = 0.01  # load fraction below the lowest observed load of an added level
CAPACITY_MARGIN = 0.998  # fraction of the valves' capacity a replaced condition runs at
BISECTIONS = 20  # flow resolution of a replacement: 2⁻²⁰ of the bracket
OVER_CAPACITY = "exceeds what the wide-open governing valves pass"
# An observed cluster's box [c − h, c + h] (normalised to [−1, 1]³) lies inside the simplex
# {s_i·x_i ≤ 1, Σ s_i·x_i ≥ −3}: its vertices are the box corner s and that corner moved by
# −ANCHOR_SPAN along each axis; 6.3 > 6 leaves the opposite corner 0.1 inside the face.
ANCHOR_SPAN = 6.3
STEADY_STEP_S = 1e12  # s between samples of one run: implicit Euler at Δt → ∞ is steady


class EnvelopeError(RomError):
    """The envelope cannot be met by the model at the given parameters; the message names the
    parameter and the plant limit."""


@dataclass(frozen=True)
class LevelBox:
    """The snapshot box of one load level, relative to the operating line at ``load``.

    ``pressure_factor`` × the sliding-line pressure, ``temperature_offset`` (K) about the
    scheduled main-steam temperature, ``flow_factor`` × the line's flow (load × rated flow).
    """

    load: float
    pressure_factor: tuple[float, float]
    temperature_offset: tuple[float, float]
    flow_factor: tuple[float, float]


@dataclass(frozen=True)
class OperatingEnvelope:
    """Per-level boxes, the valve points (load fractions) and what widened the boxes.

    ``line``: the model's operating line at the build's parameters (index load fraction;
    columns the inputs and ``control_stage_pressure`` Pa, ``active_admission_arc``; NaN where
    the model cannot run it). ``observed``: the observed samples with finite inputs, their
    ``load`` and ``equivalent_load`` (fractions; None without observations).
    """

    levels: tuple[LevelBox, ...]
    valve_points: tuple[float, ...]
    line: pd.DataFrame
    sources: tuple[str, ...]
    observed: pd.DataFrame | None = None

    def describe(self) -> dict[str, object]:
        """JSON-serialisable summary for provenance."""
        return {"sources": list(self.sources),
                "valve_points": [float(v) for v in self.valve_points],
                "levels": [{"load": box.load,
                            "pressure_factor": [float(v) for v in box.pressure_factor],
                            "temperature_offset_K": [float(v) for v in box.temperature_offset],
                            "flow_factor": [float(v) for v in box.flow_factor]}
                           for box in self.levels]}


def line_box(load: float, pressure_variation: float, temperature_variation: float,
             flow_variation: float, maximum_flow_fraction: float) -> LevelBox:
    """The box about the operating line at ``load``: pressure × (1 ± ``pressure_variation``),
    temperature ± ``temperature_variation`` K, flow × (1 ± ``flow_variation``) shifted down so
    that it ends at ``maximum_flow_fraction`` of rated flow."""
    centre = min(1.0 + flow_variation, maximum_flow_fraction / load) - flow_variation
    return LevelBox(float(load), (1.0 - pressure_variation, 1.0 + pressure_variation),
                    (-temperature_variation, temperature_variation),
                    (centre - flow_variation, centre + flow_variation))


def parse_parameter_interval(text: str) -> tuple[str, tuple[float, float]]:
    """``"NAME=LOW:HIGH"`` → (name, (low, high)); ValueError naming the expected form."""
    name, _, bounds = text.partition("=")
    low, _, high = bounds.partition(":")
    try:
        interval = (float(low), float(high))
    except ValueError:
        interval = None
    if name.strip() not in PARAMETER_BOUNDS or interval is None or not interval[0] <= interval[1]:
        raise ValueError(f"parameter interval {text!r}: expected NAME=LOW:HIGH with NAME one of "
                         f"{', '.join(PARAMETER_BOUNDS)} and LOW ≤ HIGH (e.g. "
                         "flow_coefficient=0.94:0.97)")
    return name.strip(), interval


def _one_sample(condition: Mapping[str, float]) -> pd.DataFrame:
    return pd.DataFrame({name: [float(condition[name])] for name in INPUT_SIGNALS}, index=[0.0])


def _run(model: FullOrderModel, condition: Mapping[str, float], params: ModelParameters
         ) -> pd.Series:
    """Diagnostics of a one-sample (steady) run; raises InputError."""
    return model.simulate_detailed(_one_sample(condition), params, stages=False
                                   ).diagnostics.iloc[0]


def operating_line(spec: TurbineSpec, params: ModelParameters | None = None,
                   loads: Sequence[float] | np.ndarray | None = None,
                   model: FullOrderModel | None = None) -> pd.DataFrame:
    """The model's steady states on the operating line (SI), NaN where it cannot run a load.

    ``loads`` default: 0.2 to the sliding line's last point in steps of 0.005. Columns: the
    inputs, ``control_stage_pressure`` (Pa), ``active_admission_arc`` (-) and ``failure`` (the
    model's reason, "" where it ran).
    """
    params = params or ModelParameters()
    model = model or FullOrderModel(spec)
    top = spec.sliding_pressure.load_fraction[-1]
    if loads is None:
        loads = np.linspace(MINIMUM_LOAD, top, int(np.ceil((top - MINIMUM_LOAD) / LINE_STEP)) + 1)
    rows = []
    for load in np.asarray(loads, dtype=float):
        point = {k: float(v) for k, v in operating_point(spec, load).items()}
        try:
            result = _run(model, point, params)
            point.update(control_stage_pressure=float(result["control_stage_pressure"]),
                         active_admission_arc=float(result["active_admission_arc"]),
                         failure="")
        except InputError as error:
            point.update(control_stage_pressure=np.nan, active_admission_arc=np.nan,
                         failure=error.reason)
        rows.append(point)
    return pd.DataFrame(rows, index=pd.Index(np.asarray(loads, dtype=float),
                                             name="load_fraction"))


def valve_points(spec: TurbineSpec, line: pd.DataFrame) -> tuple[float, ...]:
    """Loads (fractions) at which a governing-valve group reaches full lift on ``line``.

    Lifts from the admitted arc (:func:`steamtwin.model.design_check.valve_openings`); a group
    already wide open at the line's first load has no valve point on it. Resolution: the line's
    load step.
    """
    ran = line[line["failure"] == ""]
    groups: dict[int, str] = {}
    for valve in spec.control_stage.valves:
        groups.setdefault(valve.opening_order, valve.name)
    lifts = pd.DataFrame([valve_openings(spec, arc) for arc in ran["active_admission_arc"]],
                         index=ran.index)
    points = []
    for name in groups.values():
        wide = lifts[name].to_numpy() >= FULL_LIFT
        first = np.flatnonzero(wide)
        if first.size and first[0] > 0:
            points.append(float(lifts.index[first[0]]))
    return tuple(sorted(points))


def _parameter_label(params: ModelParameters, name: str, source: str | None) -> str:
    where = f"from {source}" if source else "(the model parameters of the build)"
    return f"{name} {getattr(params, name):.4g} {where}"


def _line_error(spec: TurbineSpec, model: FullOrderModel, params: ModelParameters,
                load: float, reason: str, source: str | None) -> EnvelopeError:
    """The error for an operating-line point the model cannot run, in plant terms."""
    point = {k: float(v) for k, v in operating_point(spec, load).items()}
    where = (f"at {load:.0%} load on the operating line (main steam "
             f"{point['main_steam_pressure'] / 1e6:.2f} MPa, "
             f"{point['main_steam_temperature'] - 273.15:.1f} °C, "
             f"{point['main_steam_flow'] * 3.6:.0f} t/h)")
    if OVER_CAPACITY in reason:
        passed = _highest_flow(model, point, params, spec, 0.5 * point["main_steam_flow"])
        # the valves' nozzle areas scale with the flow coefficient (model.parameters), so their
        # capacity at a throttle state is ∝ flow_coefficient (choked/Stodola nozzle flow)
        needed = params.flow_coefficient * point["main_steam_flow"] / passed if passed else None
        fix = (f"the model needs flow_coefficient ≥ {needed:.3f} to pass it"
               if needed is not None else "the model cannot pass even half of it")
        return EnvelopeError(
            f"{_parameter_label(params, 'flow_coefficient', source)}: {where} the wide-open "
            f"governing valves pass only {(passed or 0.0) * 3.6:.0f} t/h; {fix}. Rebuild with "
            f"parameters whose flow coefficient passes the unit's rated flow (a flow coefficient "
            f"at its bound {PARAMETER_BOUNDS['flow_coefficient']} usually hides a spec error: "
            f"control_stage.valves, design.valve_outlet_pressure), or with loads below "
            f"{load:.0%}")
    named = ", ".join(_parameter_label(params, f.name, source)
                      for f in dataclasses.fields(params))
    return EnvelopeError(f"{named}: the model cannot run {where}: {reason}; rebuild with other "
                         f"parameters or loads")


def _with_flow(spec: TurbineSpec, condition: Mapping[str, float], flow: float
               ) -> dict[str, float]:
    """``condition`` at main-steam ``flow`` (kg/s), its HP-exhaust pressure on the line's law
    at its own load (:func:`steamtwin.model.operating.hp_exhaust_pressure`)."""
    load = flow / spec.design.main_steam_flow
    return dict(condition, main_steam_flow=flow,
                hp_exhaust_pressure=float(hp_exhaust_pressure(spec, flow, load)))


def _highest_flow(model: FullOrderModel, condition: Mapping[str, float],
                  params: ModelParameters, spec: TurbineSpec, lowest: float) -> float | None:
    """Highest flow (kg/s) ≤ the condition's that the model runs at its (p0, T0), times
    CAPACITY_MARGIN; None if not even ``lowest`` runs."""
    def runs(flow: float) -> bool:
        trial = _with_flow(spec, condition, flow)
        try:
            _run(model, trial, params)
        except InputError:
            return False
        return True

    low, high = lowest, float(condition["main_steam_flow"])
    if not runs(low):
        return None
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if runs(middle) else (low, middle)
    flow = CAPACITY_MARGIN * low
    return flow if runs(flow) else low


def _widen(interval: tuple[float, float], low: float, high: float) -> tuple[float, float]:
    return (min(interval[0], low), max(interval[1], high))


def operating_envelope(spec: TurbineSpec, params: ModelParameters | None = None, *,
                       loads: Sequence[float], pressure_variation: float,
                       temperature_variation: float, flow_variation: float,
                       maximum_flow_fraction: float,
                       parameter_intervals: Mapping[str, tuple[float, float]] | None = None,
                       observed: pd.DataFrame | None = None,
                       params_source: str | None = None,
                       model: FullOrderModel | None = None) -> OperatingEnvelope:
    """The boxes the snapshots must cover (see the module docstring).

    ``loads``: the design's load levels (fractions, increasing); ``pressure_variation``
    (fraction), ``temperature_variation`` (K), ``flow_variation`` (fraction): the boxes about
    the operating line; ``maximum_flow_fraction``: the highest flow of the boxes, fraction of
    rated (the rated box is shifted down to end there). ``parameter_intervals``: name →
    (low, high) of model parameters (within their physical bounds). ``observed``: historian
    signals (SI) with the ROM's inputs and optionally ``main_steam_flow`` (kg/s).
    ``params_source`` names where ``params`` came from, for errors. Raises
    :class:`EnvelopeError` when the model cannot run the operating line at a level.
    """
    params = params or ModelParameters()
    model = model or FullOrderModel(spec)
    top = spec.sliding_pressure.load_fraction[-1]
    line = operating_line(spec, params, model=model)
    sources = ["operating line"]
    levels = [float(v) for v in loads]
    observed_rows = _observed_offsets(spec, line, observed) if observed is not None else None
    if observed_rows is not None and len(observed_rows):
        sources.append(f"observed inputs ({len(observed_rows)} samples)")
        lowest = float(observed_rows["equivalent_load"].min()) - OBSERVED_LOAD_MARGIN
        if lowest < levels[0] * (1.0 - flow_variation):  # below the lowest level's box
            levels.insert(0, max(MINIMUM_LOAD, lowest))
    for level in levels:
        if not MINIMUM_LOAD <= level <= top:
            raise ValueError(f"load level {level:g} outside {MINIMUM_LOAD}…{top:g} (the "
                             "spec's sliding_pressure line)")
    at_levels = operating_line(spec, params, levels, model=model)
    for level, row in at_levels.iterrows():
        if row["failure"]:
            raise _line_error(spec, model, params, float(level), row["failure"], params_source)
    boxes = [line_box(level, pressure_variation, temperature_variation, flow_variation,
                      maximum_flow_fraction) for level in levels]
    if parameter_intervals:
        boxes = _widen_by_parameters(spec, model, params, boxes, at_levels, parameter_intervals,
                                     params_source)
        sources.append("parameter intervals " + ", ".join(
            f"{name} {low:g}…{high:g}" for name, (low, high) in parameter_intervals.items()))
    if observed_rows is not None and len(observed_rows):
        boxes = _widen_by_observations(boxes, observed_rows)
    points = valve_points(spec, line)
    if points:
        sources.append("valve points")
    return OperatingEnvelope(tuple(boxes), points, line, tuple(sources), observed_rows)


def _widen_by_parameters(spec: TurbineSpec, model: FullOrderModel, params: ModelParameters,
                         boxes: list[LevelBox], at_levels: pd.DataFrame,
                         intervals: Mapping[str, tuple[float, float]],
                         source: str | None) -> list[LevelBox]:
    """Flow boxes widened by the p1 a plant at each interval end shows on the line."""
    loads = [box.load for box in boxes]
    reference = at_levels["control_stage_pressure"].to_numpy()
    low_ratio, high_ratio = np.ones(len(boxes)), np.ones(len(boxes))
    for name, interval in intervals.items():
        if name not in PARAMETER_BOUNDS:
            raise ParameterError(f"parameter interval {name!r}: unknown parameter (expected one "
                                 f"of {', '.join(PARAMETER_BOUNDS)})")
        low, high = (float(v) for v in interval)
        value = getattr(params, name)
        if not low <= value <= high:
            raise ParameterError(f"parameter interval {name} {low:g}…{high:g} does not contain "
                                 f"{_parameter_label(params, name, source)}")
        for end in (low, high):
            ended = dataclasses.replace(params, **{name: end})  # checks the physical bounds
            ratio = operating_line(spec, ended, loads, model=model
                                   )["control_stage_pressure"].to_numpy() / reference
            # an end the model cannot run at a level passes no plant state there: no widening
            ratio = np.where(np.isfinite(ratio), ratio, 1.0)
            low_ratio, high_ratio = np.minimum(low_ratio, ratio), np.maximum(high_ratio, ratio)
    return [dataclasses.replace(box, flow_factor=(float(box.flow_factor[0] * lo),
                                                  float(box.flow_factor[1] * hi)))
            for box, lo, hi in zip(boxes, low_ratio, high_ratio, strict=True)]


def _observed_offsets(spec: TurbineSpec, line: pd.DataFrame, observed: pd.DataFrame
                      ) -> pd.DataFrame:
    """Per observed sample: its load and its offsets from the operating line at that load."""
    names = ["main_steam_pressure", "main_steam_temperature", "control_stage_pressure"]
    missing = [name for name in names if name not in observed.columns]
    if missing:
        raise ValueError(f"the observed data lack the ROM input signal(s) {missing}")
    data = observed[names].apply(pd.to_numeric, errors="coerce")
    ran = line[line["failure"] == ""]
    p1_line = ran["control_stage_pressure"].to_numpy()
    load_from_p1 = np.interp(data["control_stage_pressure"].to_numpy(), p1_line,
                             ran.index.to_numpy(), left=np.nan, right=np.nan)
    # beyond the line's ends: p1 ∝ flow (module docstring) extrapolates the load
    low_end, high_end = data["control_stage_pressure"] < p1_line[0], \
        data["control_stage_pressure"] > p1_line[-1]
    load_from_p1[low_end.to_numpy()] = (ran.index[0] * data["control_stage_pressure"][low_end]
                                        / p1_line[0]).to_numpy()
    load_from_p1[high_end.to_numpy()] = (ran.index[-1] * data["control_stage_pressure"][high_end]
                                         / p1_line[-1]).to_numpy()
    flow = (pd.to_numeric(observed["main_steam_flow"], errors="coerce").to_numpy()
            if "main_steam_flow" in observed.columns else np.full(len(data), np.nan))
    load_from_flow = flow / spec.design.main_steam_flow
    has_flow = np.isfinite(load_from_flow)
    load = np.where(has_flow, load_from_flow, load_from_p1)
    table = pd.DataFrame({"load": load, **{name: data[name].to_numpy() for name in names}})
    table = table[np.all(np.isfinite(table.to_numpy(dtype=float)), axis=1)]
    top = spec.sliding_pressure.load_fraction[-1]
    on_line = np.clip(table["load"].to_numpy(), MINIMUM_LOAD, top)
    point = operating_point(spec, on_line)
    table["pressure_factor"] = table["main_steam_pressure"] / point["main_steam_pressure"]
    table["temperature_offset"] = (table["main_steam_temperature"]
                                   - point["main_steam_temperature"])
    p1_at_load = np.interp(on_line, ran.index.to_numpy(), p1_line)
    # the sample's flow as a load fraction, where it sits along the levels' flow axis: from
    # the line's at its load by the cone law m ∝ p1/sqrt(T) (Stodola 1927; Cooke 1985; the
    # control-stage temperature taken ∝ the main-steam temperature), exact on the line
    table["equivalent_load"] = (on_line * table["control_stage_pressure"] / p1_at_load
                                * np.sqrt(point["main_steam_temperature"]
                                          / table["main_steam_temperature"]))
    return table


def _widen_by_observations(boxes: list[LevelBox], rows: pd.DataFrame) -> list[LevelBox]:
    """Each level's box widened to its band's observed offsets, plus the instruments' margins.

    A level's band runs halfway to its neighbours; the outer bands are open-ended, and the
    outer levels' flow boxes also reach their bands' equivalent loads.
    """
    loads = np.array([box.load for box in boxes])
    edges = 0.5 * (loads[1:] + loads[:-1])
    band = np.searchsorted(edges, rows["load"].to_numpy())
    widened = []
    for k, box in enumerate(boxes):
        mine = rows[band == k]
        if mine.empty:
            widened.append(box)
            continue
        pressure = _widen(box.pressure_factor,
                          mine["pressure_factor"].min() - OBSERVED_PRESSURE_MARGIN,
                          mine["pressure_factor"].max() + OBSERVED_PRESSURE_MARGIN)
        temperature = _widen(box.temperature_offset,
                             mine["temperature_offset"].min() - OBSERVED_TEMPERATURE_MARGIN,
                             mine["temperature_offset"].max() + OBSERVED_TEMPERATURE_MARGIN)
        flow = box.flow_factor
        equivalent = mine["equivalent_load"] / box.load
        if k == 0:  # inner bands lie between their levels' boxes
            flow = _widen(flow, equivalent.min() - OBSERVED_PRESSURE_MARGIN, flow[1])
        if k == len(boxes) - 1:
            flow = _widen(flow, flow[0], equivalent.max() + OBSERVED_PRESSURE_MARGIN)
        widened.append(dataclasses.replace(box, pressure_factor=pressure,
                                           temperature_offset=temperature, flow_factor=flow))
    return widened


def feasible_conditions(spec: TurbineSpec, conditions: pd.DataFrame,
                        params: ModelParameters | None = None, *,
                        params_source: str | None = None, model: FullOrderModel | None = None
                        ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``conditions`` with every row the model cannot run replaced by one it can (SI).

    Over the valves' capacity: the same (p0, T0) at the highest flow they pass (× 0.998), plus
    one added row at the same flow and the lowest throttle pressure that passes it, when that
    lies within the level's planned pressures — the two points on the capacity limit
    (∝ p0: choked nozzle flow) that the infeasible corner stood for, so the snapshots' hull
    keeps the flows near the limit. Any other failure, or no flow passing: the farthest point
    that runs on the segment from the level's operating-line point (``load_level``) to the row.
    Returns the conditions and a table of the replacements (``row``, ``reason``,
    ``flow_before``, ``flow_after`` kg/s, ``pressure_before``, ``pressure_after`` Pa,
    ``temperature_before``, ``temperature_after`` K; an added row has the row number it got).
    Raises :class:`EnvelopeError` (naming the parameters, from ``params_source``) if a level's
    operating-line point itself fails.
    """
    params = params or ModelParameters()
    model = model or FullOrderModel(spec)
    table = conditions.reset_index(drop=True).copy()
    replaced = []
    added = []

    def record(i: int, reason: str, before: Mapping[str, float], after: Mapping[str, float]
               ) -> None:
        replaced.append({"row": i, "reason": reason,
                         **{f"{key}_{when}": value[name] for key, name in (
                             ("flow", "main_steam_flow"), ("pressure", "main_steam_pressure"),
                             ("temperature", "main_steam_temperature"))
                            for when, value in (("before", before), ("after", after))}})

    for i in range(len(table)):
        row = {name: float(table.loc[i, name]) for name in INPUT_SIGNALS}
        try:
            _run(model, row, params)
            continue
        except InputError as error:
            reason = error.reason
        level = float(table.loc[i, "load_level"])
        new = None
        if OVER_CAPACITY in reason:
            flow = _highest_flow(model, row, params, spec, 0.5 * row["main_steam_flow"])
            if flow is not None:
                new = _with_flow(spec, row, flow)
                highest = float(table.loc[table["load_level"] == level,
                                          "main_steam_pressure"].max())
                pressure = _lowest_pressure(model, row, params, highest)
                if pressure is not None:
                    extra = dict(row, main_steam_pressure=pressure)
                    record(len(table) + len(added), reason, row, extra)
                    added.append({**table.loc[i].to_dict(), **extra})
        if new is None:
            new = _toward_line(spec, model, params, row, level)
        if new is None:
            raise _line_error(spec, model, params, level, reason, params_source)
        record(i, reason, row, new)
        for name in INPUT_SIGNALS:
            table.loc[i, name] = new[name]
        table.loc[i, "load_fraction"] = new["main_steam_flow"] / spec.design.main_steam_flow
    if added:
        table = pd.concat([table, pd.DataFrame(added)], ignore_index=True)
    return table, pd.DataFrame(replaced, columns=[
        "row", "reason", "flow_before", "flow_after", "pressure_before", "pressure_after",
        "temperature_before", "temperature_after"]).sort_values("row", ignore_index=True)


def _lowest_pressure(model: FullOrderModel, condition: Mapping[str, float],
                     params: ModelParameters, highest: float) -> float | None:
    """Lowest throttle pressure (Pa) in [the condition's, ``highest``] at which the model runs
    the condition's flow, times 1/CAPACITY_MARGIN; None if not even ``highest`` does."""
    def runs(pressure: float) -> bool:
        try:
            _run(model, dict(condition, main_steam_pressure=pressure), params)
        except InputError:
            return False
        return True

    low, high = float(condition["main_steam_pressure"]), highest
    if high <= low or not runs(high):
        return None
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if runs(middle) else (middle, high)
    pressure = min(high / CAPACITY_MARGIN, highest)
    return pressure if runs(pressure) else high


def _toward_line(spec: TurbineSpec, model: FullOrderModel, params: ModelParameters,
                 row: Mapping[str, float], level: float) -> dict[str, float] | None:
    """The farthest point from the level's line point toward ``row`` that runs (bisection)."""
    centre = {k: float(v) for k, v in operating_point(spec, level).items()}

    def at(share: float) -> dict[str, float]:
        point = {name: centre[name] + share * (row[name] - centre[name])
                 for name in ("main_steam_pressure", "main_steam_temperature",
                              "main_steam_flow")}
        return _with_flow(spec, point, point["main_steam_flow"])

    def runs(share: float) -> bool:
        try:
            _run(model, at(share), params)
        except InputError:
            return False
        return True

    if not runs(0.0):
        return None
    low, high = 0.0, 1.0
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if runs(middle) else (low, middle)
    return at(low)


def observed_anchors(spec: TurbineSpec, envelope: OperatingEnvelope, conditions: pd.DataFrame,
                     params: ModelParameters | None = None, *,
                     model: FullOrderModel | None = None) -> pd.DataFrame:
    """Snapshot conditions (SI) that put the observed samples outside the hull of
    ``conditions`` inside it: per load band, a simplex about those samples' box.

    A Latin hypercube's points span only part of their box, and the unit's holds (the samples
    that matter most) may sit near a box's edge, e.g. at rated flow near the valves' capacity.
    The ROM's inputs (p0, T0, p1) of ``conditions`` come from one steady model run; an
    observed sample outside their convex hull (scaled by their range, as the ROM's
    extrapolation check) joins its band's group; each group's box in (p0, T0, flow) — flow
    from the equivalent load — plus the instruments' margins gets the four vertices of a
    simplex containing it (ANCHOR_SPAN), pointing into the design (towards the conditions'
    mean). Empty without observations or with all of them inside.
    """
    from scipy.spatial import Delaunay  # only needed when there are observations

    columns = ["load_level", "load_fraction", *INPUT_SIGNALS]
    rows = envelope.observed
    if rows is None or rows.empty:
        return pd.DataFrame(columns=columns)
    params = params or ModelParameters()
    model = model or FullOrderModel(spec)
    inputs = conditions[list(INPUT_SIGNALS)].set_index(
        pd.Index(np.arange(len(conditions)) * STEADY_STEP_S))
    p1 = model.simulate_detailed(inputs, params, stages=False).diagnostics[
        "control_stage_pressure"].to_numpy()
    planned = np.column_stack([conditions["main_steam_pressure"],
                               conditions["main_steam_temperature"], p1])
    low, span = planned.min(axis=0), np.ptp(planned, axis=0)
    seen = rows[["main_steam_pressure", "main_steam_temperature",
                 "control_stage_pressure"]].to_numpy()
    outside = Delaunay((planned - low) / span).find_simplex((seen - low) / span) < 0
    if not outside.any():
        return pd.DataFrame(columns=columns)
    flow = rows["equivalent_load"].to_numpy() * spec.design.main_steam_flow
    points = np.column_stack([rows["main_steam_pressure"], rows["main_steam_temperature"],
                              flow])[outside]
    loads = np.array([box.load for box in envelope.levels])
    band = np.searchsorted(0.5 * (loads[1:] + loads[:-1]),
                           rows["equivalent_load"].to_numpy()[outside])
    mean = conditions[["main_steam_pressure", "main_steam_temperature",
                       "main_steam_flow"]].to_numpy().mean(axis=0)
    anchors = []
    for k in np.unique(band):
        group = points[band == k]
        centre = 0.5 * (group.min(axis=0) + group.max(axis=0))
        half = 0.5 * (group.max(axis=0) - group.min(axis=0)) + np.array([
            OBSERVED_PRESSURE_MARGIN * centre[0], OBSERVED_TEMPERATURE_MARGIN,
            OBSERVED_PRESSURE_MARGIN * centre[2]])
        sign = np.where(centre >= mean, 1.0, -1.0)
        corner = centre + sign * half
        vertices = [corner] + [corner - ANCHOR_SPAN * sign[i] * half[i] * np.eye(3)[i]
                               for i in range(3)]
        for p0, t0, m in vertices:
            load = m / spec.design.main_steam_flow
            anchors.append({"load_level": float(loads[k]), "load_fraction": load,
                            "main_steam_pressure": p0, "main_steam_temperature": t0,
                            "main_steam_flow": m,
                            "hp_exhaust_pressure": float(hp_exhaust_pressure(spec, m, load))})
    return pd.DataFrame(anchors, columns=columns)
