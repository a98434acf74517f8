"""Calibration of the model parameters against DCS data (Wang et al.'s GA method).

``Calibrator(simulator, objective=ObjectiveSettings(...), search=GeneticSearch(...) |
SurrogateSearch(...), random_state=0).fit(windows)`` fits
:class:`~steamtwin.model.parameters.ModelParameters` to measured windows — or a
:class:`WindowSet` of several files, loads and ramps (:mod:`~steamtwin.calibration.windowset`)
— by minimising the negative log posterior under the parameters' priors (the RMSE in K without
them; :mod:`~steamtwin.calibration.objective`) with the method's real-coded GA
(:mod:`~steamtwin.calibration.ga`) or the GA on a surrogate
(:mod:`~steamtwin.calibration.surrogate`); :class:`Posterior` holds the 95 % intervals
(:mod:`~steamtwin.calibration.posterior`).
Errors are ``ValueError`` subclasses: :class:`CalibrationError` when no candidate gave a finite
RMSE, :class:`CheckpointError` for a checkpoint that cannot resume the run.
The public objects are imported on first use (:mod:`steamtwin.lazy`): a GA worker, which
imports :mod:`~steamtwin.calibration.evaluation` and the objective, does not load the posterior,
the surrogate and their SciPy modules.
"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "CalibrationError": "steamtwin.calibration.calibrator",
    "Calibrator": "steamtwin.calibration.calibrator",
    "CheckpointError": "steamtwin.calibration.checkpoint",
    "RemutationRepair": "steamtwin.calibration.ga",
    "make_ga": "steamtwin.calibration.ga",
    "PENALTY_RMSE": "steamtwin.calibration.objective",
    "CalibrationProblem": "steamtwin.calibration.objective",
    "fitness": "steamtwin.calibration.objective",
    "window_rmse": "steamtwin.calibration.objective",
    "Posterior": "steamtwin.calibration.posterior",
    "fit_map": "steamtwin.calibration.posterior",
    "laplace_posterior": "steamtwin.calibration.posterior",
    "GeneticSearch": "steamtwin.calibration.search",
    "DEFAULT_SENSORS": "steamtwin.calibration.settings",
    "THERMOCOUPLE_BIAS": "steamtwin.calibration.settings",
    "ObjectiveSettings": "steamtwin.calibration.settings",
    "SurrogateSearch": "steamtwin.calibration.surrogate",
    "CalibrationWindow": "steamtwin.calibration.windowset",
    "WindowSet": "steamtwin.calibration.windowset",
    "WindowSource": "steamtwin.calibration.windowset",
    "find_calibration_windows": "steamtwin.calibration.windowset",
    "joint_window_set": "steamtwin.calibration.windowset",
}

__all__ = [
    "DEFAULT_SENSORS",
    "PENALTY_RMSE",
    "THERMOCOUPLE_BIAS",
    "CalibrationError",
    "CalibrationProblem",
    "CalibrationWindow",
    "Calibrator",
    "CheckpointError",
    "GeneticSearch",
    "ObjectiveSettings",
    "Posterior",
    "RemutationRepair",
    "SurrogateSearch",
    "WindowSet",
    "WindowSource",
    "find_calibration_windows",
    "fit_map",
    "fitness",
    "joint_window_set",
    "laplace_posterior",
    "make_ga",
    "window_rmse",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
