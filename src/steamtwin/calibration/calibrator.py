"""Calibrator: fit the three model parameters to measured windows with the method's GA.

By default the GA minimises the posterior score (the negative log posterior with the default
priors, :mod:`~steamtwin.calibration.objective`), i.e. it finds the MAP, and the Laplace
posterior at the result gives 95 % intervals (:mod:`~steamtwin.calibration.posterior`; for a
``WindowSet`` each the wider of it and the cluster-robust interval over the load bands);
``priors=None`` gives the method's plain RMSE fit.
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
from pymoo.core.algorithm import Algorithm

from steamtwin.calibration.checkpoint import (
    load_checkpoint,
    restore_algorithm,
    run_fingerprint,
    save_checkpoint,
)
from steamtwin.calibration.evaluation import make_evaluator
from steamtwin.calibration.ga import RemutationRepair, check_ga_settings, make_ga
from steamtwin.calibration.identifiability import check_identifiability
from steamtwin.calibration.objective import (
    DEFAULT_SENSORS,
    MAX_INPUT_GAP_S,
    MIN_WINDOW_SAMPLES,
    PARAMETER_NAMES,
    PENALTY_RMSE,
    CalibrationProblem,
    Evaluation,
    fitness,
)
from steamtwin.calibration.posterior import (
    INPUT_UNCERTAINTIES,
    Posterior,
    laplace_posterior,
    likelihood_tempering,
    window_clusters,
)
from steamtwin.errors import CalibrationAreaError
from steamtwin.model.parameters import (
    DEFAULT_PRIORS,
    PARAMETER_BOUNDS,
    PARAMETERS_SCHEMA_VERSION,
    ModelParameters,
    ParameterPrior,
)
from steamtwin.model.simulator import Simulator
from steamtwin.progress import ProgressCallback

__all__ = ["HISTORY_COLUMNS", "CalibrationError", "Calibrator", "ProgressCallback",
           "check_calibration_result", "check_common_settings", "write_parameters"]


HISTORY_COLUMNS: tuple[str, ...] = (
    "generation", "best_rmse", "mean_rmse", "best_fitness", "mean_fitness", *PARAMETER_NAMES,
    "evaluations", "penalised", "remutations")
"""Columns of a GA history row (``generation`` becomes the index of ``history_``).
``best_rmse``/``mean_rmse`` are the minimised objective: the RMSE (K) without priors and σ,
otherwise the posterior score (:mod:`~steamtwin.calibration.objective`)."""


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


def check_common_settings(*, seed: object, max_input_gap_s: object, min_samples: object
                          ) -> None:
    """Check the arguments every calibrator shares; ValueError naming the argument.

    ``seed`` an integer ≥ 0, ``max_input_gap_s`` a number ≥ 0 (s), ``min_samples`` an
    integer ≥ 1.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be an integer ≥ 0 (got {seed!r})")
    if isinstance(max_input_gap_s, bool) or not isinstance(
            max_input_gap_s, int | float | np.integer | np.floating) or not max_input_gap_s >= 0:
        raise ValueError(f"max_input_gap_s must be a number ≥ 0 s (got {max_input_gap_s!r})")
    if isinstance(min_samples, bool) or not isinstance(min_samples, int | np.integer) or (
            min_samples < 1):
        raise ValueError(f"min_samples must be an integer ≥ 1 (got {min_samples!r})")


