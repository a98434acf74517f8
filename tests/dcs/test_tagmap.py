"""Tag maps: valid maps parse, every mistake is named with file and field, maps round-trip."""

from __future__ import annotations

import re

import pytest

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import (
    TagMap,
    TagMapError,
    TagSpec,
    load_tag_map,
    parse_tag_map,
    write_tag_map,
)

WIDE = """
[historian]
layout = "wide"
time_column = "Timestamp"
time_zone = "Asia/Shanghai"

[signals.main_steam_pressure]
column = "10LBA10CP001"
unit = "MPa"
range = [0.0, 25.0]

[signals.main_steam_temperature]
column = "10LBA10CT001"
unit = "degC"
range = [0, 600]

[signals.main_steam_flow]
column = "10LBA10CF001"
unit = "t/h"
"""

LONG = """
[historian]
layout = "long"
time_column = "time"
tag_column = "tag"
value_column = "value"
quality_column = "quality"

[signals.load]
column = "10MKA01CE001"
unit = "MW"
"""

KNOWN = ", ".join(SIGNALS)


def _fails(text: str, message: str) -> None:
    with pytest.raises(TagMapError, match="^" + re.escape(message) + "$"):
        parse_tag_map(text, "plant.toml")


def test_wide_map_parses_with_ranges_in_si():
    tag_map = parse_tag_map(WIDE, "plant.toml")
    assert tag_map.layout == "wide"
    assert tag_map.time_column == "Timestamp"
    assert tag_map.time_zone == "Asia/Shanghai"
    assert tag_map.tag_column is tag_map.value_column is tag_map.quality_column is None
    assert tag_map.source == "plant.toml"
    assert list(tag_map.signals) == ["main_steam_pressure", "main_steam_temperature",
                                     "main_steam_flow"]
    pressure = tag_map.signals["main_steam_pressure"]
    assert pressure == TagSpec("main_steam_pressure", "10LBA10CP001", "MPa", (0.0, 25e6))
    low, high = tag_map.signals["main_steam_temperature"].valid_range_si
    assert (low, high) == pytest.approx((273.15, 873.15))
    assert tag_map.signals["main_steam_flow"].valid_range_si is None
    assert tag_map.column_of("main_steam_flow") == "10LBA10CF001"
    with pytest.raises(KeyError, match="'load' is not mapped"):
        tag_map.column_of("load")


def test_long_map_parses():
    tag_map = parse_tag_map(LONG, "plant.toml")
    assert (tag_map.layout, tag_map.tag_column, tag_map.value_column, tag_map.quality_column) == (
        "long", "tag", "value", "quality")
    assert tag_map.time_zone is None


