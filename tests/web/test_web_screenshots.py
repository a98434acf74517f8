"""Screenshots of the dashboard pages for the demo report (issue 22, item 4): the check that
reads a page's dumped DOM, the PNG header, a missing browser (a message, never an
exception), and Debian's chromium on a served historian (:class:`web_fixtures.ServedSite`)."""

from __future__ import annotations

import struct
import zlib

import pytest
from hypothesis import given
from hypothesis import strategies as st
from web_fixtures import ServedSite

from steamtwin.validation.html import FigureSection, NotesSection
from steamtwin.web import screenshots
from steamtwin.web.screenshots import (
    CHROMIUM_ENV,
    DASHBOARD_PAGES,
    PageShot,
    dashboard_sections,
    find_chromium,
    page_check,
    png_size,
    screenshot_pages,
)

PAGES = {page.name: page for page in DASHBOARD_PAGES}


def _png(width: int, height: int) -> bytes:
    """A valid one-colour PNG (ISO/IEC 15948: signature, IHDR, IDAT, IEND)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))
    rows = b"".join(b"\x00" + b"\x00" * width for _ in range(height))  # filter 0, grey 8 bit
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0,
                                                             0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def _dom(ready: str | None, charts: list[int], bad: str = "", unit: str = "unit1") -> str:
    """A page's DOM as Chromium gives it (the shell of steamtwin.web.pages)."""
    body = f'<body data-unit="{unit}"' + (f' data-ready="{ready}"' if ready else "") + ">"
    status = (f'<span id="status" role="status" class="bad">{bad}</span>' if bad
              else '<span id="status" role="status">live</span>')
    drawn = "".join(f'<div class="chart" data-signal="s{k}" data-points="{n}"><canvas></canvas>'
                    "</div>" for k, n in enumerate(charts))
    return f"<html><head></head>{body}<header>{status}</header><main>{drawn}</main></body></html>"


@pytest.mark.parametrize(("width", "height"), [(1366, 768), (800, 1100), (1, 1)])
def test_png_size_reads_the_ihdr(tmp_path, width, height):
    path = tmp_path / "page.png"
    path.write_bytes(_png(width, height))
    assert png_size(path) == (width, height)
    path.write_bytes(b"<html>" + bytes(30))
    with pytest.raises(ValueError, match=r"page\.png: not a PNG"):
        png_size(path)


@given(charts=st.lists(st.integers(min_value=0, max_value=5000), max_size=4),
       ready=st.sampled_from(["yes", None, "no-rom"]), bad=st.sampled_from(["", "404 unit"]),
       name=st.sampled_from(sorted(PAGES)))
def test_a_page_rendered_exactly_when_ready_without_error_and_every_chart_has_data(
        charts, ready, bad, name):
    page = PAGES[name]
    rendered, detail = page_check(_dom(ready, charts, bad), page)
    expected = (ready == "yes" and not bad and all(n > 0 for n in charts)
                and (bool(charts) or not page.charts))
    assert rendered == expected
    for k, n in enumerate(charts):
        assert f"s{k}: {n} points" in detail
    if bad:
        assert "404 unit" in detail


def test_the_check_says_why_a_page_did_not_render():
    unit = PAGES["Unit"]
    assert "did not finish drawing" in page_check(_dom(None, [10]), unit)[1]
    assert "no blade ROM" in page_check(_dom("no-rom", []), PAGES["Blade"])[1]
    assert page_check(_dom("yes", []), unit) == (False, "drawn without a chart")
    assert "without data: s1" in page_check(_dom("yes", [10, 0]), unit)[1]
    error = page_check(_dom(None, [], bad="bearer token is required"), unit)
    assert error == (False, "error on the page: bearer token is required; no chart")
    fleet = page_check(_dom("yes", [], unit=""), PAGES["Fleet"])
    assert fleet == (True, "no chart")
    forwarded = page_check(_dom("yes", [5]), PAGES["Fleet"])  # one unit: its page instead
    assert forwarded[0] and forwarded[1].startswith("one unit: forwarded")


