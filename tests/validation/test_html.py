"""The HTML report writer: escaping, one CSV per table, report.json, missing files refused."""

from __future__ import annotations

import base64
import json

import numpy as np
import pandas as pd
import pytest

from steamtwin.validation.html import ReportError, ValidationReport, format_value

PNG = b"\x89PNG\r\n\x1a\n" + b"\x00" * 16  # content does not matter to the writer


def _deviations() -> pd.DataFrame:
    return pd.DataFrame({"signal": ["hp_exhaust_temperature"] * 2,
                         "window": ["30 % load", "50 % load"],
                         "n_used": [7200, 7190],
                         "rmse_K": [0.123456789012, np.nan]})


def _operating() -> pd.DataFrame:
    return pd.DataFrame({"main_steam_pressure_MPa_mean": [8.5, 11.1],
                         "samples": [7200, 7200]},
                        index=pd.Index(["30 % load", "50 % load"], name="window"))


def test_text_is_escaped(tmp_path):
    report = ValidationReport("<b>Unit 1</b> & co", settings={"data": "<script>x</script>"})
    report.add_table("t", pd.DataFrame({"<col>": ["a<b"]}), caption="caption <i>")
    report.add_notes("notes & more", ["T < 500 °C", '"quoted"'])
    page = report.write(tmp_path).read_text(encoding="utf-8")
    assert "<script>" not in page and "&lt;script&gt;x&lt;/script&gt;" in page
    assert "&lt;b&gt;Unit 1&lt;/b&gt; &amp; co" in page
    assert "&lt;col&gt;" in page and "a&lt;b" in page and "caption &lt;i&gt;" in page
    assert "T &lt; 500 °C" in page and "&quot;quoted&quot;" in page


def test_one_csv_per_table_equal_to_the_frame(tmp_path):
    report = ValidationReport("r")
    report.add_table("table8_deviation", _deviations())
    report.add_table("table5_operating", _operating())
    report.write(tmp_path)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "table8_deviation.csv"), _deviations())
    pd.testing.assert_frame_equal(
        pd.read_csv(tmp_path / "table5_operating.csv", index_col="window"), _operating())
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert 'href="table8_deviation.csv"' in page and ">0.12<" in page  # rmse_K: 0.01 K


def test_report_json_holds_the_tables_settings_and_timings(tmp_path):
    report = ValidationReport("r", settings={"hours": 2.0, "windows": ["30 % load"]},
                              timings={"read": 1.5})
    report.versions["extra-package"] = "9.9"
    report.add_table("table8_deviation", _deviations())
    report.add_table("table5_operating", _operating())
    report.write(tmp_path)
    document = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert document["settings"] == {"hours": 2.0, "windows": ["30 % load"]}
    assert document["timings_s"] == {"read": 1.5}
    assert document["versions"]["extra-package"] == "9.9"
    assert {"python", "steamtwin", "numpy", "scipy", "pandas"} <= set(document["versions"])
    records = document["tables"]["table8_deviation"]["records"]
    assert records[0]["rmse_K"] == _deviations()["rmse_K"][0]  # full precision
    assert records[1]["rmse_K"] is None  # NaN → null
    assert pd.DataFrame(records).iloc[0].to_dict() == _deviations().iloc[0].to_dict()
    operating = pd.DataFrame(document["tables"]["table5_operating"]["records"])
    pd.testing.assert_frame_equal(operating.set_index("window"), _operating())


