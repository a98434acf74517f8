"""Fuzzing the historian reader and the tag-map parser (issue 16).

Whatever bytes a CSV holds and whatever text a tag map holds, ``read_historian`` and
``parse_tag_map`` either return a valid result or raise their ``ValueError`` subclass naming the
file — never another exception. Unmutated exports in any supported dialect read back exactly.
"""

from __future__ import annotations

import contextlib
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from steamtwin.dcs.readers import HistorianData, HistorianFormatError, read_historian
from steamtwin.dcs.tagmap import TagMap, TagMapError, load_tag_map, parse_tag_map, write_tag_map

FUZZ = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# Column names per encoding: each must be representable in it (GBK names for GBK, ...).
NAMES = {
    "utf-8": ("时间", "主汽压力 MPa", "Temp °C"),
    "utf-8-sig": ("Zeit", "Druck", "Temp °C"),
    "utf-16": ("时间", "压力", "温度"),
    "gbk": ("时间", "主汽压力", "主汽温度"),
    "cp1252": ("Zeit", "Druck bar", "Temp °C"),
}
TAG_MAP = """
[historian]
layout = "{layout}"
time_column = "{time}"
time_zone = "UTC"
{long}
{dialect}

[signals.main_steam_pressure]
column = "{pressure}"
unit = "MPa"

[signals.main_steam_temperature]
column = "{temperature}"
unit = "degC"
{wide_quality}
"""
LONG_KEYS = 'tag_column = "Tag"\nvalue_column = "Value"\nquality_column = "Q"'
QUALITIES = ("Good", "Bad", "Uncertain", "192", "0", "64")
number = st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: round(x, 4))


def _tag_map_text(layout: str, names: tuple[str, str, str], dialect: str = "") -> str:
    time, pressure, temperature = names
    return TAG_MAP.format(layout=layout, time=time, pressure=pressure, temperature=temperature,
                          dialect=dialect, long=LONG_KEYS if layout == "long" else "",
                          wide_quality='quality_column = "Q"' if layout == "wide" else "")


@st.composite
def exports(draw):
    """A CSV export, wide or long: (bytes, tag-map text, SI pressure, SI temperature, bad mask)."""
    layout = draw(st.sampled_from(["wide", "long"]))
    encoding = draw(st.sampled_from(sorted(NAMES)))
    delimiter = draw(st.sampled_from([",", ";", "\t", "|"]))
    decimal = draw(st.sampled_from(["."] if delimiter == "," else [".", ","]))
    time, pressure, temperature = NAMES[encoding]
    rows = draw(st.lists(st.tuples(number, number, st.sampled_from(QUALITIES)),
                         min_size=1, max_size=8))
    if layout == "wide":
        lines = [[time, pressure, temperature, "Q"]]
    else:
        lines = [[time, "Tag", "Value", "Q"]]
    for second, (p, t, q) in enumerate(rows):
        stamp = f"2026-03-01 00:00:{second:02d}"
        p_text, t_text = (repr(v).replace(".", decimal) for v in (p, t))
        if layout == "wide":
            lines.append([stamp, p_text, t_text, q])
        else:
            lines += [[stamp, pressure, p_text, "Good"], [stamp, temperature, t_text, q]]
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    data = newline.join(delimiter.join(line) for line in lines) + newline
    dialect = ""
    if draw(st.booleans()):  # the dialect in the tag map, or sniffed
        toml_delimiter = "\\t" if delimiter == "\t" else delimiter
        dialect = (f'delimiter = "{toml_delimiter}"\ndecimal = "{decimal}"\n'
                   f'encoding = "{encoding}"')
    pressure_si = [p * 1e6 for p, _, _ in rows]
    temperature_si = [t + 273.15 for _, t, _ in rows]
    bad = [q in ("Bad", "Uncertain", "0", "64") for _, _, q in rows]
    return (data.encode(encoding), _tag_map_text(layout, NAMES[encoding], dialect),
            pressure_si, temperature_si, bad)


