"""Tag maps: which historian column or tag is which canonical signal, in which unit.

Kept as one module because it is one job, the tag-map format: its dataclasses, the TOML reader
that validates every entry and the writer that must round-trip what the reader accepts.

A plant historian names signals by plant tags (KKS such as ``10LBA10CP001``) in mixed units. A tag
map (TOML) translates them to the canonical names of :data:`steamtwin.dcs.signals.SIGNALS`::

    [historian]
    layout = "wide"              # "wide": time + one column per tag; "long": tag/time/value rows
    time_column = "Timestamp"
    time_zone = "Asia/Shanghai"  # IANA zone for timestamps without a UTC offset
    tag_column = "tag"           # long layout only
    value_column = "value"       # long layout only
    quality_column = "quality"   # long layout only, optional: the quality of each row's value
    delimiter = ";"              # CSV only, optional: one character (";", "\t", "|", ",")
    decimal = ","                # CSV only, optional: "." or ","
    encoding = "gbk"             # CSV only, optional: a Python codec ("gb18030", "cp1252", ...)

    [historian.quality]          # optional: how quality values are classified
    good = ["Good", 192]         # strings (case-insensitive) or integers, as in the file
    uncertain = ["Uncertain", 64]
    bad = ["Bad", 0]
    exclude = ["bad", "uncertain"]  # classes excluded from model inputs (default: both)

    [signals.main_steam_pressure]
    column = "10LBA10CP001"      # wide: column name; long: the tag value
    unit = "MPa"                 # convertible to the signal's SI unit (Pa)
    range = [0.0, 25.0]          # optional valid range, in `unit`
    noise = 0.02                 # optional instrument white-noise σ, in `unit`
    resolution = 0.001           # optional historian quantum (smallest step), in `unit`
    max_rate = 0.05              # optional physical rate limit, in `unit` per second
    time_constant = 20.0         # optional first-order sensor time constant τ, in s (a
                                 # thermowell's, from its data sheet or a step test)
    depth = "20 mm"              # hp_inner_casing_temperature only, optional: how deep the
                                 # metal thermocouple sits under the casing bore
    quality_column = "CP001_Q"   # wide layout only, optional: this signal's quality column
    node_id = "nsu=urn:plant;s=10LBA10CP001"  # optional OPC UA node id of the tag (live twin:
                                 # the NodeId string form of OPC UA Part 6 §5.3.1.10, ns= or nsu=)

``noise``, ``resolution`` and ``max_rate`` are differences, so they convert without the unit's
offset (0.5 degC of noise is 0.5 K; 1 degF is 5/9 K).

CSV dialect: ``delimiter``, ``decimal`` and ``encoding`` are sniffed from the file when absent
(see :mod:`steamtwin.dcs.readers`); set them when the sniffed choice is wrong.

Quality classes: without ``good``/``uncertain``/``bad`` lists (``exclude`` alone may be given) a
value is classified by the OPC conventions — a text by its OPC UA status-code name prefix
("Good…", "Uncertain…", "Bad…", case-insensitive; OPC 10000-4, UA Part 4, "StatusCode", and
the symbolic names of OPC 10000-6 Annex A) and an integer 0–255 by bits 7–6 of the OPC DA
quality byte QQSSSSLL (0b11 good: 192–255, 0b01 uncertain: 64–127, 0b00 bad: 0–63; 0b10,
128–191, is not used; OPC Data Access Custom Interface Standard 2.05a, §6.8 "OPC Quality
flags"). An OPC UA numeric status code is *not*
understood by default (its 0 is Good, while DA's 0 is Bad): list the codes. With any list
given, only the listed values are known. A value that cannot be classified is an error, never
a guess.

Every validation error names the file and the field.
"""

from __future__ import annotations

import codecs
import math
import re
import tomllib
import zoneinfo
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pint

from steamtwin.dcs.signals import SIGNALS
from steamtwin.errors import DataError
from steamtwin.keys import unknown_key_message
from steamtwin.textfile import read_utf8_text
from steamtwin.units import UnitError, convert, parse_quantity, unit_registry

