"""The HTTP service's JSON API (issue 22, item 1) on a historian filled by the live twin's
writer: units and signals with SI units, series raw and downsampled, downloads, alarms,
parameters, data quality, provenance, health; bad requests get a 4xx naming the problem and
no traceback ever reaches the client."""

from __future__ import annotations

import io
import shutil
import subprocess
import sys
from typing import get_args

import pandas as pd
import pytest
from fastapi.testclient import TestClient
from web_fixtures import unit_block, write_serve_config

from steamtwin.errors import DataError
from steamtwin.live.historian import SOURCES, LiveHistorian
from steamtwin.web.app import SourceName, WebSettings, create_app

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

SERIES = "/api/units/unit1/series?signal=hp_exhaust_temperature"


def _client(db, config) -> TestClient:
    return TestClient(create_app(db, config, settings=WebSettings(max_points=500)))


@pytest.fixture
def client(filled_db, serve_config):
    """A client of the app on a fresh copy (tests that acknowledge)."""
    with _client(filled_db, serve_config) as client:
        yield client


@pytest.fixture(scope="module")
def reading(tmp_path_factory, pristine_db):
    """One client for the tests that only read."""
    folder = tmp_path_factory.mktemp("reading")
    shutil.copyfile(pristine_db, folder / "twin.duckdb")
    with _client(folder / "twin.duckdb",
                 write_serve_config(folder, folder / "twin.duckdb")) as client:
        yield client


def test_the_api_names_the_historians_sources():
    assert set(get_args(get_args(SourceName)[0])) == set(SOURCES)


def test_units_and_signals_carry_si_units_and_instrument_errors(reading):
    units = reading.get("/api/units").json()
    assert units == [
        {"name": "unit1", "last_sample": "2026-03-01T01:59:59+00:00", "configured": True},
        {"name": "unit2", "last_sample": "2026-03-01T00:09:59+00:00", "configured": True}]
    signals = {(s["source"], s["signal"]): s for s in
               reading.get("/api/units/unit1/signals").json()}
    assert set(signals) == {("measured", "hp_exhaust_temperature"),
                            ("measured", "control_stage_pressure"),
                            ("twin", "hp_exhaust_temperature"), ("twin", "blade_leading_edge"),
                            ("residual", "hp_exhaust_temperature")}
    exhaust = signals[("measured", "hp_exhaust_temperature")]
    assert exhaust["si_unit"] == "K" and exhaust["instrument_sigma"] == 1.5
    assert exhaust["tag"] == "10LBC10CT001"
    assert signals[("measured", "control_stage_pressure")]["si_unit"] == "Pa"
    assert signals[("twin", "blade_leading_edge")]["si_unit"] == "K"


def test_a_short_range_is_raw_with_the_gates_flags(reading):
    answer = reading.get(f"{SERIES}&start=2026-03-01T01:29:59%2B01:00"
                        "&end=2026-03-01T00:30:01Z").json()  # an offset other than UTC
    assert not answer["downsampled"] and answer["si_unit"] == "K"
    assert answer["time"] == ["2026-03-01T00:29:59+00:00", "2026-03-01T00:30:00+00:00",
                              "2026-03-01T00:30:01+00:00"]
    assert answer["value"][1] == 700.0
    assert answer["flag"] == [None, ["SPIKE", "OUT_OF_RANGE"], None]


def test_a_long_range_is_downsampled_and_keeps_the_spike(reading):
    answer = reading.get(f"{SERIES}&start=2026-03-01T00:00:00Z&end=2026-03-01T02:00:00Z"
                        "&max_points=100").json()
    assert answer["downsampled"] and len(answer["time"]) == 100 and answer["count"] == 7200
    assert answer["bucket_s"] == 72.0
    peak = max(range(100), key=lambda k: answer["max"][k])
    assert answer["max"][peak] == 700.0
    assert answer["max_time"][peak] == "2026-03-01T00:30:00+00:00"
    default = reading.get(SERIES).json()  # the last hour, at the service's max_points
    assert default["start"] == "2026-03-01T00:59:59+00:00" and len(default["time"]) == 500
    minute = reading.get(f"{SERIES}&span_s=60").json()  # the last minute: raw
    assert minute["start"] == "2026-03-01T01:58:59+00:00" and len(minute["time"]) == 61


