"""The live service's configuration file (``steamtwin serve --config unit.toml``).

::

    database = "twin.duckdb"              # one DuckDB file per service (relative: to this file)
    historian_memory_mb = 32              # optional: DuckDB's memory limit for the service, MB

    [[units]]                             # one table per unit; several run side by side
    name = "unit1"
    turbine = "reference"                 # or a turbine spec TOML
    tags = "live-tags.toml"               # tag map; for OPC UA each signal needs a node_id
    params = "params.json"                # optional: calibrated coefficients + sensor offsets
    rom = "rom.npz"                       # optional: blade ROM (probe temperatures)
    monitor = "monitor.json"              # optional: residual alarms (steamtwin monitor fit)
    rotor = "rotor.npz"                   # optional: HP rotor model (RotorModel.save), or "fit"
    rotor_allowable_mpa = 450             # optional: allowable rotor stress (Rotor page, API)
    block_samples = 60                    # samples per processing block

    [units.recalibration]                 # optional: online recalibration
    every_h = 24                          # scheduled swap of the tracked parameters
    step_min = 10                         # tracker step (data per update)
    settle_steps = 3                      # steps still swapped after a degradation alarm ends

    [units.source]
    kind = "opcua"                        # or "replay"
    endpoint = "opc.tcp://10.0.0.5:4840/"
    certificate = "client.der"            # Basic256Sha256 / SignAndEncrypt ...
    private_key = "client.pem"
    user = "twin"                         # optional user token
    password_file = "password.txt"        # (the password is read from a file, not written here)
    # allow_insecure = true               # only to reach a test plant without security
    # kind = "replay": path = "historian.parquet", speed = 60 (or "max")

Paths are relative to the configuration file. Every mistake is a :class:`ConfigError` naming
the file and the key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from steamtwin.errors import DataError
from steamtwin.textfile import read_utf8_text

__all__ = ["MIN_MEMORY_LIMIT_MB", "SERVICE_MEMORY_LIMIT_MB", "ConfigError",
           "RecalibrationConfig", "ServiceConfig", "SourceConfig", "UnitConfig", "load_config"]

SOURCE_KINDS = ("opcua", "replay")


class ConfigError(DataError):
    """A live-service configuration that cannot be used (names file and key)."""


@dataclass(frozen=True)
class SourceConfig:
    """Where a unit's samples come from (see the module docstring); paths absolute."""

    kind: str
    endpoint: str | None = None
    path: Path | None = None
    speed: float | None = None
    certificate: Path | None = None
    private_key: Path | None = None
    user: str | None = None
    password_file: Path | None = None
    allow_insecure: bool = False


@dataclass(frozen=True)
class RecalibrationConfig:
    """``every_s``: scheduled swap interval, ``step_s``: tracker step (both s of data time);
    ``settle_steps``: steps swapped after a degradation alarm ends."""

    every_s: float = 86_400.0
    step_s: float = 600.0
    settle_steps: int = 3


@dataclass(frozen=True)
class UnitConfig:
    """One unit: ``name``, ``turbine`` ("reference" or a spec path), ``tags``, optional
    ``params``, ``rom``, ``monitor`` (a fitted monitor file) and ``recalibration``,
    ``block_samples`` and its ``source``; ``rotor``: a rotor model file, ``"fit"`` (fitted
    from the spec at start) or None; ``rotor_allowable``: allowable rotor stress (Pa) or
    None."""

    name: str
    turbine: str
    tags: Path
    source: SourceConfig
    params: Path | None = None
    rom: Path | None = None
    block_samples: int = 60
    monitor: Path | None = None
    recalibration: RecalibrationConfig | None = None
    rotor: Path | Literal["fit"] | None = None
    rotor_allowable: float | None = None


MIN_MEMORY_LIMIT_MB = 16.0
"""The smallest DuckDB memory limit accepted (MB): below it the rows of one checkpoint
interval alone do not fit."""

