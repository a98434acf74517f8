"""The HTTP service's FastAPI application (issue 22, items 1 and 3): :func:`create_app`.

JSON API on the live twin's historian (all times ISO 8601 with an offset, answers in UTC; all
values SI):

* ``GET /api/units``, ``GET /api/units/{unit}/signals`` — units, and each unit's stored
  signals per source with SI unit, meaning, tag and instrument σ where the tag map says;
* ``GET /api/units/{unit}/series`` — one signal over a range, downsampled to at most
  ``max_points`` (extrema kept: :mod:`steamtwin.web.queries`); ``…/series/download`` — the
  raw samples as CSV or Parquet (built in memory: no endpoint writes a file);
* ``GET /api/alarms``, ``GET /api/alarms/{id}`` (with evidence), ``POST
  /api/alarms/{id}/acknowledge`` (a token of role "ack", or open loopback access);
* ``GET /api/units/{unit}/parameters`` (trajectory and current), ``…/quality`` (the gate's
  flags), ``GET /api/provenance`` (model files, hashes, versions);
* ``GET /api/units/{unit}/blade/surface`` (the ROM's blade surface, once) and ``…/blade``
  (its temperatures for the sample at a time: :mod:`steamtwin.web.blade`);
* ``GET /api/units/{unit}/rotor`` (the rotor's latest stresses and temperatures, the
  allowable, the life consumed over a range: :mod:`steamtwin.web.rotor`) and
  ``…/rotor/advice?to=0.3`` (the fastest ramp to a load within the allowable);
* ``GET /api/events`` — server-sent events (:mod:`steamtwin.web.events`);
* ``GET /health`` (liveness, and whether each unit keeps up: its last stored sample's age),
  ``GET /metrics`` (Prometheus text), ``GET /docs`` (API reference), ``GET /openapi.json``.

Bad requests get a 4xx with ``{"error": "...", "details": [...]}`` naming the parameter and
what was expected; an unexpected error is logged and answered with a 500 without a traceback
(:class:`~steamtwin.web.access.SecurityMiddleware` is the outermost layer).
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Annotated, Literal

import duckdb
import pandas as pd
from fastapi import FastAPI, Header, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, Response, StreamingResponse
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from steamtwin.errors import DataError, SteamtwinError
from steamtwin.live.config import ServiceConfig
from steamtwin.rom.romfile import RomFileError
from steamtwin.web.access import AccessPolicy, SecurityMiddleware
from steamtwin.web.apidocs import render_api_docs
from steamtwin.web.blade import BladeFields, NoRomError
from steamtwin.web.catalog import Catalog, signal_info
from steamtwin.web.coalesce import ResponseCoalescer
from steamtwin.web.events import LiveFeed
from steamtwin.web.metrics import CONTENT_TYPE, RequestMetrics, RequestStats, exposition
from steamtwin.web.pages import STATIC_DIR
from steamtwin.web.pages import router as pages_router
from steamtwin.web.queries import HistorianReader, SeriesQuery
from steamtwin.web.rotor import NoAdviceError, NoRotorError, RotorViews

__all__ = ["ApiError", "WebSettings", "create_app"]

LOG = logging.getLogger("steamtwin.web")

SourceName = Annotated[Literal["measured", "twin", "residual"],
                       Query(description="measured (cleaned DCS), twin or residual")]
SignalName = Annotated[str, Query(description="canonical signal name, e.g. "
                                  "hp_exhaust_temperature")]
Start = Annotated[str | None, Query(description="ISO 8601 with offset, e.g. "
                                    "2026-03-01T12:00:00+00:00; default: end minus the "
                                    "default span")]
Span = Annotated[float | None, Query(ge=0.0, description="instead of start: the range's "
                                    "length before end (s), e.g. 60 for the last minute")]
MaxPoints = Annotated[int | None, Query(ge=10, description="most points (buckets) in the "
                                       "answer; default and limit: the service's max_points")]
End = Annotated[str | None, Query(description="ISO 8601 with offset; default: the last "
                                  "stored sample")]


@dataclass(frozen=True)
class WebSettings:
    """Limits of the API. ``max_points``: largest series answer (points or buckets);
    ``max_span_s``: longest range a series, parameter or quality query may ask (s, default
    400 days); ``max_download_s``: longest raw download (s, default 7 days: 604 800 rows of
    1-s data); ``default_span_s``: the range when none is given (s, ending at the last
    sample); ``stale_after_s``: last-sample age (wall clock, s) beyond which /health says a
    unit does not keep up; ``readers``: pooled database connections; ``poll_s``: the live
    feed's poll interval (s); ``cache_s``: how old an answer to an identical GET, and the
    units' last-sample times, may be when reused across requests (s; 0: never reused —
    :mod:`steamtwin.web.coalesce`); ``signals_cache_s``: the same for each unit's signal
    list and the unit names; ``recent_s``: the recent past of each unit's series kept in
    memory for short raw ranges (s; 0: none — :mod:`steamtwin.web.queries`)."""

    max_points: int = 2000
    max_span_s: float = 400 * 86_400.0
    max_download_s: float = 7 * 86_400.0
    default_span_s: float = 3600.0
    stale_after_s: float = 30.0
    readers: int = 4
    poll_s: float = 0.25
    cache_s: float = 0.2
    signals_cache_s: float = 5.0
    recent_s: float = 600.0


class ApiError(SteamtwinError, ValueError):
    """A refused request: HTTP ``status`` and a message for the client."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.message = message


