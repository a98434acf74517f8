"""Physics features of the ROM: the governing stage's steady state at (p0, T0, p1), tabulated.

The blade's boundary conditions (:mod:`steamtwin.blade.steam`) depend on the main-steam state
(p0, T0), the control-stage pressure p1, the wheel-chamber temperature T_cs (the FOM's
control-stage temperature: idle arc and root) and the admitted arc e. T_cs is a *kinked*
function of (p0, T0, p1): with nozzle governing, the steam of the part-open valve is throttled
before its nozzle group, and that throttling loss vanishes at every valve point, where the
valve reaches full lift and the next one starts to open (the "valve-point" sawtooth of the
governing-stage efficiency: Cotton, *Evaluating and Improving Steam Turbine Performance*, 2nd
ed., 1998, ch. 6; Traupel, *Thermische Turbomaschinen* Bd. 2, 2001, §9 nozzle governing). A
radial-basis map from (p0, T0, p1) smooths that kink over its snapshots' spacing; from
(p0, T0, p1, T_cs, e) the field is smooth, because the blade's heat balance is.

:class:`ControlStageFeatures` therefore maps the ROM's inputs (p0, T0, p1) to those five
features with the FOM itself (:class:`steamtwin.model.fom.FullOrderModel`, the same
control-stage model that made the snapshots), through a table computed once at ``fit``:

* nodes in p0 and T0 (covering the snapshots' inputs with a margin) and in the valve flow
  ratio q = m·p0,design/(m_design·p0) (flow over the rated flow scaled by throttle pressure,
  Stodola/nozzle capacity ∝ p0), q from ``flow_ratio_range`` up to just below what the
  wide-open valves pass (found per (p0, T0) node by bisection on the FOM's capacity check);
* HP-exhaust pressure ∝ flow, as along the operating line and in the design of experiments
  (:mod:`steamtwin.model.operating`, :mod:`steamtwin.rom.snapshots`);
* one FOM run over all nodes as a sequence of samples 10¹² s apart — implicit Euler with
  Δt → ∞ puts the metal at its steady state at every sample, as in a snapshot;
* stored: p1, T_cs and e at every node.

``transform`` interpolates the table bilinearly in (p0, T0) and, along the flow-ratio axis,
finds the q at which the interpolated p1 equals the sample's p1 (p1 rises monotonically with
flow), then takes T_cs and e there: linear interpolation, exact at the nodes, so a valve-point
kink costs at most a quarter of the slope change times the q spacing (≈ 0.004 with the default
160 nodes). A compiled loop: 7 200 samples in ~2 ms (measured on a busy 2-core machine).
Inputs outside the table are clamped to its edge (they are outside the snapshots' range, which
the ROM flags); a (p0, T0) node the FOM cannot run at two flows (a corner of a wide envelope:
highest pressure with lowest temperature) takes the column of the nearest node that runs.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from steamtwin.cache import njit
from steamtwin.model.fom import MINIMUM_FLOW_FRACTION, FullOrderModel, InputError
from steamtwin.model.parameters import ModelParameters
from steamtwin.spec import TurbineSpec

FEATURE_NAMES = ("main_steam_pressure", "main_steam_temperature", "control_stage_pressure",
                 "control_stage_temperature", "active_admission_arc")
TABLE_COLUMNS = ("control_stage_pressure", "control_stage_temperature", "active_admission_arc")
STEADY_STEP_S = 1e12  # s between table samples: implicit Euler at Δt → ∞ is the steady state
CAPACITY_MARGIN = 0.998  # fraction of the valves' capacity the table's top flow reaches
CAPACITY_BISECTIONS = 8  # q resolution (0.65)/2⁸ ≈ 0.0025


class ControlStageFeatures:
    """(p0, T0, p1) → (p0, T0, p1, T_cs, e) from a table of the FOM's steady governing stage.

    Hyper-parameters: ``spec`` (the turbine), ``params`` (the FOM's parameters, as for the
    snapshots), node counts in p0, T0 and the flow ratio q, ``flow_ratio_range`` (q bounds;
    the top is lowered to the valves' capacity), ``pressure_margin`` (fraction of the inputs'
    p0 span added on each side) and ``temperature_margin`` (K). Learned: ``pressure_nodes_``
    (Pa), ``temperature_nodes_`` (K), ``flow_ratio_nodes_`` (-) and ``table_`` (nodes in
    p0 × T0 × q × [p1 Pa, T_cs K, e -]).
    """

    input_names = FEATURE_NAMES[:3]
    feature_names = FEATURE_NAMES

    def __init__(self, spec: TurbineSpec | None = None, params: ModelParameters | None = None,
                 pressure_nodes: int = 15, temperature_nodes: int = 4, flow_ratio_nodes: int = 160,
                 flow_ratio_range: tuple[float, float] = (0.45, 1.10),
                 pressure_margin: float = 0.1, temperature_margin: float = 10.0) -> None:
        self.spec = spec
        self.params = params
        self.pressure_nodes = pressure_nodes
        self.temperature_nodes = temperature_nodes
        self.flow_ratio_nodes = flow_ratio_nodes
        self.flow_ratio_range = flow_ratio_range
        self.pressure_margin = pressure_margin
        self.temperature_margin = temperature_margin

    @property
    def is_fitted(self) -> bool:
        """Whether the table exists (``fit`` or ``restore`` ran)."""
        return hasattr(self, "table_")

    def fit(self, conditions: np.ndarray) -> ControlStageFeatures:
        """Tabulate the governing stage over the range of ``conditions`` (m, 3) SI + margins."""
        if self.spec is None:
            raise ValueError("ControlStageFeatures needs the turbine spec to fit its table")
        counts = (self.pressure_nodes, self.temperature_nodes, self.flow_ratio_nodes)
        if min(counts) < 2:
            raise ValueError(f"node counts must be ≥ 2, got {counts}")
        low_q, high_q = (float(v) for v in self.flow_ratio_range)
        if not 0.0 < low_q < high_q:
            raise ValueError(f"flow_ratio_range must be 0 < low < high, got "
                             f"{self.flow_ratio_range!r}")
        if self.pressure_margin < 0 or self.temperature_margin < 0:
            raise ValueError("pressure_margin and temperature_margin must be ≥ 0")
        c = np.asarray(conditions, dtype=float)
        if c.ndim != 2 or c.shape[1] != 3 or not np.all(np.isfinite(c)):
            raise ValueError(f"conditions must be finite with columns {self.input_names}, got "
                             f"shape {c.shape}")
        params = self.params or ModelParameters()
        model = FullOrderModel(self.spec)
        design = self.spec.design
        p_low, p_high = c[:, 0].min(), c[:, 0].max()
        p_pad = self.pressure_margin * max(p_high - p_low, 0.05 * p_high)
        pressures = np.linspace(p_low - p_pad, p_high + p_pad, self.pressure_nodes)
        temperatures = np.linspace(c[:, 1].min() - self.temperature_margin,
                                   c[:, 1].max() + self.temperature_margin,
                                   self.temperature_nodes)
        ratios = np.linspace(low_q, high_q, self.flow_ratio_nodes)

        def inputs(p0: np.ndarray, t0: np.ndarray, q: np.ndarray) -> pd.DataFrame:
            flow = q * design.main_steam_flow * p0 / design.main_steam_pressure
            return pd.DataFrame({
                "main_steam_pressure": p0, "main_steam_temperature": t0, "main_steam_flow": flow,
                "hp_exhaust_pressure": design.hp_exhaust_pressure * flow
                / design.main_steam_flow}, index=np.arange(p0.size) * STEADY_STEP_S)

        def passes(p0: float, t0: float, q: float) -> bool:
            try:
                model.simulate_detailed(inputs(np.array([p0]), np.array([t0]), np.array([q])),
                                        params, stages=False)
            except InputError:
                return False
            return True

        p_grid, t_grid, q_grid = np.meshgrid(pressures, temperatures, ratios, indexing="ij")
        lowest = MINIMUM_FLOW_FRACTION * design.main_steam_pressure / p_grid * 1.001
        top = np.empty((pressures.size, temperatures.size))
        for i, p0 in enumerate(pressures):
            for j, t0 in enumerate(temperatures):
                lo, hi = low_q, high_q
                if passes(p0, t0, hi):
                    top[i, j] = hi
                    continue
                for _ in range(CAPACITY_BISECTIONS):
                    middle = 0.5 * (lo + hi)
                    lo, hi = (middle, hi) if passes(p0, t0, middle) else (lo, middle)
                top[i, j] = CAPACITY_MARGIN * lo
        feasible = (q_grid >= lowest) & (q_grid <= top[:, :, None])
        supported = feasible.sum(axis=2) >= 2
        if not supported.any():
            raise ValueError("the FOM passes fewer than two flow-ratio nodes at every (p0, T0) "
                             "node: widen flow_ratio_range")
        feasible &= supported[:, :, None]
        try:
            result = model.simulate_detailed(
                inputs(p_grid[feasible], t_grid[feasible], q_grid[feasible]), params,
                stages=False).diagnostics
        except InputError as error:
            raise ValueError(f"the FOM cannot tabulate the governing stage: {error}") from None
        table = np.full((*p_grid.shape, len(TABLE_COLUMNS)), np.nan)
        table[feasible] = result[list(TABLE_COLUMNS)].to_numpy(dtype=float)
        for i in range(pressures.size):  # outside the valves' range: the edge values
            for j in range(temperatures.size):
                rows = np.flatnonzero(feasible[i, j])
                if rows.size:
                    table[i, j, : rows[0]] = table[i, j, rows[0]]
                    table[i, j, rows[-1] + 1:] = table[i, j, rows[-1]]
        # a (p0, T0) node the FOM cannot run (e.g. the highest pressure with the lowest
        # temperature of a wide envelope: wet steam) lies outside the snapshots, where the ROM
        # flags its samples anyway: it takes the column of the nearest node that runs
        good = np.argwhere(supported)
        for i, j in np.argwhere(~supported):
            k, m = good[np.argmin((good[:, 0] - i) ** 2 / pressures.size ** 2
                                  + (good[:, 1] - j) ** 2 / temperatures.size ** 2)]
            table[i, j] = table[k, m]
        self.pressure_nodes_ = pressures
        self.temperature_nodes_ = temperatures
        self.flow_ratio_nodes_ = ratios
        self.table_ = np.ascontiguousarray(table)
        self._check_table()
        return self

    def restore(self, *, pressure_nodes: np.ndarray, temperature_nodes: np.ndarray,
                flow_ratio_nodes: np.ndarray, table: np.ndarray) -> ControlStageFeatures:
        """Set the table from stored arrays (a ROM file); raises ValueError if inconsistent."""
        self.pressure_nodes_ = np.asarray(pressure_nodes, dtype=float)
        self.temperature_nodes_ = np.asarray(temperature_nodes, dtype=float)
        self.flow_ratio_nodes_ = np.asarray(flow_ratio_nodes, dtype=float)
        self.table_ = np.ascontiguousarray(table, dtype=float)
        self._check_table()
        return self

    def _check_table(self) -> None:
        axes = (self.pressure_nodes_, self.temperature_nodes_, self.flow_ratio_nodes_)
        for name, axis in zip(("pressure", "temperature", "flow_ratio"), axes, strict=True):
            if axis.ndim != 1 or axis.size < 2 or not np.all(np.diff(axis) > 0):
                raise ValueError(f"feature table {name} nodes must increase strictly (≥ 2)")
        shape = (*(axis.size for axis in axes), len(TABLE_COLUMNS))
        if self.table_.shape != shape:
            raise ValueError(f"feature table has shape {self.table_.shape}, expected {shape}")
        if not np.all(np.isfinite(self.table_)):
            raise ValueError("feature table holds NaN or infinite values")
        if np.any(np.diff(self.table_[..., 0], axis=2) < 0):
            raise ValueError("feature table: control-stage pressure must not fall with flow")

    def transform(self, conditions: np.ndarray) -> np.ndarray:
        """Features (n, 5) [p0 Pa, T0 K, p1 Pa, T_cs K, e -] of conditions (n, 3) SI."""
        if not self.is_fitted:
            raise RuntimeError("ControlStageFeatures is not fitted: call fit(...) first")
        c = np.ascontiguousarray(np.atleast_2d(np.asarray(conditions, dtype=float)))
        if c.ndim != 2 or c.shape[1] != 3:
            raise ValueError(f"conditions must have 3 columns {self.input_names}, got shape "
                             f"{np.shape(conditions)}")
        out = np.empty((c.shape[0], len(FEATURE_NAMES)))
        out[:, :3] = c
        _interpolate(self.pressure_nodes_, self.temperature_nodes_, self.table_, c, out)
        return out

    def describe(self) -> dict[str, object]:
        """JSON-serialisable summary for provenance."""
        return {"kind": "control_stage", "features": list(FEATURE_NAMES),
                "nodes": [int(self.pressure_nodes), int(self.temperature_nodes),
                          int(self.flow_ratio_nodes)],
                "flow_ratio_range": [float(v) for v in self.flow_ratio_range]}


@njit(cache=True)
def _cell(axis: np.ndarray, value: float) -> tuple[int, float]:
    """Index of the cell holding ``value`` and its linear weight, clamped to the axis."""
    i = int(np.searchsorted(axis, value)) - 1
    i = min(max(i, 0), axis.size - 2)
    weight = (value - axis[i]) / (axis[i + 1] - axis[i])
    return i, min(max(weight, 0.0), 1.0)



@njit(cache=True)
def _interpolate(pressures: np.ndarray, temperatures: np.ndarray, table: np.ndarray,
                 conditions: np.ndarray, out: np.ndarray) -> None:
    """out[:, 3:5] = (T_cs, e) at each row's (p0, T0) where the table's p1 equals its p1."""
    n_q = table.shape[2]
    column = np.empty(n_q)
    for row in range(conditions.shape[0]):
        i, wp = _cell(pressures, conditions[row, 0])
        j, wt = _cell(temperatures, conditions[row, 1])
        w00, w01 = (1.0 - wp) * (1.0 - wt), (1.0 - wp) * wt
        w10, w11 = wp * (1.0 - wt), wp * wt
        for k in range(n_q):
            column[k] = (w00 * table[i, j, k, 0] + w01 * table[i, j + 1, k, 0]
                         + w10 * table[i + 1, j, k, 0] + w11 * table[i + 1, j + 1, k, 0])
        p1 = conditions[row, 2]
        k = 0
        while k < n_q - 2 and column[k + 1] < p1:
            k += 1
        rise = column[k + 1] - column[k]
        w = (p1 - column[k]) / rise if rise > 0.0 else 0.0
        w = min(max(w, 0.0), 1.0)
        for f in range(1, 3):
            low = (w00 * table[i, j, k, f] + w01 * table[i, j + 1, k, f]
                   + w10 * table[i + 1, j, k, f] + w11 * table[i + 1, j + 1, k, f])
            high = (w00 * table[i, j, k + 1, f] + w01 * table[i, j + 1, k + 1, f]
                    + w10 * table[i + 1, j, k + 1, f] + w11 * table[i + 1, j + 1, k + 1, f])
            out[row, 2 + f] = (1.0 - w) * low + w * high


def feature_table_arrays(features: ControlStageFeatures | None) -> dict[str, np.ndarray]:
    """Arrays of a fitted transform for a ROM file (empty arrays when there is none)."""
    if features is None:
        return {"feature_pressure_nodes": np.zeros(0), "feature_temperature_nodes": np.zeros(0),
                "feature_flow_ratio_nodes": np.zeros(0),
                "feature_table": np.zeros((0, 0, 0, len(TABLE_COLUMNS)))}
    return {"feature_pressure_nodes": features.pressure_nodes_,
            "feature_temperature_nodes": features.temperature_nodes_,
            "feature_flow_ratio_nodes": features.flow_ratio_nodes_,
            "feature_table": features.table_}


def features_from_arrays(arrays: dict[str, np.ndarray],
                         names: Sequence[str]) -> ControlStageFeatures | None:
    """Rebuild the transform stored by :func:`feature_table_arrays` (None if there is none)."""
    if arrays["feature_table"].size == 0:
        return None
    shape = arrays["feature_table"].shape
    transform = ControlStageFeatures(pressure_nodes=shape[0], temperature_nodes=shape[1],
                                     flow_ratio_nodes=shape[2])
    if tuple(names) != FEATURE_NAMES:
        raise ValueError(f"feature names {tuple(names)} differ from {FEATURE_NAMES}")
    return transform.restore(pressure_nodes=arrays["feature_pressure_nodes"],
                             temperature_nodes=arrays["feature_temperature_nodes"],
                             flow_ratio_nodes=arrays["feature_flow_ratio_nodes"],
                             table=arrays["feature_table"])
