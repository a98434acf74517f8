"""The built-in full-order model (FOM) of the HP section: a :class:`Simulator`.

Kept as one module because it is one class, :class:`FullOrderModel`, with the input checks and
result types of its public methods.

Quasi-steady stage-by-stage steam path (``steampath``) coupled to 1-D metal conduction of rotor
and inner casing per stage group (``metal``), solved sample by sample in a compiled loop
(``kernel``) with superheated-steam properties from spline tables of IAPWS-IF97
(``steamtwin.steam.tables``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.errors import ModelError
from steamtwin.model import kernel
from steamtwin.model.design import (
    EFFICIENCY_SCALE_RANGE,
    DesignConstants,
    active_leakages,
    kernel_constants,
    leakage_capacities,
)
from steamtwin.model.measurement import check_time_constants, lag
from steamtwin.model.parameters import PARAMETER_BOUNDS, ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.model.stream_state import StreamState
from steamtwin.spec import SpecError, TurbineSpec
from steamtwin.steam import if97
from steamtwin.steam.tables import lower_boundary_temperature, steam_tables

# Physical validity of the inputs (SI); the tables cover 0.05–25 MPa and up to 650 °C.
INPUT_RANGES = {
    "main_steam_pressure": (1.0e6, 25.0e6, "Pa"),
    "main_steam_temperature": (523.15, 913.15, "K"),
    "main_steam_flow": (1.0, 2000.0, "kg/s"),
    "hp_exhaust_pressure": (0.1e6, 20.0e6, "Pa"),
}

# Below this share of rated flow (start-up, no-load) windage and ventilation dominate the
# stages and the velocity-ratio and partial-admission loss correlations, made for loaded
# operation, lose their meaning (the control stage's efficiency heads below zero); deep peak
# shaving stays above 25 %.
MINIMUM_FLOW_FRACTION = 0.15

# The design step sizes the nozzles of the valves open at design at the heat balance's
# control-stage pressure, then once more at the model's own (``FullOrderModel.design_``). The
# second sizing absorbs a small disagreement between the heat balance's control-stage pressure
# and the stages' flow capacities (the reference unit's is −0.07 %, a derived spec's 0.00 %, a
# 1 % error in the capacities gives ~1 %); a model pressure more than this share above the heat
# balance's means the valves open at design cannot pass the rated flow where the stages put
# the control stage, and the spec is refused instead of silently re-sized.
DESIGN_PRESSURE_EXCESS = 0.05

# With leakages the design step also fixes each seal's labyrinth constant at the model's design
# state where the leakage leaves; that state moves little with the constant (a 1 % leakage moves
# the control-stage pressure by ~1 %), so each pass shrinks the miss of the design leakage flow
# by about two orders: four passes leave < 1e-6 (tests/model/test_leakage.py).
LEAKAGE_DESIGN_PASSES = 4

_STATUS_TEXT = {
    kernel.STATUS_OVER_CAPACITY: "main_steam_flow exceeds what the wide-open governing valves "
    "pass at this throttle pressure",
    kernel.STATUS_OUT_OF_TABLES: "a steam state leaves the superheated region covered by the "
    "property tables (0.05–25 MPa, saturation…650 °C)",
    kernel.STATUS_NO_CONVERGENCE: "the steam-path iteration did not converge",
    kernel.STATUS_PRESSURE_INVERSION: "hp_exhaust_pressure is too high for this flow: the "
    "stage pressures reach the throttle pressure",
}


class InputError(ModelError):
    """Model inputs are missing, not finite, or outside the model's validity.

    When one sample is at fault the error says where, so that a caller can re-word it in its
    own terms (a file's line numbers, its units): ``row`` is the sample's 0-based position in
    the input frame (the message says it 1-based), ``column`` the signal (``"time"`` for the
    index, None when the sample as a whole fails), ``reason`` the message without the
    location and ``count`` how many rows fail the same check. A range check also gives the SI
    ``value`` and its valid ``limits`` in the SI ``unit``.
    """

    def __init__(self, message: str, *, row: int | None = None, column: str | None = None,
                 reason: str | None = None, count: int = 1, value: float | None = None,
                 limits: tuple[float, float] | None = None, unit: str | None = None) -> None:
        super().__init__(message)
        self.row, self.column, self.reason, self.count = row, column, reason or message, count
        self.value, self.limits, self.unit = value, limits, unit

    @classmethod
    def at(cls, index: pd.Index, row: int, column: str | None, reason: str, **details: Any
           ) -> InputError:
        """The error for the sample at 0-based position ``row`` of ``index``: the message
        names the column, the 1-based row and the sample's time."""
        stamp = index[row]
        time = f"{stamp:g} s" if isinstance(stamp, numbers.Real) else str(stamp)
        where = f"column {column!r} row" if column else "row"
        return cls(f"inputs {where} {row + 1} (1-based; time {time}): {reason}", row=row,
                   column=column, reason=reason, **details)


@dataclass(frozen=True)
class SimulationResult:
    """Outputs (SI) plus diagnostics and per-stage states of one simulation.

    ``outputs`` holds the sensor predictions; ``diagnostics`` every kernel result column
    (powers and energy flows in W); ``stage_pressures``/``stage_temperatures`` (Pa/K) the
    control-stage outlet (column 0) and each pressure stage's outlet, when requested.
    """

    outputs: pd.DataFrame
    diagnostics: pd.DataFrame | None
    stage_pressures: pd.DataFrame | None
    stage_temperatures: pd.DataFrame | None


@dataclass(frozen=True)
class CheckedInputs:
    """An input series checked once by :meth:`FullOrderModel.check_inputs`.

    ``columns``: one contiguous SI array per input signal (Pa, K, kg/s); ``time_step``: seconds
    since the previous sample (the first is ∞: steady start); ``index``: the series' time index.
    """

    index: pd.Index
    columns: dict[str, np.ndarray]
    time_step: np.ndarray

    @cached_property
    def first_enthalpy(self) -> float:
        """Specific enthalpy (J/kg, IAPWS-IF97) of the first sample's main steam, where a fresh
        run starts: computed once per series, not at each of a calibration's runs."""
        return float(if97.enthalpy_pt(self.columns["main_steam_pressure"][0],
                                      self.columns["main_steam_temperature"][0]))

    def inlet_states(self, constants: kernel.KernelConstants) -> np.ndarray:
        """:func:`~steamtwin.model.kernel.inlet_states` of this series for ``constants`` (the
        valves' pressure drop, the design flow and the Reynolds exponent are all it depends
        on), computed on first use and kept: a calibration's thousands of runs of one series
        share them."""
        key = (constants.control.valve_pressure_drop, constants.design_flow,
               constants.reynolds_exponent)
        cache = self._inlet_cache
        if key not in cache:
            p0, t0, flow, p_exhaust = (self.columns[name] for name in INPUT_SIGNALS)
            inlet = np.empty((kernel.INLET_ROWS, p0.size))
            kernel.inlet_states(steam_tables(), *key, p0, t0, flow, p_exhaust, inlet)
            cache[key] = inlet
        return cache[key]

    @cached_property
    def _inlet_cache(self) -> dict[tuple[float, float, float], np.ndarray]:
        return {}


class FullOrderModel:
    """HP-section full-order model of a turbine described by ``spec``.

    ``simulate(inputs, params)`` maps canonical boundary conditions (SI) to canonical sensor
    predictions (SI). The design step (constants from the spec's heat balance) runs on first use
    and is cached in ``design_``. ``pressure_tolerance`` (relative) and ``enthalpy_tolerance``
    (J/kg) bound the estimated error each sample's sweeps leave (see ``model.kernel``).
    ``sensor_time_constants`` (output → τ in s, e.g.
    :data:`~steamtwin.model.measurement.TYPICAL_TIME_CONSTANTS_S`): those outputs become what
    their thermocouples read, a first-order lag of the computed temperature (``measurement``);
    the diagnostics keep the computed values. Default: no lag. ``sensor_offsets`` (output →
    K, measured − model, e.g. a calibration's thermocouple-bias estimates): added to what those
    sensors read. Default: none.
    """

    input_signals = INPUT_SIGNALS

    def __init__(self, spec: TurbineSpec, *,
                 pressure_tolerance: float = kernel.PRESSURE_TOLERANCE,
                 enthalpy_tolerance: float = kernel.ENTHALPY_TOLERANCE,
                 sensor_time_constants: Mapping[str, float] | None = None,
                 sensor_offsets: Mapping[str, float] | None = None) -> None:
        self.spec = spec
        self.pressure_tolerance = pressure_tolerance
        self.enthalpy_tolerance = enthalpy_tolerance
        self.sensor_time_constants = sensor_time_constants
        self.sensor_offsets = sensor_offsets

    @property
    def output_signals(self) -> tuple[str, ...]:
        """Predicted signals: the spec's sensors the model computes, plus ``hp_power``."""
        computed = ("control_stage_pressure", "control_stage_temperature",
                    "hp_exhaust_temperature", "hp_inner_casing_temperature")
        return (*(name for name in computed if name in self.spec.sensors), "hp_power")

    @cached_property
    def design_(self) -> DesignConstants:
        """Kernel constants with the efficiency scale that meets the design exhaust temperature.

        The nozzle area is sized at the model's own design control-stage pressure (two passes),
        so rated load sits exactly on the valve point the spec names. Raises
        :class:`~steamtwin.spec.SpecError` when the first pass puts the control stage more than
        :data:`DESIGN_PRESSURE_EXCESS` above the heat balance's pressure.
        """
        given = self.spec.design.control_stage_pressure
        control_stage_pressure = given
        leaking = bool(active_leakages(self.spec))
        capacity = None
        for design_pass in range(LEAKAGE_DESIGN_PASSES if leaking else 2):
            scale = self._solve_efficiency_scale(control_stage_pressure, capacity)
            constants = kernel_constants(self.spec, scale, control_stage_pressure,
                                         leakage_capacity=capacity)
            if leaking:
                run = self._design_result(constants, stages=True)
                diagnostics = run.diagnostics
                capacity = _leakage_capacities_at(self.spec, run)
            else:
                diagnostics = self._design_run(constants)
            control_stage_pressure = float(diagnostics["control_stage_pressure"].iloc[0])
            if design_pass == 0 and control_stage_pressure > (1.0 + DESIGN_PRESSURE_EXCESS) * given:
                raise SpecError(
                    f"turbine {self.spec.name!r}: the design point cannot be solved with the "
                    f"valves open at design: {_STATUS_TEXT[kernel.STATUS_OVER_CAPACITY]} (their "
                    f"nozzles sized at design.control_stage_pressure {given / 1e6:.3f} MPa; the "
                    f"pressure stages put the control stage at "
                    f"{control_stage_pressure / 1e6:.3f} MPa, "
                    f"{control_stage_pressure / given - 1.0:+.1%}, more than the "
                    f"{DESIGN_PRESSURE_EXCESS:.0%} the design step re-sizes them for)")
        return DesignConstants(kernel=constants, efficiency_scale=scale)

    def _design_run(self, constants: kernel.KernelConstants) -> pd.DataFrame:
        return self._design_result(constants).diagnostics

    def _design_result(self, constants: kernel.KernelConstants, stages: bool = False
                       ) -> SimulationResult:
        try:
            return self._run(constants, self.design_inputs(), ModelParameters(), stages)
        except InputError as error:
            raise SpecError(
                f"turbine {self.spec.name!r}: the design point cannot be solved ({error}); the "
                "spec's flow capacities, valves and heat balance are inconsistent"
            ) from None

    def _solve_efficiency_scale(self, control_stage_pressure: float,
                                leakage_capacity: np.ndarray | None = None) -> float:
        """Secant on the scale of all stage efficiencies for the design exhaust temperature."""
        target = self.spec.design.hp_exhaust_temperature

        def exhaust_error(scale: float) -> float:
            constants = kernel_constants(self.spec, scale, control_stage_pressure,
                                         leakage_capacity=leakage_capacity)
            return float(self._design_run(constants)["hp_exhaust_temperature"].iloc[0]) - target

        low, high = EFFICIENCY_SCALE_RANGE
        scale_a, scale_b = 1.0, 0.98
        error_a, error_b = exhaust_error(scale_a), exhaust_error(scale_b)
        for _ in range(30):
            if abs(error_b) < 1e-6:
                return scale_b
            if error_b == error_a:
                break
            scale_a, scale_b, error_a = scale_b, scale_b - error_b * (scale_b - scale_a) / (
                error_b - error_a), error_b
            if not low <= scale_b <= high:
                raise SpecError(
                    f"turbine {self.spec.name!r}: meeting the design HP-exhaust temperature "
                    f"{target - 273.15:.1f} °C needs stage efficiencies scaled by {scale_b:.3f}, "
                    f"outside {EFFICIENCY_SCALE_RANGE}: the blade efficiencies and the heat "
                    "balance are inconsistent"
                )
            error_b = exhaust_error(scale_b)
        raise SpecError(
            f"turbine {self.spec.name!r}: no efficiency scale meets the design HP-exhaust "
            f"temperature {target - 273.15:.1f} °C (last miss {error_b:.3g} K)"
        )

    def design_inputs(self) -> pd.DataFrame:
        """A one-sample input frame at the design point (SI units)."""
        design = self.spec.design
        return pd.DataFrame(
            {
                "main_steam_pressure": [design.main_steam_pressure],
                "main_steam_temperature": [design.main_steam_temperature],
                "main_steam_flow": [design.main_steam_flow],
                "hp_exhaust_pressure": [design.hp_exhaust_pressure],
            },
            index=pd.to_datetime(["2000-01-01T00:00:00Z"]),
        )

    def simulate(self, inputs: pd.DataFrame, params: ModelParameters | None = None
                 ) -> pd.DataFrame:
        """Sensor predictions (SI: Pa, K, W) for a time series of boundary conditions (SI).

        The metal starts in equilibrium with the first sample. Raises :class:`InputError` naming
        the column and row of any input the model cannot take.
        """
        return self._run(self.design_.kernel, inputs, params or ModelParameters(), False,
                         diagnostics=False).outputs

    def simulate_detailed(self, inputs: pd.DataFrame, params: ModelParameters | None = None,
                          stages: bool = True) -> SimulationResult:
        """Like :meth:`simulate`, plus diagnostics and (``stages=True``) per-stage states."""
        return self._run(self.design_.kernel, inputs, params or ModelParameters(), stages)

    def simulate_varying(self, inputs: pd.DataFrame, parameters: pd.DataFrame,
                         stages: bool = False) -> SimulationResult:
        """Like :meth:`simulate_detailed` with parameters that change in time (e.g. fouling).

        ``parameters`` has the :class:`ModelParameters` fields as columns (dimensionless) and
        one row per input row; each row must lie within the parameter bounds.
        """
        names = [f.name for f in fields(ModelParameters)]
        missing = [name for name in names if name not in parameters.columns]
        if missing or len(parameters) != len(inputs):
            raise InputError(f"parameters need the columns {names} and one row per input row "
                             f"(got columns {list(parameters.columns)}, {len(parameters)} rows "
                             f"for {len(inputs)} inputs)")
        schedule = parameters[names].to_numpy(dtype=float)
        for j, name in enumerate(names):
            low, high = PARAMETER_BOUNDS[name]
            outside = np.flatnonzero(~((schedule[:, j] >= low) & (schedule[:, j] <= high)))
            if outside.size:
                row = int(outside[0])
                raise InputError(f"parameters column {name!r} row {row + 1} (1-based): "
                                 f"{schedule[row, j]:g} outside [{low:g}, {high:g}] "
                                 f"({_rows(outside.size)})", row=row, column=name,
                                 count=outside.size)
        return self._run(self.design_.kernel, inputs, schedule, stages)

    def check_inputs(self, inputs: pd.DataFrame) -> CheckedInputs:
        """Check an input series once (SI: Pa, K, kg/s) for repeated :meth:`simulate_checked`.

        Raises :class:`InputError` naming the column and row of any input the model cannot take.
        """
        columns, time_step = _validated_inputs(inputs)
        flow = columns["main_steam_flow"]
        minimum_flow = MINIMUM_FLOW_FRACTION * self.spec.design.main_steam_flow
        low = np.flatnonzero(flow < minimum_flow)
        if low.size:
            row = int(low[0])
            raise InputError.at(
                inputs.index, row, "main_steam_flow",
                f"{flow[row] * 3.6:.0f} t/h is below {MINIMUM_FLOW_FRACTION:.0%} of rated flow "
                f"({minimum_flow * 3.6:.0f} t/h), outside the validity of the stage-efficiency "
                f"and partial-admission loss correlations ({_rows(low.size)})", count=low.size)
        return CheckedInputs(index=inputs.index, columns=columns, time_step=time_step)

    def simulate_checked(self, checked: CheckedInputs, params: ModelParameters | None = None,
                         signals: Sequence[str] | None = None) -> np.ndarray:
        """Like :meth:`simulate` on inputs checked by :meth:`check_inputs`, as an array.

        Returns (samples, signals) in SI units (Pa, K, W), columns in the order of ``signals``
        (default: :attr:`output_signals`). What a calibration runs thousands of times: the
        inputs are not checked again and no DataFrame is built.
        """
        signals = self.output_signals if signals is None else tuple(signals)
        unknown = [name for name in signals if name not in self.output_signals]
        if unknown:
            raise ValueError(f"the model does not predict {unknown} "
                             f"(it predicts {list(self.output_signals)})")
        results, _, _ = self._solve(self.design_.kernel, checked, params or ModelParameters(),
                                    False)
        return self._readings(results, checked.time_step, signals)

    def simulate_stream(self, inputs: pd.DataFrame, params: ModelParameters | None = None,
                        state: StreamState | None = None) -> tuple[pd.DataFrame, StreamState]:
        """Sensor predictions (SI) for the next block of a stream, and the state after it.

        Without ``state`` the block starts like :meth:`simulate` (steady metal); with the state
        a previous block returned, it continues that run: the outputs equal those of one
        :meth:`simulate` over all blocks together (to round-off; tested). ``inputs`` must start
        after ``state.time``. Raises :class:`InputError` as :meth:`simulate` does.
        """
        run, after = self._stream(inputs, params, state, False)
        return run.outputs, after

    def simulate_stream_detailed(self, inputs: pd.DataFrame,
                                 params: ModelParameters | None = None,
                                 state: StreamState | None = None
                                 ) -> tuple[SimulationResult, StreamState]:
        """Like :meth:`simulate_stream`, with the kernel's diagnostics and the per-stage
        states (Pa, K) of :meth:`simulate_detailed` — what the live rotor's steam side needs
        (:mod:`steamtwin.rotor.steam_side`)."""
        return self._stream(inputs, params, state, True)

    def _stream(self, inputs: pd.DataFrame, params: ModelParameters | None,
                state: StreamState | None, detail: bool
                ) -> tuple[SimulationResult, StreamState]:
        params = params or ModelParameters()
        checked = self.check_inputs(inputs)
        constants = self.design_.kernel
        carry = self._carry(constants, checked, state)
        time_step = checked.time_step
        if state is not None:
            gap = (pd.Timestamp(checked.index[0]) - pd.Timestamp(state.time)).total_seconds()
            if not gap > 0.0:
                raise InputError.at(checked.index, 0, None,
                                    f"the block starts at {checked.index[0]}, not after the "
                                    f"stream's last sample {state.time}")
            time_step = time_step.copy()
            time_step[0] = gap
            checked = CheckedInputs(index=checked.index, columns=checked.columns,
                                    time_step=time_step)
        results, stage_p, stage_t = self._solve(constants, checked, params, detail, carry,
                                                resume=state is not None)
        lags = check_time_constants(self.sensor_time_constants, self.output_signals)
        offsets = dict(self.sensor_offsets or {})
        readings = np.empty((results.shape[0], len(self.output_signals)))
        sensors: dict[str, tuple[float, float]] = {}
        for j, name in enumerate(self.output_signals):
            values = results[:, kernel.RESULT_COLUMNS.index(name)]
            if name in lags:
                before = None if state is None else state.sensors.get(name)
                read = lag(values, time_step, lags[name], before=before)
                sensors[name] = (float(read[-1]), float(values[-1]))
            else:
                read = values
            readings[:, j] = read + offsets.get(name, 0.0)
        outputs = pd.DataFrame(readings, index=inputs.index, columns=list(self.output_signals))
        after = StreamState(pd.Timestamp(checked.index[-1]), carry, sensors).copy()
        if not detail:
            return SimulationResult(outputs, None, None, None), after
        stage_names = ["control_stage"] + [f"stage_{i}" for i in range(1, stage_p.shape[1])]
        return SimulationResult(
            outputs, pd.DataFrame(results, index=inputs.index, columns=kernel.RESULT_COLUMNS),
            pd.DataFrame(stage_p, index=inputs.index, columns=stage_names),
            pd.DataFrame(stage_t, index=inputs.index, columns=stage_names)), after

    def _carry(self, constants: kernel.KernelConstants, checked: CheckedInputs,
               state: StreamState | None) -> dict[str, np.ndarray]:
        """The kernel's carried arrays: a fresh start's, or a copy of ``state``'s (checked
        against this model's shapes)."""
        p0, t0, flow, p_exhaust = (checked.columns[name] for name in INPUT_SIGNALS)
        stages = constants.stage_capacity.size
        fresh = {
            # a rough start for the first sample's sweeps (only its p·v values are used):
            # pressures falling linearly from 80 % of throttle to the exhaust, enthalpy
            # 100 kJ/kg under inlet
            "pressures": np.linspace(0.8 * p0[0], p_exhaust[0], stages + 1),
            "enthalpies": np.full(stages + 1, checked.first_enthalpy - 1.0e5),
            "metal": np.full(constants.metal.capacity.shape, t0[0]),
            "throttled": np.zeros((2, constants.control.level_area.size)),
            "cs_out": np.zeros(7),
            "leak_flow": np.zeros(constants.leak_origin.size),
            "inlet_pv": np.zeros(stages),
            "previous": np.array([p0[0], t0[0], flow[0], p_exhaust[0]]),
        }
        if state is None:
            return fresh
        carried = {}
        for name, array in fresh.items():
            given = np.array(state.arrays[name], dtype=float)
            if given.shape != array.shape:
                raise ValueError(f"stream state array {name!r} has shape {given.shape}; this "
                                 f"model needs {array.shape} (a state of another turbine?)")
            carried[name] = given
        return carried

    def _run(self, constants: kernel.KernelConstants, inputs: pd.DataFrame,
             params: ModelParameters | np.ndarray, detail: bool, diagnostics: bool = True
             ) -> SimulationResult:
        checked = self.check_inputs(inputs)
        results, stage_p, stage_t = self._solve(constants, checked, params, detail)
        outputs = pd.DataFrame(
            self._readings(results, checked.time_step, self.output_signals),
            index=inputs.index, columns=list(self.output_signals))
        stages = constants.stage_capacity.size
        stage_names = ["control_stage"] + [f"stage_{i}" for i in range(1, stages + 1)]
        return SimulationResult(
            outputs=outputs,
            diagnostics=pd.DataFrame(results, index=inputs.index, columns=kernel.RESULT_COLUMNS)
            if diagnostics else None,
            stage_pressures=pd.DataFrame(stage_p, index=inputs.index, columns=stage_names)
            if detail else None,
            stage_temperatures=pd.DataFrame(stage_t, index=inputs.index, columns=stage_names)
            if detail else None,
        )

    def _readings(self, results: np.ndarray, time_step: np.ndarray, signals: Sequence[str]
                  ) -> np.ndarray:
        """Columns of the kernel's ``results`` for ``signals``, lagged where a sensor lags."""
        lags = check_time_constants(self.sensor_time_constants, self.output_signals)
        offsets = dict(self.sensor_offsets or {})
        unknown = sorted(set(offsets) - set(self.output_signals))
        if unknown:
            raise ValueError(f"sensor_offsets for {unknown}, which the model does not predict "
                             f"(it predicts {list(self.output_signals)})")
        readings = np.empty((results.shape[0], len(signals)))
        for j, name in enumerate(signals):
            values = results[:, kernel.RESULT_COLUMNS.index(name)]
            readings[:, j] = lag(values, time_step, lags[name]) if name in lags else values
            if name in offsets:
                readings[:, j] += offsets[name]
        return readings

    def _solve(self, constants: kernel.KernelConstants, checked: CheckedInputs,
               params: ModelParameters | np.ndarray, detail: bool,
               carry: dict[str, np.ndarray] | None = None, resume: bool = False
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Run the kernel: results (samples × N_RESULTS) and, with ``detail``, stage pressures
        (Pa) and temperatures (K); raises :class:`InputError` at the first failed sample.
        ``carry``: the kernel's carried arrays (:meth:`_carry`; updated in place), ``resume``:
        continue from them."""
        p0, t0, flow, p_exhaust = (checked.columns[name] for name in INPUT_SIGNALS)
        n = p0.size
        stages = constants.stage_capacity.size
        if carry is None:
            carry = self._carry(constants, checked, None)
        results = np.full((n, kernel.N_RESULTS), np.nan)
        status = np.zeros(n, dtype=np.int64)
        rows = n if detail else 0
        stage_p = np.zeros((rows, stages + 1))
        stage_t = np.zeros((rows, stages + 1))
        if isinstance(params, ModelParameters):
            parameter_array = np.array([[params.flow_coefficient, params.friction_coefficient,
                                         params.heat_transfer_coefficient]])
        else:
            parameter_array = np.ascontiguousarray(params, dtype=float)
        tolerance = np.array([self.pressure_tolerance, self.enthalpy_tolerance], dtype=float)
        if not (np.isfinite(tolerance).all() and (tolerance > 0).all()):
            raise ValueError(f"pressure_tolerance and enthalpy_tolerance must be finite and > 0 "
                             f"(got {self.pressure_tolerance!r}, {self.enthalpy_tolerance!r})")
        solved = kernel.run_kernel(constants, steam_tables(), checked.time_step, p0, t0, flow,
                                   p_exhaust, checked.inlet_states(constants), parameter_array,
                                   tolerance, carry["pressures"],
                                   carry["enthalpies"], carry["metal"], results, status, stage_p,
                                   stage_t, carry["throttled"], carry["cs_out"],
                                   carry["leak_flow"], carry["inlet_pv"], carry["previous"],
                                   resume)
        if solved < n:
            raise InputError.at(
                checked.index, int(solved), None,
                f"{_STATUS_TEXT[int(status[solved])]} (main_steam_pressure "
                f"{p0[solved] / 1e6:.3f} MPa, main_steam_temperature "
                f"{t0[solved] - 273.15:.1f} °C, main_steam_flow {flow[solved] * 3.6:.0f} t/h, "
                f"hp_exhaust_pressure {p_exhaust[solved] / 1e6:.3f} MPa)"
            )
        return results, stage_p, stage_t


def _leakage_capacities_at(spec: TurbineSpec, run: SimulationResult) -> np.ndarray:
    """The seals' labyrinth constants (m²) that pass the design leakage flows at the state
    (stage pressures and temperatures) of a design run."""
    leakages = active_leakages(spec)
    assert run.stage_pressures is not None and run.stage_temperatures is not None
    pressure = np.array([run.stage_pressures.iloc[0, leak.from_stage] for leak in leakages])
    temperature = np.array([run.stage_temperatures.iloc[0, leak.from_stage]
                            for leak in leakages])
    pv = pressure * np.asarray(if97.specific_volume_pt(pressure, temperature), dtype=float)
    return leakage_capacities(spec, pressure, pv)


def _validated_inputs(inputs: pd.DataFrame) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Check the input frame; return SI arrays per signal and the time step per sample (s)."""
    if not isinstance(inputs, pd.DataFrame) or inputs.empty:
        raise InputError("inputs must be a non-empty DataFrame of canonical signals")
    missing = [name for name in INPUT_SIGNALS if name not in inputs.columns]
    if missing:
        raise InputError(f"inputs lack required column(s) {missing} (SI units: Pa, K, kg/s)")
    columns: dict[str, np.ndarray] = {}
    for name in INPUT_SIGNALS:
        values = pd.to_numeric(inputs[name], errors="coerce").to_numpy(dtype=float)
        low, high, unit = INPUT_RANGES[name]
        bad = np.flatnonzero(~np.isfinite(values) | (values < low) | (values > high))
        if bad.size:
            row = int(bad[0])
            raw = inputs[name].iloc[row]
            shown = repr(raw) if isinstance(raw, str) else f"{values[row]:g} {unit}"
            raise InputError.at(
                inputs.index, row, name, f"{shown} is not a number within [{low:g}, {high:g}] "
                f"{unit} ({_rows(bad.size)})", count=bad.size, value=float(values[row]),
                limits=(low, high), unit=unit)
        columns[name] = np.ascontiguousarray(values)
    ratio = columns["hp_exhaust_pressure"] / columns["main_steam_pressure"]
    bad = np.flatnonzero(ratio >= 0.95)
    if bad.size:
        row = int(bad[0])
        raise InputError.at(
            inputs.index, row, None, f"pressure ratio hp_exhaust_pressure/main_steam_pressure = "
            f"{ratio[row]:.3f} ≥ 0.95: the HP section cannot expand ({_rows(bad.size)})",
            count=bad.size)
    p0, t0 = columns["main_steam_pressure"], columns["main_steam_temperature"]
    # the boundary rises with pressure (Tsat, then the B23 line), so rows hotter than the
    # boundary at the series' highest pressure are superheated; only the others are looked up
    near = np.flatnonzero(t0 <= lower_boundary_temperature(p0.max()))
    bad = near[t0[near] <= lower_boundary_temperature(p0[near])]
    if bad.size:
        row = int(bad[0])
        t_min = float(lower_boundary_temperature(p0[row]))
        raise InputError.at(
            inputs.index, row, "main_steam_temperature",
            f"{t0[row] - 273.15:.1f} °C is not superheated at {p0[row] / 1e6:.3f} MPa "
            f"(must exceed {t_min - 273.15:.1f} °C; {_rows(bad.size)})", count=bad.size)
    return columns, _time_steps(inputs.index)


def _rows(count: int) -> str:
    return f"{count} bad row" if count == 1 else f"{count} bad rows"


_TICKS_PER_SECOND = {"s": 1, "ms": 10**3, "us": 10**6, "ns": 10**9}
"""A DatetimeIndex's integer ticks per second, by its unit."""


def _time_steps(index: pd.Index) -> np.ndarray:
    """Seconds since the previous sample (first entry ∞: steady start)."""
    if isinstance(index, pd.DatetimeIndex):  # as TimedeltaIndex.total_seconds, without one
        ticks = index.asi8
        seconds = (ticks - ticks[0]) / _TICKS_PER_SECOND[index.unit]
    elif isinstance(index, pd.TimedeltaIndex):
        seconds = index.total_seconds().to_numpy(dtype=float)
    elif pd.api.types.is_numeric_dtype(index) and not pd.api.types.is_bool_dtype(index):
        seconds = index.to_numpy(dtype=float)
    else:
        raise InputError(
            "inputs must be indexed by time: a DatetimeIndex, a TimedeltaIndex or seconds"
        )
    steps = np.empty_like(seconds)
    steps[0] = math.inf
    steps[1:] = np.diff(seconds)
    bad = np.flatnonzero(~(steps[1:] > 0.0))
    if bad.size:
        raise InputError.at(index, int(bad[0]) + 1, "time",
                            "timestamps must increase strictly", count=bad.size)
    return steps
