"""Online tracking of the model parameters: a recursive Bayesian filter, step by step.

Between recalibrations a plant's coefficients drift slowly (deposits narrow the blade passages:
the flow coefficient; roughness: friction; fouling: heat transfer) and sometimes step (a
washing, a damaged blade row). :class:`ParameterTracker` follows them as data arrive, as a
random-walk state θ with an iterated extended Kalman filter (Jazwinski 1970, *Stochastic
Processes and Filtering Theory*, §8.3; Bell & Cathey 1993 — the iterated EKF update is the MAP
of the step's posterior by Gauss–Newton):

* **state**: the three coefficients in their priors' normal coordinates θ (x, or ln x for a
  log-normal prior; :class:`~steamtwin.model.parameters.ParameterPrior`), with a diagonal
  covariance;
* **predict**: over Δt the variance of each grows by q²·Δt (a random walk with
  ``drift_per_hour`` q, the largest change per hour the tracker follows without lagging);
* **update**: on the data of the last ``step_s`` seconds only (steps do not overlap, so no
  sample counts twice) the MAP of the step's posterior — the measurement likelihood with the
  per-sensor instrument error σ, times the predicted state as the prior — by Gauss–Newton
  (:func:`~steamtwin.calibration.posterior.fit_map`), then its Laplace covariance
  (:func:`~steamtwin.calibration.posterior.laplace_posterior`, with the residuals'
  autocorrelation correction) as the new state.

The control-stage pressure is the sharpest witness of the flow coefficient (Stodola: the stage
group's swallowing capacity sets it at a given flow), so the tracker uses it beside the
temperatures whenever the model computes it and the data measure it. A step whose data cannot
be used (too few samples, the model rejects the inputs) keeps the predicted state and logs why:
the variance keeps growing, so the next good step weighs its data more.

With ``scheduler`` (a Dask scheduler address or ``distributed.Client``) each step's fit — the
Gauss–Newton MAP and its Laplace covariance, all of a step's model runs — is one task on that
cluster: the model is broadcast to the workers once, each step ships only its data, priors and
start, and the filter's update uses the task's answer exactly as it would the local one (the
same function on the same inputs: the trajectory equals the local run's, tested). The caller
waits for the answer, so a step's estimate applies at the same sample wherever it ran and a
restarted service still reproduces an uninterrupted one; what moves off the service's machine
is the step's CPU (a fraction of a second of model runs per 10-min step and unit). A single
step is one serial Gauss–Newton run, so without a scheduler it runs in the calling process: a
local pool would only add the hand-over.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.calibration.evaluation import dask_client
from steamtwin.calibration.objective import CalibrationProblem
from steamtwin.calibration.online import ParameterStore, append_chunk, replay_chunks
from steamtwin.calibration.posterior import (
    FLOW_MEASUREMENT_UNCERTAINTY,
    fit_map,
    laplace_posterior,
)
from steamtwin.calibration.settings import (
    DEFAULT_SENSORS,
    MAX_INPUT_GAP_S,
    PARAMETER_NAMES,
    ObjectiveSettings,
)
from steamtwin.calibration.windowset import measurement_sigma
from steamtwin.dcs.tagmap import TagMap
from steamtwin.jsonframe import frame_from_json, frame_to_json
from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    PARAMETER_BOUNDS,
    ModelParameters,
    ParameterPrior,
)
from steamtwin.model.simulator import Simulator

__all__ = ["DEFAULT_DRIFT_PER_HOUR", "TRACKED_PARAMETERS", "ParameterTracker", "tracking_sigma"]

#: Random-walk rates q (per √hour, in the priors' normal coordinates: absolute for the normal
#: flow coefficient, relative for log-normal ones). A flow coefficient may step by a few per
#: cent (a blade-row washing, a damaged row: 2-3 % of capacity [Cotton, ch. 7]); the tracker
#: follows a step of 0.02 within a few 10-minute steps when q = 0.02/√h. Friction and heat
#: transfer change over weeks; 5 %/√h keeps them loose enough to follow what the data show.
DEFAULT_DRIFT_PER_HOUR: dict[str, float] = {
    "flow_coefficient": 0.02,
    "friction_coefficient": 0.05,
    "heat_transfer_coefficient": 0.05,
}
#: Sensors tracked when the model computes and the data hold them: the temperatures and the
#: control-stage pressure (the flow coefficient's witness).
TRACKING_SENSORS: tuple[str, ...] = (*DEFAULT_SENSORS, "control_stage_pressure")
#: Tracked by default: the flow coefficient (the control-stage pressure sees it in minutes) and
#: friction (the expansion's temperatures at any steady load). The heat-transfer coefficient
#: acts only through metal storage in ramps, which a 10-minute step rarely holds; tracked on
#: such steps it explains whatever transient the other two miss and wanders (seen: 1.0 → 0.55
#: over a flow-coefficient step), so it is held at its prior — the calibration's — unless asked.
TRACKED_PARAMETERS: tuple[str, ...] = ("flow_coefficient", "friction_coefficient")
#: Prior spread (normal coordinate) that holds an untracked parameter in a step's fit.
_HELD_SPREAD = 1e-9
MIN_STEP_SAMPLES = 60
#: Instrument error where the tag map states none (SI): a class-1 thermocouple's tolerance is
#: ±1.5 K up to 375 °C and ±0.004·|t| above (IEC 60584-1:2013, Table 1; ~±2 K at 500 °C),
#: taken as the 95 % limit, σ ≈ 1 K; a pressure transmitter of accuracy class 0.1 % on a
#: 0-25 MPa span (IEC 60770-1), σ = 25 kPa.
TYPICAL_INSTRUMENT_ERROR: dict[str, float] = {
    "control_stage_temperature": 1.0,
    "hp_exhaust_temperature": 1.0,
    "hp_inner_casing_temperature": 1.0,
    "control_stage_pressure": 25.0e3,
}


def tracking_sigma(tag_map: TagMap | None) -> dict[str, float]:
    """Instrument error σ per tracked sensor (SI): the tag map's noise and resolution
    (:func:`~steamtwin.calibration.windowset.measurement_sigma`), else
    :data:`TYPICAL_INSTRUMENT_ERROR`."""
    given: dict[str, float] = {}
    if tag_map is not None:
        given = measurement_sigma({n: s.noise_si for n, s in tag_map.signals.items()},
                                  {n: s.resolution_si for n, s in tag_map.signals.items()})
    return {**TYPICAL_INSTRUMENT_ERROR, **given}


class ParameterTracker:
    """Track the coefficients step by step (module docstring).

    ``simulator``: the model (read through its sensors); ``sigma``: instrument error per sensor
    (SI: K, Pa) — give the control-stage pressure's, else it is not used; ``priors``: the start
    state (default :data:`~steamtwin.model.parameters.DEFAULT_PRIORS`, or a calibration's
    posterior); ``step_s``: seconds of data per update; ``drift_per_hour``: q per parameter;
    ``tracked``: the coefficients followed (:data:`TRACKED_PARAMETERS`), the others stay at
    their prior's centre; ``flow_uncertainty``: the flow measurement's relative standard
    uncertainty, in the flow coefficient's reported interval
    (:data:`FLOW_MEASUREMENT_UNCERTAINTY`); ``trajectory_rows``: the most recent steps the
    trajectory keeps (None: all; a live service keeps a day's). After :meth:`run`/:meth:`update`:
    ``trajectory_`` (one row per step, indexed by the step's end: each coefficient, its
    ``<name>_std`` (the filter's, normal coordinate) and 95 % ``<name>_low`` / ``_high``,
    ``samples``, ``error``) and ``params_`` (current). ``scheduler``: a Dask scheduler address
    or ``distributed.Client`` on which each step's fit runs (module docstring; None: in this
    process); a client made here from an address is closed by :meth:`close`.
    """

    def __init__(self, simulator: Simulator, *, sigma: Mapping[str, float],
                 priors: Mapping[str, ParameterPrior] | None = None, step_s: float = 600.0,
                 drift_per_hour: Mapping[str, float] | None = None,
                 sensors: Sequence[str] = TRACKING_SENSORS,
                 tracked: Sequence[str] = TRACKED_PARAMETERS,
                 flow_uncertainty: float = FLOW_MEASUREMENT_UNCERTAINTY,
                 store: ParameterStore | None = None,
                 max_input_gap_s: float = MAX_INPUT_GAP_S,
                 trajectory_rows: int | None = None, scheduler: Any = None) -> None:
        self.simulator = simulator
        self.sigma = sigma
        self.priors = priors
        self.step_s = step_s
        self.drift_per_hour = drift_per_hour
        self.sensors = sensors
        self.tracked = tracked
        self.flow_uncertainty = flow_uncertainty
        self.store = store
        self.max_input_gap_s = max_input_gap_s
        self.trajectory_rows = trajectory_rows
        self.scheduler = scheduler
        self._cluster: tuple[Any, bool, Any] | None = None  # client, own, broadcast model

    def _start(self) -> None:
        rows = self.trajectory_rows
        if rows is not None and (isinstance(rows, bool) or not isinstance(rows, int) or rows < 1):
            raise ValueError(f"trajectory_rows must be a whole number ≥ 1 or None (got {rows!r})")
        if not (isinstance(self.step_s, int | float) and math.isfinite(self.step_s)
                and self.step_s > 0):
            raise ValueError(f"step_s must be a positive number of seconds (got {self.step_s!r})")
        priors = dict(self.priors or DEFAULT_PRIORS)
        missing = [name for name in PARAMETER_NAMES if name not in priors]
        if missing:
            raise ValueError(f"priors: missing {missing}")
        drift = {**DEFAULT_DRIFT_PER_HOUR, **(self.drift_per_hour or {})}
        for name, q in drift.items():
            if name not in PARAMETER_NAMES or not (math.isfinite(q) and q >= 0.0):
                raise ValueError(f"drift_per_hour[{name!r}] = {q!r}: expected a parameter name "
                                 "and a finite rate ≥ 0")
        self._drift = drift
        unknown = [name for name in self.tracked if name not in PARAMETER_NAMES]
        if unknown or not self.tracked:
            raise ValueError(f"tracked: expected some of {list(PARAMETER_NAMES)}, got "
                             f"{list(self.tracked)}")
        self._held = np.array([name not in self.tracked for name in PARAMETER_NAMES])
        self._kinds = {name: priors[name].distribution for name in PARAMETER_NAMES}
        self._theta = np.array([priors[n].mean_internal for n in PARAMETER_NAMES])
        self._variance = np.array([priors[n].spread ** 2 for n in PARAMETER_NAMES])
        self._prior_variance = self._variance.copy()
        outputs = set(self.simulator.output_signals)
        self._sensors = tuple(s for s in self.sensors if s in outputs and s in self.sigma)
        if not self._sensors:
            raise ValueError(f"sigma names none of the sensors {list(self.sensors)} the model "
                             f"computes ({sorted(outputs)})")
        self.store_ = self.store if self.store is not None else ParameterStore()
        self._buffer = pd.DataFrame()
        self._step_start: pd.Timestamp | None = None
        self._rows: list[dict[str, object]] = []
        self.trajectory_ = pd.DataFrame()
        self.params_ = self._params()
        self.store_.swap(self.params_)

    def _prior(self, index: int, variance: float) -> ParameterPrior:
        name = PARAMETER_NAMES[index]
        kind = self._kinds[name]
        center = self._theta[index] if kind == "normal" else math.exp(self._theta[index])
        return ParameterPrior(kind, float(center), float(math.sqrt(variance)), "tracked state")

    def _params(self) -> ModelParameters:
        values = {}
        for i, name in enumerate(PARAMETER_NAMES):
            value = self._prior(i, self._variance[i]).center
            low, high = PARAMETER_BOUNDS[name]
            values[name] = float(np.clip(value, low, high))
        return ModelParameters(**values)

    def update(self, chunk: pd.DataFrame) -> pd.DataFrame:
        """Take newly arrived data (canonical SI signals, after the last chunk); run every step
        that has come due. Returns the trajectory rows added."""
        if not hasattr(self, "_buffer"):
            self._start()
        self._buffer = append_chunk(self._buffer, chunk)
        if self._buffer.empty:
            return pd.DataFrame()
        if self._step_start is None:
            self._step_start = self._buffer.index[0]
        step = pd.Timedelta(seconds=self.step_s)
        added = []
        while self._buffer.index[-1] >= self._step_start + step:
            end = self._step_start + step
            data = self._buffer.loc[(self._buffer.index >= self._step_start)
                                    & (self._buffer.index < end)]
            added.append(self._step(data, end))
            self._step_start = end
            self._buffer = self._buffer.loc[self._buffer.index >= end]
        if added:
            self._rows.extend(added)
            if self.trajectory_rows is not None:  # a service that runs for months
                self._rows = self._rows[-self.trajectory_rows:]
            self.trajectory_ = pd.DataFrame(self._rows).set_index("time")
        return pd.DataFrame(added).set_index("time") if added else pd.DataFrame()

    def start(self) -> ParameterTracker:
        """Validate the settings and set the state to the priors (``update`` does this on its
        first call); returns self."""
        self._start()
        return self

    def reset(self, names: Sequence[str]) -> None:
        """Covariance resetting (Goodwin & Sin, *Adaptive Filtering, Prediction and Control*,
        1984, §3.3.2): the variance of each named, tracked coefficient goes back to at least its
        prior's, so the next steps weigh their data as a fresh calibration would and follow a
        change the random walk's q would take hours to admit. The estimate itself is kept."""
        if not hasattr(self, "_buffer"):
            self._start()
        unknown = [name for name in names if name not in PARAMETER_NAMES]
        if unknown:
            raise ValueError(f"reset: unknown parameters {unknown}; expected some of "
                             f"{list(PARAMETER_NAMES)}")
        for name in names:
            index = PARAMETER_NAMES.index(name)
            if not self._held[index]:
                self._variance[index] = max(self._variance[index], self._prior_variance[index])

    def get_state(self) -> dict[str, object]:
        """JSON-ready filter state (θ, variances, the data of the step under way and its start)
        to restart from; the trajectory is not part of it."""
        if not hasattr(self, "_buffer"):
            self._start()
        return {"theta": [float(x) for x in self._theta],
                "variance": [float(x) for x in self._variance],
                "step_start": None if self._step_start is None else self._step_start.isoformat(),
                "buffer": frame_to_json(self._buffer)}

    def set_state(self, state: Mapping[str, object]) -> ParameterTracker:
        """Restore :meth:`get_state`'s output exactly (settings from this instance)."""
        self._start()
        self._theta = np.array(state["theta"], dtype=float)
        self._variance = np.array(state["variance"], dtype=float)
        start = state["step_start"]
        self._step_start = None if start is None else pd.Timestamp(start)
        self._buffer = frame_from_json(state["buffer"])
        self.params_ = self._params()
        self.store_.swap(self.params_)
        return self

    def run(self, data: pd.DataFrame | Iterable[pd.DataFrame], chunk_s: float = 60.0
            ) -> ParameterTracker:
        """Replay ``data`` (a frame cut into ``chunk_s``-second chunks, or an iterable of
        chunks) through :meth:`update`; returns self."""
        chunks, _ = replay_chunks(data, chunk_s)
        self._start()
        for chunk in chunks:
            self.update(chunk)
        return self

    def _step(self, data: pd.DataFrame, end: pd.Timestamp) -> dict[str, object]:
        hours = self.step_s / 3600.0
        self._variance = self._variance + np.where(self._held, 0.0, np.array(
            [self._drift[n] ** 2 * hours for n in PARAMETER_NAMES]))
        row: dict[str, object] = {"time": end, "samples": len(data), "error": ""}
        if len(data) < MIN_STEP_SAMPLES:
            return self._row(row, f"{len(data)} samples, fewer than {MIN_STEP_SAMPLES}")
        priors = {name: self._prior(i, _HELD_SPREAD**2 if self._held[i] else self._variance[i])
                  for i, name in enumerate(PARAMETER_NAMES)}
        settings = {"sensors": self._sensors, "sigma": dict(self.sigma), "priors": priors,
                    "max_input_gap_s": self.max_input_gap_s, "min_samples": MIN_STEP_SAMPLES}
        if self.scheduler is None:
            fitted = _fit_step(self.simulator, data, settings, self._params())
        else:
            client, _, model = self._connect()
            fitted = client.submit(_fit_step, model, data, settings, self._params(),
                                   pure=False).result()
        if isinstance(fitted, str):
            return self._row(row, fitted)
        theta, covariance = fitted
        tracked = ~self._held
        self._theta[tracked] = theta[tracked]
        self._variance[tracked] = np.diag(covariance)[tracked]
        self.params_ = self._params()
        self.store_.swap(self.params_)
        return self._row(row, "")

    def _connect(self) -> tuple[Any, bool, Any]:
        """The Dask client, whether it is this tracker's own, and the model broadcast to every
        worker (once: steps then ship only their data)."""
        if self._cluster is None:
            client, own = dask_client(self.scheduler)
            [model] = client.scatter([self.simulator], broadcast=True, hash=False)
            self._cluster = (client, own, model)
        return self._cluster

    def close(self) -> None:
        """Release the model broadcast to the Dask workers and close a client made from an
        address (idempotent; a later step connects again)."""
        if self._cluster is not None:
            client, own, _ = self._cluster
            self._cluster = None
            if own:
                client.close()

    def _row(self, row: dict[str, object], error: str) -> dict[str, object]:
        row["error"] = error
        row.update(asdict(self._params()))
        for i, name in enumerate(PARAMETER_NAMES):
            variance = self._variance[i]
            row[f"{name}_std"] = math.sqrt(variance)
            if name == "flow_coefficient":  # the flow meter's bias (FLOW_MEASUREMENT_UNCERTAINTY)
                scale = self._prior(i, variance).center if self._kinds[name] == "normal" else 1.0
                variance += (scale * self.flow_uncertainty) ** 2
            row[f"{name}_low"], row[f"{name}_high"] = self._prior(i, variance).interval(0.95)
        return row


def _fit_step(simulator: Simulator, data: pd.DataFrame, settings: Mapping[str, Any],
              start: ModelParameters) -> tuple[np.ndarray, np.ndarray] | str:
    """One step's fit (module docstring): the MAP from ``start`` under the objective
    ``settings`` (:class:`ObjectiveSettings`' arguments) and its Laplace posterior, as
    (θ, covariance) in the priors' normal coordinates, or why the step's data cannot be used.
    Module-level: a Dask worker runs it by reference."""
    try:
        objective = CalibrationProblem(simulator, [data], ObjectiveSettings(**settings)).objective
        estimate = fit_map(objective, start, settings["priors"])
        posterior = laplace_posterior(objective, estimate, settings["priors"])
    except ValueError as error:
        return str(error)
    return np.asarray(posterior.theta, dtype=float), np.asarray(posterior.covariance, dtype=float)