LAYOUTS = ("wide", "long")
QUALITY_CLASSES = ("good", "uncertain", "bad")
DECIMALS = (".", ",")
_HISTORIAN_KEYS = (
    "layout", "time_column", "time_zone", "tag_column", "value_column", "quality_column",
    "delimiter", "decimal", "encoding", "quality",
)
_LONG_ONLY = ("tag_column", "value_column", "quality_column")
_QUALITY_KEYS = (*QUALITY_CLASSES, "exclude")
_SIGNAL_KEYS = ("column", "unit", "range", "noise", "resolution", "max_rate", "time_constant",
                "depth", "quality_column", "node_id")
#: OPC UA NodeId string form (Part 6 §5.3.1.10): optional ns=<index>; or nsu=<uri>; then
#: i=<number>, s=<string>, g=<GUID> or b=<base64>.
_NODE_ID = re.compile(r"^(?:(?:ns=\d+|nsu=[^;]+);)?"
                      r"(?:i=\d+|s=.+|g=[0-9A-Fa-f-]{36}|b=[A-Za-z0-9+/=]+)$")
#: The signal measured by a thermocouple in the metal, the only one with a depth.
METAL_THERMOCOUPLE = "hp_inner_casing_temperature"
#: Deepest metal thermocouple accepted, m (an HP inner casing wall is 0.1-0.3 m thick).
MAX_THERMOCOUPLE_DEPTH_M = 0.2
#: Longest sensor time constant accepted (s): heavy thermowells in slow steam reach a few
#: minutes (ASME PTC 19.3 TW-2016, response-time discussion); ten minutes is no sensor's.
MAX_TIME_CONSTANT_S = 600.0
_DELTA_KEYS = {  # tag-map key → (TagSpec field, what it is, unit suffix)
    "noise": ("noise_si", "instrument white-noise standard deviation", ""),
    "resolution": ("resolution_si", "historian quantum", ""),
    "max_rate": ("max_rate_si", "physical rate limit", " per second"),
}
_INTEGER_TEXT = re.compile(r"[+-]?\d{1,18}(?:\.0*)?")  # integer text (".0" allowed)
# OPC DA Custom Interface 2.05a §6.8: bits 7-6 of the quality byte QQSSSSLL; 0b10 is unused.
_OPC_DA_QUALITY_BITS = {0b11: "good", 0b01: "uncertain", 0b00: "bad"}


class TagMapError(DataError):
    """A tag map is missing a field, has a bad value or is inconsistent (names file and field)."""


@dataclass(frozen=True)
class TagSpec:
    """One mapped signal: historian ``column`` (wide) or tag value (long), its ``unit``.

    ``valid_range_si`` is the optional valid range converted to the signal's SI unit
    (e.g. Pa, K, kg/s, W). ``noise_si`` (instrument white-noise σ), ``resolution_si``
    (historian quantum) and ``max_rate_si`` (physical rate limit, per second) are optional
    differences in the SI unit (K, Pa, ...; per second for the rate). ``time_constant_s`` is
    the sensor's first-order time constant (s), which the model's readings are lagged by.
    ``depth_m`` is how deep a metal thermocouple sits under the casing bore (m; only
    :data:`METAL_THERMOCOUPLE`). ``quality_column`` is the wide layout's column holding this
    signal's quality, if any. ``node_id`` is the tag's OPC UA node id (NodeId string form,
    e.g. ``"ns=2;s=10LBA10CP001"``), for the live twin's OPC UA source.
    """

    signal: str
    column: str
    unit: str
    valid_range_si: tuple[float, float] | None = None
    noise_si: float | None = None
    resolution_si: float | None = None
    max_rate_si: float | None = None
    time_constant_s: float | None = None
    quality_column: str | None = None
    depth_m: float | None = None
    node_id: str | None = None