def test_a_missing_browser_is_a_message_not_an_exception(monkeypatch, tmp_path):
    monkeypatch.setenv(CHROMIUM_ENV, str(tmp_path / "no-such-chromium"))
    assert find_chromium() is None
    assert screenshot_pages("http://127.0.0.1:9", "unit1", tmp_path / "shots") == []
    [notes] = dashboard_sections([])
    assert isinstance(notes, NotesSection)
    assert "no-such-chromium" in notes.paragraphs[0] and "is not a file" in notes.paragraphs[0]
    monkeypatch.delenv(CHROMIUM_ENV)
    monkeypatch.setattr(screenshots.shutil, "which", lambda name: None)
    assert find_chromium() is None
    text = dashboard_sections(screenshot_pages("http://127.0.0.1:9", "u", tmp_path))[0]
    assert "no chromium or chromium-browser on the PATH" in text.paragraphs[0]
    assert "apt-get install chromium" in text.paragraphs[0]
    assert CHROMIUM_ENV in text.paragraphs[0]


def test_a_browser_that_does_not_answer_fails_each_page_without_raising(tmp_path):
    shots = screenshot_pages("http://127.0.0.1:9", "unit1", tmp_path,
                             [PAGES["Unit"], PAGES["History"]], chromium="/bin/true")
    assert [shot.page.name for shot in shots] == ["Unit", "History"]
    assert all(not shot.rendered and shot.png is None for shot in shots)
    assert "Chromium closed its DevTools pipe" in shots[0].detail
    shots = screenshot_pages("http://127.0.0.1:9", "unit1", tmp_path, [PAGES["Unit"]],
                             chromium=tmp_path)  # a folder: cannot be started
    assert "did not start" in shots[0].detail


def test_a_failed_page_is_named_in_the_section_beside_its_screenshot(tmp_path):
    png = tmp_path / "dashboard-unit.png"
    png.write_bytes(_png(4, 3))
    shots = [PageShot(PAGES["Unit"], "http://x/units/u", png, True, "s: 9 points", 1.0),
             PageShot(PAGES["Blade"], "http://x/units/u/blade", png, False,
                      "not drawn (the unit has no blade ROM); no chart", 2.0),
             PageShot(PAGES["History"], "http://x/units/u/history", None, False,
                      "Chromium did not finish within 60 s", 60.0)]
    notes, *figures = dashboard_sections(shots, "lead")
    assert notes.paragraphs[0] == "lead"
    assert notes.paragraphs[1].startswith("1 of 3 pages drew the database's values")
    assert "Blade (http://x/units/u/blade): not drawn (the unit has no blade ROM)" in (
        notes.paragraphs[1])
    assert "History (http://x/units/u/history): Chromium did not finish" in notes.paragraphs[1]
    assert all(isinstance(f, FigureSection) for f in figures) and len(figures) == 2
    assert "did not render" in figures[1].caption and "did not render" not in figures[0].caption


@pytest.fixture(scope="module")
def open_site(tmp_path_factory):
    served = ServedSite(tmp_path_factory.mktemp("shots-site"), tokens=False)
    yield served
    served.close()


NEEDS_CHROMIUM = pytest.mark.skipif(find_chromium() is None,
                                    reason="no chromium (CI installs it)")


@NEEDS_CHROMIUM
def test_chromium_draws_the_unit_page_at_1366_by_768(open_site, tmp_path):
    [unit] = screenshot_pages(open_site.url, "unit1", tmp_path, [PAGES["Unit"]])
    assert unit.rendered, unit.detail
    assert png_size(unit.png) == (1366, 768) and unit.png.name == "dashboard-unit.png"
    # the last 600 s of unit1: measured, twin and the twin ± 2σ band of the exhaust signal
    assert "hp_exhaust_temperature: 2400 points" in unit.detail


@NEEDS_CHROMIUM
def test_chromium_reports_a_page_whose_chart_drew_nothing(open_site, tmp_path):
    [swaps] = screenshot_pages(open_site.url, "unit2", tmp_path, [PAGES["Calibration"]],
                               size=(800, 600))  # unit2 has no parameter swap stored
    assert not swaps.rendered
    assert swaps.detail == "chart(s) without data: trajectory; trajectory: 0 points"
    assert png_size(swaps.png) == (800, 600)
