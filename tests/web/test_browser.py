"""The dashboard pages in a real headless Chromium (issue 22, item 4): Debian's ``chromium``
driven by Playwright, the service's HTTP companion on loopback with tokens, on the test
historian (:mod:`web_fixtures`) plus a small blade ROM. Each page must draw the database's
values, the unit page must show a sample committed while it is open, an alarm must be
acknowledged through the page, the blade view must render the ROM's field, and the API must
refuse a request without the token. Chromium missing is a failure, not a skip: CI installs it
(tools/install-system-deps.sh).

``STEAMTWIN_SCREENSHOTS=docs/img`` also saves a screenshot of each page there (docs/web.md).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from web_fixtures import ACK, READ, START, ServedSite

from steamtwin.live.historian import Alarm, BlockEvents

pytestmark = pytest.mark.slow

CHROMIUM = Path("/usr/bin/chromium")
VIEWPORT = {"width": 1366, "height": 768}
EMPTY_STYLE = "sha256-47DEQpj8HBSa+/TImW+5JCeuQeRkm5NMpJWZG3hSuFU="
"""CSP hash of an empty style: plotly.js clears a colour bar rect's style attribute (d3
``.attr("style", "")``); the policy blocks that no-op, the only inline style left."""


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    served = ServedSite(tmp_path_factory.mktemp("site"))
    yield served
    served.close()


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.is_file():
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium "
                    "(tools/install-system-deps.sh does it)")
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=str(CHROMIUM), args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run"])
        yield launched
        launched.close()


@pytest.fixture
def page(browser, site):
    """A tab whose session holds the ack token; console errors fail the test."""
    context = browser.new_context(viewport=VIEWPORT)
    context.add_init_script(f"sessionStorage.setItem('steamtwin-token', '{ACK}')")
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    tab.on("console", lambda m: errors.append(m.text) if m.type == "error"
           and EMPTY_STYLE not in m.text else None)
    yield tab
    context.close()
    assert not errors, errors


def _open(page, site, path: str, suffix: str = "") -> None:
    page.goto(site.url + path)
    page.wait_for_function("() => document.body.dataset.ready", timeout=15_000)
    assert page.locator("#status.bad").count() == 0, page.locator("#status").text_content()
    folder = os.environ.get("STEAMTWIN_SCREENSHOTS")
    if folder:
        name = path.strip("/").replace("units/unit1", "unit").replace("/", "-") or "fleet"
        page.screenshot(path=str(Path(folder) / f"web-{name}{suffix}.png"))


def _stored(site, source: str, signal: str, start_s: int, end_s: int) -> np.ndarray:
    """unit1's stored values of ``source``/``signal`` from ``start_s`` to ``end_s`` (s after
    START), read from the database directly."""
    start, end = (START + pd.Timedelta(seconds=s) for s in (start_s, end_s))
    rows = site.historian.connection.execute(
        "SELECT value FROM series WHERE unit = 'unit1' AND source = ? AND signal = ? AND time "
        ">= ? AND time <= ? ORDER BY time",
        [source, signal, start.to_pydatetime(), end.to_pydatetime()])
    return np.array([r[0] for r in rows.fetchall()], dtype=float)


def test_the_api_refuses_a_request_without_the_token(browser, site):
    page = browser.new_page()
    page.goto(site.url + "/units/unit1")  # the shell itself carries no data
    assert "bearer token is required" in page.locator("#status.bad").text_content()
    assert page.locator("#tiles > *, #temperatures > *, canvas, td").count() == 0
    answers = page.evaluate("""async (token) => Promise.all([
        fetch('/api/units').then((r) => r.status),
        fetch('/api/units', {headers: {Authorization: 'Bearer ' + token}}).then((r) => r.status),
    ])""", READ)
    page.close()
    assert answers == [401, 200]


def test_the_unit_page_draws_the_database_and_a_new_sample_live(page, site):
    _open(page, site, "/units/unit1")
    last_s = site.next_s - 1
    drawn = page.evaluate("""() => {
        const div = document.querySelector('#temperatures .chart');
        const data = div._uplot.data;  // [time (s), twin − 2σ, twin + 2σ, twin, measured]
        return {signal: div.dataset.signal, measured: data[4],
                band: [data[1].at(-1), data[2].at(-1), data[3].at(-1)]};
    }""")
    assert drawn["signal"] == "hp_exhaust_temperature"
    expected = _stored(site, "measured", "hp_exhaust_temperature", last_s - 599, last_s)
    np.testing.assert_allclose(drawn["measured"], expected - 273.15, atol=1e-9)
    low, high, twin = drawn["band"]  # the tag map's σ = 1.5 K: twin ± 3 K
    assert high - twin == pytest.approx(3.0) and twin - low == pytest.approx(3.0)
    assert page.locator("#alarms li").count() == 1  # the degradation alarm stays active
    assert "flow_coefficient" in page.locator("#parameters").text_content()
    started = time.monotonic()
    stamp = site.commit()
    page.wait_for_function(
        "(x) => document.querySelector('#temperatures .chart')._uplot.data[0].at(-1) === x",
        arg=stamp.timestamp(), timeout=5_000)
    assert time.monotonic() - started < 3.0
    value = _stored(site, "measured", "hp_exhaust_temperature", site.next_s - 1,
                    site.next_s - 1)[0]
    assert page.evaluate("document.querySelector('#temperatures .chart')._uplot.data[4].at(-1)"
                         ) == pytest.approx(value - 273.15)
    assert page.evaluate("document.querySelector('#temperatures .chart')._uplot.data[0].length"
                         ) == 600  # the window keeps 10 minutes
    fault = START + pd.Timedelta(seconds=site.next_s)  # a sensor fault, raised live
    site.commit(events=BlockEvents(alarms=(Alarm("unit1", "sensor_fault", fault,
                                                 "hp_exhaust_temperature",
                                                 evidence={"statistic": 8.0}),)))
    page.wait_for_function("() => document.querySelectorAll('#alarms li').length === 2",
                           timeout=5_000)
    assert "sensor_fault (hp_exhaust_temperature)" in page.locator("#alarms").text_content()


def test_history_zoom_requeries_raw_samples_and_offers_downloads(page, site):
    _open(page, site, "/units/unit1/history")
    assert "buckets" in page.locator("#summary").text_content()  # 2 h: downsampled
    # a drag over 01:00:00 … 01:05:00 (as uPlot's selection reports it) re-queries that range
    page.evaluate("""() => { const plot = document.getElementById('chart')._uplot;
        const [from, to] = ['2026-03-01T01:00:00Z', '2026-03-01T01:05:00Z'].map(
            (t) => plot.valToPos(Date.parse(t) / 1e3, 'x'));
        plot.setSelect({left: from, width: to - from, top: 0, height: 10}); }""")
    page.wait_for_function("() => !document.getElementById('summary').textContent"
                           ".includes('buckets')")
    chart = page.evaluate("""() => { const div = document.getElementById('chart');
        return {...div.dataset, time: div._uplot.data[0], y: div._uplot.data[1]}; }""")
    start, end = (pd.Timestamp(chart[k]) for k in ("start", "end"))
    pixel_s = 7200 / 1200  # the 2-h chart is < 1366 px wide: a pixel is > 6 s
    assert abs((start - pd.Timestamp("2026-03-01T01:00:00Z")).total_seconds()) < 2 * pixel_s
    assert abs((end - pd.Timestamp("2026-03-01T01:05:00Z")).total_seconds()) < 2 * pixel_s
    signal = page.locator("#signal").input_value().split("/")
    start_s, end_s = (int((t - START).total_seconds()) for t in (start, end))
    stored = _stored(site, *signal, start_s, end_s)
    assert int(chart["count"]) == len(chart["y"]) == len(stored)  # raw samples
    np.testing.assert_allclose(chart["y"], stored)
    assert chart["time"][0] == start.timestamp()
    href = page.get_attribute("#csv", "href")
    assert "/series/download" in href and "format=csv" in href
    text = page.evaluate("""async ([href, token]) => (await fetch(href, {headers:
        {Authorization: 'Bearer ' + token}})).text()""", [href, READ])
    assert text.splitlines()[0].startswith("time,") and len(text.splitlines()) == 1 + len(stored)


def test_an_alarm_is_acknowledged_through_the_page(page, site):
    _open(page, site, "/units/unit1/alarms")
    assert page.evaluate("document.getElementById('evidence-chart')._uplot.data.length") >= 2
    row = page.locator("#alarms tr[data-alarm='2']")
    assert "active" in row.text_content()
    row.get_by_role("button", name="acknowledge").click()
    page.wait_for_function("() => document.querySelector(\"#alarms tr[data-alarm='2']\")"
                           ".textContent.includes('shift-lead')")
    assert row.get_by_role("button", name="acknowledge").is_disabled()
    acknowledged = site.historian.connection.execute(
        "SELECT acknowledged_by FROM alarms WHERE id = 2").fetchone()[0]
    assert acknowledged == "shift-lead"


def test_calibration_and_fleet_pages_draw_the_stored_swaps_and_units(page, site):
    _open(page, site, "/units/unit1/calibration")
    flow = page.evaluate("""() => { const plot = document.getElementById('trajectory')._uplot;
        const k = plot.series.findIndex((s) => s.label === 'flow_coefficient');
        return plot.data[k].filter((v) => v !== undefined); }""")
    assert flow == [0.99, 0.98]
    assert page.locator("#swaps tr").count() == 3  # header and two swap times
    # the degradation swap's value with the filter's 95 % interval; the scheduled one without
    values = [page.locator("#swaps tr").nth(k).locator("td").nth(1).text_content()
              for k in (1, 2)]
    assert values[1] == "flow_coefficient = 0.98 [0.9650, 0.9950]"
    assert "[" not in values[0]
    before, after = (page.locator("#swaps tr").nth(1).locator("td").nth(k).text_content()
                     for k in (3, 4))  # the first swap, 00:30:00: 10 min either side
    residual = "residual", "hp_exhaust_temperature"
    for text, (start_s, end_s) in ((before, (1200, 1799)), (after, (1800, 2400))):
        values = _stored(site, *residual, start_s, end_s)
        assert float(text.split()[-1]) == pytest.approx(np.sqrt(np.mean(values ** 2)),
                                                        rel=2e-3)
    _open(page, site, "/")
    assert page.locator(".card").count() == 2
    active = site.historian.connection.execute(
        "SELECT count(*) FROM alarms WHERE unit = 'unit1' AND \"end\" IS NULL").fetchone()[0]
    assert active >= 1  # the degradation alarm (and the live test's fault, if it ran)
    assert f"{active} active alarm" in page.locator(".card", has_text="unit1").text_content()
    assert "0 active alarms" in page.locator(".card", has_text="unit2").text_content()


def test_the_blade_view_renders_the_rom_field(page, site):
    _open(page, site, "/units/unit1/blade")
    drawn = page.evaluate("""() => { const div = document.getElementById('blade');
        return {type: div.data[0].type, n: div.data[0].intensity.length,
                points: div.data[0].x.length, canvas: div.querySelectorAll('canvas').length}; }""")
    assert drawn["type"] == "mesh3d" and drawn["n"] == drawn["points"] > 0
    assert drawn["canvas"] >= 1
    assert page.locator("#probes tr").count() == 7  # header and the six regions' probes
    page.fill("#time", "2026-03-01T00:30:00Z")
    page.click("#query button[type=submit]")
    page.wait_for_function("() => document.getElementById('blade').dataset.time === "
                           "'2026-03-01T00:30:00+00:00'")
    shown = []  # the replay of 00:29:00 … 00:31:00 every 60 s draws three fields
    page.expose_function("noteField", lambda time: shown.append(time))
    page.evaluate("""() => { const div = document.getElementById('blade');
        new MutationObserver(() => window.noteField(div.dataset.time)).observe(
            div, {attributes: true, attributeFilter: ['data-time']}); }""")
    page.fill("#replay-from", "2026-03-01T00:29:00Z")
    page.fill("#replay-to", "2026-03-01T00:31:00Z")
    page.fill("#replay-step", "60")
    page.click("#replay button[type=submit]")
    page.wait_for_function("() => document.getElementById('blade').dataset.time === "
                           "'2026-03-01T00:31:00+00:00'")
    for _ in range(100):  # the last note's round trip to Python
        if len(shown) >= 3:
            break
        page.wait_for_timeout(20)
    assert shown == [f"2026-03-01T00:{m}:00+00:00" for m in (29, 30, 31)]
    other = page.context.new_page()  # its 404 is expected: no console check on this tab
    other.goto(site.url + "/units/unit2/blade")
    other.wait_for_function("() => document.body.dataset.ready")
    assert "no blade ROM" in other.locator("#summary").text_content()
    other.close()


def test_the_pages_fit_a_tablet(browser, site):
    context = browser.new_context(viewport={"width": 800, "height": 1100})
    context.add_init_script(f"sessionStorage.setItem('steamtwin-token', '{READ}')")
    tab = context.new_page()
    try:
        for path in ("/units/unit1", "/units/unit1/alarms", "/units/unit1/calibration"):
            _open(tab, site, path, "-tablet")
            assert tab.evaluate("document.documentElement.scrollWidth") <= 800, path
    finally:
        context.close()


def test_without_tokens_the_operator_named_in_the_page_acknowledges(browser, tmp_path):
    open_site = ServedSite(tmp_path, tokens=False)  # loopback, no token file: open access
    context = browser.new_context(viewport=VIEWPORT)
    try:
        page = context.new_page()
        _open(page, open_site, "/units/unit1/alarms")
        page.fill("#operator", "A. Operator")
        page.dispatch_event("#operator", "change")
        page.locator("#alarms tr[data-alarm='1']").get_by_role("button",
                                                               name="acknowledge").click()
        page.wait_for_function("() => document.querySelector(\"#alarms tr[data-alarm='1']\")"
                               ".textContent.includes('A. Operator')")
    finally:
        context.close()
        open_site.close()