@dataclass(frozen=True)
class QualityMapping:
    """Quality value → class ("good", "uncertain", "bad"); ``exclude`` lists the excluded classes.

    With all three value lists empty, the OPC defaults of the module docstring apply. Strings
    match case-insensitively after stripping blanks; integers match integers and integer text.
    """

    good: tuple[str | int, ...] = ()
    uncertain: tuple[str | int, ...] = ()
    bad: tuple[str | int, ...] = ()
    exclude: tuple[str, ...] = ("bad", "uncertain")

    @property
    def is_default(self) -> bool:
        """True when values are classified by the OPC defaults (no value lists given)."""
        return not (self.good or self.uncertain or self.bad)

    def classify(self, value: object) -> str | None:
        """The class of one quality value as read (text or number), or None if unknown."""
        text, number = _quality_key(value)
        if text is None:
            return None
        if self.is_default:
            folded = text.casefold()
            for name in QUALITY_CLASSES:
                if folded.startswith(name):
                    return name
            if number is not None and 0 <= number <= 255:
                return _OPC_DA_QUALITY_BITS.get(number >> 6)
            return None
        for name in QUALITY_CLASSES:
            for known in getattr(self, name):
                if isinstance(known, int) and known == number:
                    return name
                if isinstance(known, str) and known.strip().casefold() == text.casefold():
                    return name
        return None

    def describe(self) -> str:
        """How values are classified, for messages."""
        if self.is_default:
            return ("the default OPC mapping (text 'Good…'/'Uncertain…'/'Bad…', "
                    "OPC DA integers 0–255)")
        return "historian.quality"


@dataclass(frozen=True)
class TagMap:
    """A validated tag map; ``source`` names the file it came from (used in error messages).

    ``delimiter``, ``decimal`` and ``encoding`` are the CSV dialect the map sets (None: sniffed
    from the file); ``quality`` classifies quality values.
    """

    layout: str
    time_column: str
    time_zone: str | None
    tag_column: str | None
    value_column: str | None
    quality_column: str | None
    signals: dict[str, TagSpec]
    source: str
    delimiter: str | None = None
    decimal: str | None = None
    encoding: str | None = None
    quality: QualityMapping = field(default_factory=QualityMapping)

    def column_of(self, signal: str) -> str:
        """Historian column (wide) or tag (long) of a canonical signal; KeyError if unmapped."""
        try:
            return self.signals[signal].column
        except KeyError:
            raise KeyError(
                f"{self.source}: signal {signal!r} is not mapped "
                f"(mapped: {', '.join(self.signals)})"
            ) from None

    @property
    def time_constants(self) -> dict[str, float]:
        """Sensor time constants (s) the map gives: signal → τ."""
        return {name: spec.time_constant_s for name, spec in self.signals.items()
                if spec.time_constant_s is not None}

    @property
    def has_quality(self) -> bool:
        """True when a quality column is configured (long layout or any wide signal)."""
        return self.quality_column is not None or any(
            spec.quality_column is not None for spec in self.signals.values()
        )


def load_tag_map(path: str | Path) -> TagMap:
    """Load and validate a tag map TOML file; raises :class:`TagMapError` naming file and field."""
    path = Path(path)
    return parse_tag_map(read_utf8_text(path, "tag map", "TOML", TagMapError), str(path))


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
    delimiter, decimal, encoding = _dialect(historian, source)
    signals_table = _table(document, "signals", "", source)
    if not signals_table:
        raise TagMapError(f"{source}: [signals] maps no signal; add e.g. [signals.load]")
    signals: dict[str, TagSpec] = {}
    owners: dict[str, str] = {}
    node_owners: dict[str, str] = {}
    for name, entry in signals_table.items():
        spec = _tag_spec(name, entry, layout, source)
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
        if spec.node_id is not None:
            if spec.node_id in node_owners:
                raise TagMapError(
                    f"{source}: signals.{name}.node_id = {spec.node_id!r} is already the node of "
                    f"signals.{node_owners[spec.node_id]}; each OPC UA node maps one signal")
            node_owners[spec.node_id] = name
        signals[name] = spec
    for name, spec in signals.items():
        if spec.quality_column is None:
            continue
        if spec.quality_column == time_column:
            raise TagMapError(f"{source}: signals.{name}.quality_column = "
                              f"{spec.quality_column!r} is the time column (historian.time_column)")
        if spec.quality_column in owners:
            raise TagMapError(
                f"{source}: signals.{name}.quality_column = {spec.quality_column!r} is the value "
                f"column of signals.{owners[spec.quality_column]}"
            )
    tag_map = TagMap(
        layout=layout,
        time_column=time_column,
        time_zone=time_zone,
        tag_column=tag_column,
        value_column=value_column,
        quality_column=quality_column,
        signals=signals,
        source=source,
        delimiter=delimiter,
        decimal=decimal,
        encoding=encoding,
    )
    if "quality" not in historian:
        return tag_map
    if not tag_map.has_quality:
        raise TagMapError(
            f"{source}: [historian.quality] is set but no quality column is configured "
            "(historian.quality_column in the long layout, signals.<name>.quality_column in "
            "the wide layout)"
        )
    return TagMap(**{**tag_map.__dict__, "quality": _quality(historian["quality"], source)})