def test_figures_are_embedded_and_copied_in(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    inside = out / "figure10.png"
    inside.write_bytes(PNG)
    outside = tmp_path / "elsewhere.png"
    outside.write_bytes(PNG)
    report = ValidationReport("r")
    report.add_figure(inside, "tracking")
    report.add_figure(outside, "copied")
    page = report.write(out).read_text(encoding="utf-8")
    embedded = f'src="data:image/png;base64,{base64.b64encode(PNG).decode()}"'
    assert page.count(embedded) == 2  # self-contained: the page carries the images
    assert 'data-file="figure10.png"' in page and 'data-file="elsewhere.png"' in page
    assert (out / "elsewhere.png").read_bytes() == PNG
    figures = json.loads((out / "report.json").read_text(encoding="utf-8"))["figures"]
    assert figures == [{"file": "figure10.png", "caption": "tracking"},
                       {"file": "elsewhere.png", "caption": "copied"}]


def test_missing_empty_or_duplicate_sections_are_refused(tmp_path):
    report = ValidationReport("r")
    report.add_figure(tmp_path / "missing.png")
    with pytest.raises(ReportError, match="does not exist"):
        report.write(tmp_path / "out")
    assert not (tmp_path / "out" / "report.html").exists()
    empty = tmp_path / "empty.png"
    empty.touch()
    report = ValidationReport("r")
    report.add_figure(empty)
    with pytest.raises(ReportError, match="is empty"):
        report.write(tmp_path / "out")
    report = ValidationReport("r")
    report.add_table("t", pd.DataFrame())
    with pytest.raises(ReportError, match="table 't' is empty"):
        report.write(tmp_path / "out")
    with pytest.raises(ReportError, match="already"):
        report.add_table("t", _deviations())
    with pytest.raises(ReportError, match="CSV file name"):
        report.add_table("../escape", _deviations())


@pytest.mark.parametrize(("value", "unit", "text"), [
    (16.7, "", "16.7"), (538.123, "", "538"), (0.012345, "", "0.0123"), (1234.7, "", "1235"),
    (12345.6, "", "12350"), (2.5e-5, "", "2.50e-05"), (3e7, "", "3.00e+07"), (0.0, "", "0"),
    (np.nan, "", "–"), (None, "", "–"), (7200, "", "7200"), (np.int64(3), "", "3"),
    (True, "", "yes"), ("a", "", "a"),
    # by quantity: never finer than the unit's resolution
    (538.123, "°C", "538"), (16.7012, "MPa", "16.7"), (2.3456, "MPa", "2.35"),
    (0.0567, "K", "0.06"), (-0.004, "K", "0.00"), (0.09806, "s", "0.1"), (1800.4, "t/h", "1800"),
    (0.38123, "%", "0.38"), (0.0123456, "mm", "0.012"), (0.99954, "", "1.00"), (999.7, "", "1000"),
    (-0.09996, "", "-0.100"),
    (pd.Timestamp("2026-03-01T00:00:00Z"), "", "2026-03-01 00:00:00+00:00"),
])
def test_numbers_are_rounded_by_quantity(value, unit, text):
    assert format_value(value, unit) == text


def test_data_files_are_linked_listed_in_json_and_checked(tmp_path):
    inside = tmp_path / "report" / "series_1_w.parquet"
    inside.parent.mkdir()
    inside.write_bytes(b"PAR1")
    outside = tmp_path / "elsewhere.parquet"
    outside.write_bytes(b"PAR1")
    report = ValidationReport("files")
    report.add_files("Series", [(inside, "window w <1>"), (outside, "another")])
    page = report.write(tmp_path / "report").read_text(encoding="utf-8")
    assert '<a href="series_1_w.parquet">series_1_w.parquet</a> — window w &lt;1&gt;' in page
    assert '<a href="elsewhere.parquet">' in page
    assert (tmp_path / "report" / "elsewhere.parquet").read_bytes() == b"PAR1"
    document = json.loads((tmp_path / "report" / "report.json").read_text(encoding="utf-8"))
    assert document["files"] == [
        {"heading": "Series", "file": "series_1_w.parquet", "description": "window w <1>"},
        {"heading": "Series", "file": "elsewhere.parquet", "description": "another"}]
    with pytest.raises(ReportError, match="already in the report"):
        report.add_files("again", [(inside, "same name")])
    missing = ValidationReport("missing")
    missing.add_files("Series", [(tmp_path / "nothing.parquet", "")])
    with pytest.raises(ReportError, match="does not exist"):
        missing.write(tmp_path / "other")
