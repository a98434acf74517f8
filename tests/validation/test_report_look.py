"""The static report's look (issue 22 item 5): summary first, readable headers with units,
numbers rounded by quantity, tables that fit 1366 px, self-contained, settings last."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest

from steamtwin.dcs.signals import SIGNALS
from steamtwin.validation.html import MAX_COLUMNS, ValidationReport
from steamtwin.validation.labels import column_label, header_text
from steamtwin.validation.summary import Headline, headline_figures
from steamtwin.validation.tables import operating_table

SCREEN_PX = 1366
MARGIN_PX = 2 * 32  # the body's 2-em padding at 16 px
FONT_PX = 0.85 * 16  # table font
CHAR_PX = 0.62 * FONT_PX  # wide for a sans-serif (digits are 0.55 em)
CELL_PAD_PX = 0.5 * FONT_PX * 2 + 1  # padding left and right, one border


class _Tables(HTMLParser):
    """Headers, cells and tables (as lists of rows of cell texts) of a page, in order."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[list[list[str]]] = []
        self.headers: list[str] = []
        self.headings: list[str] = []
        self.attrs: list[tuple[str, dict[str, str | None]]] = []
        self._cell: list[str] | None = None
        self._tag = ""
        self._heading: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        self.attrs.append((tag, dict(attrs)))
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell, self._tag = [], tag
        elif tag in ("h2", "h3"):
            self._heading = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            text = "".join(self._cell)
            self.tables[-1][-1].append(text)
            if self._tag == "th" and len(self.tables[-1]) == 1:
                self.headers.append(text)
            self._cell = None
        elif tag in ("h2", "h3") and self._heading is not None:
            self.headings.append("".join(self._heading))
            self._heading = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
        if self._heading is not None:
            self._heading.append(data)


def _table8() -> pd.DataFrame:
    """Table 8's columns (as deviation_table writes them) for HP-exhaust and a pressure."""
    rows = []
    for signal, unit, measured_unit, mean_abs, max_abs in (
            ("hp_exhaust_temperature", "K", "degC", 0.2134567, 1.2298765),
            ("hp_exhaust_temperature", "K", "degC", 1.3456789, 3.98765),
            ("hp_exhaust_pressure", "MPa", "MPa", 0.0123456, 0.0456789)):
        rows.append({"signal": signal, "window": f"{30 + 20 * (len(rows) % 2)} % load",
                     "unit": unit, "n_samples": 900, "n_used": 898, "n_skipped_missing": 2,
                     "n_skipped_rom_invalid": 0, "n_extrapolated": 0,
                     "mean_deviation": -0.0812345, "mean_abs_deviation": mean_abs,
                     "max_abs_deviation": max_abs, "rmse": 0.2712345,
                     "mean_measured": 321.98765, "measured_unit": measured_unit,
                     "mean_deviation_pct": -0.0252345, "relative_error_pct": 0.0662345,
                     "rmse_pct": 0.0842345, "max_relative_error_pct": 0.3812345})
    return pd.DataFrame(rows)


def _table5() -> pd.DataFrame:
    """Table 5 from operating_table on two synthetic windows (27 columns)."""
    index = pd.date_range("2026-03-01 08:00", periods=60, freq="s", tz="Asia/Shanghai")
    rng = np.random.default_rng(0)
    window = pd.DataFrame({name: (1.0 + 0.01 * rng.standard_normal(60)) * base for name, base in (
        ("load", 180e6), ("main_steam_pressure", 8.7654321e6), ("main_steam_temperature", 811.3),
        ("main_steam_flow", 151.23456), ("control_stage_pressure", 6.1e6),
        ("hp_exhaust_pressure", 1.61e6), ("hp_exhaust_temperature", 595.2),
        ("hp_inner_casing_temperature", 760.1))}, index=index)
    return operating_table({"30 % load": window, "50 % load": window * 1.01})


