"""The model's own design point and off-design line, and whether a spec can pass its rated flow.

A spec is a heat balance plus geometry; the full-order model derives its constants from them
(``model.design``) and then *predicts* the control-stage pressure and HP power at rated load
(only the HP-exhaust temperature is met by construction, through one efficiency scale). This
module puts those predictions beside the spec's figures (:func:`design_point`), runs the model
steady along the spec's sliding-pressure line (:func:`design_line`) and says, in plant terms, why
a spec cannot be run at all (:func:`consistency_problems`); :func:`check_design` does all three
(and, given a thermal kit, the model at each of its points) as ``steamtwin turbine check`` does.
All values SI (Pa, K, kg/s, W), except :func:`line_in_engineering_units`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np
import pandas as pd

from steamtwin.errors import ModelError
from steamtwin.model.design_fit import point_residuals
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.model.operating import operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import SpecError, TurbineSpec
from steamtwin.spec.heat_balance import HeatBalance

__all__ = ["DEFAULT_LOADS", "LINE_COLUMNS", "DesignCheck", "DesignError", "check_design",
           "checked_loads", "consistency_problems", "design_line", "design_point",
           "line_in_engineering_units", "valve_openings"]

DEFAULT_LOADS = (1.0, 0.75, 0.5, 0.4, 0.3)

# The sliding-pressure line at 100 % load and the design main-steam pressure must agree within
# the acceptance band of issue 17 for pressures (0.5 %): otherwise the off-design line's 100 %
# point is not the design point the model was sized at.
RATED_PRESSURE_TOLERANCE = 0.005
# Likewise the temperature schedule at 100 % load and the design main-steam temperature, within
# the band of issue 17 for temperatures (1.0 K).
RATED_TEMPERATURE_TOLERANCE = 1.0

# Admitting arc (share of the circumference) below which a valve level counts as shut: the
# round-off of summing the arcs of the levels before it.
_OPENING_BISECTIONS = 60  # demand resolution 2⁻⁶⁰ of the levels: far below round-off
_ARC_ROUND_OFF = 1e-12

# The spec fields behind each way the model's design step can fail, matched on the model's own
# message (model.fom / model.design); the last entry is the fallback.
_DESIGN_FAILURES = (
    ("exceeds what the wide-open governing valves pass",
     "the governing valves open at design (control_stage.valves[*].open_at_design, "
     "admission_arc), their nozzles sized to pass design.main_steam_flow at "
     "design.control_stage_pressure, cannot pass it at the higher control-stage pressure the "
     "pressure stages impose (stages[*].flow_capacity with design.hp_exhaust_pressure): the heat "
     "balance's control-stage pressure and the stages' flow capacities disagree"),
    ("stage pressures reach the throttle pressure",
     "the pressure stages (stages[*].flow_capacity) are too small to swallow "
     "design.main_steam_flow between design.main_steam_pressure and design.hp_exhaust_pressure"),
    ("leaves the superheated region",
     "a steam state of the design expansion leaves superheated steam or the property tables "
     "(design.main_steam_pressure, design.main_steam_temperature, design.hp_exhaust_pressure, "
     "stage efficiencies)"),
    ("did not converge",
     "the steam path does not converge at the design point (stages[*].flow_capacity, "
     "design.hp_exhaust_pressure, design.main_steam_flow)"),
    ("stage efficiencies scaled by",
     "the blade efficiencies (control_stage and stages[*].peak_blade_efficiency, "
     "friction_loss) cannot reproduce design.hp_exhaust_temperature"),
    ("no efficiency scale meets",
     "the blade efficiencies (control_stage and stages[*].peak_blade_efficiency, "
     "friction_loss) cannot reproduce design.hp_exhaust_temperature"),
    ("not below the valve outlet pressure",
     "design.control_stage_pressure is not below the pressure after the wide-open valves, "
     "design.main_steam_pressure·(1 − design.valve_pressure_drop)"),
    ("", "the design point cannot be solved (design, control_stage.valves, stages)"),
)


_KELVIN = 273.15

#: Design-line columns in engineering units: SI column → (column with its unit, SI → that unit).
LINE_COLUMNS: dict[str, tuple[str, Callable[[np.ndarray], np.ndarray]]] = {
    "main_steam_pressure": ("main_steam_pressure_MPa", lambda x: x / 1e6),
    "main_steam_temperature": ("main_steam_temperature_degC", lambda x: x - _KELVIN),
    "main_steam_flow": ("main_steam_flow_t_per_h", lambda x: x * 3.6),
    "control_stage_pressure": ("control_stage_pressure_MPa", lambda x: x / 1e6),
    "control_stage_temperature": ("control_stage_temperature_degC", lambda x: x - _KELVIN),
    "hp_exhaust_pressure": ("hp_exhaust_pressure_MPa", lambda x: x / 1e6),
    "hp_exhaust_temperature": ("hp_exhaust_temperature_degC", lambda x: x - _KELVIN),
    "hp_power": ("hp_power_MW", lambda x: x / 1e6),
    "control_stage_efficiency": ("control_stage_efficiency_pct", lambda x: x * 100),
    "admission_arc": ("admission_arc_pct", lambda x: x * 100),
}


class DesignError(ModelError):
    """The model cannot run a spec's design point or off-design line; the message says why and
    names the spec fields involved."""


@dataclass(frozen=True)
class DesignCheck:
    """What :func:`check_design` found.

    ``problems``: why the spec cannot pass its rated flow (empty: it can; then the rest is
    filled). ``point``: :func:`design_point`; ``line``: :func:`design_line` (SI);
    ``residuals``: model − kit per heat-balance point (``model.design_fit.point_residuals``;
    % or K), None without a kit.
    """

    problems: list[str]
    point: pd.DataFrame | None = None
    line: pd.DataFrame | None = None
    residuals: pd.DataFrame | None = None


def check_design(spec: TurbineSpec, loads: Sequence[float] = DEFAULT_LOADS,
                 heat_balance: HeatBalance | None = None) -> DesignCheck:
    """Whether the model can pass the spec's rated flow and, if it can, its design point, its
    steady off-design line at ``loads`` (fractions of rated load) and, given ``heat_balance``,
    its residuals at every point of that thermal kit.

    Raises :class:`DesignError` when the model cannot run one of the loads, and
    ``DesignFitError`` (``model.design_fit``) when it cannot run a kit's point.
    """
    model = FullOrderModel(spec)
    problems = consistency_problems(spec, model)
    if problems:
        return DesignCheck(problems)
    point = design_point(spec, model=model)
    line = design_line(spec, loads, model=model)
    residuals = None if heat_balance is None else point_residuals(spec, heat_balance)
    return DesignCheck([], point, line, residuals)


def line_in_engineering_units(spec: TurbineSpec, line: pd.DataFrame) -> pd.DataFrame:
    """The design line (:func:`design_line`) with the unit in each column name (MPa, degC,
    t/h, MW, %; :data:`LINE_COLUMNS`, then ``<valve>_opening_pct``), indexed by ``load_pct``."""
    shown = pd.DataFrame({name: convert(line[column].to_numpy())
                          for column, (name, convert) in LINE_COLUMNS.items()})
    for valve in spec.control_stage.valves:
        shown[f"{valve.name}_opening_pct"] = line[f"{valve.name}_opening"].to_numpy() * 100
    shown.insert(0, "load_pct", line.index.to_numpy() * 100)
    return shown.set_index("load_pct")


def consistency_problems(spec: TurbineSpec, model: FullOrderModel | None = None) -> list[str]:
    """Why ``spec`` cannot pass its own rated flow in the model (empty list: it can).

    Checks, in plant terms: a governing valve left closed at rated load; the sliding-pressure
    line reaching rated load at the design main-steam pressure, and a temperature schedule at
    the design main-steam temperature; the model's design step (nozzle
    sizing, efficiency scale, rated flow through the valves open at design). ``model`` (of this
    spec) reuses a model already designed; otherwise one is built (the first run compiles the
    kernel, ~20 s).
    """
    problems = [*_sliding_line_problems(spec), *_temperature_schedule_problems(spec)]
    valves = spec.control_stage.valves
    if (all(valve.open_at_design for valve in valves)
            and spec.design.valve_outlet_pressure is None
            and any(valve.throat_area is None for valve in valves)):
        # the model's design step would only fail with a less telling reason
        return [_all_valves_open_problem(spec), *problems]
    model = _model_of(spec, model)
    try:
        _ = model.design_
    except SpecError as error:
        reason = next(fields for key, fields in _DESIGN_FAILURES if key in str(error))
        problems.append(f"turbine {spec.name!r}: {reason} (the model says: {error})")
    return problems


def design_point(spec: TurbineSpec, params: ModelParameters | None = None,
                 model: FullOrderModel | None = None) -> pd.DataFrame:
    """The model's steady design point beside the spec's heat balance (SI).

    Rows ``control_stage_pressure`` (Pa), ``hp_exhaust_temperature`` (K), ``hp_power`` (W);
    columns ``spec``, ``model`` and ``difference`` (model − spec). The HP-exhaust temperature is
    met by the design step with the empirical parameters; the other two are predictions.
    Raises :class:`DesignError` when the model cannot run the spec.
    """
    model = _designed(spec, model)
    diagnostics = _steady(model, model.design_inputs(), params, "the design point")
    design = spec.design
    rows = {"control_stage_pressure": design.control_stage_pressure,
            "hp_exhaust_temperature": design.hp_exhaust_temperature,
            "hp_power": design.hp_power}
    table = pd.DataFrame({"spec": pd.Series(rows, dtype=float),
                          "model": diagnostics[list(rows)].iloc[0].astype(float)})
    table["difference"] = table["model"] - table["spec"]
    table.index.name = "quantity"
    return table


def design_line(spec: TurbineSpec, loads: Sequence[float] = DEFAULT_LOADS,
                params: ModelParameters | None = None, model: FullOrderModel | None = None
                ) -> pd.DataFrame:
    """The model's steady states along the spec's sliding-pressure line (SI), one row per load.

    ``loads``: fractions of rated load (0.2 up to the line's last point), distinct; boundary
    conditions from :func:`~steamtwin.model.operating.operating_point`; each load is run as its
    own one-sample (steady) simulation. Index ``load_fraction``; columns: the inputs
    ``main_steam_pressure``, ``main_steam_temperature``, ``main_steam_flow``,
    ``hp_exhaust_pressure``; the model's ``control_stage_pressure``,
    ``control_stage_temperature``, ``hp_exhaust_temperature``, ``hp_power``,
    ``control_stage_efficiency``, ``admission_arc`` (admitting share of the circumference) and
    ``<valve>_opening`` per governing valve (0–1, see :func:`valve_openings`). Raises
    :class:`DesignError` for bad loads or when the model cannot run one of them.
    """
    load_array = checked_loads(spec, loads)
    model = _designed(spec, model)
    boundary = operating_point(spec, load_array)
    rows = []
    for k, load in enumerate(load_array):
        inputs = pd.DataFrame({name: [values[k]] for name, values in boundary.items()},
                              index=pd.to_datetime(["2000-01-01T00:00:00Z"]))
        diagnostics = _steady(model, inputs, params, f"{load:.0%} load")
        row = {name: float(values[k]) for name, values in boundary.items()}
        for name in ("control_stage_pressure", "control_stage_temperature",
                     "hp_exhaust_temperature", "hp_power", "control_stage_efficiency"):
            row[name] = float(diagnostics[name].iloc[0])
        arc = float(diagnostics["active_admission_arc"].iloc[0])
        row["admission_arc"] = arc
        row.update({f"{name}_opening": opening
                    for name, opening in valve_openings(spec, arc).items()})
        rows.append(row)
    columns = ["main_steam_pressure", "main_steam_temperature", "main_steam_flow",
               "control_stage_pressure", "control_stage_temperature", "hp_exhaust_pressure",
               "hp_exhaust_temperature", "hp_power", "control_stage_efficiency", "admission_arc",
               *(f"{valve.name}_opening" for valve in spec.control_stage.valves)]
    return pd.DataFrame(rows, index=pd.Index(load_array, name="load_fraction"))[columns]


def valve_openings(spec: TurbineSpec, admission_arc: float) -> dict[str, float]:
    """Each governing valve's lift (0–1 of full lift) for the model's admitting arc (share of
    the circumference).

    The model opens the valves level by level in ``opening_order`` and counts a part-open
    level's arc in proportion to its flow (``model.kernel``). With a valve overlap v
    (``control_stage.valve_overlap``) level k's lift is clamp(x − k·(1 − v), 0, 1) of one
    common demand x — the next level starts ``v`` of a lift before the previous one is wide
    open; v = 0 is strictly sequential opening — and x is the demand whose levels admit
    ``admission_arc`` (bisection; the admitted arc rises monotonically with x). A level's
    flow, as a share of its wide-open flow at the same pressures, is the valves' flow
    characteristic (``control_stage.valve_characteristic``, linear by default) at its lift.
    """
    cs = spec.control_stage
    valves = cs.valves
    orders = sorted({valve.opening_order for valve in valves})
    level_arcs = np.array([sum(valve.admission_arc for valve in valves
                               if valve.opening_order == order) for order in orders])
    starts = np.arange(len(orders)) * (1.0 - cs.valve_overlap)
    characteristic_lift, characteristic_flow = cs.valve_characteristic

    def lifts_at(demand: float) -> np.ndarray:
        return np.clip(demand - starts, 0.0, 1.0)

    low, high = 0.0, float(starts[-1]) + 1.0
    if admission_arc <= _ARC_ROUND_OFF:
        high = 0.0
    for _ in range(_OPENING_BISECTIONS):
        middle = 0.5 * (low + high)
        shares = np.interp(lifts_at(middle), characteristic_lift, characteristic_flow)
        if float(level_arcs @ shares) < admission_arc:
            low = middle
        else:
            high = middle
    by_order = dict(zip(orders, lifts_at(high), strict=True))
    return {valve.name: float(by_order[valve.opening_order]) for valve in valves}


def _all_valves_open_problem(spec: TurbineSpec) -> str:
    """What goes wrong, in plant terms, when every governing valve is open at rated load."""
    valves = spec.control_stage.valves
    last = max(valve.opening_order for valve in valves)
    names = ", ".join(valve.name for valve in valves if valve.opening_order == last)
    design = spec.design
    return (
        f"turbine {spec.name!r}: every governing valve is open at rated load "
        f"(control_stage.valves[*].open_at_design = true), so rated flow is the valves' "
        f"full capacity: the nozzles are sized to pass exactly design.main_steam_flow "
        f"({design.main_steam_flow * 3.6:.0f} t/h) at design.control_stage_pressure "
        f"({design.control_stage_pressure / 1e6:.2f} MPa) with no valve left to open, and "
        f"any higher control-stage pressure (the model's first steam-path sweep passes "
        f"through one) or any flow above rated leaves them short of it; the model cannot "
        f"solve the design point. A nozzle-governed unit reaches rated load at a valve "
        f"point with a valve still closed (its overload reserve): set open_at_design = "
        f"false on {names} (opening_order {last})")


def _sliding_line_problems(spec: TurbineSpec) -> list[str]:
    """The sliding-pressure line must reach rated load at the design main-steam pressure."""
    problems = []
    line = spec.sliding_pressure
    if line.load_fraction[-1] < 1.0:
        problems.append(
            f"turbine {spec.name!r}: sliding_pressure.load_fraction ends at "
            f"{line.load_fraction[-1]:g}, below rated load (1.0): the operating line does not "
            f"reach the design point")
    else:
        rated = float(np.interp(1.0, line.load_fraction, line.pressure))
        design_pressure = spec.design.main_steam_pressure
        if abs(rated / design_pressure - 1.0) > RATED_PRESSURE_TOLERANCE:
            problems.append(
                f"turbine {spec.name!r}: sliding_pressure gives {rated / 1e6:.2f} MPa at rated "
                f"load but design.main_steam_pressure is {design_pressure / 1e6:.2f} MPa "
                f"(more than {RATED_PRESSURE_TOLERANCE:.1%} apart): the operating line misses "
                f"the design point")
    return problems


def _temperature_schedule_problems(spec: TurbineSpec) -> list[str]:
    """A temperature schedule must give the design main-steam temperature at rated load."""
    schedule = spec.temperature_schedule
    if schedule is None:
        return []
    rated = float(np.interp(1.0, schedule.load_fraction, schedule.main_steam_temperature))
    design_temperature = spec.design.main_steam_temperature
    if abs(rated - design_temperature) <= RATED_TEMPERATURE_TOLERANCE:
        return []
    return [f"turbine {spec.name!r}: temperature_schedule gives {rated - 273.15:.1f} °C at rated "
            f"load but design.main_steam_temperature is {design_temperature - 273.15:.1f} °C "
            f"(more than {RATED_TEMPERATURE_TOLERANCE:g} K apart): the operating line misses "
            "the design point"]


def _model_of(spec: TurbineSpec, model: FullOrderModel | None) -> FullOrderModel:
    if model is None:
        return FullOrderModel(spec)
    if model.spec != spec:
        raise ValueError(f"model is of turbine {model.spec.name!r}, not of the spec checked "
                         f"({spec.name!r})")
    return model


def _designed(spec: TurbineSpec, model: FullOrderModel | None) -> FullOrderModel:
    """A model of ``spec`` whose design step has run; DesignError with the reasons if it cannot."""
    model = _model_of(spec, model)
    problems = consistency_problems(spec, model)
    if problems:
        raise DesignError("; ".join(problems))
    return model


def _steady(model: FullOrderModel, inputs: pd.DataFrame, params: ModelParameters | None,
            where: str) -> pd.DataFrame:
    """Diagnostics of a one-sample (hence steady) run; DesignError naming ``where`` on failure."""
    try:
        result = model.simulate_detailed(inputs, params, stages=False)
    except InputError as error:
        raise DesignError(f"turbine {model.spec.name!r}: the model cannot run {where}: "
                          f"{error.reason}") from None
    return cast(pd.DataFrame, result.diagnostics)  # simulate_detailed always returns them


def checked_loads(spec: TurbineSpec, loads: Sequence[float]) -> np.ndarray:
    """``loads`` as an array of distinct load fractions on the spec's sliding-pressure line
    (0.2 up to its last point); :class:`DesignError` naming the bad value otherwise."""
    try:
        values = np.asarray(loads, dtype=float)
    except (TypeError, ValueError):
        raise DesignError(f"loads: expected load fractions (numbers), got {loads!r}") from None
    if values.ndim != 1 or values.size == 0:
        raise DesignError(f"loads: expected a non-empty list of load fractions, got {loads!r}")
    for number, value in enumerate(values, start=1):
        try:
            operating_point(spec, float(value))  # its range: 0.2 up to the line's last point
        except ValueError as error:
            raise DesignError(f"loads[{number}] (1-based): {error}") from None
    if np.unique(values).size != values.size:
        raise DesignError(f"loads repeat a value: {values.tolist()}")
    return values