@pytest.mark.parametrize(("text", "message"), [
    (WIDE.replace("main_steam_flow]", "main_stem_flow]"),
     f"plant.toml: signals.main_stem_flow: 'main_stem_flow' is not a canonical signal "
     f"(known: {KNOWN})"),
    (WIDE.replace('"t/h"', '"degC"'),
     "plant.toml: signals.main_steam_flow.unit = 'degC': signal main_steam_flow has SI unit "
     "'kg/s'; 'degC' is not convertible to 'kg/s'"),
    (WIDE.replace('"t/h"', '"furlong_per_blip"'),
     "plant.toml: signals.main_steam_flow.unit = 'furlong_per_blip': unknown unit "
     "(signal main_steam_flow is in 'kg/s')"),
    (WIDE.replace("[0.0, 25.0]", "[25.0, 0.0]"),
     "plant.toml: signals.main_steam_pressure.range = [25.0, 0.0]: expected two increasing "
     "finite numbers [low, high] in MPa"),
    (WIDE.replace("[0.0, 25.0]", "[0.0]"),
     "plant.toml: signals.main_steam_pressure.range = [0.0]: expected two increasing "
     "finite numbers [low, high] in MPa"),
    (WIDE.replace("[0.0, 25.0]", '["0", 25.0]'),
     "plant.toml: signals.main_steam_pressure.range = ['0', 25.0]: expected two increasing "
     "finite numbers [low, high] in MPa"),
    (WIDE.replace("[0.0, 25.0]", "[true, 25.0]"),
     "plant.toml: signals.main_steam_pressure.range = [True, 25.0]: expected two increasing "
     "finite numbers [low, high] in MPa"),
    (WIDE.replace("[0.0, 25.0]", "[0.0, inf]"),
     "plant.toml: signals.main_steam_pressure.range = [0.0, inf]: expected two increasing "
     "finite numbers [low, high] in MPa"),
    (WIDE.replace("10LBA10CF001", "10LBA10CP001"),
     "plant.toml: signals.main_steam_flow.column = '10LBA10CP001' is already mapped to "
     "signals.main_steam_pressure.column; each column maps one signal"),
    (WIDE.replace("10LBA10CF001", "Timestamp"),
     "plant.toml: signals.main_steam_flow.column = 'Timestamp' is the time column "
     "(historian.time_column)"),
    (WIDE.replace('"wide"', '"tall"'),
     "plant.toml: historian.layout = 'tall': expected one of wide, long"),
    (WIDE.replace('"Asia/Shanghai"', '"Mars/Olympus_Mons"'),
     "plant.toml: historian.time_zone = 'Mars/Olympus_Mons': not a known IANA time zone "
     "(e.g. 'Asia/Shanghai', 'Europe/Berlin', 'UTC')"),
    (WIDE.replace('time_column = "Timestamp"', ""),
     "plant.toml: historian.time_column is missing"),
    (WIDE.replace('time_column = "Timestamp"', "time_column = 3"),
     "plant.toml: historian.time_column = 3: expected a non-empty string"),
    (WIDE.replace('layout = "wide"', 'layout = "wide"\ntag_column = "tag"'),
     "plant.toml: historian.tag_column is only used with layout = \"long\" "
     "(this map has layout = 'wide')"),
    (WIDE.replace('unit = "t/h"', 'unit = "t/h"\ncolum = "x"'),
     "plant.toml: signals.main_steam_flow.colum is not a tag map field "
     "(expected: column, unit, range)"),
    (WIDE.replace('unit = "t/h"', ""),
     "plant.toml: signals.main_steam_flow.unit is missing"),
    (WIDE.replace("[historian]", "[historain]"),
     "plant.toml: historain is not a tag map field (expected: historian, signals)"),
    (LONG.replace('tag_column = "tag"', ""),
     "plant.toml: historian.tag_column is missing"),
    (LONG.replace('value_column = "value"', ""),
     "plant.toml: historian.value_column is missing"),
    (LONG.replace('quality_column = "quality"', 'quality_column = "tag"'),
     "plant.toml: historian.quality_column = 'tag' is also historian.tag_column; the long layout "
     "needs distinct columns"),
    ("[historian]\nlayout = 'wide'\ntime_column = 't'\n[signals]\n",
     "plant.toml: [signals] maps no signal; add e.g. [signals.load]"),
    ("[signals.load]\ncolumn = 'x'\nunit = 'MW'\n", "plant.toml: [historian] is missing"),
    ("[historian\n", None),
])
def test_every_mistake_names_file_and_field(text, message):
    if message is None:
        with pytest.raises(TagMapError, match=r"^plant\.toml: not valid TOML: "):
            parse_tag_map(text, "plant.toml")
    else:
        _fails(text, message)


def test_load_names_the_file(tmp_path):
    path = tmp_path / "plant.toml"
    path.write_text(WIDE.replace('"MPa"', '"K"'), encoding="utf-8")
    with pytest.raises(TagMapError, match=re.escape(
        f"{path}: signals.main_steam_pressure.unit = 'K': signal main_steam_pressure has SI unit "
        "'Pa'; 'K' is not convertible to 'Pa'"
    )):
        load_tag_map(path)
    with pytest.raises(TagMapError, match=re.escape(f"{tmp_path / 'none.toml'}: cannot read")):
        load_tag_map(tmp_path / "none.toml")


@pytest.mark.parametrize("text", [WIDE, LONG])
def test_write_and_load_round_trip(tmp_path, text):
    original = parse_tag_map(text, "original.toml")
    path = tmp_path / "saved.toml"
    write_tag_map(original, path)
    loaded = load_tag_map(path)
    assert loaded.source == str(path)
    for key in ("layout", "time_column", "time_zone", "tag_column", "value_column",
                "quality_column"):
        assert getattr(loaded, key) == getattr(original, key)
    assert loaded.signals == original.signals  # ranges re-read exactly (round-off dropped)


def test_round_trip_escapes_awkward_column_names(tmp_path):
    awkward = TagMap(
        layout="wide", time_column='Zeit "UTC"', time_zone="UTC", tag_column=None,
        value_column=None, quality_column=None,
        signals={"load": TagSpec("load", "C:\\tags\\MKA01\tCE001 功率", "kW", (-1e6, 7e8))},
        source="generated",
    )
    path = tmp_path / "awkward.toml"
    write_tag_map(awkward, path)
    loaded = load_tag_map(path)
    assert loaded.time_column == awkward.time_column
    assert loaded.signals == awkward.signals
