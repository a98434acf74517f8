"""Historian reader: units to SI, file order kept, extras kept, errors naming file/column/row."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from steamtwin.dcs.readers import (
    NOTE_KEYS,
    HistorianFormatError,
    canonical_to_historian,
    read_historian,
)
from steamtwin.dcs.tagmap import parse_tag_map

HISTORIAN = """
[historian]
layout = "{layout}"
time_column = "Timestamp"
{zone}
{long}

[signals.main_steam_pressure]
column = "10LBA10CP001"
unit = "bar"
range = [0, 250]

[signals.main_steam_temperature]
column = "10LBA10CT001"
unit = "degC"

[signals.main_steam_flow]
column = "10LBA10CF001"
unit = "t/h"

[signals.load]
column = "10MKA01CE001"
unit = "MW"
"""
LONG_FIELDS = 'tag_column = "tag"\nvalue_column = "value"\nquality_column = "quality"'
COLUMNS = {
    "main_steam_pressure": "10LBA10CP001",
    "main_steam_temperature": "10LBA10CT001",
    "main_steam_flow": "10LBA10CF001",
    "load": "10MKA01CE001",
}


def _map(layout="wide", zone="Asia/Shanghai"):
    text = HISTORIAN.format(
        layout=layout,
        zone=f'time_zone = "{zone}"' if zone else "",
        long=LONG_FIELDS if layout == "long" else "",
    )
    return parse_tag_map(text, "plant.toml")


# Local plant time (UTC+8), one duplicate and one step back in time: both must survive.
STAMPS = ["2026-03-01 10:00:00", "2026-03-01 10:00:01", "2026-03-01 10:00:01",
          "2026-03-01 10:00:03", "2026-03-01 10:00:02", "2026-03-01 10:00:04"]
EXPECTED_UTC = pd.DatetimeIndex(
    ["2026-03-01 02:00:00", "2026-03-01 02:00:01", "2026-03-01 02:00:01",
     "2026-03-01 02:00:03", "2026-03-01 02:00:02", "2026-03-01 02:00:04"],
    name="time").tz_localize("UTC").as_unit("ns")


def _wide_frame() -> pd.DataFrame:
    n = len(STAMPS)
    return pd.DataFrame({
        "Timestamp": STAMPS,
        "10LBA10CP001": 160.0 + np.arange(n),  # bar
        "10LBA10CT001": 538.0 + np.arange(n),  # degC
        "10LBA10CF001": [1800.0, 1801.0, np.nan, 1803.0, 1804.0, 1805.0],  # t/h, one gap
        "10MKA01CE001": 600.0 - np.arange(n),  # MW
        "10LAB10AA001": ["OPEN", "OPEN", "CLOSED", "OPEN", "OPEN", "OPEN"],  # unmapped
        "10HAD10CT001": np.linspace(300.0, 305.0, n),  # unmapped number
    })


def _long_frame() -> pd.DataFrame:
    """The wide frame as long rows, time-major (row by row of the wide file)."""
    wide = _wide_frame()
    long = wide.melt(id_vars="Timestamp", var_name="tag", value_name="value", ignore_index=False)
    long = long.sort_index(kind="stable").reset_index(drop=True)
    long = long[long["value"].notna()].reset_index(drop=True)
    long["value"] = long["value"].astype(str)  # numbers and "OPEN" share one text column
    long["quality"] = "GOOD"
    return long


def _write(frame: pd.DataFrame, path: Path) -> Path:
    if path.suffix == ".csv":
        frame.to_csv(path, index=False)
    else:
        frame.to_parquet(path, index=False)
    return path


def _expected_signals() -> pd.DataFrame:
    wide = _wide_frame()
    return pd.DataFrame({
        "main_steam_pressure": wide["10LBA10CP001"].to_numpy() * 1e5,
        "main_steam_temperature": wide["10LBA10CT001"].to_numpy() + 273.15,
        "main_steam_flow": wide["10LBA10CF001"].to_numpy() / 3.6,
        "load": wide["10MKA01CE001"].to_numpy() * 1e6,
    }, index=EXPECTED_UTC)


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_wide_read_converts_to_si_and_keeps_order_and_extras(tmp_path, suffix):
    data = read_historian(_write(_wide_frame(), tmp_path / f"h{suffix}"), _map())
    pd.testing.assert_frame_equal(data.signals, _expected_signals(), rtol=1e-12)
    assert data.signals["main_steam_pressure"].iloc[0] == pytest.approx(16.0e6)  # 160 bar
    assert data.signals["main_steam_temperature"].iloc[0] == pytest.approx(811.15)  # 538 °C
    assert data.signals["main_steam_flow"].iloc[0] == pytest.approx(500.0)  # 1800 t/h
    assert data.signals["load"].iloc[0] == pytest.approx(600e6)  # 600 MW
    assert list(data.extras.columns) == ["10LAB10AA001", "10HAD10CT001"]
    assert data.extras.index.equals(data.signals.index)
    assert list(data.extras["10LAB10AA001"]) == list(_wide_frame()["10LAB10AA001"])
    assert data.notes == {**dict.fromkeys(NOTE_KEYS, 0), "timestamps_localized": 6}
    assert data.source == str(tmp_path / f"h{suffix}")
    assert data.missing_signals == {}


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_long_layout_gives_the_same_signals_as_wide(tmp_path, suffix):
    wide = read_historian(_write(_wide_frame(), tmp_path / f"w{suffix}"), _map())
    long = read_historian(_write(_long_frame(), tmp_path / f"l{suffix}"), _map("long"))
    pd.testing.assert_frame_equal(long.signals, wide.signals)
    # Disorder in the file: the key order is the file's, the duplicate timestamp stays twice.
    assert long.notes["long_tags_out_of_order"] == 6
    assert long.notes["long_duplicate_entries"] == 5  # 10:00:01 twice; flow has no 2nd value
    assert "10LAB10AA001" in long.extras.columns
    assert list(long.extras["quality:10LBA10CP001"]) == ["GOOD"] * 6
    assert long.extras["quality:10LBA10CF001"].isna().tolist() == [
        False, False, True, False, False, False]


def test_csv_and_parquet_give_the_same_frame(tmp_path):
    tag_map = _map()
    csv = read_historian(_write(_wide_frame(), tmp_path / "h.csv"), tag_map)
    parquet = read_historian(_write(_wide_frame(), tmp_path / "h.parquet"), tag_map)
    pd.testing.assert_frame_equal(csv.signals, parquet.signals)
    pd.testing.assert_frame_equal(csv.extras, parquet.extras)


def test_parquet_timestamp_columns_naive_and_aware(tmp_path):
    frame = _wide_frame()
    frame["Timestamp"] = pd.to_datetime(frame["Timestamp"])  # naive: local plant time
    naive = read_historian(_write(frame, tmp_path / "naive.parquet"), _map())
    frame["Timestamp"] = frame["Timestamp"].dt.tz_localize("Asia/Shanghai")
    aware = read_historian(_write(frame, tmp_path / "aware.parquet"), _map(zone=None))
    assert naive.signals.index.equals(EXPECTED_UTC)
    assert aware.signals.index.equals(EXPECTED_UTC)
    assert naive.notes["timestamps_localized"] == 6
    assert aware.notes["timestamps_localized"] == 0


def test_offsets_are_honoured_and_naive_rows_localized(tmp_path):
    path = tmp_path / "mixed.csv"
    path.write_text("Timestamp,10MKA01CE001\n2026-03-01T10:00:00+08:00,1\n"
                    "2026-03-01T02:00:01Z,2\n2026-03-01 10:00:02,3\n", encoding="utf-8")
    data = read_historian(path, _map())
    assert data.signals.index.equals(pd.DatetimeIndex(
        ["2026-03-01 02:00:00", "2026-03-01 02:00:01", "2026-03-01 02:00:02"], name="time"
    ).tz_localize("UTC").as_unit("ns"))
    assert data.notes["timestamps_localized"] == 1


def test_long_tag_sorted_export_is_merged_in_time_order(tmp_path):
    # Exception-based historian: each tag has its own timestamps, rows grouped by tag.
    long = pd.DataFrame({
        "Timestamp": ["2026-03-01T00:00:00Z", "2026-03-01T00:00:05Z", "2026-03-01T00:00:02Z",
                      "2026-03-01T00:00:05Z", "2026-03-01T00:00:05Z"],
        "tag": ["10MKA01CE001", "10MKA01CE001", "10LBA10CP001", "10LBA10CP001", "10LBA10CP001"],
        "value": [600.0, 590.0, 160.0, 161.0, 162.0],
        "quality": [0, 0, 0, 0, 1],
    })
    data = read_historian(_write(long, tmp_path / "l.parquet"), _map("long", zone=None))
    assert [str(t.time()) for t in data.signals.index] == [
        "00:00:00", "00:00:02", "00:00:05", "00:00:05"]
    load = data.signals["load"].to_numpy()
    assert load[0] == 600e6
    assert np.isnan(load[1])
    assert load[2] == 590e6  # first 00:00:05 row; the repeat of the pressure tag has no load
    assert np.isnan(load[3])
    assert data.signals["main_steam_pressure"].tolist()[1:] == [160e5, 161e5, 162e5]
    assert data.notes["long_duplicate_entries"] == 1
    assert data.notes["long_tags_out_of_order"] == 0
    assert data.extras["quality:10LBA10CP001"].tolist()[1:] == [0, 0, 1]
    assert data.missing_signals == {"main_steam_temperature": "10LBA10CT001",
                                    "main_steam_flow": "10LBA10CF001"}
    assert data.notes["missing_signal_columns"] == 2


def test_missing_mapped_column_is_a_note_not_an_error(tmp_path):
    frame = _wide_frame().drop(columns=["10LBA10CF001"])
    data = read_historian(_write(frame, tmp_path / "h.csv"), _map())
    assert "main_steam_flow" not in data.signals.columns
    assert data.notes["missing_signal_columns"] == 1
    assert data.missing_signals == {"main_steam_flow": "10LBA10CF001"}


def test_blank_lines_and_empty_cells(tmp_path):
    path = tmp_path / "h.csv"
    path.write_text("Timestamp,10MKA01CE001,10LBA10CP001\n2026-03-01 10:00:00,600,\n\n"
                    "2026-03-01 10:00:01, ,160\n", encoding="utf-8")
    data = read_historian(path, _map())
    assert np.isnan(data.signals["main_steam_pressure"].iloc[0])
    assert np.isnan(data.signals["load"].iloc[1])
    assert len(data.signals) == 2
    assert data.notes["blank_lines"] == 1


def _raises(path: Path, tag_map, message: str) -> None:
    with pytest.raises(HistorianFormatError, match="^" + re.escape(message)):
        read_historian(path, tag_map)


def _csv(tmp_path: Path, text: str, name: str = "h.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_unreadable_files(tmp_path):
    _raises(tmp_path / "none.csv", _map(), f"{tmp_path / 'none.csv'}: cannot read CSV:")
    for name, text in (("empty.csv", ""), ("blank.csv", "\n \n")):
        _raises(_csv(tmp_path, text, name), _map(), f"{tmp_path / name}: cannot read CSV: the file "
                "is empty (no header, no data rows)")
    garbage = tmp_path / "g.parquet"
    garbage.write_bytes(b"not parquet at all")
    _raises(garbage, _map(), f"{garbage}: cannot read Parquet:")
    _raises(_csv(tmp_path, "x", "h.xlsx"), _map(),
            f"{tmp_path / 'h.xlsx'}: unsupported file type '.xlsx'; expected .csv or .parquet")


def test_missing_time_column(tmp_path):
    path = _csv(tmp_path, "Time,10MKA01CE001\n2026-03-01 10:00:00,600\n")
    _raises(path, _map(), f"{path}: no column 'Timestamp' (historian.time_column in plant.toml); "
            "columns are: Time, 10MKA01CE001")


def test_unparseable_timestamp_names_line_and_value(tmp_path):
    path = _csv(tmp_path, "Timestamp,10MKA01CE001\n2026-03-01 10:00:00,600\n"
                "2026-03-01 10:00:01,600\n2026-02-30 10:00:02,600\n")
    _raises(path, _map(), f"{path}: column 'Timestamp' line 4: '2026-02-30 10:00:02' is not a "
            "timestamp (expected ISO 8601, e.g. '2026-03-01 10:00:00' or "
            "'2026-03-01T10:00:00+08:00')")
    frame = pd.DataFrame({"Timestamp": ["2026-03-01 10:00:00", "soon"], "10MKA01CE001": [1, 2]})
    parquet = _write(frame, tmp_path / "h.parquet")
    _raises(parquet, _map(), f"{parquet}: column 'Timestamp' row index 1: 'soon' is not a "
            "timestamp")


def test_empty_timestamp(tmp_path):
    path = _csv(tmp_path, "Timestamp,10MKA01CE001\n2026-03-01 10:00:00,600\n,601\n")
    _raises(path, _map(), f"{path}: column 'Timestamp' line 3: empty timestamp (expected ISO 8601")


def test_naive_timestamps_need_a_time_zone(tmp_path):
    path = _csv(tmp_path, "Timestamp,10MKA01CE001\n2026-03-01T10:00:00Z,600\n"
                "2026-03-01 10:00:01,600\n")
    _raises(path, _map(zone=None), f"{path}: column 'Timestamp' line 3: '2026-03-01 10:00:01' has "
            "no UTC offset and plant.toml sets no historian.time_zone; add time_zone "
            "(e.g. \"Asia/Shanghai\") to the tag map or export with offsets")


def test_ambiguous_local_time_is_named(tmp_path):
    path = _csv(tmp_path, "Timestamp,10MKA01CE001\n2026-10-25 01:30:00,600\n"
                "2026-10-25 02:30:00,600\n")
    _raises(path, _map(zone="Europe/Berlin"), f"{path}: column 'Timestamp' line 3: "
            "'2026-10-25 02:30:00' is ambiguous or does not exist in time zone 'Europe/Berlin' "
            "(daylight-saving change); export with UTC offsets")


def test_non_numeric_values_name_column_line_value_and_unit(tmp_path):
    path = _csv(tmp_path, "Timestamp,10LBA10CP001\n2026-03-01 10:00:00,160\n\n"
                "2026-03-01 10:00:01,Bad Input\n")
    _raises(path, _map(), f"{path}: column '10LBA10CP001' line 4: 'Bad Input' is not a number in "
            "bar (signal main_steam_pressure)")
    frame = pd.DataFrame({"Timestamp": ["2026-03-01 10:00:00", "2026-03-01 10:00:01"],
                          "10LBA10CT001": ["538", "I/O Timeout"]})
    parquet = _write(frame, tmp_path / "h.parquet")
    _raises(parquet, _map(), f"{parquet}: column '10LBA10CT001' row index 1: 'I/O Timeout' is not "
            "a number in degC (signal main_steam_temperature)")
    long = _csv(tmp_path, "Timestamp,tag,value,quality\n2026-03-01 10:00:00,10LBA10CF001,1800,0\n"
                "2026-03-01 10:00:00,10LAB10AA001,OPEN,0\n2026-03-01 10:00:01,10LBA10CF001,n/a,0\n",
                "long.csv")
    _raises(long, _map("long"), f"{long}: tag '10LBA10CF001' (column 'value') line 4: 'n/a' is not "
            "a number in t/h (signal main_steam_flow)")


def test_long_layout_format_errors(tmp_path):
    path = _csv(tmp_path, "Timestamp,name,value\n2026-03-01 10:00:00,10LBA10CF001,1800\n")
    _raises(path, _map("long"), f"{path}: no column 'tag' (historian.tag_column in plant.toml)")
    path = _csv(tmp_path, "Timestamp,tag,value\n2026-03-01 10:00:00,,1800\n", "empty_tag.csv")
    _raises(path, _map("long"), f"{path}: column 'tag' line 2: empty tag; every row of the long "
            "layout needs a tag")
    path = _csv(tmp_path, "Timestamp,tag,value\n2026-03-01 10:00:00,10LBA10CF001,1800\n", "q.csv")
    assert read_historian(path, _map("long")).notes["missing_quality_column"] == 1


def test_repeated_mapped_header_is_an_error_unmapped_is_a_note(tmp_path):
    path = _csv(tmp_path, "Timestamp,10MKA01CE001,10MKA01CE001\n2026-03-01 10:00:00,600,601\n")
    _raises(path, _map(), f"{path}: column '10MKA01CE001' appears more than once in the header "
            "(line 1)")
    path = _csv(tmp_path, "Timestamp,X,X\n2026-03-01 10:00:00,1,2\n", "x.csv")
    data = read_historian(path, _map())
    assert data.notes["duplicate_column_names"] == 1
    assert data.extras.shape == (1, 2)


def test_canonical_to_historian_round_trip(tmp_path):
    signals = _expected_signals()
    historian = canonical_to_historian(signals, _map())
    assert list(historian.columns) == ["Timestamp", *COLUMNS.values()]
    assert historian["10LBA10CP001"].iloc[0] == pytest.approx(160.0)
    assert str(historian["Timestamp"].dt.tz) == "Asia/Shanghai"
    for suffix in (".csv", ".parquet"):
        back = read_historian(_write(historian, tmp_path / f"rt{suffix}"), _map())
        pd.testing.assert_frame_equal(back.signals, signals, rtol=1e-12)
    with pytest.raises(ValueError, match=r"signals \['hp_power'\] are not mapped in plant.toml"):
        canonical_to_historian(signals.assign(hp_power=1.0), _map())


finite = st.floats(min_value=-1e9, max_value=1e9, allow_nan=False, allow_infinity=False)


@settings(max_examples=25, deadline=None)
@given(
    values=st.lists(st.tuples(finite, finite, finite, finite), min_size=1, max_size=12),
    seconds=st.lists(st.integers(0, 10**6), min_size=12, max_size=12),
    suffix=st.sampled_from([".csv", ".parquet"]),
)
def test_random_values_round_trip(values, seconds, suffix):
    index = pd.DatetimeIndex(
        pd.Timestamp("2026-03-01", tz="UTC") + pd.to_timedelta(seconds[: len(values)], unit="s"),
        name="time",
    ).as_unit("ns")
    signals = pd.DataFrame(values, columns=list(COLUMNS), index=index)
    with tempfile.TemporaryDirectory() as folder:
        path = _write(canonical_to_historian(signals, _map()), Path(folder) / f"rt{suffix}")
        back = read_historian(path, _map())
    assert back.signals.index.equals(index)  # order and duplicates as written
    scale = np.maximum(np.abs(signals.to_numpy()), 1e-6)
    assert np.all(np.abs(back.signals.to_numpy() - signals.to_numpy()) <= 1e-12 * scale + 1e-9)


# --- CSV dialect and encoding (issue 16, findings 6 and 7) ---------------------------------------

CHINESE = """
[historian]
layout = "wide"
time_column = "时间"
time_zone = "Asia/Shanghai"
{extra}

