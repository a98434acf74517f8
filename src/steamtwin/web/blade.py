"""The control-stage blade's temperature field for the HTTP service (issue 22, item 2, the
Blade page): each configured unit's ROM (``rom`` in the serve configuration,
:func:`~steamtwin.rom.romfile.load_rom`) is read once, on first use, and its field is
reconstructed for one stored sample's inputs (the cleaned measured values the live twin fed
it; :func:`~steamtwin.rom.reconstruction.predict_field`: x̄ + a(u)·Φ, POD–RBF).

Only the blade's outer surface is sent to the browser — the boundary triangles and the nodes
they use, renumbered — since a 3-D view shows the surface; the interior's temperatures are
on the same modes but nobody sees them in a mesh plot. The surface (m) is sent once
(:meth:`BladeFields.surface`, cacheable: it changes only with the ROM file), the nodal
temperatures (K) per request (:meth:`BladeFields.field`).
"""

from __future__ import annotations

import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from steamtwin.errors import SteamtwinError
from steamtwin.live.config import ServiceConfig
from steamtwin.rom.estimator import ExtrapolationWarning
from steamtwin.rom.reconstruction import predict_field
from steamtwin.rom.romfile import BladeRom, load_rom

__all__ = ["BladeFields", "BladeSurface", "NoRomError"]


class NoRomError(SteamtwinError, LookupError):
    """The unit has no ROM configured (the message says so and where to add it)."""


@dataclass(frozen=True)
class BladeSurface:
    """A ROM mesh's outer surface: ``nodes`` (n,) indices of the mesh's nodes it uses,
    ``points`` (n, 3) m, ``triangles`` (k, 3) indices into ``points``, and ``probes`` (the
    ROM's blade probes → index into ``points``)."""

    nodes: np.ndarray
    points: np.ndarray
    triangles: np.ndarray
    probes: dict[str, int]


def surface_of(bundle: BladeRom) -> BladeSurface:
    """The boundary triangles of ``bundle``'s mesh on their own, renumbered, nodes."""
    triangles = bundle.mesh.boundary_triangles
    nodes, local = np.unique(triangles, return_inverse=True)
    where = {int(node): k for k, node in enumerate(nodes)}
    return BladeSurface(nodes, bundle.mesh.points[nodes], local.reshape(triangles.shape),
                        {name: where[node] for name, node in bundle.probes.items()
                         if node in where})


class BladeFields:
    """The units' ROMs (of ``config``; None: no unit has one), each loaded on first use
    (:class:`~steamtwin.rom.romfile.RomFileError` if its file is unreadable)."""

    def __init__(self, config: ServiceConfig | None) -> None:
        self._paths: dict[str, Path] = {} if config is None else {
            unit.name: unit.rom for unit in config.units if unit.rom is not None}
        self._loaded: dict[str, tuple[BladeRom, BladeSurface]] = {}
        self._lock = threading.Lock()

    def _bundle(self, unit: str) -> tuple[BladeRom, BladeSurface]:
        path = self._paths.get(unit)
        if path is None:
            raise NoRomError(f"unit {unit!r} has no blade ROM: add rom = \"….npz\" to its "
                             "[[units]] table in the serve configuration")
        with self._lock:  # one load per unit, however many requests arrive at once
            if unit not in self._loaded:
                bundle = load_rom(path)
                self._loaded[unit] = (bundle, surface_of(bundle))
            return self._loaded[unit]

    def inputs(self, unit: str) -> tuple[str, ...]:
        """The ROM's input signals (canonical names, SI)."""
        return self._bundle(unit)[0].rom.input_names_

    def surface(self, unit: str) -> dict[str, object]:
        """The blade surface as JSON: points (m), triangles, probe indices, the ROM file."""
        bundle, surface = self._bundle(unit)
        return {"unit": unit, "rom": str(self._paths[unit]),
                "points": np.round(surface.points, 7).tolist(),
                "triangles": surface.triangles.tolist(), "probes": surface.probes,
                "inputs": list(bundle.rom.input_names_)}

    def field(self, unit: str, inputs: dict[str, float]) -> dict[str, object]:
        """Surface temperatures (K, the order of :meth:`surface`'s points) and the probes'
        at ``inputs`` (the ROM's input signals, SI)."""
        bundle, surface = self._bundle(unit)
        with warnings.catch_warnings():  # the answer says how far outside: no log line
            warnings.simplefilter("ignore", ExtrapolationWarning)
            nodal = predict_field(bundle, inputs)
        temperature = nodal[surface.nodes]
        point = np.array([[inputs[name] for name in bundle.rom.input_names_]], dtype=float)
        distance = float(bundle.rom.extrapolation_distance(point)[0])
        return {"extrapolation_distance": distance,
                "temperature": np.round(temperature, 3).tolist(),
                "min": float(temperature.min()), "max": float(temperature.max()),
                "probes": {name: float(nodal[node]) for name, node in bundle.probes.items()}}
