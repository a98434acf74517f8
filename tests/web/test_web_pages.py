"""The dashboard's server side (issue 22, item 2): the blade endpoints reconstruct the ROM's
field for a stored sample's inputs (checked against the ROM itself), a unit without a ROM gets
a 404 that says so, the page shells carry no data and need no token while the API does, and
plotly.js is served from the installed package."""

from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient
from web_fixtures import ROM_INPUTS, write_rom

from steamtwin.live.config import load_config
from steamtwin.rom.reconstruction import predict_field
from steamtwin.rom.romfile import load_rom
from steamtwin.web.access import is_page_shell, load_tokens
from steamtwin.web.app import create_app
from steamtwin.web.pages import PLOTLY_JS, STATIC_DIR, bundled_style_ids

ACK = "a" * 40


@pytest.fixture
def rom_config(tmp_path, serve_config):
    write_rom(tmp_path / "rom.npz")
    source = serve_config.source
    source.write_text(source.read_text().replace('name = "unit1"\n',
                                                 'name = "unit1"\nrom = "rom.npz"\n'))
    return load_config(source)


@pytest.mark.filterwarnings("ignore::steamtwin.rom.estimator.ExtrapolationWarning")
def test_the_blade_field_is_the_roms_for_the_stored_samples_inputs(tmp_path, rom_config):
    bundle = load_rom(tmp_path / "rom.npz")
    with TestClient(create_app(rom_config.database, rom_config)) as client:
        surface = client.get("/api/units/unit1/blade/surface")
        assert surface.status_code == 200 and "max-age" in surface.headers["cache-control"]
        mesh = surface.json()
        assert mesh["inputs"] == list(ROM_INPUTS)
        triangles = np.array(mesh["triangles"])
        assert triangles.max() == len(mesh["points"]) - 1  # renumbered onto its own nodes
        nodes = np.unique(bundle.mesh.boundary_triangles)
        np.testing.assert_allclose(mesh["points"], bundle.mesh.points[nodes], atol=1e-7)
        for name, index in mesh["probes"].items():  # the probes sit on the surface
            np.testing.assert_allclose(mesh["points"][index],
                                       bundle.mesh.points[bundle.probes[name]], atol=1e-7)
        field = client.get("/api/units/unit1/blade",
                           params={"time": "2026-03-01T00:30:00.5+00:00"}).json()
        assert field["time"] == "2026-03-01T00:30:00+00:00"  # the last sample at or before
        measured = client.get("/api/units/unit1/series", params={
            "signal": "hp_exhaust_temperature", "start": field["time"],
            "end": field["time"]}).json()["value"][0]
        assert field["inputs"]["hp_exhaust_temperature"] == measured == 700.0  # the spike
        expected = predict_field(bundle, field["inputs"])
        np.testing.assert_allclose(field["temperature"], expected[nodes], atol=1e-3)
        assert field["probes"] == pytest.approx({n: expected[k] for n, k in
                                                 bundle.probes.items()})
        assert field["min"] == pytest.approx(expected[nodes].min())
        latest = client.get("/api/units/unit1/blade").json()
        assert latest["time"] == "2026-03-01T01:59:59+00:00"
        missing = client.get("/api/units/unit2/blade/surface")
        assert missing.status_code == 404 and "no blade ROM" in missing.json()["error"]
        early = client.get("/api/units/unit1/blade", params={"time": "2026-02-01T00:00:00Z"})
        assert early.status_code == 404 and "no sample" in early.json()["error"]
    (tmp_path / "rom.npz").write_bytes(b"not a ROM")
    with TestClient(create_app(rom_config.database, rom_config)) as client:
        broken = client.get("/api/units/unit1/blade")
        assert broken.status_code == 503 and "rom.npz" in broken.json()["error"]


def test_page_shells_are_open_and_data_free_while_the_api_needs_the_token(tmp_path,
                                                                          serve_config):
    tokens = tmp_path / "tokens.toml"
    tokens.write_text(f'[[tokens]]\nname = "lead"\nrole = "ack"\ntoken = "{ACK}"\n')
    app = create_app(serve_config.database, serve_config, load_tokens(tokens))
    with TestClient(app) as client:
        for path in ("/", "/units/unit1", "/units/unit1/history", "/units/unit1/alarms",
                     "/units/unit1/calibration", "/units/unit1/blade"):
            page = client.get(path)
            assert page.status_code == 200, path
            assert "unit2" not in page.text and "flow_coefficient" not in page.text
        shell = client.get('/units/"><b>x/alarms').text  # the name from the URL, escaped
        assert "<b>" not in shell and "&quot;&gt;&lt;b&gt;x" in shell
        for path in ("/units/unit1", "/units/unit1/blade"):  # no unit is looked up: the
            known = client.get(path).text                  # shells tell none exists
            assert client.get(path.replace("unit1", "unitX")).text == known.replace(
                "unit1", "unitX")
        for path in ("/docs", "/openapi.json"):  # the API reference: no stored value
            reference = client.get(path)
            assert reference.status_code == 200, path
            assert "01:59:59" not in reference.text and "unit2" not in reference.text
        for path in ("/api/units", "/api/units/unit1/blade", "/api/events", "/health",
                     "/metrics", "/api/units/unit1/series/download?signal=load"):
            assert client.get(path).status_code == 401, path
        assert client.post("/api/alarms/1/acknowledge", json={"by": "x"}).status_code == 401
    assert is_page_shell("GET", "/units/u1") and not is_page_shell("POST", "/units/u1")
    assert not is_page_shell("GET", "/api/units") and not is_page_shell("GET", "/unitsx")


def test_plotly_js_comes_from_the_installed_package(serve_config):
    with TestClient(create_app(serve_config.database, serve_config)) as client:
        script = client.get("/vendor/plotly.min.js")
        assert script.status_code == 200
        assert script.headers["content-type"].startswith("text/javascript")
        assert len(script.content) == PLOTLY_JS.stat().st_size
        assert "max-age" in script.headers["cache-control"]
        page = client.get("/units/unit1/blade").text  # the one page that draws with it
        for name in bundled_style_ids():  # its inline style sheets are kept out
            assert f'<template id="{name}">' in page
        assert 'id="plotly.js-style-global" class="no-inline-styles"' in page


def test_time_series_pages_load_the_vendored_uplot_not_plotly(serve_config):
    """uPlot (50 kB) rather than plotly.js (4.8 MB) on every time-series page: evaluating
    plotly.js took most of the Unit page's load time (issue 22); its MIT licence ships
    beside it."""
    vendor = STATIC_DIR / "vendor" / "uplot"
    assert "Permission is hereby granted" in (vendor / "LICENSE").read_text(encoding="utf-8")
    with TestClient(create_app(serve_config.database, serve_config)) as client:
        script = client.get("/static/vendor/uplot/uPlot.iife.min.js")
        assert script.status_code == 200
        assert script.content.startswith(b"/*! https://github.com/leeoniya/uPlot")
        assert len(script.content) < 100_000
        assert client.get("/static/vendor/uplot/uPlot.min.css").status_code == 200
        for path in ("", "/history", "/alarms", "/calibration"):
            page = client.get(f"/units/unit1{path}").text
            assert "/static/vendor/uplot/uPlot.iife.min.js" in page
            assert "/static/vendor/uplot/uPlot.min.css" in page
            assert "plotly" not in page, path
        assert "uPlot" not in client.get("/").text  # the fleet page draws no chart
