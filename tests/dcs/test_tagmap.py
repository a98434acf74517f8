"""Tag maps: valid maps parse, every mistake is named with file and field, maps round-trip."""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest

from steamtwin.dcs.signals import SIGNALS
from steamtwin.dcs.tagmap import (
    QualityMapping,
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
     "plant.toml: signals.main_steam_flow.colum is not a tag map field (did you mean 'column'?); "
     "expected one of: column, depth, max_rate, node_id, noise, quality_column, range, resolution, "
     "time_constant, unit"),
    (WIDE.replace('unit = "t/h"', ""),
     "plant.toml: signals.main_steam_flow.unit is missing"),
    (WIDE.replace("[historian]", "[historain]"),
     "plant.toml: historain is not a tag map field (did you mean 'historian'?); "
     "expected one of: historian, signals"),
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


# --- detector keys: differences, not absolute values (issue 16) ---------------------------------

@pytest.mark.parametrize(("unit", "noise_si"), [
    ("degC", 0.5), ("K", 0.5), ("degF", 0.5 * 5 / 9), ("degR", 0.5 * 5 / 9)])
def test_noise_resolution_and_rate_convert_as_differences(unit, noise_si):
    tag_map = parse_tag_map(WIDE.replace(
        'unit = "degC"', f'unit = "{unit}"\nnoise = 0.5\nresolution = 0.1\nmax_rate = 2'),
        "plant.toml")
    spec = tag_map.signals["main_steam_temperature"]
    assert spec.noise_si == pytest.approx(noise_si, rel=1e-12)  # 0.5 degC of σ is 0.5 K
    assert spec.resolution_si == pytest.approx(noise_si / 5, rel=1e-12)
    assert spec.max_rate_si == pytest.approx(noise_si * 4, rel=1e-12)  # K/s
    assert tag_map.signals["main_steam_flow"].noise_si is None


def test_detector_keys_in_multiplicative_units():
    tag_map = parse_tag_map(WIDE.replace(
        'range = [0.0, 25.0]', 'range = [0.0, 25.0]\nnoise = 0.02\nmax_rate = 0.05').replace(
        'unit = "t/h"', 'unit = "t/h"\nresolution = 3.6'), "plant.toml")
    assert tag_map.signals["main_steam_pressure"].noise_si == pytest.approx(2e4)  # Pa
    assert tag_map.signals["main_steam_pressure"].max_rate_si == pytest.approx(5e4)  # Pa/s
    assert tag_map.signals["main_steam_flow"].resolution_si == pytest.approx(1.0)  # kg/s


@pytest.mark.parametrize("value", ["0", "-0.5", "inf", "nan", '"0.5"', "true", "[0.5]"])
@pytest.mark.parametrize(("key", "meaning", "per"), [
    ("noise", "instrument white-noise standard deviation", ""),
    ("resolution", "historian quantum", ""),
    ("max_rate", "physical rate limit", " per second")])
def test_detector_keys_must_be_positive_finite_numbers(key, meaning, per, value):
    text = WIDE.replace('unit = "degC"', f'unit = "degC"\n{key} = {value}')
    shown = repr(tomllib.loads(f"x = {value}")["x"])
    _fails(text, f"plant.toml: signals.main_steam_temperature.{key} = {shown}: expected the "
           f"{meaning} as a positive finite number in degC{per}")


# --- CSV dialect keys ----------------------------------------------------------------------------

def test_dialect_keys_parse():
    tag_map = parse_tag_map(WIDE.replace(
        'layout = "wide"', 'layout = "wide"\ndelimiter = "\\t"\ndecimal = ","\nencoding = "gbk"'),
        "plant.toml")
    assert (tag_map.delimiter, tag_map.decimal, tag_map.encoding) == ("\t", ",", "gbk")
    plain = parse_tag_map(WIDE, "plant.toml")
    assert plain.delimiter is plain.decimal is plain.encoding is None