def _report(tmp_path, field_error_pct: float = 0.42) -> tuple[str, _Tables]:
    report = ValidationReport("Validation", settings={"hold_hours": 0.25, "workers": 1},
                              timings={"ROM prediction over the windows": 0.09806})
    report.add_table("table5_operating", _table5(), "Table 5")
    report.add_table("table8_deviation", _table8(), "Table 8")
    report.add_table("figure9_field_error", pd.DataFrame(
        {"main_steam_pressure_MPa": [16.7], "max_abs_error_K": [0.567891],
         "mean_abs_error_K": [0.0345678], "max_relative_error_pct": [field_error_pct]}), "Fig. 9")
    report.add_notes("Notes", ["text"])
    page = report.write(tmp_path).read_text(encoding="utf-8")
    parser = _Tables()
    parser.feed(page)
    return page, parser


def test_the_summary_leads_and_settings_versions_timings_close(tmp_path):
    page, parser = _report(tmp_path)
    headings = parser.headings
    assert headings[:2] == ["Summary", "Contents"]
    assert headings.index("Settings") > headings.index("Notes") > headings.index("Table 8")
    assert headings[-3:] == ["Settings", "Versions", "Timings"]
    assert page.index("Summary") < page.index("Table 5") < page.index("Hold hours")
    assert ">0.1 s<" in page  # the timing rounded to 0.1 s, not 0.09806


def test_headline_figures_sit_beside_their_limits_and_published_values(tmp_path):
    page, parser = _report(tmp_path)
    summary = parser.tables[0]
    assert summary[0] == ["Figure", "This run", "Limit", "The method (published)", "Limit from",
                          "Result"]
    rows = {row[0]: row[1:] for row in summary[1:]}
    field = rows["Blade field, ROM vs FOM: max relative error over 1 held-out field(s)"]
    assert field[:3] == ["0.42 %", "≤ 2.5 %", "< 2.5 %"] and field[-1] == "✓ within"
    mean_30 = rows["HP-exhaust temperature, twin − DCS: mean |d|, 30 % load"]
    assert mean_30[:3] == ["0.21 K", "≤ 1 K", "1.8 °C"] and mean_30[-1] == "✓ within"
    # the second exhaust row has mean 1.35 K > 1.0 K and max 3.99 K > 2.5 K: both fail
    mean_50 = rows["HP-exhaust temperature, twin − DCS: mean |d|, 50 % load"]
    max_50 = rows["HP-exhaust temperature, twin − DCS: max |d|, 50 % load"]
    assert mean_50[0] == "1.35 K" and mean_50[-1] == "✗ outside"
    assert max_50[:3] == ["3.99 K", "≤ 2.5 K", "3.2 °C"] and max_50[-1] == "✗ outside"
    assert "2 of 5 headline figures within their limits" not in page  # 3 of 5 pass
    assert "3 of 5 headline figures within their limits" in page
    assert len(re.findall(r'<tr class="fail">', page)) == 2
    document = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    assert [h["passed"] for h in document["headlines"]] == [True, True, True, False, False]
    assert document["headlines"][4]["value"] == pytest.approx(3.98765)  # full precision


def test_a_failing_rom_error_is_marked_failing(tmp_path):
    page, parser = _report(tmp_path, field_error_pct=3.1)
    row = next(r for r in parser.tables[0] if r[0].startswith("Blade field"))
    assert row[1:3] == ["3.10 %", "≤ 2.5 %"] and row[-1] == "✗ outside"
    assert '<tr class="fail"><td>Blade field' in page  # styled as failing


def test_headers_are_readable_with_units(tmp_path):
    _, parser = _report(tmp_path)
    assert parser.headers, "no table header found"
    snake = [h for h in parser.headers if "_" in h]
    assert not snake, snake
    assert "Main-steam pressure, mean [MPa]" in parser.headers
    assert "Main-steam flow, max [t/h]" in parser.headers
    assert "Max relative error [%]" in parser.headers