class Calibrator:
    """GA calibration of flow, friction and heat-transfer coefficients against DCS temperatures.

    The constructor stores its arguments; :meth:`fit` validates them, runs the GA and sets
    ``params_`` (:class:`ModelParameters`), ``rmse_`` (K), ``history_`` (one row per
    generation), ``n_evaluations_``, ``window_info_`` (per window: samples, filled and dropped
    input rows, excluded measured samples), ``n_penalised_``, ``repair_counts_``,
    ``population_`` (final GA population) and ``identifiability_`` (per parameter, see
    :mod:`~steamtwin.calibration.identifiability`; an :class:`IdentifiabilityWarning` is issued
    for each parameter the windows cannot identify), ``score_`` (the minimised posterior
    score), ``posterior_`` (:class:`~steamtwin.calibration.posterior.Posterior` at the MAP;
    None without priors) and ``sensor_offsets_`` (sensor → its estimated bias, measured −
    model, SI, with ``sensor_bias``; empty without).

    ``windows`` of :meth:`fit`: DataFrames, or a
    :class:`~steamtwin.calibration.windowset.WindowSet` (joint calibration: its load-band
    weights and per-file σ). ``priors``: name → :class:`ParameterPrior` (default
    :data:`DEFAULT_PRIORS`; None = plain RMSE, no intervals); ``sigma``: measurement error per
    sensor (K) for windows without their own (default 1 K); ``sensor_bias``: the sensors'
    constant biases integrated out (:data:`~steamtwin.calibration.objective.THERMOCOUPLE_BIAS`:
    class-1 thermocouples; default None: none; see :mod:`~steamtwin.calibration.objective`);
    ``tempering``: κ ∈ (0, 1] weighting the likelihood, or "auto" (default: 1/(τ·S²) at the
    priors' centres, :func:`~steamtwin.calibration.posterior.likelihood_tempering`; 1 without
    priors), set as ``tempering_``.
    Same ``seed`` → same result, whatever evaluates the candidates.

    ``workers``: local processes (default every core; 1 = in this process); ``scheduler``: a
    Dask scheduler address or ``distributed.Client`` (overrides ``workers``). ``checkpoint``:
    a file rewritten after every generation; ``fit(windows, resume=True)`` continues from it
    and ends with the same result as an uninterrupted run.
    """

    def __init__(self, simulator: Simulator, *,
                 bounds: Mapping[str, tuple[float, float]] | None = None,
                 sensors: Sequence[str] = DEFAULT_SENSORS,
                 weights: Mapping[str, float] | Sequence[float] | None = None,
                 population: int = 50, generations: int = 200,
                 crossover_probability: float = 0.9, crossover_eta: float = 15.0,
                 mutation_probability: float | None = None, mutation_eta: float = 20.0,
                 tournament_size: int = 2, seed: int = 0,
                 progress: ProgressCallback | None = None,
                 max_input_gap_s: float = MAX_INPUT_GAP_S,
                 min_samples: int = MIN_WINDOW_SAMPLES, workers: int | None = None,
                 scheduler: Any = None, checkpoint: str | Path | None = None,
                 priors: Mapping[str, ParameterPrior] | None = DEFAULT_PRIORS,
                 sigma: Mapping[str, float] | None = None,
                 sensor_bias: str | Mapping[str, float] | None = None,
                 tempering: float | str = "auto") -> None:
        self.simulator = simulator
        self.bounds = bounds
        self.sensors = sensors
        self.weights = weights
        self.population = population
        self.generations = generations
        self.crossover_probability = crossover_probability
        self.crossover_eta = crossover_eta
        self.mutation_probability = mutation_probability
        self.mutation_eta = mutation_eta
        self.tournament_size = tournament_size
        self.seed = seed
        self.progress = progress
        self.max_input_gap_s = max_input_gap_s
        self.min_samples = min_samples
        self.workers = workers
        self.scheduler = scheduler
        self.checkpoint = checkpoint
        self.priors = priors
        self.sigma = sigma
        self.sensor_bias = sensor_bias
        self.tempering = tempering

    # -- pieces (seams for parallel evaluation, checkpointing and other modes) ---------------

    def _problem(self, windows: Sequence[pd.DataFrame]) -> CalibrationProblem:
        return CalibrationProblem(self.simulator, windows, bounds=self.bounds,
                                  sensors=self.sensors, weights=self.weights,
                                  max_input_gap_s=self.max_input_gap_s,
                                  min_samples=self.min_samples, sigma=self.sigma,
                                  priors=self.priors, sensor_bias=self.sensor_bias)

    def _algorithm(self, problem: CalibrationProblem) -> tuple[Algorithm, RemutationRepair]:
        repair = RemutationRepair(eta=self.mutation_eta)
        algorithm = make_ga(
            problem.n_var, population=self.population,
            crossover_probability=self.crossover_probability, crossover_eta=self.crossover_eta,
            mutation_probability=self.mutation_probability, mutation_eta=self.mutation_eta,
            tournament_size=self.tournament_size, repair=repair,
        )
        return algorithm, repair

    def _validate(self) -> None:
        """Check every argument, one message each, before any work (ValueError)."""
        check_ga_settings(len(PARAMETER_NAMES), population=self.population,
                          crossover_probability=self.crossover_probability,
                          crossover_eta=self.crossover_eta,
                          mutation_probability=self.mutation_probability,
                          mutation_eta=self.mutation_eta, tournament_size=self.tournament_size)
        generations = self.generations
        if (isinstance(generations, bool) or not isinstance(generations, int | np.integer)
                or generations < 1):
            raise ValueError(f"generations must be an integer ≥ 1 (got {generations!r})")
        check_common_settings(seed=self.seed, max_input_gap_s=self.max_input_gap_s,
                              min_samples=self.min_samples)

    # -- public API -------------------------------------------------------------------------

    def _settings(self) -> dict[str, object]:
        """Everything that shapes the GA's course (for the checkpoint fingerprint)."""
        return {name: getattr(self, name) for name in (
            "bounds", "sensors", "weights", "population", "generations",
            "crossover_probability", "crossover_eta", "mutation_probability", "mutation_eta",
            "tournament_size", "seed", "max_input_gap_s", "min_samples", "priors", "sigma",
            "sensor_bias", "tempering")}

    def fit(self, windows: Sequence[pd.DataFrame], resume: bool = False) -> Calibrator:
        """Calibrate against measured windows (canonical SI signals); returns self.

        ``resume=True`` continues from ``checkpoint`` (a
        :class:`~steamtwin.calibration.checkpoint.CheckpointError` if there is none, if it is
        not a valid checkpoint or if it was written for other settings or data); a finished
        checkpoint just gives its result. Arguments outside their range raise ``ValueError``
        naming the argument; a run in which no candidate gave a finite RMSE raises
        :class:`CalibrationError`.
        """
        self._validate()
        if resume and self.checkpoint is None:
            raise ValueError("resume needs a checkpoint file")
        problem = self._problem(windows)
        self.tempering_ = apply_tempering(problem, self.tempering)
        fingerprint = run_fingerprint(self._settings(), problem.objective)
        checkpoint = None if self.checkpoint is None else Path(self.checkpoint)
        algorithm, repair = self._algorithm(problem)
        algorithm.setup(problem, termination=("n_gen", self.generations),
                        seed=int(self.seed), verbose=False, save_history=False)
        rows: list[dict[str, object]] = []
        if resume:
            state = load_checkpoint(checkpoint, problem, fingerprint,
                                    population=self.population, generations=self.generations,
                                    history_columns=HISTORY_COLUMNS)
            restore_algorithm(algorithm, state)
            rows = state.history
            problem.n_evaluations, problem.n_penalised = state.evaluations, state.penalised
            problem.last_error = state.last_error
        evaluator = make_evaluator(self.workers, self.scheduler)
        evaluator.start(problem.objective)
        problem.evaluator = evaluator
        try:
            while algorithm.has_next():
                algorithm.next()
                rows.append(self._history_row(algorithm, problem, repair))
                if checkpoint is not None:
                    save_checkpoint(checkpoint, algorithm, problem, rows, fingerprint)
                if self.progress is not None:
                    done = int(rows[-1]["generation"])
                    self.progress(done / self.generations,
                                  f"generation {done}/{self.generations}: best objective "
                                  f"{rows[-1]['best_rmse']:.3f}")
        finally:
            problem.evaluator = None
            evaluator.close()
        best = algorithm.opt[0]
        result = problem.objective.evaluate(best.X)
        check_calibration_result(result.rmse, problem)
        self.params_ = problem.parameters(best.X)
        self.rmse_, self.score_ = result.rmse, result.value
        self.posterior_ = posterior_at(problem, self.params_, result, windows)
        self.sensor_offsets_ = problem.objective.sensor_offsets(self.params_)
        self.history_ = pd.DataFrame(rows).set_index("generation")
        self.n_evaluations_ = problem.n_evaluations
        self.n_penalised_ = problem.n_penalised
        self.repair_counts_ = {"out_of_bounds": repair.n_out_of_bounds,
                               "remutations": repair.n_remutations, "clipped": repair.n_clipped}
        self.population_ = algorithm.pop.get("X").copy()
        self.identifiability_ = check_identifiability(problem, self.params_, self.rmse_)
        self.window_info_ = pd.DataFrame([
            {"start": w.inputs.index[0], "end": w.inputs.index[-1], "samples": len(w.inputs),
             "filled_rows": w.filled_rows, "dropped_rows": w.dropped_rows,
             **{f"excluded:{s}": n for s, n in zip(problem.sensors, w.excluded, strict=True)}}
            for w in problem.windows
        ])
        return self

    @staticmethod
    def _history_row(algorithm: Algorithm, problem: CalibrationProblem,
                     repair: RemutationRepair) -> dict[str, object]:
        rmse = algorithm.pop.get("F")[:, 0]
        best = algorithm.opt[0]
        best_rmse = float(best.F[0])
        return {
            "generation": int(algorithm.n_gen) - 1,  # pymoo counts ahead; 1 = initial population
            "best_rmse": best_rmse,
            "mean_rmse": float(np.mean(rmse)),
            "best_fitness": fitness(best_rmse),
            "mean_fitness": float(np.mean(fitness(rmse))),
            **dict(zip(PARAMETER_NAMES, (float(v) for v in best.X), strict=True)),
            "evaluations": problem.n_evaluations,
            "penalised": problem.n_penalised,
            "remutations": repair.n_remutations,
        }

    def rmse(self, windows: Sequence[pd.DataFrame], params: ModelParameters | None = None
             ) -> float:
        """Weighted RMSE (K) of ``params`` (default: the empirical 1, 1, 1) on ``windows``."""
        problem = self._problem(windows)
        return problem.rmse(params or ModelParameters())

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write the parameters JSON (readable by ``ModelParameters.from_json``) and history.

        The history goes to ``<path stem>.history.csv`` next to it; returns both paths.
        """
        if not hasattr(self, "params_"):
            raise RuntimeError("Calibrator is not fitted; call fit(windows) first")
        settings = {"mode": "ga", "population": self.population,
                    "generations": self.generations, "seed": self.seed,
                    "score": self.score_, "tempering": self.tempering_}
        return write_parameters(path, self.params_, self.rmse_, self.sensors,
                                self.n_evaluations_, settings, self.history_,
                                self.priors, self.posterior_, self.sensor_offsets_)


def apply_tempering(problem: CalibrationProblem, tempering: float | str) -> float:
    """Set the problem's likelihood tempering κ (a number in (0, 1], or "auto": estimated at
    the priors' centres; 1 without priors or when the model rejects that point); returns κ."""
    if tempering == "auto":
        kappa = 1.0
        priors = problem.objective.priors
        if priors is not None:
            centre = ModelParameters(**{
                name: float(np.clip(prior.center, *problem.parameter_bounds[name]))
                for name, prior in zip(PARAMETER_NAMES, priors, strict=True)})
            try:
                kappa = likelihood_tempering(problem.objective, centre)
            except ValueError:
                kappa = 1.0
    elif (isinstance(tempering, int | float) and not isinstance(tempering, bool)
          and 0.0 < tempering <= 1.0):
        kappa = float(tempering)
    else:
        raise ValueError(f"tempering must be a number in (0, 1] or 'auto' (got {tempering!r})")
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