def write_tag_map(tag_map: TagMap, path: str | Path) -> None:
    """Write a tag map as TOML that :func:`load_tag_map` reads back (values in the tag's unit)."""
    lines = ["[historian]", f"layout = {_toml_string(tag_map.layout)}"]
    for key in ("time_column", "time_zone", "tag_column", "value_column", "quality_column",
                "delimiter", "decimal", "encoding"):
        value = getattr(tag_map, key)
        if value is not None:
            lines.append(f"{key} = {_toml_string(value)}")
    quality = tag_map.quality
    if quality != QualityMapping():
        lines += ["", "[historian.quality]"]
        for name in QUALITY_CLASSES:
            values = getattr(quality, name)
            if values:
                lines.append(f"{name} = [{', '.join(map(_toml_value, values))}]")
        lines.append(f"exclude = [{', '.join(map(_toml_string, quality.exclude))}]")
    for name, spec in tag_map.signals.items():
        si_unit = SIGNALS[spec.signal].si_unit
        lines += ["", f"[signals.{_toml_key(name)}]", f"column = {_toml_string(spec.column)}",
                  f"unit = {_toml_string(spec.unit)}"]
        if spec.valid_range_si is not None:
            low, high = convert(list(spec.valid_range_si), si_unit, spec.unit).tolist()
            lines.append(f"range = [{_toml_float(low)}, {_toml_float(high)}]")
        for key, (attribute, _, _) in _DELTA_KEYS.items():
            value = getattr(spec, attribute)
            if value is not None:
                lines.append(f"{key} = {_toml_float(_delta(value, si_unit, spec.unit))}")
        if spec.time_constant_s is not None:
            lines.append(f"time_constant = {_toml_float(spec.time_constant_s)}")
        if spec.depth_m is not None:
            lines.append(f'depth = "{_toml_float(spec.depth_m * 1e3)} mm"')
        if spec.quality_column is not None:
            lines.append(f"quality_column = {_toml_string(spec.quality_column)}")
        if spec.node_id is not None:
            lines.append(f"node_id = {_toml_string(spec.node_id)}")
    Path(path).write_text("\n".join(lines) + "\n", encoding="utf-8")


