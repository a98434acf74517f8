"""The twin folder: one directory a user can zip and hand to a colleague; nothing is pickled.

Written by :meth:`steamtwin.Twin.save`, read by :meth:`steamtwin.Twin.load`:

* ``spec.toml`` — the turbine spec's TOML text; its content hash
  (:func:`~steamtwin.spec.fingerprint.spec_hash`, SHA-256 of the canonical validated spec)
  is recorded in ``twin.json``;
* ``params.json`` — the model parameters as calibration writes them (priors, 95 % intervals,
  sensor offsets when calibrated; :meth:`~steamtwin.model.parameters.ModelParameters.from_json`
  reads it), and ``params.history.csv`` after a GA calibration;
* ``rom.npz`` — the blade ROM in its data-only file format (:mod:`steamtwin.rom.romfile`);
* ``reports/`` — the calibration's windows (``calibration_windows.csv``) and the last
  validation report (``reports/validation/``);
* ``twin.json`` — the manifest: ``format`` ("steamtwin-twin") and ``format_version``, the
  save time (UTC), Python's and the numerical packages' versions, the spec's name and hash,
  the parameters, the SHA-256 of every file above (path relative to the folder) and the
  provenance (the steps that made the twin, with their settings).

Reading checks, in this order, and refuses with :class:`TwinError` naming the file and both
values: the manifest's format and version; every listed file present with the recorded
SHA-256 (a file changed after saving); the spec's hash against the manifest's; the parameter
file strictly (:class:`~steamtwin.model.parameters.ParameterError`); the ROM built from this
spec (hash) and these parameters (its provenance), so no twin pairs a ROM with another turbine
or other coefficients.
"""

from __future__ import annotations

import hashlib
import json
import platform
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

from steamtwin.errors import SteamtwinError
from steamtwin.model.parameters import (
    PARAMETER_BOUNDS,
    PARAMETERS_SCHEMA_VERSION,
    ModelParameters,
    sensor_offsets_from_json,
)
from steamtwin.rom.romfile import BladeRom
from steamtwin.spec import TurbineSpec
from steamtwin.spec.fingerprint import short_hash, spec_hash
from steamtwin.spec.loader import parse_spec

__all__ = ["FORMAT", "FORMAT_VERSION", "MANIFEST", "PARAMS_FILE", "REPORTS", "ROM_FILE",
           "SPEC_FILE", "TwinError", "TwinFolder", "read_folder", "write_manifest",
           "write_parameters_file"]

FORMAT = "steamtwin-twin"
FORMAT_VERSION = 1
MANIFEST = "twin.json"
SPEC_FILE = "spec.toml"
PARAMS_FILE = "params.json"
ROM_FILE = "rom.npz"
REPORTS = "reports"
_VERSIONED = ("steamtwin", "numpy", "scipy", "pandas", "pymoo", "numba", "scikit-fem",
              "CoolProp")


class TwinError(SteamtwinError, ValueError):
    """A twin folder is missing a file, changed after saving, or inconsistent; or a twin lacks
    what a method needs (a ROM to validate, a calibration to report)."""


@dataclass(frozen=True)
class TwinFolder:
    """What a checked twin folder holds: the spec and its TOML text, the parameters, sensor
    offsets (K) and the parameter file's text, the ROM (or None) and the provenance steps."""

    spec: TurbineSpec
    spec_text: str
    params: ModelParameters
    offsets: dict[str, float]
    params_text: str
    rom: BladeRom | None
    provenance: list[dict[str, Any]]


def write_parameters_file(path: Path, params: ModelParameters,
                          offsets: Mapping[str, float]) -> Path:
    """``params.json`` of a twin that was not calibrated here (coefficients, bounds, sensor
    offsets in SI: K, Pa for a pressure); the schema :meth:`ModelParameters.from_json` reads."""
    document: dict[str, object] = {
        "schema_version": PARAMETERS_SCHEMA_VERSION, "parameters": asdict(params),
        "bounds": {name: list(bounds) for name, bounds in PARAMETER_BOUNDS.items()}}
    if offsets:
        document["sensor_offsets"] = dict(offsets)
    path.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    return path


