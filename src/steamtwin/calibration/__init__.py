"""Calibration of the model parameters against DCS data (Wang et al.'s GA method).

:class:`Calibrator` fits :class:`~steamtwin.model.parameters.ModelParameters` to measured
windows by minimising the RMSE (K) between simulated and measured temperatures
(:mod:`~steamtwin.calibration.objective`) with a real-coded GA (:mod:`~steamtwin.calibration.ga`).
Errors are ``ValueError`` subclasses: :class:`CalibrationError` when no candidate gave a finite
RMSE, :class:`CheckpointError` for a checkpoint that cannot resume the run.
"""

from steamtwin.calibration.calibrator import CalibrationError, Calibrator
from steamtwin.calibration.checkpoint import CheckpointError
from steamtwin.calibration.ga import RemutationRepair, make_ga
from steamtwin.calibration.objective import (
    DEFAULT_SENSORS,
    PENALTY_RMSE,
    CalibrationProblem,
    fitness,
    window_rmse,
)

__all__ = [
    "DEFAULT_SENSORS",
    "PENALTY_RMSE",
    "CalibrationError",
    "CalibrationProblem",
    "Calibrator",
    "CheckpointError",
    "RemutationRepair",
    "fitness",
    "make_ga",
    "window_rmse",
]
