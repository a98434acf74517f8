"""steamtwin's exception family: one base, one class per area.

Every error steamtwin raises on purpose derives from :class:`SteamtwinError`, so a caller (a
notebook, the CLI, the live service) can catch the package's own refusals in one clause and
let programming errors through. Each area's class also derives from the built-in exception
its errors always were (``ValueError`` for bad input; ``RuntimeError`` for a solver or an
estimator used out of order), so existing ``except ValueError`` code keeps working. The
specific errors (``TagMapError``, ``RomFileError``, …) stay beside the code that raises them
and derive from their area here.
"""

from __future__ import annotations

__all__ = [
    "CalibrationAreaError",
    "DataError",
    "GeometryAreaError",
    "MeshError",
    "ModelError",
    "RomError",
    "RotorAreaError",
    "SpecAreaError",
    "SteamtwinError",
]


class SteamtwinError(Exception):
    """Base of every error steamtwin raises on purpose."""


class SpecAreaError(SteamtwinError, ValueError):
    """A turbine spec, heat balance or design derivation that cannot be used."""


class DataError(SteamtwinError, ValueError):
    """Historian data, tag maps, units or their quality that cannot be used."""


class ModelError(SteamtwinError, ValueError):
    """The full-order model's inputs, parameters or design that it cannot run with."""


class CalibrationAreaError(SteamtwinError, ValueError):
    """A calibration that cannot run or resume."""


class RomError(SteamtwinError, ValueError):
    """A reduced-order model file, envelope or provenance that cannot be used."""


class RotorAreaError(SteamtwinError, ValueError):
    """Rotor geometry, material data, thermal/stress solutions and life figures that cannot be
    used (missing ``[rotor]`` data, a negative dimension, an allowable below the standing
    stress)."""


class GeometryAreaError(SteamtwinError, ValueError):
    """Point clouds, scans, reconstructions and CAD export that cannot go on."""


class MeshError(SteamtwinError, ValueError):
    """An invalid volume mesh or mesh file (the message names the file when there is one);
    the one mesh error of the blade and geometry code."""