def test_downloads_hold_the_raw_samples(reading):
    window = "&start=2026-03-01T00:29:00Z&end=2026-03-01T00:31:00Z"
    csv = reading.get(f"/api/units/unit1/series/download?signal=hp_exhaust_temperature{window}")
    assert csv.status_code == 200 and "attachment" in csv.headers["content-disposition"]
    table = pd.read_csv(io.StringIO(csv.text))
    assert list(table.columns) == ["time", "hp_exhaust_temperature [K]", "flag"]
    assert len(table) == 121 and table["hp_exhaust_temperature [K]"].max() == 700.0
    parquet = reading.get("/api/units/unit1/series/download?signal=blade_leading_edge&source="
                         f"twin&format=parquet{window}")
    frame = pd.read_parquet(io.BytesIO(parquet.content))
    assert len(frame) == 121 and str(frame["time"].dt.tz) == "UTC"
    assert frame["blade_leading_edge [K]"].iloc[0] == pytest.approx(780.0 + 0.001 * 1740)


def test_alarms_parameters_quality_and_provenance(client):
    alarms = client.get("/api/alarms").json()
    assert [(a["id"], a["kind"], a["active"]) for a in alarms] == [
        (2, "degradation", True), (1, "sensor_fault", False)]
    assert [a["id"] for a in client.get("/api/alarms?active=true&unit=unit1").json()] == [2]
    assert client.get("/api/alarms?unit=unit2").json() == []
    one = client.get("/api/alarms/1").json()
    assert one["evidence"] == {"statistic": 9.1, "threshold": 5.0}
    assert one["end"] == "2026-03-01T00:30:10+00:00"
    done = client.post("/api/alarms/2/acknowledge", json={"by": "operator A"}).json()
    assert done["acknowledged_by"] == "operator A" and done["acknowledged_at"] is not None
    parameters = client.get("/api/units/unit1/parameters").json()
    assert parameters["current"]["flow_coefficient"]["value"] == 0.98
    assert parameters["current"]["flow_coefficient"]["reason"] == "degradation"
    # the filter's 95 % interval where the value came from it, None where it did not
    flow, friction = (parameters["current"][n] for n in ("flow_coefficient",
                                                         "friction_coefficient"))
    assert (flow["low"], flow["high"]) == (0.965, 0.995)
    assert friction["low"] is None and friction["high"] is None
    assert [(p["name"], p["value"]) for p in parameters["trajectory"]] == [
        ("flow_coefficient", 0.99), ("friction_coefficient", 1.0), ("flow_coefficient", 0.98)]
    quality = client.get("/api/units/unit1/quality?start=2026-03-01T00:00:00Z").json()
    assert quality["flagged"] == 2
    assert quality["signals"]["hp_exhaust_temperature"] == {
        "samples": 7200, "flagged": 1, "flags": {"SPIKE": 1, "OUT_OF_RANGE": 1}}
    assert quality["signals"]["control_stage_pressure"]["flags"] == {"STUCK": 1}
    provenance = client.get("/api/provenance").json()
    assert provenance["units"]["unit1"]["turbine"] == "reference"
    assert len(provenance["units"]["unit1"]["tags"]["sha256"]) == 64
    assert provenance["versions"]["duckdb"] and provenance["versions"]["steamtwin"]
    assert provenance["parameters"]["unit1"]["flow_coefficient"]["value"] == 0.98


def test_health_tells_whether_the_service_keeps_up(filled_db):
    with TestClient(create_app(filled_db, settings=WebSettings(stale_after_s=1e9))) as client:
        health = client.get("/health").json()
        assert health["status"] == "ok" and health["keeps_up"]
        assert health["units"]["unit1"]["age_s"] > 0.0
    with TestClient(create_app(filled_db)) as client:  # March's samples are not fresh
        assert client.get("/health").json()["keeps_up"] is False


@pytest.mark.parametrize(("url", "status", "message"), [
    ("/api/units/unit9/signals", 404, "unknown unit 'unit9'; units: unit1, unit2"),
    (SERIES.replace("hp_exhaust_temperature", "colour"), 404,
     "unit 'unit1' has no measured signal 'colour'; measured signals: control_stage_pressure"),
    (f"{SERIES}&source=twin&signal=control_stage_pressure", 404, "no twin signal"),
    (f"{SERIES}&start=2026-03-01T02:00:00Z&end=2026-03-01T01:00:00Z", 422,
     "start=2026-03-01T02:00:00+00:00 is after end=2026-03-01T01:00:00+00:00"),
    (f"{SERIES}&start=1900-01-01T00:00:00Z", 422, "at most 400 days"),
    (f"{SERIES}&span_s=1e12", 422, "at most 400 days"),
    (f"{SERIES}&span_s=60&start=2026-03-01T00:00:00Z", 422, "start or span_s, not both"),
    (f"{SERIES}&start=yesterday", 422, "start='yesterday': not an ISO 8601 time"),
    (f"{SERIES}&end=2026-03-01T00:00:00", 422, "the time has no offset"),
    (f"{SERIES}&source=forecast", 422, "query.source"),
    (f"{SERIES}&max_points=5", 422, "query.max_points"),
    (f"{SERIES}&max_points=501", 422, "max_points=501: at most 500"),
    ("/api/units/unit1/series/download?signal=hp_exhaust_temperature&start="
     "2026-01-01T00:00:00Z", 422, "at most 7 days"),
    ("/api/alarms/99", 404, "no alarm 99"),
    ("/api/alarms/one", 422, "path.alarm_id"),
    ("/api/nothing", 404, "Not Found"),
])
def test_bad_requests_get_a_clear_4xx(reading, url, status, message):
    response = reading.get(url)
    assert response.status_code == status
    assert message in response.json()["error"]
    assert "Traceback" not in response.text