SERVICE_MEMORY_LIMIT_MB = 32.0
"""DuckDB's memory limit for the service's historian connection (MB), which the dashboard's
queries share (``serve --http-port``): room for the rows not yet checkpointed (DuckDB
checkpoints at a 16 MB write-ahead log) and a small block cache, and a bound for a service
that runs for months (:class:`~steamtwin.live.historian.LiveHistorian`). Measured: one unit's
24-h replay flat within +7 MB of resident memory (DuckDB's default: +49 MB, its cache growing
with the file); ten units × 6 h with whole-table aggregates every hour ran within it
(docs/benchmarks.md, "Throughput and memory, session 16")."""


@dataclass(frozen=True)
class ServiceConfig:
    """The service: its ``database`` and ``units``; ``source`` the file it came from."""

    database: Path
    units: tuple[UnitConfig, ...]
    source: Path
    historian_memory_mb: float = SERVICE_MEMORY_LIMIT_MB


def _keys(table: dict[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown}; expected some of "
                          f"{sorted(allowed)}")


def _text(table: dict[str, Any], key: str, where: str, required: bool = True) -> str | None:
    value = table.get(key)
    if value is None:
        if required:
            raise ConfigError(f"{where}.{key} is missing")
        return None
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where}.{key} = {value!r}: expected a non-empty string")
    return value


def _path(base: Path, table: dict[str, Any], key: str, where: str, required: bool = True,
          must_exist: bool = True) -> Path | None:
    text = _text(table, key, where, required)
    if text is None:
        return None
    path = (base / text).resolve()
    if must_exist and not path.exists():
        raise ConfigError(f"{where}.{key} = {text!r}: no such file ({path})")
    return path


def _source(base: Path, table: Any, where: str) -> SourceConfig:
    if not isinstance(table, dict):
        raise ConfigError(f"{where} is missing or not a table (kind = \"opcua\" or \"replay\")")
    _keys(table, {"kind", "endpoint", "path", "speed", "certificate", "private_key", "user",
                  "password_file", "allow_insecure"}, where)
    kind = _text(table, "kind", where)
    if kind not in SOURCE_KINDS:
        raise ConfigError(f"{where}.kind = {kind!r}: expected one of {SOURCE_KINDS}")
    if kind == "replay":
        speed = table.get("speed", "max")
        if speed == "max":
            rate = None
        elif isinstance(speed, int | float) and not isinstance(speed, bool) and speed > 0:
            rate = float(speed)
        else:
            raise ConfigError(f"{where}.speed = {speed!r}: expected a positive factor of real "
                              "time or \"max\"")
        return SourceConfig(kind, path=_path(base, table, "path", where), speed=rate)
    insecure = table.get("allow_insecure", False)
    if not isinstance(insecure, bool):
        raise ConfigError(f"{where}.allow_insecure = {insecure!r}: expected true or false")
    certificate = _path(base, table, "certificate", where, required=False)
    private_key = _path(base, table, "private_key", where, required=False)
    if (certificate is None) != (private_key is None):
        raise ConfigError(f"{where}: certificate and private_key go together")
    if certificate is None and not insecure:
        raise ConfigError(f"{where}: no certificate/private_key for Basic256Sha256 "
                          "SignAndEncrypt; set allow_insecure = true only for a test plant")
    user = _text(table, "user", where, required=False)
    password_file = _path(base, table, "password_file", where, required=False)
    if (user is None) != (password_file is None):
        raise ConfigError(f"{where}: user and password_file go together")
    return SourceConfig(kind, endpoint=_text(table, "endpoint", where), certificate=certificate,
                        private_key=private_key, user=user, password_file=password_file,
                        allow_insecure=insecure)


