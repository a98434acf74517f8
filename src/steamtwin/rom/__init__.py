"""Reduced-order model of the blade temperature field: snapshots, POD, RBF, file, DMD.

``build_rom(spec, mesh)`` → (``BladeRom``, snapshots); ``PodRbfRom(energy=0.992,
kernel="thin_plate_spline").fit(snapshots, conditions).predict(conditions)``; ``save_rom`` /
``load_rom`` (one ``.npz``, no pickles); ``predict_series`` for DCS data. See docs/rom.md.
"""

from steamtwin.rom.estimator import ExtrapolationWarning, NotFittedError, PodRbfRom
from steamtwin.rom.romfile import BladeRom, RomFileError, load_rom, save_rom

__all__ = [
    "BladeRom",
    "ExtrapolationWarning",
    "NotFittedError",
    "PodRbfRom",
    "RomFileError",
    "load_rom",
    "save_rom",
]
