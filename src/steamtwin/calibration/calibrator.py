"""Calibrator: fit the three model parameters to measured windows — one calibrator, a search.

``Calibrator(simulator, objective=ObjectiveSettings(...), search=GeneticSearch(...) |
SurrogateSearch(...), random_state=0).fit(windows)``: the objective's settings
(:class:`~steamtwin.calibration.settings.ObjectiveSettings`) say what is minimised, the search
strategy (:mod:`~steamtwin.calibration.search`) how. By default the GA minimises the posterior
score (the negative log posterior with the default priors,
:mod:`~steamtwin.calibration.objective`), i.e. it finds the MAP, and the Laplace posterior at the
result gives 95 % intervals (:mod:`~steamtwin.calibration.posterior`; for a ``WindowSet`` each
the wider of it and the cluster-robust interval over the load bands); ``priors=None`` gives the
method's plain RMSE fit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from steamtwin.calibration.evaluation import make_evaluator
from steamtwin.calibration.identifiability import check_identifiability
from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem, Evaluation
from steamtwin.calibration.posterior import (
    INPUT_UNCERTAINTIES,
    Posterior,
    laplace_posterior,
    likelihood_tempering,
    window_clusters,
)
from steamtwin.calibration.search import GeneticSearch, SearchResult
from steamtwin.calibration.settings import (
    PARAMETER_NAMES,
    ObjectiveSettings,
    check_random_state,
)
from steamtwin.calibration.surrogate import SurrogateSearch
from steamtwin.errors import CalibrationAreaError
from steamtwin.model.parameters import (
    PARAMETER_BOUNDS,
    PARAMETERS_SCHEMA_VERSION,
    ModelParameters,
    ParameterPrior,
)
from steamtwin.model.simulator import Simulator
from steamtwin.progress import ProgressCallback

__all__ = ["CalibrationError", "Calibrator", "apply_tempering", "check_calibration_result",
           "posterior_at", "write_parameters"]


class CalibrationError(CalibrationAreaError):
    """A calibration that found no usable result (no candidate gave a finite RMSE)."""


def check_calibration_result(rmse: float, problem: CalibrationProblem) -> None:
    """Raise :class:`CalibrationError` unless the best RMSE (K) is a real, finite fit.

    A candidate the model rejects scores :data:`PENALTY_RMSE`; a best RMSE at or above it means
    that no candidate gave a finite RMSE, and such a "result" must never be written.
    """
    if math.isfinite(rmse) and rmse < PENALTY_RMSE:
        return
    runs = problem.n_evaluations
    reason = f" (last reason: {problem.last_error})" if problem.last_error else ""
    if problem.n_penalised >= runs:
        raise CalibrationError(
            f"no candidate gave a finite RMSE: the model rejected all {runs} runs{reason}. "
            "It may be unable to run on the windows' inputs: check their units and ranges "
            "(e.g. a pressure declared in the wrong unit) and the parameter bounds")
    raise CalibrationError(
        f"no candidate gave a finite RMSE better than the {PENALTY_RMSE:g} K penalty of a "
        f"rejected run (best {rmse:.6g} K; {problem.n_penalised} of {runs} runs "
        f"rejected{reason}). The "
        "measured temperatures may be in another unit than declared, or the model cannot run "
        "on the windows' inputs: check their units and ranges")


class Calibrator:
    """Calibration of flow, friction and heat-transfer coefficients against DCS temperatures.

    ``objective``: what is minimised (:class:`ObjectiveSettings`; default: the three
    temperatures, the default priors, σ 1 K, no sensor biases, tempering "auto");
    ``search``: how (:class:`~steamtwin.calibration.search.GeneticSearch`, the default, or
    :class:`~steamtwin.calibration.surrogate.SurrogateSearch`); ``random_state``: the seed (an
    integer ≥ 0; the same value gives the same result, whatever evaluates the candidates);
    ``workers``: local processes (default every core; 1 = in this process); ``scheduler``: a
    Dask scheduler address or ``distributed.Client`` (overrides ``workers``); ``progress``:
    ``progress(fraction, message)`` after each generation or surrogate round.

    The constructor stores its arguments; :meth:`fit` checks them, runs the search and sets
    ``params_`` (:class:`ModelParameters`, the MAP), ``rmse_`` (K), ``score_`` (the minimised
    posterior score), ``tempering_`` (κ), ``posterior_``
    (:class:`~steamtwin.calibration.posterior.Posterior` at the MAP; None without priors),
    ``sensor_offsets_`` (sensor → its estimated bias, measured − model, SI, with
    ``sensor_bias``; empty without), ``history_`` (the GA: one row per generation,
    :data:`~steamtwin.calibration.search.HISTORY_COLUMNS`; the surrogate: one per round),
    ``n_evaluations_`` (model runs), ``n_penalised_``, ``window_info_`` (per window: samples,
    filled and dropped input rows, excluded measured samples), ``identifiability_`` (per
    parameter, :mod:`~steamtwin.calibration.identifiability`; an ``IdentifiabilityWarning``
    for each parameter the windows cannot identify) and what only one search has, else None:
    ``population_`` (the GA's final population), ``repair_counts_`` (its re-mutation
    repair's counters), ``samples_`` (the surrogate's model-evaluated points and scores).

    ``windows`` of :meth:`fit`: DataFrames, or a
    :class:`~steamtwin.calibration.windowset.WindowSet` (joint calibration: its load-band
    weights and per-file σ).
    """

    def __init__(self, simulator: Simulator, *, objective: ObjectiveSettings | None = None,
                 search: GeneticSearch | SurrogateSearch | None = None, random_state: int = 0,
                 workers: int | None = None, scheduler: Any = None,
                 progress: ProgressCallback | None = None) -> None:
        self.simulator = simulator
        self.objective = objective
        self.search = search
        self.random_state = random_state
        self.workers = workers
        self.scheduler = scheduler
        self.progress = progress

    @property
    def objective_settings(self) -> ObjectiveSettings:
        """The objective's settings in use (``objective``, else the defaults)."""
        return ObjectiveSettings() if self.objective is None else self.objective

    @property
    def search_strategy(self) -> GeneticSearch | SurrogateSearch:
        """The search in use (``search``, else the default :class:`GeneticSearch`)."""
        return GeneticSearch() if self.search is None else self.search

    def _check(self) -> int:
        """Check the arguments before any work (TypeError/ValueError naming the argument);
        the random state as an int."""
        for name, value, kind in (("objective", self.objective, ObjectiveSettings | None),
                                  ("search", self.search,
                                   GeneticSearch | SurrogateSearch | None)):
            if not isinstance(value, kind):
                raise TypeError(f"Calibrator: {name} must be {kind} "
                                f"(got {type(value).__name__})")
        return check_random_state(self.random_state)

    def problem(self, windows: Sequence[pd.DataFrame]) -> CalibrationProblem:
        """The pymoo problem of ``windows`` under the objective's settings."""
        return CalibrationProblem(self.simulator, windows, self.objective_settings)

    def run_settings(self) -> dict[str, object]:
        """The settings that, with the search's and the prepared data, identify a run (its
        checkpoint's fingerprint): the objective's and the random state."""
        return {**asdict(self.objective_settings), "random_state": self.random_state}

    def fit(self, windows: Sequence[pd.DataFrame], resume: bool = False) -> Calibrator:
        """Calibrate against measured windows (canonical SI signals); returns self.

        ``resume=True`` continues a :class:`GeneticSearch` from its ``checkpoint`` (a
        :class:`~steamtwin.calibration.checkpoint.CheckpointError` if there is none, if it is
        not a valid checkpoint or if it was written for other settings or data; the surrogate
        has none: ``ValueError``); a finished checkpoint just gives its result. Arguments
        outside their range raise ``ValueError`` naming the argument; a run in which no
        candidate gave a finite RMSE raises :class:`CalibrationError`.
        """
        random_state = self._check()
        search = self.search_strategy
        problem = self.problem(windows)
        self.tempering_ = apply_tempering(problem)
        evaluator = make_evaluator(self.workers, self.scheduler)
        evaluator.start(problem.objective)
        problem.evaluator = evaluator
        try:
            found = search.run(problem, random_state=random_state, progress=self.progress,
                               resume=resume, settings=self.run_settings())
        finally:
            problem.evaluator = None
            evaluator.close()
        self._set_result(problem, found, windows)
        # here, not in _set_result: the warning then points at the caller of fit
        self.identifiability_ = check_identifiability(problem, self.params_, self.rmse_)
        return self

    def _set_result(self, problem: CalibrationProblem, found: SearchResult,
                    windows: Sequence[pd.DataFrame]) -> None:
        result = problem.objective.evaluate(found.x)
        check_calibration_result(result.rmse, problem)
        self.params_ = problem.parameters(found.x)
        self.rmse_, self.score_ = result.rmse, result.value
        self.posterior_ = posterior_at(problem, self.params_, result, windows)
        self.sensor_offsets_ = problem.objective.sensor_offsets(self.params_)
        self.history_ = found.history
        self.n_evaluations_ = problem.n_evaluations
        self.n_penalised_ = problem.n_penalised
        self.population_ = found.population
        self.repair_counts_ = found.repair_counts
        self.samples_ = found.samples
        self.window_info_ = pd.DataFrame([
            {"start": w.inputs.index[0], "end": w.inputs.index[-1], "samples": len(w.inputs),
             "filled_rows": w.filled_rows, "dropped_rows": w.dropped_rows,
             **{f"excluded:{s}": n for s, n in zip(problem.sensors, w.excluded, strict=True)}}
            for w in problem.windows
        ])

    def rmse(self, windows: Sequence[pd.DataFrame], params: ModelParameters | None = None
             ) -> float:
        """Weighted RMSE (K) of ``params`` (default: the empirical 1, 1, 1) on ``windows``."""
        return self.problem(windows).rmse(params or ModelParameters())

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write the parameters JSON (readable by ``ModelParameters.from_json``) and history.

        The history goes to ``<path stem>.history.csv`` next to it; returns both paths.
        """
        if not hasattr(self, "params_"):
            raise RuntimeError("Calibrator is not fitted; call fit(windows) first")
        search, objective = self.search_strategy, self.objective_settings
        settings = {"mode": search.mode, **search.record(), "random_state": self.random_state,
                    "score": self.score_, "tempering": self.tempering_}
        return write_parameters(path, self.params_, self.rmse_, objective.sensors,
                                self.n_evaluations_, settings, self.history_,
                                objective.priors, self.posterior_, self.sensor_offsets_)


def apply_tempering(problem: CalibrationProblem) -> float:
    """Set the problem's likelihood tempering κ from its settings' ``tempering`` (a number in
    (0, 1], or "auto": estimated at the priors' centres by
    :func:`~steamtwin.calibration.posterior.likelihood_tempering`; 1 without priors or when
    the model rejects that point); returns κ."""
    tempering = problem.settings.tempering
    kappa = 1.0 if tempering == "auto" else float(tempering)
    priors = problem.objective.priors
    if tempering == "auto" and priors is not None:
        centre = ModelParameters(**{
            name: float(np.clip(prior.center, *problem.parameter_bounds[name]))
            for name, prior in zip(PARAMETER_NAMES, priors, strict=True)})
        try:
            kappa = likelihood_tempering(problem.objective, centre)
        except ValueError:
            kappa = 1.0
    problem.objective = replace(problem.objective, tempering=kappa)
    return kappa


def posterior_at(problem: CalibrationProblem, params: ModelParameters, result: Evaluation,
                 windows: object = None) -> Posterior | None:
    """The Laplace posterior at a calibration result (None without priors or if rejected); the
    intervals carry the measured inputs' calibration errors
    (:data:`~steamtwin.calibration.posterior.INPUT_UNCERTAINTIES`) and, for a
    :class:`~steamtwin.calibration.windowset.WindowSet` of ``windows``, the cluster-robust
    sandwich over its load bands where that is wider
    (:func:`~steamtwin.calibration.posterior.window_clusters`)."""
    if problem.objective.priors is None or result.penalised:
        return None
    return laplace_posterior(problem.objective, params, inputs=INPUT_UNCERTAINTIES,
                             clusters=window_clusters(windows))


def write_parameters(path: str | Path, params: ModelParameters, rmse: float,
                     sensors: Sequence[str], evaluations: int, settings: dict[str, object],
                     history: pd.DataFrame,
                     priors: Mapping[str, ParameterPrior] | None = None,
                     posterior: Posterior | None = None,
                     sensor_offsets: Mapping[str, float] | None = None) -> tuple[Path, Path]:
    """Parameters JSON (``ModelParameters.from_json`` reads it; schema version
    :data:`PARAMETERS_SCHEMA_VERSION`, with the priors, the posterior intervals and the sensor
    offsets (measured − model, SI) when given) + ``<stem>.history.csv``."""
    path = Path(path)
    document: dict[str, object] = {
        "schema_version": PARAMETERS_SCHEMA_VERSION,
        "parameters": asdict(params),
        "bounds": {name: list(bounds) for name, bounds in PARAMETER_BOUNDS.items()},
        "calibration": {"rmse_K": rmse, "sensors": list(sensors), "evaluations": evaluations,
                        **settings},
    }
    if priors is not None:
        document["priors"] = {name: asdict(prior) for name, prior in priors.items()}
    if posterior is not None:
        document["posterior"] = posterior.to_dict()
    if sensor_offsets:
        document["sensor_offsets"] = dict(sensor_offsets)
    path.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    history_path = path.with_name(f"{path.stem}.history.csv")
    history.to_csv(history_path)
    return path, history_path
