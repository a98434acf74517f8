"""The Rotor page in headless Chromium (Playwright, Debian's ``/usr/bin/chromium``, as
test_browser.py): the service's HTTP companion with tokens on loopback, on a historian holding
a rotor's stored series (:mod:`rotor_fixtures`). The page must draw the database's stress
points with the allowable line, the temperatures, and the life table's damage.

``STEAMTWIN_SCREENSHOTS=docs/img`` also saves the page's screenshot there (docs/web.md)."""

from __future__ import annotations

import asyncio
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from rotor_fixtures import ALLOWABLE_MPA, SECONDS, fill_rotor, rotor_frames, write_rotor_config

from steamtwin.live.historian import LiveHistorian
from steamtwin.web.access import load_tokens
from steamtwin.web.app import WebSettings
from steamtwin.web.server import HttpSettings, http_companion

pytestmark = pytest.mark.slow

CHROMIUM = Path("/usr/bin/chromium")
READ = "r" * 40


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rotor-site")
    db = folder / "twin.duckdb"
    fill_rotor(db)
    config = write_rotor_config(folder, db)
    (folder / "tokens.toml").write_text(
        f'[[tokens]]\nname = "viewer"\nrole = "read"\ntoken = "{READ}"\n')
    bound: dict[str, int] = {}
    companion = http_companion(
        HttpSettings(port=0, access=load_tokens(folder / "tokens.toml"), web=WebSettings()),
        config, on_bound=lambda _host, port: bound.update(port=port))
    historian = LiveHistorian(db)
    historian.open()
    loop, done = asyncio.new_event_loop(), asyncio.Event()
    thread = threading.Thread(target=loop.run_until_complete, args=(companion(historian, done),))
    thread.start()
    yield f"http://127.0.0.1:{bound['port']}"
    loop.call_soon_threadsafe(done.set)
    thread.join(10.0)
    historian.close()


def test_the_rotor_page_draws_the_stored_stress_and_life(site):
    if not CHROMIUM.is_file():
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium "
                    "(tools/install-system-deps.sh does it)")
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run"])
        context = browser.new_context(viewport={"width": 1366, "height": 768})
        context.add_init_script(f"sessionStorage.setItem('steamtwin-token', '{READ}')")
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.goto(f"{site}/units/unit1/rotor")
        page.wait_for_function("() => document.body.dataset.ready", timeout=15_000)
        assert page.locator("#status.bad").count() == 0, page.locator("#status").text_content()
        folder = os.environ.get("STEAMTWIN_SCREENSHOTS")
        if folder:
            page.screenshot(path=str(Path(folder) / "web-unit-rotor.png"), full_page=True)
        data = page.evaluate("() => document.getElementById('stress')._uplot.data")
        temperature = page.evaluate(
            "() => document.getElementById('temperature')._uplot.data")
        life_text = page.locator("#life").inner_text()
        tiles = page.locator("#tiles").inner_text()
        api = page.evaluate(
            "async () => (await fetch('/api/units/unit1/series?source=twin&signal="
            "rotor_groove_stress&span_s=86400', {headers: {Authorization: 'Bearer "
            f"{READ}'}}}})).json()")
        drawn_without_errors = list(errors)  # the advice's 404 below is logged by chromium
        page.click("#advise button")  # rotor = "fit": no model file to advise from
        page.wait_for_function("() => !document.getElementById('advice-note').textContent"
                               ".startsWith('computing')", timeout=15_000)
        advice_note = page.locator("#advice-note").inner_text()
        browser.close()
    assert not drawn_without_errors, drawn_without_errors
    assert "ramp advice needs the rotor model file" in advice_note
    # the page draws the API's answer for the day (2 h stored: equal buckets of 43 s, each
    # drawn at its mean), in MPa; those means lie within the stored values' range
    means = np.array([np.nan if v is None else v for v in api["mean"]], dtype=float)
    assert api["downsampled"] and len(data[0]) == len(means) > 100
    np.testing.assert_allclose(np.array(data[1], dtype=float), means / 1e6, rtol=1e-12)
    stored = rotor_frames(0, SECONDS)["twin"]["rotor_groove_stress"].to_numpy() / 1e6
    drawn = np.array(data[1], dtype=float)
    assert stored.min() - 1e-6 <= np.nanmin(drawn) < stored.min() + 5.0
    assert stored.max() - 5.0 < np.nanmax(drawn) <= stored.max() + 1e-6
    np.testing.assert_allclose(data[3], ALLOWABLE_MPA)  # the allowable line, + and −
    np.testing.assert_allclose(data[4], -ALLOWABLE_MPA)
    assert np.nanmax(np.array(temperature[1], dtype=float)) == pytest.approx(
        800.0 - 273.15, abs=0.5)  # °C
    assert "groove root" in life_text and "e-" in life_text  # damages shown
    assert f"{ALLOWABLE_MPA} MPa" in tiles