def _tag_spec(name: str, entry: Any, layout: str, source: str) -> TagSpec:
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
            AttributeError, TypeError, AssertionError):
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
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise TagMapError(f"{where}.range = {bounds!r}: out of the representable range "
                              f"once converted to {si_unit}")
        valid_range = (low, high)
    deltas: dict[str, float] = {}
    for key, (attribute, meaning, per) in _DELTA_KEYS.items():
        if key not in entry:
            continue
        value = entry[key]
        if (not isinstance(value, int | float) or isinstance(value, bool)
                or not math.isfinite(value) or value <= 0):
            raise TagMapError(f"{where}.{key} = {value!r}: expected the {meaning} as a positive "
                              f"finite number in {unit}{per}")
        converted = _delta(float(value), unit, si_unit)
        if not (math.isfinite(converted) and converted > 0):
            raise TagMapError(f"{where}.{key} = {value!r}: out of the representable range once "
                              f"converted to {si_unit}{per}")
        deltas[attribute] = converted
    time_constant = None
    if "time_constant" in entry:
        time_constant = entry["time_constant"]
        if (not isinstance(time_constant, int | float) or isinstance(time_constant, bool)
                or not 0.0 <= time_constant <= MAX_TIME_CONSTANT_S):
            raise TagMapError(f"{where}.time_constant = {time_constant!r}: expected the sensor's "
                              f"first-order time constant in s, a number in [0, "
                              f"{MAX_TIME_CONSTANT_S:g}]")
        time_constant = float(time_constant)
    depth = _depth(entry, name, where)
    quality_column = None
    if "quality_column" in entry:
        if layout != "wide":
            raise TagMapError(
                f"{where}.quality_column is only used with layout = \"wide\"; the long layout "
                "has one quality column for all tags (historian.quality_column)"
            )
        quality_column = _text(entry, "quality_column", f"signals.{name}", source)
    node_id = None
    if "node_id" in entry:
        node_id = _text(entry, "node_id", f"signals.{name}", source)
        if not _NODE_ID.match(node_id):
            raise TagMapError(f"{where}.node_id = {node_id!r}: expected an OPC UA node id such as "
                              "\"ns=2;s=10LBA10CP001\", \"nsu=urn:plant;s=TAG\" or \"ns=3;i=1001\"")
    return TagSpec(signal=name, column=column, unit=unit, valid_range_si=valid_range,
                   time_constant_s=time_constant, quality_column=quality_column,
                   depth_m=depth, node_id=node_id, **deltas)


def _depth(entry: dict[str, Any], name: str, where: str) -> float | None:
    """The metal thermocouple's depth under the bore (m), refused on any other signal."""
    if "depth" not in entry:
        return None
    raw = entry["depth"]
    if name != METAL_THERMOCOUPLE:
        raise TagMapError(f"{where}.depth: only the metal thermocouple ({METAL_THERMOCOUPLE}) "
                          "has a depth under the casing bore")
    try:
        depth = parse_quantity(raw, "m", f"{where}.depth") if isinstance(raw, str) else None
    except UnitError as error:
        raise TagMapError(str(error)) from None
    if depth is None or not 0.0 <= depth <= MAX_THERMOCOUPLE_DEPTH_M:
        raise TagMapError(f"{where}.depth = {raw!r}: expected a length such as \"20 mm\" in "
                          f"[0, {MAX_THERMOCOUPLE_DEPTH_M * 1e3:g}] mm")
    return depth


def _delta(value: float, from_unit: str, to_unit: str) -> float:
    """Convert a difference (σ, quantum, rate) between units, without the units' offsets."""
    registry = unit_registry()
    return float(registry.Quantity(value, _difference_unit(from_unit))
                 .to(_difference_unit(to_unit)).magnitude)


def _difference_unit(unit: str) -> str:
    """``unit``, or ``delta_<unit>`` for a unit with an offset (degC, degF: 0 is not 0 K)."""
    registry = unit_registry()
    parsed = registry.Unit(unit)
    offset = registry.Quantity(0.0, parsed).to_base_units().magnitude != 0.0
    return f"delta_{parsed}" if offset else str(parsed)


def _dialect(historian: dict[str, Any], source: str) -> tuple[str | None, str | None, str | None]:
    """The CSV ``delimiter``, ``decimal`` and ``encoding`` the map sets (None when absent)."""
    delimiter = decimal = encoding = None
    if "delimiter" in historian:
        delimiter = historian["delimiter"]
        if (not isinstance(delimiter, str) or len(delimiter) != 1 or delimiter.isalnum()
                or delimiter in '."\r\n' or (delimiter.isspace() and delimiter not in " \t")):
            raise TagMapError(
                f"{source}: historian.delimiter = {delimiter!r}: expected one character that is "
                "not a letter, digit, '.', quote or line break, e.g. \",\", \";\", \"\\t\" or \"|\""
            )
    if "decimal" in historian:
        decimal = historian["decimal"]
        if decimal not in DECIMALS:
            raise TagMapError(
                f"{source}: historian.decimal = {decimal!r}: expected \".\" or \",\""
            )
    if delimiter is not None and delimiter == decimal:
        raise TagMapError(
            f"{source}: historian.delimiter and historian.decimal are both {delimiter!r}; "
            "a CSV cannot use one character for both"
        )
    if "encoding" in historian:
        encoding = _text(historian, "encoding", "historian", source)
        try:
            codecs.lookup(encoding)
            "a".encode(encoding)  # refuses codecs that are not text encodings (hex, rot13, ...)
        except (LookupError, ValueError, TypeError):
            raise TagMapError(
                f"{source}: historian.encoding = {encoding!r}: not a text encoding Python knows "
                "(e.g. \"utf-8\", \"gbk\", \"gb18030\", \"cp1252\")"
            ) from None
    return delimiter, decimal, encoding