@pytest.mark.parametrize(("line", "message"), [
    ('delimiter = ";;"', "historian.delimiter = ';;': expected one character that is not a "
     "letter, digit, '.', quote or line break, e.g. \",\", \";\", \"\\t\" or \"|\""),
    ('delimiter = "."', "historian.delimiter = '.': expected one character"),
    ('delimiter = "a"', "historian.delimiter = 'a': expected one character"),
    ('delimiter = "\\""', "historian.delimiter = '\"': expected one character"),
    ('delimiter = "\\n"', "historian.delimiter = '\\n': expected one character"),
    ("delimiter = 59", "historian.delimiter = 59: expected one character"),
    ('decimal = ";"', "historian.decimal = ';': expected \".\" or \",\""),
    ('delimiter = ","\ndecimal = ","', "historian.delimiter and historian.decimal are both ',';"
     " a CSV cannot use one character for both"),
    ('encoding = "klingon"', "historian.encoding = 'klingon': not a text encoding Python knows "
     "(e.g. \"utf-8\", \"gbk\", \"gb18030\", \"cp1252\")"),
    ('encoding = "hex"', "historian.encoding = 'hex': not a text encoding Python knows"),
    ('encoding = "undefined"', "historian.encoding = 'undefined': not a text encoding"),
    ('encoding = ""', "historian.encoding = '': expected a non-empty string"),
    ('encodng = "gbk"', "historian.encodng is not a tag map field (did you mean 'encoding'?)"),
])
def test_dialect_key_mistakes(line, message):
    with pytest.raises(TagMapError, match="^" + re.escape("plant.toml: " + message)):
        parse_tag_map(WIDE.replace('layout = "wide"', f'layout = "wide"\n{line}'), "plant.toml")


# --- quality mapping -----------------------------------------------------------------------------

def test_default_quality_mapping_follows_opc():
    default = parse_tag_map(LONG, "plant.toml").quality
    assert default == QualityMapping()
    assert default.exclude == ("bad", "uncertain")
    cases = [("Good", "good"), (" good_LocalOverride ", "good"),
             ("UncertainLastUsableValue", "uncertain"), ("BAD", "bad"),
             ("Bad_SensorFailure", "bad"), (192, "good"), (255, "good"), (216, "good"),
             (64, "uncertain"), (127, "uncertain"), (0, "bad"), (63, "bad"), ("28", "bad"),
             (np.int64(192), "good"), (192.0, "good"), (np.float64(64.0), "uncertain"),
             ("192.0", "good"), (128, None), (191, None), (256, None), (-1, None),
             ("OK", None), (1.5, None), ("", None), (float("nan"), None), (None, None),
             (True, None)]
    for value, expected in cases:
        assert default.classify(value) == expected, value


def test_explicit_quality_mapping_replaces_the_default():
    tag_map = parse_tag_map(LONG + '\n[historian.quality]\ngood = ["OK", 3]\nuncertain = ["?"]\n'
                            'bad = ["Fail", 0]\nexclude = ["bad"]\n', "plant.toml")
    quality = tag_map.quality
    assert (quality.good, quality.uncertain, quality.bad, quality.exclude) == (
        ("OK", 3), ("?",), ("Fail", 0), ("bad",))
    assert [quality.classify(v) for v in ("ok", "3", 3, "?", "FAIL", 0, "Good", 192)] == [
        "good", "good", "good", "uncertain", "bad", "bad", None, None]
    exclude_only = parse_tag_map(LONG + '\n[historian.quality]\nexclude = []\n', "p.toml")
    assert exclude_only.quality.exclude == ()
    assert exclude_only.quality.classify("Bad") == "bad"  # default classes kept


WIDE_QUALITY = WIDE.replace('unit = "t/h"', 'unit = "t/h"\nquality_column = "CF001 Q"')


@pytest.mark.parametrize(("text", "message"), [
    (LONG + '\n[historian.quality]\ngood = ["OK"]\nbad = ["ok"]\n',
     "historian.quality.bad lists 'ok', which historian.quality.good lists too; a value has "
     "one class"),
    (LONG + "\n[historian.quality]\ngood = [192.0]\n",
     "historian.quality.good = [192.0]: expected a list of quality values as they appear in the "
     "file: non-empty strings or integers"),
    (LONG + '\n[historian.quality]\ngood = "Good"\n', "historian.quality.good = 'Good': expected"),
    (LONG + '\n[historian.quality]\ngood = [" "]\n', "historian.quality.good = [' ']: expected"),
    (LONG + "\n[historian.quality]\nbad = [true]\n", "historian.quality.bad = [True]: expected"),
    (LONG + '\n[historian.quality]\nexclude = ["good"]\n',
     "historian.quality.exclude = ['good']: expected a list of the classes excluded from model "
     "inputs, from \"bad\" and \"uncertain\""),
    (LONG + '\n[historian.quality]\nexclude = ["bad", "bad"]\n',
     "historian.quality.exclude = ['bad', 'bad']: expected"),
    (LONG + '\n[historian.quality]\nbda = ["x"]\n',
     "historian.quality.bda is not a tag map field (did you mean 'bad'?)"),
    (LONG.replace('quality_column = "quality"', 'quality_column = "quality"\nquality = 1'),
     "historian.quality must be a table (good, uncertain, bad, exclude)"),
    (WIDE + '\n[historian.quality]\nexclude = ["bad"]\n',
     "[historian.quality] is set but no quality column is configured (historian.quality_column "
     "in the long layout, signals.<name>.quality_column in the wide layout)"),
    (LONG.replace('unit = "MW"', 'unit = "MW"\nquality_column = "q"'),
     "signals.load.quality_column is only used with layout = \"wide\"; the long layout has one "
     "quality column for all tags (historian.quality_column)"),
    (WIDE_QUALITY.replace('"CF001 Q"', '"Timestamp"'),
     "signals.main_steam_flow.quality_column = 'Timestamp' is the time column"),
    (WIDE_QUALITY.replace('"CF001 Q"', '"10LBA10CP001"'),
     "signals.main_steam_flow.quality_column = '10LBA10CP001' is the value column of "
     "signals.main_steam_pressure"),
])
def test_quality_mistakes(text, message):
    with pytest.raises(TagMapError, match="^" + re.escape("plant.toml: " + message)):
        parse_tag_map(text, "plant.toml")


