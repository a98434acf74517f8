"""Tag maps: which historian column or tag is which canonical signal, in which unit.

A plant historian names signals by plant tags (KKS such as ``10LBA10CP001``) in mixed units. A tag
map (TOML) translates them to the canonical names of :data:`steamtwin.dcs.signals.SIGNALS`::

    [historian]
    layout = "wide"              # "wide": time + one column per tag; "long": tag/time/value rows
    time_column = "Timestamp"
    time_zone = "Asia/Shanghai"  # IANA zone for timestamps without a UTC offset
    tag_column = "tag"           # long layout only
    value_column = "value"       # long layout only
    quality_column = "quality"   # long layout only, optional

    [signals.main_steam_pressure]
    column = "10LBA10CP001"      # wide: column name; long: the tag value
    unit = "MPa"                 # convertible to the signal's SI unit (Pa)
    range = [0.0, 25.0]          # optional valid range, in `unit`

Every validation error names the file and the field.
"""

from __future__ import annotations

import math
import tomllib
import zoneinfo
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pint

from steamtwin.dcs.signals import SIGNALS
from steamtwin.units import convert, unit_registry

LAYOUTS = ("wide", "long")
_HISTORIAN_KEYS = (
    "layout", "time_column", "time_zone", "tag_column", "value_column", "quality_column",
)
_LONG_ONLY = ("tag_column", "value_column", "quality_column")
_SIGNAL_KEYS = ("column", "unit", "range")


class TagMapError(ValueError):
    """A tag map is missing a field, has a bad value or is inconsistent (names file and field)."""


@dataclass(frozen=True)
class TagSpec:
    """One mapped signal: historian ``column`` (wide) or tag value (long), its ``unit``.

    ``valid_range_si`` is the optional valid range converted to the signal's SI unit
    (e.g. Pa, K, kg/s, W).
    """

    signal: str
    column: str
    unit: str
    valid_range_si: tuple[float, float] | None = None


@dataclass(frozen=True)
class TagMap:
    """A validated tag map; ``source`` names the file it came from (used in error messages)."""

    layout: str
    time_column: str
    time_zone: str | None
    tag_column: str | None
    value_column: str | None
    quality_column: str | None
    signals: dict[str, TagSpec]
    source: str

    def column_of(self, signal: str) -> str:
        """Historian column (wide) or tag (long) of a canonical signal; KeyError if unmapped."""
        try:
            return self.signals[signal].column
        except KeyError:
            raise KeyError(
                f"{self.source}: signal {signal!r} is not mapped "
                f"(mapped: {', '.join(self.signals)})"
            ) from None


