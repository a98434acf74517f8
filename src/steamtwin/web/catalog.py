"""What the HTTP service knows about its units besides the database: each signal's SI unit,
meaning and instrument error (from the canonical signal table and the unit's tag map), and
the provenance of the unit's model (turbine spec, parameters, ROM, monitor and tag-map files
with their SHA-256, and the software versions) — read once from the serve configuration."""

from __future__ import annotations

import hashlib
import platform
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import TagMap, load_tag_map
from steamtwin.live.config import ServiceConfig

__all__ = ["Catalog", "UnitEntry", "signal_info", "software_versions"]

VERSIONED = ("steamtwin", "numpy", "pandas", "duckdb", "asyncua", "fastapi", "uvicorn")


ROTOR_MEANINGS: dict[str, tuple[str, str]] = {
    "rotor_groove_temperature": ("K", "rotor metal temperature at the groove root (rotor model)"),
    "rotor_bore_temperature": ("K", "rotor metal temperature at the bore (rotor model)"),
    "rotor_mean_temperature": ("K", "rotor volume-mean temperature (rotor model)"),
    "rotor_groove_stress": ("Pa", "rotor equivalent stress at the groove root: the stress in "
                                  "the von Mises metric along the location's direction of "
                                  "largest variance, tensile positive (rotor model)"),
    "rotor_bore_stress": ("Pa", "rotor equivalent stress at the bore: the stress in the von "
                                "Mises metric along the location's direction of largest "
                                "variance, tensile positive (rotor model)"),
    "rotor_groove_von_mises": ("Pa", "rotor von Mises stress at the groove root (rotor model)"),
    "rotor_bore_von_mises": ("Pa", "rotor von Mises stress at the bore (rotor model)"),
}
"""SI unit and meaning of the rotor's twin signals (:mod:`steamtwin.live.rotor_stream`)."""


def software_versions() -> dict[str, str | None]:
    """Installed versions of steamtwin and the libraries the live twin rests on."""
    versions: dict[str, str | None] = {"python": platform.python_version()}
    for name in VERSIONED:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def _file(path: Path | None) -> dict[str, object] | None:
    if path is None:
        return None
    entry: dict[str, object] = {"path": str(path)}
    try:
        digest = hashlib.sha256()
        with path.open("rb") as handle:
            for chunk in iter(lambda: handle.read(1 << 20), b""):
                digest.update(chunk)
        entry |= {"sha256": digest.hexdigest(), "bytes": path.stat().st_size}
    except OSError as error:
        entry["error"] = f"cannot read: {error.strerror}"
    return entry


@dataclass(frozen=True)
class UnitEntry:
    """One configured unit: its ``tag_map`` (None if unreadable) and ``provenance``."""

    name: str
    tag_map: TagMap | None
    provenance: dict[str, object] = field(default_factory=dict)


def signal_info(signal: str, tag_map: TagMap | None) -> dict[str, object]:
    """A stored signal's SI unit, meaning, DCS tag and instrument σ (SI) where known. Blade
    probes of the ROM (``blade_*``) are temperatures (K)."""
    known = SIGNALS.get(signal)
    spec = None if tag_map is None else tag_map.signals.get(signal)
    si_unit = known.si_unit if known else ("K" if signal.startswith("blade_") else None)
    meaning = known.meaning if known else (
        "blade probe temperature (ROM)" if signal.startswith("blade_") else None)
    if signal in ROTOR_MEANINGS:
        si_unit, meaning = ROTOR_MEANINGS[signal]
    return {"si_unit": si_unit, "meaning": meaning,
            "tag": None if spec is None else spec.column,
            "instrument_sigma": None if spec is None else spec.noise_si,
            "resolution": None if spec is None else spec.resolution_si}


class Catalog:
    """The units of ``config`` (None: only what the database holds) and their provenance."""

    def __init__(self, config: ServiceConfig | None = None) -> None:
        self.config = config
        self.versions = software_versions()
        self.units: dict[str, UnitEntry] = {}
        for unit in () if config is None else config.units:
            try:
                tag_map = load_tag_map(unit.tags)
            except (OSError, ValueError):
                tag_map = None
            turbine = (unit.turbine if unit.turbine == "reference"
                       else _file(Path(unit.turbine)))
            self.units[unit.name] = UnitEntry(unit.name, tag_map, {
                "turbine": turbine, "tags": _file(unit.tags), "params": _file(unit.params),
                "rom": _file(unit.rom), "monitor": _file(unit.monitor),
                "rotor": unit.rotor if unit.rotor == "fit" else _file(unit.rotor),
                "source": unit.source.kind,
                "recalibration": None if unit.recalibration is None else {
                    "every_s": unit.recalibration.every_s,
                    "step_s": unit.recalibration.step_s}})

    def tag_map(self, unit: str) -> TagMap | None:
        """The unit's tag map, None if not configured."""
        entry = self.units.get(unit)
        return None if entry is None else entry.tag_map

    def provenance(self) -> dict[str, object]:
        """Configuration file, database, each unit's model files and the versions."""
        return {"config": None if self.config is None else str(self.config.source),
                "database": None if self.config is None else str(self.config.database),
                "units": {name: entry.provenance for name, entry in self.units.items()},
                "versions": self.versions}