def test_wide_quality_column_parses():
    tag_map = parse_tag_map(WIDE_QUALITY + '\n[historian.quality]\nexclude = ["bad"]\n',
                            "plant.toml")
    assert tag_map.signals["main_steam_flow"].quality_column == "CF001 Q"
    assert tag_map.signals["main_steam_pressure"].quality_column is None
    assert tag_map.has_quality
    assert not parse_tag_map(WIDE, "plant.toml").has_quality


@pytest.mark.parametrize("text", [
    WIDE_QUALITY.replace('layout = "wide"', 'layout = "wide"\ndelimiter = "\\t"\ndecimal = ","\n'
                         'encoding = "gb18030"').replace(
        'unit = "degC"', 'unit = "degF"\nnoise = 0.9\nresolution = 0.1\nmax_rate = 3.7')
    + '\n[historian.quality]\ngood = ["OK", 192]\nbad = ["Bad \\"x\\""]\nexclude = ["bad"]\n',
    LONG + '\n[historian.quality]\nexclude = []\n',
])
def test_new_keys_round_trip(tmp_path, text):
    original = parse_tag_map(text, "original.toml")
    path = tmp_path / "saved.toml"
    write_tag_map(original, path)
    loaded = load_tag_map(path)
    for key in ("delimiter", "decimal", "encoding", "quality", "signals"):
        assert getattr(loaded, key) == getattr(original, key), key
    assert "noise = 0.9\n" in path.read_text(encoding="utf-8") or original.layout == "long"


def test_opc_ua_node_ids_parse_round_trip_and_are_checked(tmp_path):
    """The live twin's OPC UA node id per signal (issue 21, item 2)."""
    text = WIDE.replace('unit = "MPa"', 'unit = "MPa"\nnode_id = "nsu=urn:plant;s=10LBA10CP001"')
    text = text.replace('unit = "t/h"', 'unit = "t/h"\nnode_id = "ns=3;i=1001"')
    tag_map = parse_tag_map(text, "plant.toml")
    assert tag_map.signals["main_steam_pressure"].node_id == "nsu=urn:plant;s=10LBA10CP001"
    assert tag_map.signals["main_steam_flow"].node_id == "ns=3;i=1001"
    assert tag_map.signals["main_steam_temperature"].node_id is None
    path = tmp_path / "saved.toml"
    write_tag_map(tag_map, path)
    assert load_tag_map(path).signals == tag_map.signals
    _fails(WIDE.replace('unit = "MPa"', 'unit = "MPa"\nnode_id = "10LBA10CP001"'),
           'plant.toml: signals.main_steam_pressure.node_id = \'10LBA10CP001\': expected an '
           'OPC UA node id such as "ns=2;s=10LBA10CP001", "nsu=urn:plant;s=TAG" or '
           '"ns=3;i=1001"')
    twice = WIDE.replace('unit = "MPa"', 'unit = "MPa"\nnode_id = "ns=2;s=X"').replace(
        'unit = "t/h"', 'unit = "t/h"\nnode_id = "ns=2;s=X"')
    _fails(twice, "plant.toml: signals.main_steam_flow.node_id = 'ns=2;s=X' is already the "
                  "node of signals.main_steam_pressure; each OPC UA node maps one signal")