@pytest.mark.parametrize("signal", list(SIGNALS))
def test_every_signal_column_takes_its_unit_from_the_data_contract(signal):
    wire = SIGNALS[signal].wire_unit
    shown = {"degC": "°C"}.get(wire, wire)
    column = f"{signal}_{wire.replace('/', '_per_')}_max"
    label, unit = column_label(column)
    assert unit == shown and "_" not in label and label.endswith(", max")
    assert column_label(signal)[1] == shown
    assert "_" not in header_text(f"empirical:{signal}")


def test_numbers_in_cells_are_rounded(tmp_path):
    """No float in a cell with more than 4 significant digits (3 below 1000)."""
    _, parser = _report(tmp_path)
    numbers = [cell for table in parser.tables for row in table for cell in row
               if re.fullmatch(r"-?\d+\.\d+", cell)]
    assert numbers, "no decimal number in the tables"
    for cell in numbers:
        digits = cell.lstrip("-").replace(".", "").lstrip("0")
        assert len(digits) <= 4, cell
    cells = {cell for table in parser.tables for row in table for cell in row}
    assert "8.77" in cells  # main-steam pressure mean 8.772894 MPa: 3 figures
    assert "1.23" in cells and "0.21" in cells  # deviations to 0.01 K


def test_tables_fit_a_1366_px_screen(tmp_path):
    """Column count ≤ MAX_COLUMNS, and the narrowest the browser can lay each table out (its
    longest unbreakable word per column, the header wrapping at spaces) fits the page."""
    page, parser = _report(tmp_path)
    assert all(len(row) <= MAX_COLUMNS for table in parser.tables for row in table)
    assert len(parser.tables) > 5  # Table 5's 27 columns and Table 8's 19 come in parts
    parts = [table[0] for table in parser.tables if table[0][0] == "Window"]
    assert len(parts) == 3  # Table 5: each part led by its window, all 27 columns shown once
    assert sum(len(header) - 1 for header in parts) == 27
    table8 = [table[0][:3] for table in parser.tables if table[0][0] == "Signal"]
    assert table8 and all(header == ["Signal", "Window", "Unit"] for header in table8)
    for table in parser.tables:
        widths = [0.0] * max(len(row) for row in table)
        for row in table:
            for k, cell in enumerate(row):
                word = max((len(w) for w in cell.split()), default=0)
                widths[k] = max(widths[k], word * CHAR_PX + CELL_PAD_PX)
        assert sum(widths) <= SCREEN_PX - MARGIN_PX, (table[0], sum(widths))
    style = page[page.index("<style>"):page.index("</style>")]
    assert "max-width: 100%" in style and "overflow-wrap: break-word" in style
    assert "overflow-x: auto" in style


def test_contents_link_to_every_section_heading(tmp_path):
    page, parser = _report(tmp_path)
    anchors = [a["href"] for tag, a in parser.attrs if tag == "a" and a["href"].startswith("#")]
    ids = [a["id"] for tag, a in parser.attrs if tag == "h2" and "id" in a]
    assert anchors == [f"#{i}" for i in ids] and len(ids) == 5  # 3 tables, notes, settings
    assert page.index("<h2>Summary</h2>") < page.index("<h2>Contents</h2>") < page.index(
        'id="section-1"')
    report = ValidationReport("r")
    report.add_table("t", pd.DataFrame({"a": [1]}), "Table 8 — monitored (twin) vs measured "
                     "temperatures (K or MPa as the unit column says) " + "and more " * 10)
    page = report.write(tmp_path / "long").read_text(encoding="utf-8")
    assert '<a href="#section-1">Table 8 — monitored (twin) vs measured temperatures</a>' in page
    report.add_notes("word " * 30, ["long heading"])
    page = report.write(tmp_path / "long").read_text(encoding="utf-8")
    assert f'<a href="#section-2">{"word " * 18}…</a>' in page  # cut before 90 characters