def _quality(table: Any, source: str) -> QualityMapping:
    """The ``[historian.quality]`` table as a :class:`QualityMapping`."""
    if not isinstance(table, dict):
        raise TagMapError(f"{source}: historian.quality must be a table "
                          "(good, uncertain, bad, exclude)")
    _check_keys(table, _QUALITY_KEYS, "historian.quality", source)
    lists: dict[str, tuple[str | int, ...]] = {}
    owner: dict[str | int, str] = {}
    for name in QUALITY_CLASSES:
        values = table.get(name, [])
        if not isinstance(values, list) or not all(
            (isinstance(v, str) and v.strip()) or (isinstance(v, int) and not isinstance(v, bool))
            for v in values
        ):
            raise TagMapError(
                f"{source}: historian.quality.{name} = {values!r}: expected a list of quality "
                "values as they appear in the file: non-empty strings or integers"
            )
        for value in values:
            key = value.strip().casefold() if isinstance(value, str) else value
            if key in owner:
                raise TagMapError(
                    f"{source}: historian.quality.{name} lists {value!r}, which "
                    f"historian.quality.{owner[key]} lists too; a value has one class"
                )
            owner[key] = name
        lists[name] = tuple(values)
    exclude = table.get("exclude", ["bad", "uncertain"])
    if (not isinstance(exclude, list) or not all(v in ("bad", "uncertain") for v in exclude)
            or len(set(exclude)) != len(exclude)):
        raise TagMapError(
            f"{source}: historian.quality.exclude = {exclude!r}: expected a list of the classes "
            "excluded from model inputs, from \"bad\" and \"uncertain\""
        )
    return QualityMapping(**lists, exclude=tuple(exclude))


def _quality_key(value: object) -> tuple[str | None, int | None]:
    """A quality value as (stripped text, integer or None); (None, None) when missing."""
    if value is None or isinstance(value, bool):
        return (None, None) if value is None else (str(value), None)
    if isinstance(value, int):  # Python and numpy integers (numpy ints are not int subclasses)
        return str(value), value
    if hasattr(value, "dtype") and getattr(value.dtype, "kind", "") in "iu":
        return str(int(value)), int(value)
    if isinstance(value, float) or (hasattr(value, "dtype") and value.dtype.kind == "f"):
        number = float(value)
        if math.isnan(number):
            return None, None
        if number.is_integer():
            return str(int(number)), int(number)
        return repr(number), None
    text = str(value).strip()
    if not text:
        return None, None
    return text, int(text.split(".")[0]) if _INTEGER_TEXT.fullmatch(text) else None


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
    message = unknown_key_message(table, allowed, path, source, "tag map")
    if message is not None:
        raise TagMapError(message)


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


def _toml_value(value: str | int) -> str:
    """A quality value (string or integer) as TOML."""
    return _toml_string(value) if isinstance(value, str) else str(value)


def _toml_key(key: str) -> str:
    bare = key and all(c.isascii() and (c.isalnum() or c in "_-") for c in key)
    return key if bare else _toml_string(key)


def _toml_float(value: float) -> str:
    """Shortest text of ``value`` after dropping conversion round-off (15 significant digits)."""
    return repr(float(f"{value:.15g}"))