[signals.load]
column = "1号机负荷"
unit = "MW"

[signals.main_steam_temperature]
column = "主汽温度"
unit = "degC"
"""
CHINESE_ROWS = ("时间,1号机负荷,主汽温度\n2026-03-01 10:00:00,600.5,538.5\n"
                "2026-03-01 10:00:01,601,539\n")


def _chinese_map(extra: str = ""):
    return parse_tag_map(CHINESE.format(extra=extra), "plant.toml")


def _bytes(tmp_path: Path, data: bytes, name: str = "h.csv") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _check_chinese(data) -> None:
    assert data.signals["load"].tolist() == [600.5e6, 601e6]
    assert data.signals["main_steam_temperature"].tolist() == pytest.approx([811.65, 812.15])
    assert data.signals.index[0] == pd.Timestamp("2026-03-01 02:00:00", tz="UTC")


def test_gbk_csv_reads_by_sniffing_and_with_the_encoding_key(tmp_path):
    path = _bytes(tmp_path, CHINESE_ROWS.encode("gbk"))
    sniffed = read_historian(path, _chinese_map())
    _check_chinese(sniffed)
    assert sniffed.dialect == {"encoding": "gb18030", "encoding_source": "sniffed",
                               "delimiter": ",", "delimiter_source": "sniffed",
                               "decimal": ".", "decimal_source": "default"}
    declared = read_historian(path, _chinese_map('encoding = "gbk"'))
    _check_chinese(declared)
    assert (declared.dialect["encoding"], declared.dialect["encoding_source"]) == (
        "gbk", "tag map")
    _raises(path, _chinese_map('encoding = "utf-8"'), f"{path}: cannot decode the file as "
            "'utf-8' (historian.encoding in plant.toml): 'utf-8' codec can't decode byte")


def test_utf8_with_and_without_bom_and_utf16(tmp_path):
    plain = read_historian(_bytes(tmp_path, CHINESE_ROWS.encode("utf-8")), _chinese_map())
    _check_chinese(plain)
    assert (plain.dialect["encoding"], plain.dialect["encoding_source"]) == ("utf-8", "default")
    bom = read_historian(_bytes(tmp_path, CHINESE_ROWS.encode("utf-8-sig"), "b.csv"),
                         _chinese_map())
    _check_chinese(bom)
    assert (bom.dialect["encoding"], bom.dialect["encoding_source"]) == ("utf-8-sig", "sniffed")
    utf16 = read_historian(_bytes(tmp_path, CHINESE_ROWS.encode("utf-16"), "u.csv"),
                           _chinese_map())
    _check_chinese(utf16)
    assert utf16.dialect["encoding"] == "utf-16"


def test_western_cp1252_export_is_sniffed(tmp_path):
    text = "Timestamp;10MKA01CE001;Temp °C\n2026-03-01 10:00:00;600;1\n"
    data = read_historian(_bytes(tmp_path, text.encode("cp1252")), _map())
    assert (data.dialect["encoding"], data.dialect["encoding_source"]) == ("cp1252", "sniffed")
    assert list(data.extras.columns) == ["Temp °C"]
    assert data.signals["load"].tolist() == [600e6]


def test_undecodable_and_binary_files_name_the_key(tmp_path):
    path = _bytes(tmp_path, b"Timestamp,x\n\x81\x8d\x8f\x90\x9d\x80\xff\n")
    _raises(path, _map(), f"{path}: cannot tell the file's encoding: not UTF-8 (byte 12), "
            "GB18030 or cp1252; set historian.encoding in plant.toml")
    binary = _bytes(tmp_path, b"Timestamp,x\n\x00\x01\x02\n", "bin.csv")
    _raises(binary, _map(), f"{binary}: line 2 holds a NUL character: not CSV text in utf-8 "
            "(default); set historian.encoding in plant.toml")


@pytest.mark.parametrize("delimiter", [";", "\t", "|"])
def test_delimiter_and_decimal_comma_are_sniffed(tmp_path, delimiter):
    rows = [["Timestamp", "10LBA10CP001", "10MKA01CE001", "note, free text"],
            ["2026-03-01 10:00:00", "160,5", "600", "a"],
            ["2026-03-01 10:00:01", "161,25", "-1,5e2", "b"]]
    path = _csv(tmp_path, "\n".join(delimiter.join(row) for row in rows) + "\n")
    data = read_historian(path, _map())
    assert data.dialect == {"encoding": "utf-8", "encoding_source": "default",
                            "delimiter": delimiter, "delimiter_source": "sniffed",
                            "decimal": ",", "decimal_source": "sniffed"}
    assert data.signals["main_steam_pressure"].tolist() == pytest.approx([160.5e5, 161.25e5])
    assert data.signals["load"].tolist() == [600e6, -150e6]
    assert list(data.extras.columns) == ["note, free text"]


def test_dialect_from_the_tag_map(tmp_path):
    tag_map = parse_tag_map(HISTORIAN.format(
        layout="wide", zone='time_zone = "UTC"\ndelimiter = ";"\ndecimal = ","', long=""),
        "plant.toml")
    # One column name with a comma and one-number lines: sniffing alone could not tell.
    path = _csv(tmp_path, "Timestamp;10LBA10CP001\n2026-03-01 10:00:00;160,5\n")
    data = read_historian(path, tag_map)
    assert data.signals["main_steam_pressure"].tolist() == [160.5e5]
    assert data.dialect["delimiter_source"] == data.dialect["decimal_source"] == "tag map"
    # With decimal "," a "." is not a decimal point (it may be a thousands separator).
    path = _csv(tmp_path, "Timestamp;10LBA10CP001\n2026-03-01 10:00:00;1.605\n", "dot.csv")
    _raises(path, tag_map, f"{path}: column '10LBA10CP001' line 2: '1.605' is not a number in bar "
            "(signal main_steam_pressure); the file is read with decimal ',' (tag map): if '.' is "
            "its decimal separator, set historian.decimal = \".\" in plant.toml")


def test_wrong_dialect_errors_suggest_the_tag_map_key(tmp_path):
    comma_map = parse_tag_map(HISTORIAN.format(
        layout="wide", zone='time_zone = "UTC"\ndelimiter = ","', long=""), "plant.toml")
    path = _csv(tmp_path, "Timestamp;10LBA10CP001\n2026-03-01 10:00:00;160\n")
    _raises(path, comma_map, f"{path}: no column 'Timestamp' (historian.time_column in "
            "plant.toml); columns are: Timestamp;10LBA10CP001; the header holds ';' but was split "
            "at ',' (tag map); if the file is ';'-separated, set historian.delimiter = \";\" in "
            "plant.toml")
    dot_map = parse_tag_map(HISTORIAN.format(
        layout="wide", zone='time_zone = "UTC"\ndecimal = "."', long=""), "plant.toml")
    path = _csv(tmp_path, "Timestamp;10LBA10CP001\n2026-03-01 10:00:00;160,5\n", "c.csv")
    _raises(path, dot_map, f"{path}: column '10LBA10CP001' line 2: '160,5' is not a number in bar "
            "(signal main_steam_pressure); it looks like a decimal comma: set historian.decimal = "
            "\",\" in plant.toml")
    path = _csv(tmp_path, 'Timestamp,10LBA10CP001\n2026-03-01 10:00:00,"160,5"\n', "q.csv")
    _raises(path, _map(), f"{path}: column '10LBA10CP001' line 2: '160,5' is not a number in bar "
            "(signal main_steam_pressure); it looks like a decimal comma: set historian.decimal = "
            "\",\" and another historian.delimiter in plant.toml")


def test_lines_with_more_fields_than_the_header(tmp_path):
    how = ("read with delimiter ',' (sniffed), decimal '.' (default), encoding 'utf-8' "
           "(default); set historian.delimiter/decimal/encoding in plant.toml if these are wrong)")
    path = _csv(tmp_path, "Timestamp,10LBA10CP001\n2026-03-01 10:00:00,1,2,3\n"
                "2026-03-01 10:00:01,1,2,3\n")
    _raises(path, _map(), f"{path}: the first data line has 4 fields but the header (line 1) has "
            f"2 ({how}")
    path = _csv(tmp_path, "Timestamp,10LBA10CP001\n2026-03-01 10:00:00,1\n"
                "2026-03-01 10:00:01,1,2\n", "later.csv")
    _raises(path, _map(), f"{path}: cannot read CSV: Error tokenizing data. C error: Expected 2 "
            f"fields in line 3, saw 3 ({how}")


def test_parquet_has_no_dialect(tmp_path):
    data = read_historian(_write(_wide_frame(), tmp_path / "h.parquet"), _map())
    assert data.dialect == {}


# --- header-only files (finding 7) ---------------------------------------------------------------

@pytest.mark.parametrize("layout", ["wide", "long"])
def test_header_only_files_are_errors(tmp_path, layout):
    frame = (_wide_frame() if layout == "wide" else _long_frame()).iloc[:0]
    parquet = _write(frame, tmp_path / "h.parquet")
    _raises(parquet, _map(layout), f"{parquet}: no data rows: the file holds 0 rows (columns: "
            f"{', '.join(frame.columns)}); a historian export needs at least one sample")
    header = ",".join(frame.columns)
    for name, text in (("h.csv", header + "\n"), ("blank.csv", header + "\n\n\n"),
                       ("bare.csv", header)):
        path = _csv(tmp_path, text, name)
        _raises(path, _map(layout), f"{path}: no data rows: the file holds only its header "
                "(line 1); a historian export needs at least one sample")


# --- quality column (finding 4) -----------------------------------------------------------------

def _long_quality(tmp_path: Path, qualities: list[object], tag_map=None, name="q.csv"):
    lines = ["Timestamp,tag,value,quality"]
    for second, quality in enumerate(qualities):
        lines.append(f"2026-03-01 10:00:{second:02d},10LBA10CT001,{538 + second},{quality}")
        lines.append(f"2026-03-01 10:00:{second:02d},10MKA01CE001,600,Good")
    path = _csv(tmp_path, "\n".join(lines) + "\n", name)
    return path, read_historian(path, tag_map or _map("long"))


def test_long_quality_bad_and_uncertain_are_masked(tmp_path):
    qualities = ["Good", "Bad", "Uncertain_LastUsableValue", "GOOD_LOCAL_OVERRIDE",
                 "bad sensor failure", "Good"]
    _, data = _long_quality(tmp_path, qualities)
    assert set(data.bad_quality) == {"main_steam_temperature", "load"}
    assert data.bad_quality["main_steam_temperature"].tolist() == [
        False, True, True, False, True, False]
    assert data.bad_quality["main_steam_temperature"].dtype == bool
    assert not data.bad_quality["load"].any()
    assert data.quality_counts == {
        "main_steam_temperature": {"good": 3, "uncertain": 1, "bad": 2},
        "load": {"good": 6, "uncertain": 0, "bad": 0}}
    assert data.notes["quality_excluded"] == 3
    # The values themselves are read unchanged; the mask says which to exclude.
    assert data.signals["main_steam_temperature"].tolist() == pytest.approx(
        [811.15 + k for k in range(6)])


def test_quality_exclude_and_explicit_mapping(tmp_path):
    keep_uncertain = parse_tag_map(HISTORIAN.format(
        layout="long", zone='time_zone = "UTC"',
        long=LONG_FIELDS + '\n[historian.quality]\nexclude = ["bad"]'), "plant.toml")
    _, data = _long_quality(tmp_path, ["Good", "Bad", "Uncertain"], keep_uncertain)
    assert data.bad_quality["main_steam_temperature"].tolist() == [False, True, False]
    explicit = parse_tag_map(HISTORIAN.format(
        layout="long", zone='time_zone = "UTC"',
        long=LONG_FIELDS + '\n[historian.quality]\ngood = ["OK", "Good", 0]\n'
                           'uncertain = ["?"]\nbad = ["FAIL"]'), "plant.toml")
    _, data = _long_quality(tmp_path, ["OK", "FAIL", "?", "ok ", "0"], explicit, "e.csv")
    assert data.bad_quality["main_steam_temperature"].tolist() == [
        False, True, True, False, False]
    with pytest.raises(HistorianFormatError, match=re.escape(
            "x.csv: tag '10LBA10CT001' (column 'quality') line 4: quality 'Bad' (signal "
            "main_steam_temperature) is not classified by "
            "historian.quality; list it under [historian.quality] good, uncertain or bad in "
            "plant.toml")):
        _long_quality(tmp_path, ["OK", "Bad"], explicit, "x.csv")


def test_opc_da_numeric_quality_by_default(tmp_path):
    path = _write(pd.DataFrame({
        "Timestamp": [f"2026-03-01T00:00:0{k}Z" for k in range(6)],
        "tag": ["10LBA10CT001"] * 6,
        "value": [538.0] * 6,
        "quality": [192, 216, 64, 87, 0, 28],  # good, good override, uncertain x2, bad x2
    }), tmp_path / "q.parquet")
    data = read_historian(path, _map("long", zone=None))
    assert data.bad_quality["main_steam_temperature"].tolist() == [
        False, False, True, True, True, True]
    assert data.quality_counts["main_steam_temperature"] == {"good": 2, "uncertain": 2, "bad": 2}
    _, data = _long_quality(tmp_path, [192, 0, 64, "192.0"])  # text integers in a CSV
    assert data.bad_quality["main_steam_temperature"].tolist() == [False, True, True, False]


@pytest.mark.parametrize("value", ["OK", "128", "300", "-1", "1.5"])
def test_unclassifiable_quality_names_file_column_line_value(tmp_path, value):
    path = _csv(tmp_path, "Timestamp,tag,value,quality\n"
                "2026-03-01 10:00:00,10LBA10CT001,538,Good\n"
                f"2026-03-01 10:00:01,10LBA10CT001,539,{value}\n")
    _raises(path, _map("long"), f"{path}: tag '10LBA10CT001' (column 'quality') line 3: quality "
            f"{value!r} (signal main_steam_temperature) is not classified by the default OPC "
            "mapping (text 'Good…'/'Uncertain…'/'Bad…', OPC DA integers 0–255); list it under "
            "[historian.quality] good, uncertain or bad in plant.toml")


def test_empty_quality_of_a_sample_is_an_error(tmp_path):
    path = _csv(tmp_path, "Timestamp,tag,value,quality\n"
                "2026-03-01 10:00:00,10LBA10CT001,538,Good\n"
                "2026-03-01 10:00:01,10LBA10CT001,,\n"
                "2026-03-01 10:00:02,10LBA10CT001,539, \n")
    _raises(path, _map("long"), f"{path}: tag '10LBA10CT001' (column 'quality') line 4: empty "
            "quality for a sample of signal main_steam_temperature; every sample needs a quality")


def test_wide_quality_column_per_signal(tmp_path):
    text = HISTORIAN.format(layout="wide", zone='time_zone = "UTC"', long="").replace(
        'unit = "degC"', 'unit = "degC"\nquality_column = "CT001 Q"').replace(
        'unit = "MW"', 'unit = "MW"\nquality_column = "CE001 Q"')
    tag_map = parse_tag_map(text, "plant.toml")
    path = _csv(tmp_path, "Timestamp,10LBA10CT001,CT001 Q,10LBA10CP001\n"
                "2026-03-01 10:00:00,538,Good,160\n2026-03-01 10:00:01,539,Bad,161\n"
                "2026-03-01 10:00:02,,,162\n")
    data = read_historian(path, tag_map)
    assert {name: mask.tolist() for name, mask in data.bad_quality.items()} == {
        "main_steam_temperature": [False, True, False],  # no sample, no quality: not excluded
        "main_steam_pressure": [False, False, False]}  # no quality column
    assert data.quality_counts == {"main_steam_temperature": {"good": 1, "uncertain": 0, "bad": 1}}
    assert data.notes["missing_quality_column"] == 0  # load is absent, so is its quality column
    assert data.notes["quality_excluded"] == 1
    path = _csv(tmp_path, "Timestamp,10LBA10CT001,10MKA01CE001\n2026-03-01 10:00:00,538,600\n",
                "noq.csv")
    data = read_historian(path, tag_map)
    assert data.notes["missing_quality_column"] == 2
    assert data.quality_counts == {}