def test_the_page_is_self_contained(tmp_path):
    page, parser = _report(tmp_path)
    for tag, attrs in parser.attrs:
        for name in ("src", "href"):
            assert not re.match(r"[a-z]+://|//", attrs.get(name) or ""), (tag, attrs)
    assert "<script" not in page and "<link" not in page


def test_headlines_are_only_those_the_tables_hold():
    assert headline_figures({}) == []
    table6 = pd.DataFrame({"condition": ["30 % load", "50 % load", "75 % load"],
                           "rmse_calibrated_K": [0.83, 2.5, 1.0],
                           "calibrated_over_instrument": [1.46, 1.51, np.nan]})
    headlines = headline_figures({"table6_rmse": table6})
    rmse = [h for h in headlines if h.figure.startswith("Calibrated RMSE of")]
    assert [(h.value, h.limit, h.passed) for h in rmse] == [(0.83, 3.12, True),
                                                           (2.5, 2.34, False)]
    ratio = [h.passed for h in headlines if "instrument" in h.figure]
    assert ratio == [True, False, False]  # 1.51 > 1.5; NaN never passes
    # the twin as delivered (sensor offsets applied) is the figure where the table has it
    table6 = table6.assign(rmse_delivered_K=[0.5, 1.2, 0.9],
                           delivered_over_instrument=[0.9, 1.4, 1.6])
    delivered = headline_figures({"table6_rmse": table6})
    assert [(h.value, h.passed) for h in delivered if "instrument" in h.figure] == [
        (0.9, True), (1.4, True), (1.6, False)]
    assert all("sensor offsets applied" in h.figure for h in delivered)
    assert [h.value for h in delivered if h.figure.startswith("Calibrated RMSE of")] == [
        0.5, 1.2]
    scan = pd.DataFrame({"row": ["hp1", "hp13", "hp2"],
                         "hp_exhaust_temperature_max_deviation_K": [0.332, 0.236, np.nan]})
    # a row not propagated to the steam path (NaN) has no headline
    assert [h.passed for h in headline_figures({"scan_uncertainty": scan})] == [False, True]
    given = [Headline("x", 1.0, "K", 2.0, "–", "test")]
    assert given[0].passed


def test_counts_stay_whole_beside_floats(tmp_path):
    report = ValidationReport("r")
    report.add_table("t", pd.DataFrame({"samples": [123456], "rmse_K": [0.123456]}))
    page = report.write(tmp_path).read_text(encoding="utf-8")
    assert ">123456<" in page and ">0.12<" in page


def test_full_precision_floats_in_text_cells_are_rounded(tmp_path):
    """Lists written into one text cell (e.g. the ROM's provenance) keep no float noise; times,
    versions and hashes are left alone."""
    report = ValidationReport("r")
    values = ["0.3, 0.8116022099447515, 0.9299999999999999, -12.3456789",
              "2026-11-27T03:54:49.123456+00:00", "ba6258d2e8d1.3d8f5df1bce2"]
    report.add_table("rom_provenance", pd.DataFrame({"item": ["levels", "created", "hash"],
                                                     "value": values}))
    page = report.write(tmp_path).read_text(encoding="utf-8")
    assert "<td>0.3, 0.812, 0.930, -12.3</td>" in page
    assert "<td>2026-11-27T03:54:49.123456+00:00</td>" in page
    assert "<td>ba6258d2e8d1.3d8f5df1bce2</td>" in page



def test_numbers_align_right_only_in_number_columns(tmp_path):
    report = ValidationReport("r")
    report.add_table("items", pd.DataFrame({"item": ["modes", "kernel"], "value": [3, "tps"]}))
    report.add_table("t", pd.DataFrame({"window": ["a"], "rmse_K": [0.5]}))
    page = report.write(tmp_path).read_text(encoding="utf-8")
    assert "<th>Modes</th><td>3</td>" in page  # a number among text: as text
    assert '<th>a</th><td class="number">0.50</td>' in page