def test_malformed_acknowledgements_are_refused(client):
    bad_json = client.post("/api/alarms/1/acknowledge", content=b'{"by": ',
                           headers={"content-type": "application/json"})
    assert bad_json.status_code == 422 and "JSON decode error" in bad_json.json()["error"]
    no_name = client.post("/api/alarms/1/acknowledge", json={})
    assert no_name.status_code == 422 and "name the operator" in no_name.json()["error"]
    assert client.post("/api/alarms/99/acknowledge", json={"by": "x"}).status_code == 404
    assert client.get("/api/alarms/1").json()["acknowledged_at"] is None


def test_an_unexpected_error_is_a_500_without_a_traceback(client, caplog):
    def broken(*_args, **_kwargs):
        raise RuntimeError("secret detail of the database")

    client.app.state.reader.alarms = broken
    response = client.get("/api/alarms")
    assert response.status_code == 500
    assert response.json() == {"error": "internal error; the service log has the details"}
    assert "secret" not in response.text and response.headers["x-frame-options"] == "DENY"
    assert "secret detail of the database" in caplog.text  # the log has it


def test_the_api_reference_is_served_without_script(reading):
    page = reading.get("/docs")
    assert page.status_code == 200 and "<script" not in page.text
    schema = reading.get("/openapi.json").json()
    for path in ("/api/units/{unit}/series", "/api/alarms/{alarm_id}/acknowledge",
                 "/api/events", "/health", "/metrics"):
        assert path in schema["paths"] and f"<code>{path}</code>" in page.text


def test_identical_polls_share_one_answer_until_it_ages(filled_db):
    app = create_app(filled_db, settings=WebSettings(cache_s=60.0))
    with TestClient(app) as client:
        reader = app.state.reader
        calls = []
        alarms = reader.alarms
        reader.alarms = lambda *args, **kwargs: calls.append(args) or alarms(*args, **kwargs)
        first = [client.get("/api/alarms?active=true").json() for _ in range(5)]
        assert len(calls) == 1 and first[0] == first[-1]
        client.get("/api/alarms?active=false")  # another query: computed
        assert len(calls) == 2
        client.post("/api/alarms/2/acknowledge", json={"by": "op"})  # a write empties the store
        again = client.get("/api/alarms?active=true").json()
        assert len(calls) == 3 and again[0]["acknowledged_by"] == "op"
        assert client.get("/metrics").headers["content-type"].startswith("text/plain")
        assert client.get("/api/alarms/99").status_code == 404  # errors are never kept
    with TestClient(create_app(filled_db, settings=WebSettings(cache_s=0.0))) as client:
        reader = client.app.state.reader
        calls.clear()
        alarms = reader.alarms
        reader.alarms = lambda *args, **kwargs: calls.append(args) or alarms(*args, **kwargs)
        for _ in range(3):
            client.get("/api/alarms")
        assert len(calls) == 3


def test_a_signal_stored_after_the_list_was_kept_is_found(filled_db):
    app = create_app(filled_db, settings=WebSettings(signals_cache_s=600.0, cache_s=0.0))
    with TestClient(app) as client:
        url = "/api/units/unit2/series?signal=blade_trailing_edge&source=twin&span_s=10"
        assert client.get(url).status_code == 404  # not stored yet; the list is now kept
        frames, flags = unit_block(600, 5)
        frames["twin"]["blade_trailing_edge"] = 760.0
        with LiveHistorian(filled_db) as historian:  # the service's writer, same database
            historian.commit_block("unit2", frames, flags)
        answer = client.get(url)
        assert answer.status_code == 200 and answer.json()["value"] == [760.0] * 5


def test_a_database_another_process_writes_is_refused_clearly(tmp_path):
    db = tmp_path / "held.duckdb"
    holder = subprocess.Popen(
        [sys.executable, "-c", f"import duckdb, sys; c = duckdb.connect({str(db)!r}); "
         "print('held', flush=True); sys.stdin.read()"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(DataError, match=r"cannot open the historian.*steamtwin serve "
                           r"--http-port"):
            create_app(db)
    finally:
        holder.communicate("", timeout=30)
