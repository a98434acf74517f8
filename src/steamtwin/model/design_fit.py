"""Design fit: the spec's part-load laws adjusted so the model meets every heat-balance point.

A thermal kit gives, at each load, the boundary conditions the model takes as inputs (main-steam
pressure, temperature and flow, HP-exhaust pressure) and what the model predicts from them:
the control-stage pressure and temperature and the HP-exhaust temperature (the exhaust pressure
is an input, so it is not a residual). :func:`fit_design` adjusts the spec's ``[part_load]``
laws (:class:`~steamtwin.spec.turbine.PartLoad`) within the schema's ranges by bounded least
squares (``scipy.optimize.least_squares``), each point run as its own steady one-sample
simulation, and reports the residuals before and after and what each point identified.
The DCS calibration's parameters (flow, friction, heat transfer) stay at 1: they are fitted
later, on plant data.

Residuals are weighted by the acceptance band of issue 17 (0.5 % in pressure, 1.0 K in
temperature), so that one unit of cost means one band missed. Parameters are scaled to their
range, so the Jacobian columns read as "change of a point's residuals (band units) over the
parameter's whole range".
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from steamtwin.errors import ModelError
from steamtwin.model.fom import FullOrderModel, InputError
from steamtwin.spec import SpecError, TurbineSpec
from steamtwin.spec.heat_balance import HeatBalance, HeatBalancePoint
from steamtwin.spec.schema import FIELD_BY_KEY
from steamtwin.spec.turbine import PartLoad

__all__ = ["ACCEPTANCE_BAND", "FIT_PARAMETERS", "RESIDUALS", "DesignFit", "DesignFitError",
           "fit_design", "fitted_spec_toml", "given_value", "outside_band", "point_residuals"]

#: The part-load laws the fit adjusts by default (fields of :class:`PartLoad`).
FIT_PARAMETERS: tuple[str, ...] = tuple(field.name for field in fields(PartLoad))

#: Residual columns: model − heat balance, in % of the given pressure or in K.
RESIDUALS = ("control_stage_pressure_pct", "control_stage_temperature_k",
             "hp_exhaust_temperature_k")
#: Acceptance band of issue 17 per residual column (0.5 % in pressure, 1.0 K in temperature):
#: the fit's weights, and the limit beyond which :func:`outside_band` reports a point.
ACCEPTANCE_BAND: dict[str, float] = {"control_stage_pressure_pct": 0.5,
                                     "control_stage_temperature_k": 1.0,
                                     "hp_exhaust_temperature_k": 1.0}
_BAND = np.array([ACCEPTANCE_BAND[column] for column in RESIDUALS])
_MODEL_COLUMNS = ("control_stage_pressure", "control_stage_temperature",
                  "hp_exhaust_temperature")
# Finite-difference step on the range-scaled parameters: single-sample runs converge to 1e-10
# relative pressure and 2.5e-5 J/kg (model.kernel START_FLOOR), so a 1e-4 step of the range
# keeps the differences far above the solver's noise.
_DIFF_STEP = 1e-4
# A scaled Jacobian's singular value below this share of the largest marks a direction the
# points do not identify (the parameters then trade off against each other).
_RANK_TOLERANCE = 1e-3


class DesignFitError(ModelError):
    """The design fit cannot run: too few or bad heat-balance points, unknown parameters, or
    a point the model cannot solve; the message names the point and field."""


@dataclass(frozen=True)
class DesignFit:
    """What :func:`fit_design` found.

    ``part_load``: the fitted laws (the ones not fitted as in the spec); ``initial_part_load``
    the spec's. ``initial_residuals``/``residuals``: one row per point (index: its label),
    columns :data:`RESIDUALS` (% or K; NaN where the point gives no control-stage temperature).
    ``sensitivity``: per point (rows) and fitted parameter (columns), how far the point's
    weighted residuals move over the parameter's whole range (norm, band units);
    ``identified_share``: each point's share of the information on each parameter (columns sum
    to 1). ``singular_values`` of the weighted, range-scaled Jacobian, its ``rank`` and
    ``condition_number``; ``unidentified``: parameters along directions the points do not fix.
    ``evaluations``: model evaluations; ``wall_time_s``: seconds; ``message``: the optimiser's.
    """

    part_load: PartLoad
    initial_part_load: PartLoad
    parameters: tuple[str, ...]
    initial_residuals: pd.DataFrame
    residuals: pd.DataFrame
    sensitivity: pd.DataFrame
    identified_share: pd.DataFrame
    singular_values: np.ndarray
    rank: int
    condition_number: float
    unidentified: tuple[str, ...]
    evaluations: int
    wall_time_s: float
    message: str

    def bound_reached(self, name: str) -> str | None:
        """"lower"/"upper" when the fitted ``name`` ended on that end of its schema range (the
        points push it further: its finite difference there is cut off, so it reads as not
        identified), else None."""
        low, high = _bounds(name)
        value = getattr(self.part_load, name)
        tolerance = 1e-6 * (high - low)
        if value <= low + tolerance:
            return "lower"
        return "upper" if value >= high - tolerance else None

    def fitted_spec(self, spec: TurbineSpec) -> TurbineSpec:
        """``spec`` with the fitted part-load laws."""
        return replace(spec, part_load=self.part_load)

    def spec_toml(self, spec_text: str) -> str:
        """The spec TOML ``spec_text`` with its ``[part_load]`` table replaced by the fitted
        laws (:func:`fitted_spec_toml`)."""
        return fitted_spec_toml(spec_text, self.part_load)


def given_value(point: HeatBalancePoint, column: str) -> float | None:
    """The heat-balance figure behind residual ``column`` (one of :data:`RESIDUALS`) at
    ``point``: the control-stage pressure (Pa) or the control-stage / HP-exhaust temperature
    (K); None where the point does not give it."""
    if column == "control_stage_pressure_pct":
        return point.control_stage_pressure_pa
    if column == "control_stage_temperature_k":
        return point.control_stage_temperature_k
    if column == "hp_exhaust_temperature_k":
        return point.hp_exhaust_temperature_k
    raise ValueError(f"column {column!r}: expected one of {list(RESIDUALS)}")


def outside_band(residuals: pd.DataFrame) -> list[str]:
    """The residuals (rows by point label, columns :data:`RESIDUALS`) outside
    :data:`ACCEPTANCE_BAND`, each as ``"<label> (<quantity> <±x.xx> <%|K>)"``; empty when
    every finite residual lies within it."""
    return [f"{label} ({column.rsplit('_', 1)[0]} {float(row[column]):+.2f} "
            f"{'%' if column.endswith('pct') else 'K'})"
            for label, row in residuals.iterrows() for column in RESIDUALS
            if math.isfinite(float(row[column]))
            and abs(float(row[column])) > ACCEPTANCE_BAND[column]]


def point_residuals(spec: TurbineSpec, heat_balance: HeatBalance) -> pd.DataFrame:
    """Model − heat balance at every point (rows by label, columns :data:`RESIDUALS`)."""
    points = _checked_points(heat_balance)
    return _table(_residuals(spec, points, heat_balance.source), points)


def fit_design(spec: TurbineSpec, heat_balance: HeatBalance,
               parameters: Sequence[str] = FIT_PARAMETERS) -> DesignFit:
    """Fit ``parameters`` (fields of the spec's ``[part_load]``) to every heat-balance point.

    Bounded least squares (bounds: the spec schema's ranges) on the residuals weighted by the
    acceptance band; starts from the spec's values. Needs at least as many points as
    parameters. Raises :class:`DesignFitError` for bad input or a point the model cannot run.
    """
    started = time.perf_counter()
    names = tuple(parameters)
    unknown = [name for name in names if name not in FIT_PARAMETERS]
    if unknown or not names or len(set(names)) != len(names):
        raise DesignFitError(f"parameters: expected distinct names among {list(FIT_PARAMETERS)},"
                             f" got {list(names)}")
    points = _checked_points(heat_balance)
    if len(points) < len(names):
        raise DesignFitError(
            f"{heat_balance.source}: {len(points)} heat-balance point(s) cannot identify "
            f"{len(names)} parameters ({', '.join(names)}): give at least {len(names)} points "
            "or fit fewer parameters")
    low = np.array([_bounds(name)[0] for name in names])
    width = np.array([_bounds(name)[1] for name in names]) - low
    start = np.array([getattr(spec.part_load, name) for name in names])
    start_scaled = np.clip((start - low) / width, 0.0, 1.0)
    evaluations = 0

    def part_load_at(scaled: np.ndarray) -> PartLoad:
        values = low + width * np.clip(scaled, 0.0, 1.0)
        return replace(spec.part_load,
                       **{name: float(v) for name, v in zip(names, values, strict=True)})

    def weighted(scaled: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        residuals = _residuals(replace(spec, part_load=part_load_at(scaled)), points,
                               heat_balance.source)
        values = residuals / _BAND
        return values[np.isfinite(values)]

    initial = _residuals(spec, points, heat_balance.source)
    solution = least_squares(weighted, start_scaled, bounds=(0.0, 1.0), diff_step=_DIFF_STEP,
                             x_scale=1.0, max_nfev=100)
    fitted = part_load_at(solution.x)
    final = _residuals(replace(spec, part_load=fitted), points, heat_balance.source)
    jacobian = np.asarray(solution.jac)
    sensitivity, share = _identification(jacobian, np.isfinite(final), points, names)
    singular = np.linalg.svd(jacobian, compute_uv=False)
    largest = singular[0] if singular.size and singular[0] > 0.0 else 1.0
    rank = int(np.sum(singular > _RANK_TOLERANCE * largest))
    _, _, vt = np.linalg.svd(jacobian)
    weak = vt[rank:] if rank < len(names) else np.zeros((0, len(names)))
    unidentified = tuple(name for j, name in enumerate(names)
                         if weak.size and np.abs(weak[:, j]).max() > 0.1)
    return DesignFit(
        part_load=fitted, initial_part_load=spec.part_load, parameters=names,
        initial_residuals=_table(initial, points), residuals=_table(final, points),
        sensitivity=sensitivity, identified_share=share, singular_values=singular, rank=rank,
        condition_number=float(singular[0] / singular[-1]) if singular[-1] > 0.0 else math.inf,
        unidentified=unidentified, evaluations=evaluations,
        wall_time_s=time.perf_counter() - started, message=str(solution.message))


def fitted_spec_toml(spec_text: str, part_load: PartLoad) -> str:
    """A copy of the spec TOML ``spec_text`` whose ``[part_load]`` table is ``part_load``.

    An existing ``[part_load]`` table (up to the next table header) is replaced; the new one is
    appended at the end with every field, written so that it reads back exactly.
    """
    lines = spec_text.splitlines()
    header = re.compile(r"^\s*\[\s*part_load\s*\]\s*(#.*)?$")
    any_header = re.compile(r"^\s*\[")
    kept: list[str] = []
    inside = False
    for line in lines:
        if header.match(line):
            inside = True
            continue
        if inside and any_header.match(line):
            inside = False
        if not inside:
            kept.append(line)
    while kept and not kept[-1].strip():
        kept.pop()
    table = ["", "[part_load]  # fitted to the thermal kit by steamtwin.model.design_fit"]
    table += [f"{field.name} = {getattr(part_load, field.name)!r}" for field in fields(PartLoad)]
    return "\n".join(kept + table) + "\n"


def _bounds(name: str) -> tuple[float, float]:
    field = FIELD_BY_KEY[f"part_load.{name}"]
    assert field.low is not None and field.high is not None  # every part-load field is bounded
    return field.low, field.high


def _checked_points(heat_balance: HeatBalance) -> tuple[HeatBalancePoint, ...]:
    """The points, refused with the point and field named if a value is not finite."""
    points = tuple(heat_balance.points)
    if not points:
        raise DesignFitError(f"{heat_balance.source}: the heat balance has no points")
    required = ("main_steam_pressure_pa", "main_steam_temperature_k", "main_steam_flow_kg_s",
                "control_stage_pressure_pa", "hp_exhaust_pressure_pa",
                "hp_exhaust_temperature_k")
    for number, point in enumerate(points, start=1):
        given = [(name, getattr(point, name)) for name in required]
        if point.control_stage_temperature_k is not None:
            given.append(("control_stage_temperature_k", point.control_stage_temperature_k))
        for name, value in given:
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0.0):
                raise DesignFitError(
                    f"{heat_balance.source}: points[{number}] ({point.label!r}): {name} = "
                    f"{value!r} is not a finite positive number (SI units)")
    return points


def _residuals(spec: TurbineSpec, points: Sequence[HeatBalancePoint], source: str
               ) -> np.ndarray:
    """(points, 3) model − heat balance: % of pressure, K, K (NaN: temperature not given)."""
    model = FullOrderModel(spec)
    try:
        _ = model.design_
    except SpecError as error:
        raise DesignFitError(f"{source}: the model cannot run the spec's design point with "
                             f"part_load = {spec.part_load}: {error}") from None
    result = np.full((len(points), 3), np.nan)
    for k, point in enumerate(points):
        inputs = pd.DataFrame({"main_steam_pressure": [point.main_steam_pressure_pa],
                               "main_steam_temperature": [point.main_steam_temperature_k],
                               "main_steam_flow": [point.main_steam_flow_kg_s],
                               "hp_exhaust_pressure": [point.hp_exhaust_pressure_pa]},
                              index=pd.to_datetime(["2000-01-01T00:00:00Z"]))
        try:
            diagnostics = model.simulate_detailed(inputs, stages=False).diagnostics
        except InputError as error:
            raise DesignFitError(f"{source}: points[{k + 1}] ({point.label!r}): the model cannot "
                                 f"run this point: {error.reason}") from None
        assert diagnostics is not None  # simulate_detailed always returns them
        p1, t1, t_exhaust = (float(diagnostics[name].iloc[0]) for name in _MODEL_COLUMNS)
        result[k, 0] = 100.0 * (p1 / point.control_stage_pressure_pa - 1.0)
        if point.control_stage_temperature_k is not None:
            result[k, 1] = t1 - point.control_stage_temperature_k
        result[k, 2] = t_exhaust - point.hp_exhaust_temperature_k
    return result


def _table(residuals: np.ndarray, points: Sequence[HeatBalancePoint]) -> pd.DataFrame:
    return pd.DataFrame(residuals, columns=list(RESIDUALS),
                        index=pd.Index([point.label for point in points], name="point"))


def _identification(jacobian: np.ndarray, given: np.ndarray,
                    points: Sequence[HeatBalancePoint], names: tuple[str, ...]
                    ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Per point and parameter: the norm of its Jacobian rows, and its share of Σ J²."""
    owner = np.repeat(np.arange(len(points)), given.sum(axis=1))  # the point of each row
    squares = np.zeros((len(points), len(names)))
    np.add.at(squares, owner, jacobian**2)
    totals = squares.sum(axis=0)
    share = np.divide(squares, totals, out=np.zeros_like(squares), where=totals > 0.0)
    index = pd.Index([point.label for point in points], name="point")
    return (pd.DataFrame(np.sqrt(squares), index=index, columns=list(names)),
            pd.DataFrame(share, index=index, columns=list(names)))
