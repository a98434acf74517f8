"""Snapshots of the blade temperature field over a design of experiments, run in parallel.

**Design.** Around each load level (30, 50, 75, 100 % by default) on the operating line
(:func:`steamtwin.model.operating.operating_point`: the sliding-pressure line and the spec's
steam-temperature schedule) the main-steam pressure, temperature and flow vary: ±5 % pressure
(sliding-pressure control band), ±10 K temperature (boiler attemperation band) and ±4 % flow.
The flow stands for the control-stage pressure, which the FOM computes from it (Stodola:
p1 ∝ flow); the snapshot stores the FOM's p1, so the ROM's inputs are the DCS
signals main-steam pressure, temperature and control-stage pressure. The points in each level's
box are a Latin hypercube (McKay, Beckman & Conover, Technometrics 21 (1979) 239) optimised for
centred discrepancy (scipy ``qmc.LatinHypercube(optimization="random-cd")``), seeded: every input
takes as many distinct values as there are points, which the RBF map needs to follow the
nonlinear (valve-point) dependence — on the reference blade the held-out error of 32 snapshots
fell from 1.95 K with the 2³ corners of each box to 1.61 K. ``layout="corners"`` takes the
corners (8 per level) instead. At rated load the flow interval is shifted down to end at 1.01 of
rated flow (the valves pass little more at −5 % pressure).

**Snapshot.** The FOM at the condition (one steady sample), the governing-stage boundary
conditions (:mod:`steamtwin.blade.steam`) and the steady FEM field (:mod:`steamtwin.blade`),
plus the FOM's sensor outputs at that condition.

**Parallelism.** A local process pool (``max_workers``) by default, a Dask
``distributed.Client`` when a scheduler address is given; each worker builds the FOM and the
FEM matrices once and reuses them for its tasks.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import qmc

from steamtwin.blade.conduction import BladeConduction
from steamtwin.blade.mesh import SolidMesh, checked_mesh
from steamtwin.blade.steam import ControlStageState, SteamBoundary, control_stage_states
from steamtwin.model.fom import FullOrderModel
from steamtwin.model.operating import hp_exhaust_pressure, operating_point
from steamtwin.model.parameters import ModelParameters
from steamtwin.model.simulator import INPUT_SIGNALS
from steamtwin.progress import ProgressCallback
from steamtwin.rom.envelope import MINIMUM_LOAD, OperatingEnvelope, line_box
from steamtwin.spec import TurbineSpec

LOAD_LEVELS = (0.30, 0.50, 0.75, 1.00)
PRESSURE_VARIATION = 0.05  # fraction of the sliding-line pressure
TEMPERATURE_VARIATION = 10.0  # K
FLOW_VARIATION = 0.04  # fraction of the level's flow
# Highest flow of the design, fraction of rated: the wide-open valves pass ~1.07 of rated flow at
# rated pressure and ~1.016 at −5 % (capacity ∝ p0); 1.01 keeps every design point feasible and
# puts the rated point inside the design's hull rather than on its edge.
MAXIMUM_FLOW_FRACTION = 1.01
LAYOUTS = ("bands", "lhs", "corners")
RATED_POINT_TOLERANCE = 0.005  # load fraction: a valve point this close stands for the top point
ROM_INPUTS = ("main_steam_pressure", "main_steam_temperature", "control_stage_pressure")


def design_conditions(spec: TurbineSpec, n_snapshots: int = 32,
                      loads: Sequence[float] = LOAD_LEVELS,
                      pressure_variation: float = PRESSURE_VARIATION,
                      temperature_variation: float = TEMPERATURE_VARIATION,
                      flow_variation: float = FLOW_VARIATION, random_state: int = 0,
                      layout: str = "lhs", envelope: OperatingEnvelope | None = None
                      ) -> pd.DataFrame:
    """FOM input conditions (SI) of the design, one row per snapshot, with ``load_fraction``.

    ``layout`` is ``"bands"`` (Latin hypercube in load band × pressure × temperature around
    each level), ``"lhs"`` (Latin hypercube per level with the flow varied by
    ``flow_variation``) or ``"corners"`` (2³ corners per level, then Latin-hypercube points).
    ``load_level`` names the level a row belongs to, ``load_fraction`` is its own load.
    ``envelope`` (:func:`steamtwin.rom.envelope.operating_envelope`) replaces ``loads`` and
    the variations by its levels' boxes and adds one snapshot on the operating line at each of
    its valve points and at its top level (taken from the count, when each level keeps at
    least one): the top level's box reaches the valves' capacity, where the model may cut its
    corners, and the line point there is one the envelope has checked the model runs.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    if envelope is None:
        levels = np.asarray(loads, dtype=float)
        if np.any(np.diff(levels) <= 0):
            raise ValueError("loads must increase")
        boxes = [line_box(float(level), pressure_variation, temperature_variation,
                          flow_variation, MAXIMUM_FLOW_FRACTION) for level in levels]
        points: tuple[float, ...] = ()
    else:
        boxes = list(envelope.levels)
        levels = np.array([box.load for box in boxes])
        points = envelope.valve_points
        if not any(abs(point - levels[-1]) <= RATED_POINT_TOLERANCE for point in points):
            points = (*points, float(levels[-1]))
    if n_snapshots < len(levels):
        raise ValueError(f"n_snapshots must be ≥ the number of load levels ({len(levels)})")
    if n_snapshots - len(points) < len(levels):
        points = ()
    middle = 0.5 * (levels[1:] + levels[:-1])
    band_low = np.concatenate([[max(MINIMUM_LOAD, 2 * levels[0] - middle[0]) if middle.size
                                else levels[0]], middle])
    band_high = np.concatenate([middle, [MAXIMUM_FLOW_FRACTION]])
    top = spec.sliding_pressure.load_fraction[-1]
    rng = np.random.default_rng(random_state)
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    n_levels = n_snapshots - len(points)
    counts = np.full(len(levels), n_levels // len(levels))
    counts[: n_levels % len(levels)] += 1
    rows = []
    for index, (box, count) in enumerate(zip(boxes, counts, strict=True)):
        pressure, temperature, flow_box = (_centre_half(box.pressure_factor),
                                           _centre_half(box.temperature_offset),
                                           _centre_half(box.flow_factor))
        if layout == "bands":
            sampler = qmc.LatinHypercube(d=3, seed=rng, optimization="random-cd")
            unit = sampler.random(count)
            for u_load, u_p, u_t in unit:
                load = band_low[index] + (band_high[index] - band_low[index]) * u_load
                point = operating_point(spec, min(load, top))
                flow = load * spec.design.main_steam_flow
                rows.append(_design_row(
                    spec, box.load, load, float(point["main_steam_pressure"])
                    * (pressure[0] + pressure[1] * (2 * u_p - 1)),
                    float(point["main_steam_temperature"])
                    + temperature[0] + temperature[1] * (2 * u_t - 1), flow))
            continue
        load = box.load
        if layout == "corners" and count >= 8:
            unit = corners
            if count > 8:
                sampler = qmc.LatinHypercube(d=3, seed=rng)
                unit = np.vstack([corners, 2.0 * sampler.random(count - 8) - 1.0])
        else:
            sampler = qmc.LatinHypercube(d=3, seed=rng, optimization="random-cd")
            unit = 2.0 * sampler.random(count) - 1.0
        point = operating_point(spec, load)
        for dp, dt, dm in unit:
            flow = float(point["main_steam_flow"]) * (flow_box[0] + flow_box[1] * dm)
            rows.append(_design_row(spec, load, flow / spec.design.main_steam_flow,
                                    float(point["main_steam_pressure"])
                                    * (pressure[0] + pressure[1] * dp),
                                    float(point["main_steam_temperature"])
                                    + temperature[0] + temperature[1] * dt, flow))
    for load in points:
        point = operating_point(spec, load)
        rows.append(_design_row(spec, load, load, float(point["main_steam_pressure"]),
                                float(point["main_steam_temperature"]),
                                float(point["main_steam_flow"])))
    return pd.DataFrame(rows)


def _centre_half(interval: tuple[float, float]) -> tuple[float, float]:
    return 0.5 * (interval[0] + interval[1]), 0.5 * (interval[1] - interval[0])


def _design_row(spec: TurbineSpec, level: float, load: float, pressure: float,
                temperature: float, flow: float) -> dict[str, float]:
    """One design condition; HP-exhaust pressure ∝ flow (times the cone law's sqrt(T_rh) of a
    scheduled reheat temperature at ``load``, ``steamtwin.model.operating``)."""
    return {
        "load_level": float(level),
        "load_fraction": float(load),
        "main_steam_pressure": pressure,
        "main_steam_temperature": temperature,
        "main_steam_flow": flow,
        "hp_exhaust_pressure": float(hp_exhaust_pressure(spec, flow, load)),
    }


@dataclass(frozen=True)
class SnapshotContext:
    """What every snapshot task needs: the turbine, the blade mesh, the model parameters."""

    spec: TurbineSpec
    mesh: SolidMesh
    params: ModelParameters

    @property
    def token(self) -> str:
        """Digest identifying the context (workers cache their models by it)."""
        digest = hashlib.sha256()
        digest.update(repr((self.spec, self.params)).encode())
        for array in (self.mesh.points, self.mesh.tetrahedra, self.mesh.boundary_regions):
            digest.update(np.ascontiguousarray(array).tobytes())
        return digest.hexdigest()


class BladeFieldSolver:
    """FOM + boundary conditions + FEM for one context; solves steady fields per condition."""

    def __init__(self, context: SnapshotContext) -> None:
        self.context = context
        self.model = FullOrderModel(context.spec)
        self.conduction = BladeConduction(context.mesh, context.spec.rotor_material)
        self.boundary = SteamBoundary(self.conduction, context.spec)

    def solve(self, condition: dict[str, float]) -> tuple[np.ndarray, ControlStageState,
                                                          dict[str, float]]:
        """Steady field (N,) K, governing-stage state and sensor outputs (SI) at a condition."""
        inputs = pd.DataFrame({name: [float(condition[name])] for name in INPUT_SIGNALS},
                              index=pd.to_datetime(["2026-01-01T00:00:00Z"]))
        states, outputs = control_stage_states(self.model, inputs, self.context.params)
        convection = self.boundary.convection(states[0], self.context.params)
        field = self.conduction.solve_steady(convection)
        return field, states[0], {k: float(v) for k, v in outputs.iloc[0].items()}


_WORKER_SOLVERS: dict[str, BladeFieldSolver] = {}


def _solver_for(context: SnapshotContext) -> BladeFieldSolver:
    token = context.token
    if token not in _WORKER_SOLVERS:
        _WORKER_SOLVERS.clear()
        _WORKER_SOLVERS[token] = BladeFieldSolver(context)
    return _WORKER_SOLVERS[token]


_PROCESS_CONTEXT: list[SnapshotContext] = []


def _init_process(context: SnapshotContext) -> None:
    _PROCESS_CONTEXT[:] = [context]


def _process_task(index: int, condition: dict[str, float]) -> tuple[int, dict]:
    return index, _snapshot_record(_solver_for(_PROCESS_CONTEXT[0]), condition)


def _dask_task(condition: dict[str, float], context: SnapshotContext) -> dict:
    return _snapshot_record(_solver_for(context), condition)


def _snapshot_record(solver: BladeFieldSolver, condition: dict[str, float]) -> dict:
    field, state, sensors = solver.solve(condition)
    return {"field": field, "control_stage_pressure": state.control_stage_pressure,
            "active_admission_arc": state.active_admission_arc, "sensors": sensors}


@dataclass(frozen=True)
class SnapshotSet:
    """Snapshots (m, N) K with their conditions (DataFrame, SI) and sensor outputs (SI)."""

    fields: np.ndarray
    conditions: pd.DataFrame
    sensors: pd.DataFrame
    mesh: SolidMesh

    def rom_inputs(self, names: Sequence[str] = ROM_INPUTS) -> np.ndarray:
        """The conditions the ROM maps from, (m, len(names))."""
        return self.conditions[list(names)].to_numpy(dtype=float)


def generate_snapshots(spec: TurbineSpec, mesh: object, conditions: pd.DataFrame,
                       params: ModelParameters | None = None, *, max_workers: int | None = None,
                       scheduler: str | None = None,
                       progress: ProgressCallback | None = None) -> SnapshotSet:
    """Solve the steady blade field at every row of ``conditions`` (FOM inputs, SI).

    ``scheduler`` (a Dask scheduler address) runs the tasks on that cluster; otherwise a local
    process pool of ``max_workers`` processes (1 = in this process).
    """
    missing = [name for name in INPUT_SIGNALS if name not in conditions.columns]
    if missing:
        raise ValueError(f"conditions lack column(s) {missing}")
    context = SnapshotContext(spec, checked_mesh(mesh), params or ModelParameters())
    rows = [{name: float(conditions[name].iloc[i]) for name in INPUT_SIGNALS}
            for i in range(len(conditions))]
    records: list[dict | None] = [None] * len(rows)

    def done(index: int, record: dict) -> None:
        records[index] = record
        if progress is not None:
            count = sum(r is not None for r in records)
            progress(count / len(records), f"snapshot {count}/{len(records)}")

    if scheduler is not None:
        from distributed import Client  # a cluster is optional; import only when asked for

        with Client(scheduler) as client:
            shared = client.scatter(context, broadcast=True)
            futures = client.map(_dask_task, rows, context=shared, pure=False)
            index_of = {future.key: i for i, future in enumerate(futures)}
            from distributed import as_completed as dask_completed

            for future in dask_completed(futures):
                done(index_of[future.key], future.result())
    elif max_workers == 1 or len(rows) == 1:
        solver = BladeFieldSolver(context)
        for i, row in enumerate(rows):
            done(i, _snapshot_record(solver, row))
    else:
        with ProcessPoolExecutor(max_workers=max_workers, initializer=_init_process,
                                 initargs=(context,)) as pool:
            futures = [pool.submit(_process_task, i, row) for i, row in enumerate(rows)]
            for future in as_completed(futures):
                done(*future.result())
    complete = [r for r in records if r is not None]
    table = conditions.reset_index(drop=True).copy()
    table["control_stage_pressure"] = [r["control_stage_pressure"] for r in complete]
    table["active_admission_arc"] = [r["active_admission_arc"] for r in complete]
    return SnapshotSet(
        fields=np.vstack([r["field"] for r in complete]),
        conditions=table,
        sensors=pd.DataFrame([r["sensors"] for r in complete]),
        mesh=context.mesh,
    )