def _recalibration(table: Any, where: str) -> RecalibrationConfig | None:
    if table is None:
        return None
    if not isinstance(table, dict):
        raise ConfigError(f"{where} is not a table")
    _keys(table, {"every_h", "step_min", "settle_steps"}, where)
    values = {}
    for key, scale, default in (("every_h", 3600.0, 24.0), ("step_min", 60.0, 10.0)):
        value = table.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise ConfigError(f"{where}.{key} = {value!r}: expected a positive number")
        values[key] = float(value) * scale
    settle = table.get("settle_steps", 3)
    if isinstance(settle, bool) or not isinstance(settle, int) or settle < 0:
        raise ConfigError(f"{where}.settle_steps = {settle!r}: expected a whole number ≥ 0")
    return RecalibrationConfig(every_s=values["every_h"], step_s=values["step_min"],
                               settle_steps=settle)


def _allowable(table: dict[str, Any], where: str) -> float | None:
    """``rotor_allowable_mpa`` in Pa (None when not given)."""
    value = table.get("rotor_allowable_mpa")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
        raise ConfigError(f"{where}.rotor_allowable_mpa = {value!r}: expected a positive "
                          "stress in MPa")
    if table.get("rotor") is None:
        raise ConfigError(f"{where}.rotor_allowable_mpa needs a rotor model: add rotor = "
                          "\"rotor.npz\" (or \"fit\")")
    return float(value) * 1e6


def load_config(path: str | Path) -> ServiceConfig:
    """Read and check a service configuration (see the module docstring)."""
    path = Path(path).resolve()
    try:
        document = tomllib.loads(read_utf8_text(path, "service configuration", "TOML",
                                                ConfigError))
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{path}: not valid TOML: {error}") from None
    base = path.parent
    _keys(document, {"database", "units", "historian_memory_mb"}, str(path))
    database_text = _text(document, "database", str(path))
    memory = document.get("historian_memory_mb", SERVICE_MEMORY_LIMIT_MB)
    if (isinstance(memory, bool) or not isinstance(memory, int | float)
            or not math.isfinite(memory) or memory < MIN_MEMORY_LIMIT_MB):
        raise ConfigError(f"{path}: historian_memory_mb = {memory!r}: expected a number of MB "
                          f"≥ {MIN_MEMORY_LIMIT_MB:g}")
    units_table = document.get("units")
    if not isinstance(units_table, list) or not units_table:
        raise ConfigError(f"{path}: no [[units]]; add one per unit")
    units, names = [], set()
    for k, table in enumerate(units_table):
        where = f"{path}: units[{k}]"
        if not isinstance(table, dict):
            raise ConfigError(f"{where} is not a table")
        _keys(table, {"name", "turbine", "tags", "params", "rom", "block_samples", "source",
                      "monitor", "recalibration", "rotor", "rotor_allowable_mpa"}, where)
        name = _text(table, "name", where)
        if name in names:
            raise ConfigError(f"{where}.name = {name!r} is used twice; names must be unique")
        names.add(name)
        turbine = table.get("turbine", "reference")
        if turbine != "reference":
            turbine = str(_path(base, table, "turbine", where))
        block = table.get("block_samples", 60)
        if not isinstance(block, int) or isinstance(block, bool) or block < 1:
            raise ConfigError(f"{where}.block_samples = {block!r}: expected a whole number ≥ 1")
        units.append(UnitConfig(
            name=name, turbine=turbine, tags=_path(base, table, "tags", where),
            source=_source(base, table.get("source"), f"{where}.source"),
            params=_path(base, table, "params", where, required=False),
            rom=_path(base, table, "rom", where, required=False), block_samples=block,
            monitor=_path(base, table, "monitor", where, required=False),
            recalibration=_recalibration(table.get("recalibration"), f"{where}.recalibration"),
            rotor="fit" if table.get("rotor") == "fit" else _path(base, table, "rotor", where,
                                                                   required=False),
            rotor_allowable=_allowable(table, where)))
    return ServiceConfig(database=(base / database_text).resolve(), units=tuple(units),
                         source=path, historian_memory_mb=float(memory))
