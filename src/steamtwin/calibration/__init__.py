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
"""

from steamtwin.calibration.calibrator import CalibrationError, Calibrator
from steamtwin.calibration.checkpoint import CheckpointError
from steamtwin.calibration.ga import RemutationRepair, make_ga
from steamtwin.calibration.objective import PENALTY_RMSE, CalibrationProblem, fitness, window_rmse
from steamtwin.calibration.posterior import Posterior, fit_map, laplace_posterior
from steamtwin.calibration.search import GeneticSearch
from steamtwin.calibration.settings import DEFAULT_SENSORS, THERMOCOUPLE_BIAS, ObjectiveSettings
from steamtwin.calibration.surrogate import SurrogateSearch
from steamtwin.calibration.windowset import (
    CalibrationWindow,
    WindowSet,
    WindowSource,
    find_calibration_windows,
    joint_window_set,
)

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