class Acknowledgement(BaseModel):
    """Body of an acknowledgement: ``by`` names the operator when the service has no tokens
    (with a token, the token's name is stored)."""

    by: str | None = Field(None, min_length=1, max_length=100,
                           description="operator (needed without tokens)")


def _error(status: int, message: str, details: list | None = None) -> JSONResponse:
    body: dict[str, object] = {"error": message}
    if details:
        body["details"] = details
    return JSONResponse(body, status_code=status)


def _validation_details(error: RequestValidationError) -> list[dict[str, str]]:
    details = []
    for item in error.errors():
        where = ".".join(str(part) for part in item.get("loc", ()))
        details.append({"where": where, "problem": str(item.get("msg", "invalid"))})
    return details


def parse_time(text: str, name: str) -> pd.Timestamp:
    """An ISO 8601 time with an offset (``2026-03-01T12:00:00+01:00``, ``…Z``) → UTC;
    ApiError 422 naming the parameter otherwise."""
    try:
        value = datetime.fromisoformat(text.strip())
    except ValueError:
        raise ApiError(422, f"{name}={text!r}: not an ISO 8601 time (expected e.g. "
                       "2026-03-01T12:00:00+00:00)") from None
    if value.tzinfo is None:
        raise ApiError(422, f"{name}={text!r}: the time has no offset (add Z or +hh:mm); "
                       "a local time is ambiguous")
    return pd.Timestamp(value).tz_convert("UTC")


def _reader(historian: str | Path | HistorianReader | Callable[[], duckdb.DuckDBPyConnection],
            size: int, recent_s: float) -> HistorianReader:
    if isinstance(historian, HistorianReader):
        return historian
    if callable(historian):
        return HistorianReader(historian, size, recent_s=recent_s)
    path = Path(historian)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such historian database")
    try:
        return HistorianReader(lambda: duckdb.connect(str(path)), size, recent_s=recent_s)
    except duckdb.IOException as error:  # e.g. the file is locked by a service elsewhere
        raise DataError(f"{path}: cannot open the historian ({error}); DuckDB lets one process "
                        "write a database: serve it from that process (steamtwin serve "
                        "--http-port)") from None


