"""The rotor's API (issue 23, item 6): ``GET /api/units/{unit}/rotor`` gives the latest stored
rotor values, the configured allowable and the life consumed over a range — the life module's
answer on the stored series, cached — and the Rotor page's shell is linked and data-free."""

from __future__ import annotations

import pandas as pd
import pytest
from fastapi.testclient import TestClient
from rotor_fixtures import (
    ALLOWABLE_MPA,
    SECONDS,
    START,
    fill_rotor,
    rotor_frames,
    write_rotor_config,
)

import steamtwin.web.rotor as web_rotor
from steamtwin.live.rotor_stream import ROTOR_SIGNALS
from steamtwin.rotor.geometry import rotor_geometry
from steamtwin.rotor.life import rotor_life
from steamtwin.rotor.steel import steel
from steamtwin.spec import load_spec
from steamtwin.web.app import create_app
from steamtwin.web.catalog import ROTOR_MEANINGS

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")
WHOLE = {"start": START.isoformat(),
         "end": (START + pd.Timedelta(seconds=SECONDS - 1)).isoformat()}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rotor")
    fill_rotor(folder / "twin.duckdb")
    config = write_rotor_config(folder, folder / "twin.duckdb")
    with TestClient(create_app(folder / "twin.duckdb", config)) as client:
        yield client


def test_the_rotor_answer_is_the_life_module_on_the_stored_series(client):
    answer = client.get("/api/units/unit1/rotor", params=WHOLE)
    assert answer.status_code == 200, answer.text
    body = answer.json()
    assert body["allowable_pa"] == ALLOWABLE_MPA * 1e6
    frames = rotor_frames(0, SECONDS)
    last = frames["twin"].iloc[-1]
    assert body["latest"]["time"] == frames["twin"].index[-1].isoformat()
    assert body["latest"]["values"]["rotor_groove_stress"] == pytest.approx(
        last["rotor_groove_stress"], rel=1e-12)
    spec = load_spec("reference")
    material = steel(rotor_geometry(spec).section.material)
    twin = frames["twin"]
    run = pd.DataFrame({f"{where}_{quantity}": twin[f"rotor_{where}_{name}"]
                        for where in ("groove", "bore")
                        for quantity, name in (("equivalent", "stress"),
                                               ("temperature", "temperature"))})
    life = body["life"]
    assert life["samples"] == SECONDS
    for where in ("groove", "bore"):
        expected = rotor_life(run, material, load=frames["measured"]["load"], location=where,
                              rated_load=spec.design.generator_power)
        got = life["locations"][where]
        assert got["fatigue_damage"] == pytest.approx(expected.fatigue_damage, rel=1e-9)
        assert got["creep_damage"] == pytest.approx(expected.creep_damage, rel=1e-9)
        assert got["ramps"] == len(expected.per_ramp) >= 3  # down, up, down, (up)
        assert sum(day["damage"] for day in got["per_day"]) == pytest.approx(
            got["total_damage"], rel=1e-9)
    # the groove root swings 360 MPa, the bore 100 MPa: more fatigue at the groove
    groove, bore = life["locations"]["groove"], life["locations"]["bore"]
    assert groove["largest_range_pa"] == pytest.approx(360e6, rel=1e-3)
    assert groove["fatigue_damage"] > bore["fatigue_damage"] > 0.0


def test_life_answers_are_cached_per_range_and_last_sample(client, monkeypatch):
    calls = []
    real = web_rotor.rotor_life
    monkeypatch.setattr(web_rotor, "rotor_life",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    params = {"end": WHOLE["end"], "span_s": 1800}
    first = client.get("/api/units/unit1/rotor", params=params).json()
    assert len(calls) == 2  # groove and bore
    assert client.get("/api/units/unit1/rotor", params=params).json() == first
    assert len(calls) == 2
    assert first["life"]["samples"] == 1801


def test_a_unit_without_a_rotor_and_bad_ranges_are_refused(client):
    answer = client.get("/api/units/unit2/rotor")
    assert answer.status_code == 404
    assert "has no rotor model: add rotor =" in answer.json()["error"]
    answer = client.get("/api/units/unit1/rotor", params={"span_s": 30 * 86400})
    assert answer.status_code == 422 and "at most 7 days" in answer.json()["error"]


def test_rotor_signals_carry_si_units_and_the_page_is_linked(client):
    assert set(ROTOR_MEANINGS) == set(ROTOR_SIGNALS)  # every stored rotor signal described
    signals = {s["signal"]: s for s in client.get("/api/units/unit1/signals").json()
               if s["source"] == "twin"}
    assert signals["rotor_groove_stress"]["si_unit"] == "Pa"
    assert signals["rotor_bore_temperature"]["si_unit"] == "K"
    unit_page = client.get("/units/unit1").text
    assert '<a href="/units/unit1/rotor">Rotor</a>' in unit_page
    shell = client.get("/units/unit1/rotor").text
    assert '<script src="/static/rotor.js"></script>' in shell
    assert "e+0" not in shell and "MPa</strong>" not in shell  # no figures in the shell
    assert client.get("/static/rotor.js").status_code == 200