def write_manifest(folder: Path, written: Sequence[Path], spec: TurbineSpec,
                   params: ModelParameters, provenance: Sequence[Mapping[str, Any]]) -> Path:
    """``twin.json`` listing ``written`` (files inside ``folder``) with their SHA-256."""
    manifest = {
        "format": FORMAT, "format_version": FORMAT_VERSION,
        "saved": datetime.now(UTC).isoformat(timespec="seconds"),
        "versions": _versions(),
        "spec": {"name": spec.name, "sha256": spec_hash(spec)},
        "parameters": asdict(params),
        "files": {p.relative_to(folder).as_posix(): _sha256(p) for p in written},
        "provenance": list(provenance),
    }
    path = folder / MANIFEST
    path.write_text(json.dumps(manifest, indent=2, default=str) + "\n", encoding="utf-8")
    return path


def read_folder(directory: str | Path) -> TwinFolder:
    """Read and check a twin folder (module docstring); TwinError naming what is wrong."""
    from steamtwin.rom.romfile import load_rom

    folder = Path(directory)
    manifest = _manifest(folder)
    files = manifest["files"]
    for name, digest in files.items():
        path = folder / name
        if not path.is_file():
            raise TwinError(f"{path}: listed in {MANIFEST} but missing")
        actual = _sha256(path)
        if actual != digest:
            raise TwinError(
                f"{path}: its SHA-256 {short_hash(actual)} differs from the "
                f"{short_hash(str(digest))} {MANIFEST} records: the file was changed after the "
                "twin was saved; restore it, or load its parts by hand and save anew")
    spec_text = (folder / SPEC_FILE).read_text(encoding="utf-8")
    spec = parse_spec(spec_text, str(folder / SPEC_FILE))
    recorded = manifest.get("spec", {}).get("sha256")
    if spec_hash(spec) != recorded:
        raise TwinError(f"{folder / SPEC_FILE}: describes turbine {spec.name!r} (sha256 "
                        f"{short_hash(spec_hash(spec))}), but {MANIFEST} records sha256 "
                        f"{short_hash(str(recorded))}")
    params_path = folder / PARAMS_FILE
    params = ModelParameters.from_json(params_path)
    rom = None
    if ROM_FILE in files:
        rom = load_rom(folder / ROM_FILE)
        _check_rom(rom, spec, params, folder / ROM_FILE)
    provenance = manifest.get("provenance", [])
    return TwinFolder(spec, spec_text, params, sensor_offsets_from_json(params_path),
                      params_path.read_text(encoding="utf-8"), rom,
                      [dict(step) for step in provenance if isinstance(step, dict)])


def _manifest(folder: Path) -> dict[str, Any]:
    path = folder / MANIFEST
    if not path.is_file():
        raise TwinError(f"{folder}: no {MANIFEST}; not a twin folder (Twin.save writes one)")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as error:
        raise TwinError(f"{path}: not valid JSON: {error}") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise TwinError(f"{path}: format is not {FORMAT!r}")
    version = manifest.get("format_version")
    if isinstance(version, bool) or not isinstance(version, int) or not (
            1 <= version <= FORMAT_VERSION):
        raise TwinError(f"{path}: format_version {version!r}; this steamtwin reads "
                        f"1…{FORMAT_VERSION}")
    files = manifest.get("files")
    if not isinstance(files, dict) or SPEC_FILE not in files or PARAMS_FILE not in files:
        raise TwinError(f"{path}: 'files' must list {SPEC_FILE} and {PARAMS_FILE}")
    return manifest


def _check_rom(rom: BladeRom, spec: TurbineSpec, params: ModelParameters, path: Path) -> None:
    """The ROM must record this spec (hash) and these parameters (TwinError naming both)."""
    from steamtwin.rom.provenance import rom_parameters

    record = rom.provenance.get("spec", {})
    digest = spec_hash(spec)
    if not isinstance(record, dict) or record.get("sha256") != digest:
        name, other = (record.get("name"), record.get("sha256")) if isinstance(record, dict) \
            else (None, None)
        raise TwinError(f"{path}: built from turbine {name!r} (sha256 "
                        f"{short_hash(str(other))}), but the twin's spec is {spec.name!r} "
                        f"(sha256 {short_hash(digest)})")
    built_with = rom_parameters(rom)
    if built_with != params:
        raise TwinError(f"{path}: built with parameters {asdict(built_with)}, but the twin's "
                        f"{PARAMS_FILE} holds {asdict(params)}; rebuild the ROM")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _versions() -> dict[str, str]:
    """Python's and the numerical packages' versions (they shape the twin's numbers)."""
    result = {"python": platform.python_version()}
    for name in _VERSIONED:
        try:
            result[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return result