def create_app(historian: str | Path | HistorianReader | Callable[[], duckdb.DuckDBPyConnection],
               config: ServiceConfig | None = None, access: AccessPolicy | None = None,
               settings: WebSettings | None = None) -> FastAPI:
    """The service's application on ``historian`` (a DuckDB file, a connection factory —
    e.g. the running service's ``historian.connection.cursor`` — or a reader), describing
    the units of ``config`` (None: those in the database), with ``access`` (None: open, for
    loopback only) and ``settings`` (see the module docstring)."""
    settings = settings or WebSettings()
    access = access or AccessPolicy()
    reader = _reader(historian, settings.readers, settings.recent_s)
    catalog = Catalog(config)
    feed = LiveFeed(reader, poll_s=settings.poll_s)
    blades = BladeFields(config)
    rotors = RotorViews(config)

    @contextlib.asynccontextmanager
    async def lifespan(_app: FastAPI):
        task = asyncio.create_task(feed.run())
        try:
            yield
        finally:
            feed.close()
            await task
            if not isinstance(historian, HistorianReader):
                reader.close()

    app = FastAPI(title="steamtwin live twin", version=catalog.versions["steamtwin"] or "",
                  description="The live twin's historian over HTTP: units, signals, series, "
                  "alarms, parameters, data quality, provenance, live events.",
                  docs_url=None, redoc_url=None, lifespan=lifespan)
    stats = RequestStats()
    app.state.reader = reader
    app.state.feed = feed
    app.state.catalog = catalog

    fresh_s = settings.cache_s

    def known_units() -> list[str]:
        return sorted(set(catalog.units) | set(reader.last_times(fresh_s)))

    # -- errors: a JSON message, never a traceback ----------------------------------------
    @app.exception_handler(ApiError)
    async def api_error(_request: Request, error: ApiError) -> JSONResponse:
        return _error(error.status, error.message)

    @app.exception_handler(RequestValidationError)
    async def invalid(_request: Request, error: RequestValidationError) -> JSONResponse:
        details = _validation_details(error)
        summary = "; ".join(f"{d['where']}: {d['problem']}" for d in details)
        return _error(422, f"invalid request: {summary}", details)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(_request: Request, error: StarletteHTTPException) -> JSONResponse:
        return _error(error.status_code, str(error.detail))

    # -- helpers --------------------------------------------------------------------------
    def check_unit(unit: str) -> str:
        # a unit once seen stays: its name may come from a list up to signals_cache_s old
        if unit in catalog.units or unit in reader.last_times(settings.signals_cache_s):
            return unit
        units = known_units()  # perhaps new since the list was kept: look again
        if unit not in units:
            raise ApiError(404, f"unknown unit {unit!r}; units: {', '.join(units) or 'none'}")
        return unit

    def time_range(unit: str, start: str | None, end: str | None, limit_s: float,
                   span_s: float | None = None) -> tuple[pd.Timestamp, pd.Timestamp]:
        if span_s is not None and start is not None:
            raise ApiError(422, "give start or span_s, not both")
        last = reader.last_times(fresh_s).get(unit, pd.Timestamp.now(tz="UTC"))
        stop = parse_time(end, "end") if end is not None else last
        span = settings.default_span_s if span_s is None else span_s
        begin = (parse_time(start, "start") if start is not None
                 else stop - pd.Timedelta(seconds=span))
        if begin > stop:
            raise ApiError(422, f"start={begin.isoformat()} is after end={stop.isoformat()}")
        span = (stop - begin).total_seconds()
        if span > limit_s:
            raise ApiError(422, f"the range {begin.isoformat()} .. {stop.isoformat()} spans "
                           f"{span / 86_400.0:.1f} days; at most {limit_s / 86_400.0:g} days")
        return begin, stop

    def series_query(unit: str, signal: str, source: str, start: str | None,
                     end: str | None, limit_s: float, span_s: float | None = None
                     ) -> SeriesQuery:
        check_unit(unit)
        stored = [s for src, s in reader.signals(unit, settings.signals_cache_s)
                  if src == source]
        if signal not in stored:  # perhaps new since the list was kept: look again
            stored = [s for src, s in reader.signals(unit) if src == source]
        if signal not in stored:
            raise ApiError(404, f"unit {unit!r} has no {source} signal {signal!r}; "
                           f"{source} signals: {', '.join(stored) or 'none'}")
        begin, stop = time_range(unit, start, end, limit_s, span_s)
        return SeriesQuery(unit, source, signal, begin, stop)

    # -- API ------------------------------------------------------------------------------
    @app.get("/api/units", summary="The units and their last stored sample")
    def units() -> list[dict]:
        last = reader.last_times(fresh_s)
        return [{"name": name, "last_sample": None if name not in last
                 else last[name].isoformat(), "configured": name in catalog.units}
                for name in known_units()]

    @app.get("/api/units/{unit}/signals", summary="A unit's stored signals with SI units")
    def signals(unit: str) -> list[dict]:
        check_unit(unit)
        tag_map = catalog.tag_map(unit)
        return [{"source": source, "signal": signal, **signal_info(signal, tag_map)}
                for source, signal in reader.signals(unit)]

    @app.get("/api/units/{unit}/series", summary="One signal over a time range")
    def series(unit: str, signal: SignalName, source: SourceName = "measured",
               start: Start = None, end: End = None, span_s: Span = None,
               max_points: MaxPoints = None) -> dict:
        """Raw samples (time, value in SI, gate flags) when the range holds at most
        ``max_points``; otherwise that many equal buckets with min, max (and their times),
        mean and count (M4 aggregation, extrema kept)."""
        if max_points is not None and max_points > settings.max_points:
            raise ApiError(422, f"max_points={max_points}: at most {settings.max_points}")
        query = series_query(unit, signal, source, start, end, settings.max_span_s, span_s)
        info = signal_info(signal, catalog.tag_map(unit))
        return {"unit": unit, "signal": signal, "source": source,
                "si_unit": info["si_unit"], "start": query.start.isoformat(),
                "end": query.end.isoformat(),
                **reader.series(query, max_points or settings.max_points)}

    @app.get("/api/units/{unit}/series/download", summary="One signal's raw samples as a file")
    def download(unit: str, signal: SignalName, source: SourceName = "measured",
                 start: Start = None, end: End = None,
                 format: Literal["csv", "parquet"] = "csv") -> Response:
        """CSV or Parquet of time (UTC), value (SI) and flag, built in memory."""
        query = series_query(unit, signal, source, start, end, settings.max_download_s)
        frame = reader.raw(query).rename(
            columns={"value": f"{signal} [{signal_info(signal, None)['si_unit'] or '-'}]"})
        name = f"{unit}_{source}_{signal}.{format}"
        buffer = io.BytesIO()
        if format == "parquet":
            frame.to_parquet(buffer, index=False)
            media = "application/vnd.apache.parquet"
        else:
            buffer.write(frame.to_csv(index=False).encode("utf-8"))
            media = "text/csv; charset=utf-8"
        return Response(buffer.getvalue(), media_type=media,
                        headers={"content-disposition": f'attachment; filename="{name}"'})

    @app.get("/api/alarms", summary="Alarms, newest first")
    def alarms(unit: str | None = None, active: bool = False) -> list[dict]:
        if unit is not None:
            check_unit(unit)
        return reader.alarms(unit, active)

    @app.get("/api/alarms/{alarm_id}", summary="One alarm with its evidence")
    def alarm(alarm_id: int) -> dict:
        found = reader.alarm(alarm_id)
        if found is None:
            raise ApiError(404, f"no alarm {alarm_id}")
        return found

    @app.post("/api/alarms/{alarm_id}/acknowledge", summary="Acknowledge an alarm")
    def acknowledge(alarm_id: int, body: Acknowledgement, request: Request) -> dict:
        """Needs a token of role "ack" when the service has tokens; without tokens (loopback
        only) ``by`` names the operator. The first acknowledgement stands (409 after)."""
        token = request.scope.get("state", {}).get("token")
        if access.required:
            if token is None or not token.may_acknowledge:
                raise ApiError(403, "this token is read-only; acknowledging alarms needs a "
                               "token of role \"ack\"")
            by = token.name
        elif body.by is None:
            raise ApiError(422, "body.by: name the operator acknowledging the alarm")
        else:
            by = body.by
        before = reader.alarm(alarm_id)
        if before is None:
            raise ApiError(404, f"no alarm {alarm_id}")
        if before["acknowledged_at"] is not None:
            raise ApiError(409, f"alarm {alarm_id} was acknowledged by "
                           f"{before['acknowledged_by']} at {before['acknowledged_at']}")
        try:
            return reader.acknowledge(alarm_id, by, pd.Timestamp.now(tz="UTC"))
        except duckdb.TransactionException:  # the service updated the alarm at that moment
            raise ApiError(503, f"alarm {alarm_id} changed while being acknowledged; try "
                           "again") from None

    @app.get("/api/units/{unit}/parameters", summary="Parameter trajectory and current set")
    def parameters(unit: str, start: Start = None, end: End = None) -> dict:
        check_unit(unit)
        begin = None if start is None else parse_time(start, "start")
        stop = None if end is None else parse_time(end, "end")
        if begin is not None and stop is not None and begin > stop:
            raise ApiError(422, f"start={begin.isoformat()} is after end={stop.isoformat()}")
        return {"unit": unit, "current": reader.current_parameters(unit),
                "trajectory": reader.parameters(unit, begin, stop)}

    @app.get("/api/units/{unit}/quality", summary="The data-quality gate's flags")
    def quality(unit: str, start: Start = None, end: End = None) -> dict:
        check_unit(unit)
        begin, stop = time_range(unit, start, end, settings.max_span_s)
        return reader.quality(unit, begin, stop)

    @app.get("/api/provenance", summary="Model files, hashes and software versions")
    def provenance() -> dict:
        document = catalog.provenance()
        document["parameters"] = {unit: reader.current_parameters(unit)
                                  for unit in known_units()}
        return document

    @app.get("/api/units/{unit}/blade/surface", summary="The blade ROM's surface mesh")
    def blade_surface(unit: str) -> JSONResponse:
        """Surface points (m), triangles and probe indices; the same while the ROM file is
        (cacheable for an hour)."""
        check_unit(unit)
        try:
            body = blades.surface(unit)
        except NoRomError as error:
            raise ApiError(404, str(error)) from None
        except RomFileError as error:  # names the file and what is wrong with it
            raise ApiError(503, f"the blade ROM cannot be used: {error}") from None
        return JSONResponse(body, headers={"cache-control": "private, max-age=3600"})

    @app.get("/api/units/{unit}/blade", summary="The blade's temperature field at a time")
    def blade_field(unit: str, time: End = None) -> dict:
        """The ROM's surface temperatures (K, order of ``…/blade/surface``) and probe
        temperatures for the last sample at or before ``time`` (default: the last), from that
        sample's measured ROM inputs (SI)."""
        check_unit(unit)
        at = parse_time(time, "time") if time is not None else reader.last_times(
            fresh_s).get(unit, pd.Timestamp.now(tz="UTC"))
        try:
            names = blades.inputs(unit)
        except NoRomError as error:
            raise ApiError(404, str(error)) from None
        except RomFileError as error:
            raise ApiError(503, f"the blade ROM cannot be used: {error}") from None
        found = reader.sample_at(unit, at)
        if found is None:
            raise ApiError(404, f"unit {unit!r} has no sample at or before {at.isoformat()}")
        stamp, values = found
        missing = [name for name in names if values.get(name) is None]
        if missing:
            raise ApiError(422, f"the sample of {stamp.isoformat()} has no measured "
                           f"{', '.join(missing)} (the ROM's inputs: {', '.join(names)})")
        inputs = {name: values[name] for name in names}
        return {"unit": unit, "time": stamp.isoformat(), "inputs": inputs,
                **blades.field(unit, inputs)}

    @app.get("/api/units/{unit}/rotor", summary="The rotor's stresses and life consumed")
    def rotor(unit: str, start: Start = None, end: End = None, span_s: Span = None) -> dict:
        """The rotor's last stored values at or before ``end`` (SI: K, Pa; ``*_stress`` the
        signed equivalent stress), the allowable stress (Pa, None if not configured) and the
        fatigue and creep damage at the groove root and the bore over the range (at most
        ``max_download_s``; dimensionless, 1 = crack initiation or rupture)."""
        check_unit(unit)
        try:
            allowable = rotors.allowable(unit)
        except NoRotorError as error:
            raise ApiError(404, str(error)) from None
        begin, stop = time_range(unit, start, end, settings.max_download_s, span_s)
        try:
            life = rotors.life(reader, unit, begin, stop, reader.last_times(fresh_s).get(unit))
        except SteamtwinError as error:  # the spec's rotor steel or section unusable
            raise ApiError(503, f"the rotor life cannot be computed: {error}") from None
        return {"unit": unit, "allowable_pa": allowable,
                "latest": rotors.latest(reader, unit, stop), "life": life}

    @app.get("/api/units/{unit}/rotor/advice", summary="The fastest ramp within the allowable")
    def rotor_advice(unit: str, to: Annotated[float, Query(
            gt=0.0, le=1.1, description="target load, fraction of rated load, e.g. 0.3")],
            hold_s: Annotated[float, Query(ge=0.0, le=86_400.0, description="hold after the "
                                           "ramp checked too (s)")] = 3600.0) -> dict:
        """From the last saved rotor state and the load measured then: the fastest constant
        ramp to ``to`` whose groove and bore equivalent stress stay within the allowable over
        the ramp and the hold (rate in %/min, peak and allowable in Pa, the ramp's fatigue and
        creep damage)."""
        check_unit(unit)
        try:
            return rotors.advice(reader, unit, to, hold_s)
        except (NoRotorError, NoAdviceError) as error:
            raise ApiError(404, str(error)) from None
        except SteamtwinError as error:  # a load off the operating line, no feasible ramp
            raise ApiError(422, str(error)) from None

    @app.get("/api/events", summary="Live samples and alarms (server-sent events)",
             response_class=StreamingResponse)
    async def events(unit: str | None = None, last_event_id: Annotated[str | None, Header(
            description="the id (sample time, ISO 8601) of the last event received: the "
            "stream starts with the samples stored since, and the active alarms")] = None
                     ) -> StreamingResponse:
        """``text/event-stream``: ``sample`` (time, values by source/signal), ``alarm`` (a
        new alarm), ``alarms`` (the active list after a change). A reconnecting client that
        sends ``Last-Event-ID`` first gets the samples it missed (:mod:`steamtwin.web.events`)."""
        if unit is not None:
            await asyncio.to_thread(check_unit, unit)
        since = None if not last_event_id else parse_time(last_event_id, "Last-Event-ID")
        return StreamingResponse(feed.stream(unit, since), media_type="text/event-stream",
                                 headers={"cache-control": "no-store",
                                          "x-accel-buffering": "no"})

    # -- operations -----------------------------------------------------------------------
    @app.get("/health", summary="Liveness and whether each unit keeps up")
    def health() -> dict:
        """``keeps_up``: every unit's last stored sample is at most ``stale_after_s`` old
        (wall clock); age in s."""
        now = pd.Timestamp.now(tz="UTC")
        units = {name: {"last_sample": last.isoformat(),
                        "age_s": (now - last).total_seconds()}
                 for name, last in reader.last_times(fresh_s).items()}
        keeps_up = bool(units) and all(u["age_s"] <= settings.stale_after_s
                                       for u in units.values())
        return {"status": "ok", "keeps_up": keeps_up, "stale_after_s": settings.stale_after_s,
                "units": units}

    @app.get("/metrics", summary="Prometheus metrics", response_class=Response)
    def prometheus() -> Response:
        now = time.time()
        last = reader.last_times(fresh_s)
        active = {}
        for alarm_row in reader.alarms(None, True):
            active[alarm_row["unit"]] = active.get(alarm_row["unit"], 0) + 1
        families = [
            ("steamtwin_unit_last_sample_timestamp_seconds", "gauge",
             "Time of the unit's last stored sample (Unix s).",
             [("", {"unit": u}, t.timestamp()) for u, t in sorted(last.items())]),
            ("steamtwin_unit_last_sample_age_seconds", "gauge",
             "Wall-clock age of the unit's last stored sample (s).",
             [("", {"unit": u}, now - t.timestamp()) for u, t in sorted(last.items())]),
            ("steamtwin_alarms_active", "gauge", "Alarms without an end, per unit.",
             [("", {"unit": u}, float(active.get(u, 0))) for u in sorted(last)]),
            ("steamtwin_events_subscribers", "gauge", "Open server-sent event streams.",
             [("", {}, float(feed.subscribers))]),
            *stats.families()]
        return Response(exposition(families), media_type=CONTENT_TYPE)

    @app.get("/docs", response_class=HTMLResponse, include_in_schema=False)
    def docs() -> HTMLResponse:
        return HTMLResponse(render_api_docs(app.openapi()))

    app.include_router(pages_router)
    app.mount("/static", StaticFiles(directory=str(STATIC_DIR)), name="static")

    # added last = outermost: the security layer sees every response, a 500 included
    app.add_middleware(ResponseCoalescer, max_age_s=settings.cache_s)
    app.add_middleware(RequestMetrics, stats=stats)
    app.add_middleware(SecurityMiddleware, policy=access)
    return app