def _read(data: bytes, tag_map: TagMap, suffix: str = ".csv") -> HistorianData:
    """Read ``data`` as a file; any exception but a HistorianFormatError naming it fails."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"export{suffix}"
        path.write_bytes(data)
        try:
            result = read_historian(path, tag_map)
        except HistorianFormatError as error:
            assert str(path) in str(error)
            raise
    assert isinstance(result.signals, pd.DataFrame)
    assert result.extras.index.equals(result.signals.index)
    assert set(result.bad_quality) == set(result.signals.columns)
    for mask in result.bad_quality.values():
        assert mask.dtype == bool and mask.shape == (len(result.signals),)
    return result


@FUZZ
@given(export=exports())
def test_exports_in_any_dialect_read_back_exactly(export):
    data, text, pressure_si, temperature_si, bad = export
    result = _read(data, parse_tag_map(text, "fuzz.toml"))
    np.testing.assert_allclose(result.signals["main_steam_pressure"], pressure_si, rtol=1e-12)
    np.testing.assert_allclose(result.signals["main_steam_temperature"], temperature_si,
                               rtol=1e-12, atol=1e-9)
    assert result.bad_quality["main_steam_temperature"].tolist() == bad
    assert set(result.dialect) == {"delimiter", "decimal", "encoding", "delimiter_source",
                                   "decimal_source", "encoding_source"}


@st.composite
def mutated_exports(draw):
    """An export with its bytes truncated, overwritten, inserted or replaced by garbage."""
    data, text, *_ = draw(exports())
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["truncate", "overwrite", "insert", "garbage"]))
        at = draw(st.integers(0, len(data)))
        chunk = draw(st.binary(min_size=1, max_size=12))
        if kind == "truncate":
            data = data[:at]
        elif kind == "overwrite":
            data = data[:at] + chunk + data[at + len(chunk):]
        elif kind == "insert":
            data = data[:at] + chunk + data[at:]
        else:
            data = draw(st.binary(max_size=200))
    return data, text


@FUZZ
@given(export=mutated_exports())
def test_mutated_csv_bytes_give_a_result_or_a_named_error(export):
    data, text = export
    with contextlib.suppress(HistorianFormatError):
        _read(data, parse_tag_map(text, "fuzz.toml"))


@settings(max_examples=30, deadline=None)
@given(data=st.binary(max_size=300))
def test_garbage_parquet_gives_a_named_error(data):
    with pytest.raises(HistorianFormatError):
        _read(data, parse_tag_map(_tag_map_text("wide", ("t", "p", "T")), "fuzz.toml"),
              ".parquet")


# --- tag maps ------------------------------------------------------------------------------------

VALID_MAP = """
[historian]
layout = "long"
time_column = "time"
time_zone = "Asia/Shanghai"
tag_column = "tag"
value_column = "value"
quality_column = "quality"
delimiter = ";"
decimal = ","
encoding = "gbk"

[historian.quality]
good = ["Good", 192]
bad = ["Bad", 0]
exclude = ["bad"]

[signals.main_steam_temperature]
column = "10LBA10CT001"
unit = "degC"
range = [0, 600]
noise = 0.5
resolution = 0.1
max_rate = 2.0
"""
FRAGMENTS = [
    'layout = "wide"', 'layout = "long"', "layout = 1", 'time_zone = "Mars/Base"',
    'delimiter = "\\t"', 'delimiter = ","', 'delimiter = ""', 'decimal = "."', 'decimal = 1',
    'encoding = "utf-16"', 'encoding = "rot13"', 'encoding = "no-such"',
    'quality_column = "q"', 'quality_column = "tag"', "[historian.quality]", "good = []",
    'uncertain = ["Bad"]', "bad = [1.5]", 'exclude = ["good"]', "exclude = []",
    "[signals.load]", "[signals.hp_power]", "[signals.nope]", 'column = "10LBA10CT001"',
    'column = "x"', 'unit = "degF"', 'unit = "MW"', 'unit = "kelvin / second"',
    'unit = "1e400 K"', 'unit = "degC ** 2"', "range = [1e308, 1.7e308]", "range = [-1, 1]",
    "noise = 1e-320", "noise = 1e308", "noise = -1", "max_rate = 0.0", 'resolution = "0.1"',
    "[signals]", "[historian]", "x = 1", "signals = 1", "historian = []",
]


@st.composite
def mutated_maps(draw):
    """The valid map with lines deleted, swapped, inserted or characters replaced."""
    lines = VALID_MAP.splitlines()
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["delete", "insert", "replace", "char"]))
        at = draw(st.integers(0, len(lines)))
        if kind == "delete" and lines:
            del lines[min(at, len(lines) - 1)]
        elif kind == "insert":
            lines.insert(at, draw(st.sampled_from(FRAGMENTS)))
        elif kind == "replace" and lines:
            lines[min(at, len(lines) - 1)] = draw(st.sampled_from(FRAGMENTS))
        elif kind == "char" and lines:
            line = lines[min(at, len(lines) - 1)]
            position = draw(st.integers(0, len(line)))
            lines[min(at, len(lines) - 1)] = (line[:position] + draw(st.characters())
                                              + line[position + 1:])
    return "\n".join(lines) + "\n"


def _parse(text: str) -> TagMap | None:
    try:
        return parse_tag_map(text, "fuzz-map.toml")
    except TagMapError as error:
        assert str(error).startswith("fuzz-map.toml: ")
        return None


@FUZZ
@given(text=mutated_maps())
def test_mutated_tag_maps_parse_or_raise_a_named_error_and_round_trip(text):
    tag_map = _parse(text)
    if tag_map is None:
        return
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "saved.toml"
        write_tag_map(tag_map, path)
        loaded = load_tag_map(path)
    for key in ("layout", "time_column", "time_zone", "tag_column", "value_column",
                "quality_column", "delimiter", "decimal", "encoding", "quality"):
        assert getattr(loaded, key) == getattr(tag_map, key), key
    assert loaded.signals.keys() == tag_map.signals.keys()
    for name, spec in tag_map.signals.items():
        back = loaded.signals[name]
        assert (back.column, back.unit, back.quality_column) == (
            spec.column, spec.unit, spec.quality_column)
        for key in ("valid_range_si", "noise_si", "resolution_si", "max_rate_si"):
            value = getattr(spec, key)
            assert getattr(back, key) == (None if value is None
                                          else pytest.approx(value, rel=1e-12)), key


@FUZZ
@given(text=st.text(max_size=300))
def test_random_text_as_tag_map(text):
    _parse(text)