def load_tag_map(path: str | Path) -> TagMap:
    """Load and validate a tag map TOML file; raises :class:`TagMapError` naming file and field."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise TagMapError(f"{path}: cannot read tag map: {error}") from None
    return parse_tag_map(text, str(path))


def parse_tag_map(text: str, source: str = "<string>") -> TagMap:
    """Parse and validate the TOML text of a tag map; ``source`` names it in errors."""
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise TagMapError(f"{source}: not valid TOML: {error}") from None
    _check_keys(document, ("historian", "signals"), "", source)
    historian = _table(document, "historian", "", source)
    _check_keys(historian, _HISTORIAN_KEYS, "historian", source)
    layout = _text(historian, "layout", "historian", source)
    if layout not in LAYOUTS:
        raise TagMapError(
            f"{source}: historian.layout = {layout!r}: expected one of {', '.join(LAYOUTS)}"
        )
    time_column = _text(historian, "time_column", "historian", source)
    time_zone = _time_zone(historian, source)
    if layout == "long":
        tag_column = _text(historian, "tag_column", "historian", source)
        value_column = _text(historian, "value_column", "historian", source)
        quality_column = (
            _text(historian, "quality_column", "historian", source)
            if "quality_column" in historian else None
        )
        columns = {"time_column": time_column, "tag_column": tag_column,
                   "value_column": value_column, "quality_column": quality_column}
        seen: dict[str, str] = {}
        for key, name in columns.items():
            if name is None:
                continue
            if name in seen:
                raise TagMapError(
                    f"{source}: historian.{key} = {name!r} is also historian.{seen[name]}; "
                    "the long layout needs distinct columns"
                )
            seen[name] = key
    else:
        for key in _LONG_ONLY:
            if key in historian:
                raise TagMapError(
                    f"{source}: historian.{key} is only used with layout = \"long\" "
                    f"(this map has layout = {layout!r})"
                )
        tag_column = value_column = quality_column = None
    signals_table = _table(document, "signals", "", source)
    if not signals_table:
        raise TagMapError(f"{source}: [signals] maps no signal; add e.g. [signals.load]")
    signals: dict[str, TagSpec] = {}
    owners: dict[str, str] = {}
    for name, entry in signals_table.items():
        spec = _tag_spec(name, entry, source)
        if spec.column in owners:
            raise TagMapError(
                f"{source}: signals.{name}.column = {spec.column!r} is already mapped to "
                f"signals.{owners[spec.column]}.column; each column maps one signal"
            )
        if layout == "wide" and spec.column == time_column:
            raise TagMapError(
                f"{source}: signals.{name}.column = {spec.column!r} is the time column "
                "(historian.time_column)"
            )
        owners[spec.column] = name
        signals[name] = spec
    return TagMap(
        layout=layout,
        time_column=time_column,
        time_zone=time_zone,
        tag_column=tag_column,
        value_column=value_column,
        quality_column=quality_column,
        signals=signals,
        source=source,
    )


def write_tag_map(tag_map: TagMap, path: str | Path) -> None:
    """Write a tag map as TOML that :func:`load_tag_map` reads back (ranges in the tag's unit)."""
    lines = ["[historian]", f"layout = {_toml_string(tag_map.layout)}"]
    for key in ("time_column", "time_zone", "tag_column", "value_column", "quality_column"):
        value = getattr(tag_map, key)
        if value is not None:
            lines.append(f"{key} = {_toml_string(value)}")
    for name, spec in tag_map.signals.items():
        lines += ["", f"[signals.{_toml_key(name)}]", f"column = {_toml_string(spec.column)}",
                  f"unit = {_toml_string(spec.unit)}"]
        if spec.valid_range_si is not None:
            low, high = convert(
                list(spec.valid_range_si), SIGNALS[spec.signal].si_unit, spec.unit
            ).tolist()
            lines.append(f"range = [{_toml_float(low)}, {_toml_float(high)}]")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def _tag_spec(name: str, entry: Any, source: str) -> TagSpec:
    where = f"{source}: signals.{name}"
    if name not in SIGNALS:
        raise TagMapError(
            f"{where}: {name!r} is not a canonical signal (known: {', '.join(SIGNALS)})"
        )
    if not isinstance(entry, dict):
        raise TagMapError(f"{where} must be a table with column, unit and optional range")
    _check_keys(entry, _SIGNAL_KEYS, f"signals.{name}", source)
    column = _text(entry, "column", f"signals.{name}", source)
    unit = _text(entry, "unit", f"signals.{name}", source)
    si_unit = SIGNALS[name].si_unit
    registry = unit_registry()
    try:
        parsed = registry.Unit(unit)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError,
            AttributeError, TypeError):
        raise TagMapError(
            f"{where}.unit = {unit!r}: unknown unit (signal {name} is in {si_unit!r})"
        ) from None
    if parsed.dimensionality != registry.Unit(si_unit).dimensionality:
        raise TagMapError(
            f"{where}.unit = {unit!r}: signal {name} has SI unit {si_unit!r}; "
            f"{unit!r} is not convertible to {si_unit!r}"
        )
    valid_range = None
    if "range" in entry:
        bounds = entry["range"]
        if (
            not isinstance(bounds, list)
            or len(bounds) != 2
            or not all(isinstance(b, int | float) and not isinstance(b, bool) for b in bounds)
            or not all(math.isfinite(b) for b in bounds)
            or not bounds[0] < bounds[1]
        ):
            raise TagMapError(
                f"{where}.range = {bounds!r}: expected two increasing finite numbers "
                f"[low, high] in {unit}"
            )
        low, high = convert([float(b) for b in bounds], unit, si_unit).tolist()
        valid_range = (low, high)
    return TagSpec(signal=name, column=column, unit=unit, valid_range_si=valid_range)


def _time_zone(historian: dict[str, Any], source: str) -> str | None:
    if "time_zone" not in historian:
        return None
    zone = _text(historian, "time_zone", "historian", source)
    try:
        zoneinfo.ZoneInfo(zone)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError):
        raise TagMapError(
            f"{source}: historian.time_zone = {zone!r}: not a known IANA time zone "
            "(e.g. 'Asia/Shanghai', 'Europe/Berlin', 'UTC')"
        ) from None
    return zone


def _table(parent: dict[str, Any], key: str, path: str, source: str) -> dict[str, Any]:
    field = f"{path}.{key}" if path else key
    if key not in parent:
        raise TagMapError(f"{source}: [{field}] is missing")
    value = parent[key]
    if not isinstance(value, dict):
        raise TagMapError(f"{source}: {field} must be a table")
    return value


def _text(table: dict[str, Any], key: str, path: str, source: str) -> str:
    if key not in table:
        raise TagMapError(f"{source}: {path}.{key} is missing")
    value = table[key]
    if not isinstance(value, str) or not value.strip():
        raise TagMapError(f"{source}: {path}.{key} = {value!r}: expected a non-empty string")
    return value


def _check_keys(table: dict[str, Any], allowed: tuple[str, ...], path: str, source: str) -> None:
    for key in table:
        if key not in allowed:
            field = f"{path}.{key}" if path else key
            raise TagMapError(
                f"{source}: {field} is not a tag map field (expected: {', '.join(allowed)})"
            )


def _toml_string(text: str) -> str:
    """A TOML basic string with backslash, quote and control characters escaped."""
    out = []
    for char in text:
        if char in '"\\':
            out.append("\\" + char)
        elif ord(char) < 0x20 or ord(char) == 0x7F:
            out.append(f"\\u{ord(char):04X}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    bare = key and all(c.isascii() and (c.isalnum() or c in "_-") for c in key)
    return key if bare else _toml_string(key)


def _toml_float(value: float) -> str:
    """Shortest text of ``value`` after dropping conversion round-off (15 significant digits)."""
    return repr(float(f"{value:.15g}"))
