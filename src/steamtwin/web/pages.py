"""The service's dashboard pages (issue 22, item 2): a router the app includes, the static
files (style sheet, the pages' scripts) served from the package's ``static`` folder, and the
charting libraries — the plant network has no CDN: the time-series pages draw with uPlot
(MIT licence, © Leon Sorokin; ``static/vendor/uplot/``, 50 kB, v1.6.32 from the npm registry,
with its LICENSE), the blade page's 3-D mesh with plotly.js, served from the installed
``plotly`` wheel (``plotly/package_data/plotly.min.js``, MIT licence, 4.8 MB: evaluating it
took most of the Unit page's load, issue 22). The style rules plotly.js would insert inline
are in ``static/plotly.css`` (taken from that bundle's plotcss module); linked under the id
plotly.js looks for, they keep it from inserting a ``<style>`` the Content-Security-Policy
refuses; the bundle's other inline sheet (MapLibre's, for map traces, unused here) is skipped
the same way: the page holds an empty element with the id the bundle checks for before
inserting it (:func:`bundled_style_ids`).

Every page is a data-free shell rendered here (the unit's name, escaped, and empty
containers); its script in ``static/`` fetches the figures from ``/api`` with the bearer token
the operator typed (kept in the tab's ``sessionStorage``), and follows ``/api/events`` for live
samples. No inline script or style: the Content-Security-Policy forbids them
(:mod:`steamtwin.web.access`).

Pages: ``/`` (fleet: one card per unit; a single unit goes straight to its page),
``/units/{unit}`` (load, main steam, measured vs twin with the instrument-error band,
residuals, parameters, active alarms; live), ``…/history`` (any range, zoom re-queries the
downsampled API, CSV/Parquet downloads), ``…/alarms`` (list, evidence plot, acknowledge),
``…/calibration`` (parameter trajectory), ``…/blade`` (the ROM's blade field, 3-D, at a
sample or replayed over a range), ``…/rotor`` (the rotor's stresses against the allowable,
its temperatures, the fatigue and creep damage so far).
"""

from __future__ import annotations

import re
from functools import cache
from html import escape
from importlib import resources
from pathlib import Path

from fastapi import APIRouter
from fastapi.responses import FileResponse, HTMLResponse

__all__ = ["PAGES", "PLOTLY_JS", "STATIC_DIR", "bundled_style_ids", "router"]

STATIC_DIR = resources.files("steamtwin.web") / "static"
PLOTLY_JS = Path(str(resources.files("plotly") / "package_data" / "plotly.min.js"))
"""plotly.js as the plotly wheel ships it (MIT licence, © Plotly, Inc.)."""

PAGES = (("", "Unit"), ("history", "History"), ("alarms", "Alarms"),
         ("calibration", "Calibration"), ("blade", "Blade"), ("rotor", "Rotor"))
"""(path under /units/{unit}/, title) of each unit page."""

router = APIRouter(include_in_schema=False)
PLOTLY_HEAD = ('<link rel="stylesheet" id="plotly.js-style-global" class="no-inline-styles" '
               'href="/static/plotly.css">')
PLOTLY_TAG = '<script src="/vendor/plotly.min.js"></script>'
UPLOT_HEAD = '<link rel="stylesheet" href="/static/vendor/uplot/uPlot.min.css">'
UPLOT_TAG = '<script src="/static/vendor/uplot/uPlot.iife.min.js"></script>'


@cache
def bundled_style_ids() -> tuple[str, ...]:
    """Ids of the style sheets the plotly.js bundle inserts unless an element has that id."""
    text = PLOTLY_JS.read_text(encoding="utf-8")
    return tuple(sorted(set(re.findall(r'getElementById\("([0-9a-f]{64})"\)', text))))


def _layout(title: str, script: str, body: str, unit: str | None = None,
            current: str = "", charts: str | None = "uplot") -> HTMLResponse:
    """A page: navigation (the unit's pages), token field, ``body``, its script and the
    charting library it draws with: ``charts`` "uplot" (time series), "plotly" (3-D) or
    None."""
    links = ""
    if unit is not None:
        base = f"/units/{escape(unit)}"
        here = ' aria-current="page"'
        links = "".join(f'<a href="{base}{"/" + path if path else ""}"'
                        f'{here if path == current else ""}>{name}</a>'
                        for path, name in PAGES)
    heading = escape(title if unit is None else f"{unit} · {title}")
    return HTMLResponse(
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<title>{heading} — steamtwin</title>'
        '<link rel="icon" href="data:,"><link rel="stylesheet" href="/static/style.css">'
        f'{UPLOT_HEAD if charts == "uplot" else PLOTLY_HEAD if charts == "plotly" else ""}'
        '</head>'
        f'<body data-unit="{escape(unit or "")}">'
        '<header class="bar"><a class="brand" href="/">steamtwin</a>'
        f'<nav>{links}</nav><span class="tools">'
        '<label>token <input id="token" type="password" autocomplete="off" size="12" '
        'placeholder="if required"></label><span id="status" role="status"></span>'
        '</span></header>'
        f'<main><h1>{heading}</h1>{body}</main>'
        + ("".join(f'<template id="{name}"></template>' for name in bundled_style_ids())
           + PLOTLY_TAG if charts == "plotly" else UPLOT_TAG if charts == "uplot" else "")
        + '<script src="/static/common.js"></script>'
        f'<script src="/static/{script}.js"></script></body></html>')


@router.get("/vendor/plotly.min.js")
def plotly_js() -> FileResponse:
    """The charting library from the installed plotly package (cached a day)."""
    return FileResponse(PLOTLY_JS, media_type="text/javascript",
                        headers={"cache-control": "public, max-age=86400"})


@router.get("/", response_class=HTMLResponse)
def fleet() -> HTMLResponse:
    """The fleet: one card per unit with its load and active alarms."""
    return _layout("fleet", "fleet", '<div id="cards" class="cards"></div>'
                   '<p class="links"><a href="/docs">API reference</a> · '
                   '<a href="/health">health</a> · <a href="/metrics">metrics</a></p>',
                   charts=None)


@router.get("/units/{unit}", response_class=HTMLResponse)
def unit_page(unit: str) -> HTMLResponse:
    """Load, main steam, measured vs twin with the instrument band, residuals, parameters,
    active alarms; live."""
    return _layout("unit", "unit", (
        '<div id="tiles" class="tiles"></div>'
        '<h2>Measured vs twin (band: twin ± 2σ of the instrument)</h2>'
        '<div id="temperatures" class="grid"></div>'
        '<h2>Residuals (measured − twin)</h2><div id="residuals" class="chart"></div>'
        '<div class="columns"><section><h2>Parameters</h2><table id="parameters"></table>'
        '</section><section><h2>Active alarms</h2><ul id="alarms"></ul></section></div>'),
        unit)


@router.get("/units/{unit}/history", response_class=HTMLResponse)
def history_page(unit: str) -> HTMLResponse:
    """Any stored range of one signal; zoom re-queries; CSV/Parquet downloads."""
    return _layout("history", "history", (
        '<form id="query" class="controls"><label>signal <select id="signal"></select></label>'
        '<label>from <input id="start" size="25" placeholder="ISO 8601, e.g. '
        '2026-03-01T00:00:00Z"></label><label>to <input id="end" size="25" '
        'placeholder="default: last sample"></label><button type="submit">show</button>'
        '</form><p id="summary"></p><div id="chart" class="chart tall"></div>'
        '<p>Download the raw samples of this range: <a id="csv" download>CSV</a> · '
        '<a id="parquet" download>Parquet</a></p>'), unit, "history")


@router.get("/units/{unit}/alarms", response_class=HTMLResponse)
def alarms_page(unit: str) -> HTMLResponse:
    """The alarms, one's evidence plot, and acknowledgement."""
    return _layout("alarms", "alarms", (
        '<p class="controls"><label>operator <input id="operator" size="14" '
        'placeholder="your name (no token)"></label></p>'
        '<table id="alarms" class="wide"></table>'
        '<h2 id="evidence-title">Evidence</h2><table id="evidence"></table>'
        '<div id="evidence-chart" class="chart"></div>'), unit, "alarms")


@router.get("/units/{unit}/calibration", response_class=HTMLResponse)
def calibration_page(unit: str) -> HTMLResponse:
    """The parameter trajectory and each swap, with the residual RMS around it."""
    return _layout("calibration", "calibration", (
        '<div id="trajectory" class="chart"></div><h2>Parameter swaps</h2>'
        '<p class="note">The historian stores each swap (time, values, reason) but not the '
        'recalibration\'s own RMSE before/after; shown instead: the RMS of the stored '
        'residuals in the 10 minutes before and after each swap.</p>'
        '<table id="swaps" class="wide"></table>'), unit, "calibration")


@router.get("/units/{unit}/blade", response_class=HTMLResponse)
def blade_page(unit: str) -> HTMLResponse:
    """The control-stage blade's temperature field (ROM) at the last or a chosen sample, or
    replayed over a range (a ramp)."""
    return _layout("blade", "blade", (
        '<form id="query" class="controls"><label>time <input id="time" size="25" '
        'placeholder="ISO 8601; default: the last sample"></label>'
        '<button type="submit">show</button><button type="button" id="latest">latest'
        '</button></form><form id="replay" class="controls"><label>replay from <input '
        'id="replay-from" size="22" placeholder="ISO 8601"></label><label>to <input '
        'id="replay-to" size="22" placeholder="ISO 8601"></label><label>every <input '
        'id="replay-step" size="4" value="60"> s</label><button type="submit">replay'
        '</button><button type="button" id="replay-stop">stop</button></form>'
        '<p id="summary"></p>'
        '<div class="columns"><div id="blade" class="chart tall"></div>'
        '<section><h2>Probes</h2><table id="probes"></table></section></div>'),
        unit, "blade", charts="plotly")


@router.get("/units/{unit}/rotor", response_class=HTMLResponse)
def rotor_page(unit: str) -> HTMLResponse:
    """The rotor's equivalent stress at the groove root and the bore against the allowable,
    their temperatures, and the fatigue and creep damage consumed over the range."""
    return _layout("rotor", "rotor", (
        '<form id="query" class="controls"><label>last <select id="span">'
        '<option value="3600">hour</option><option value="21600">6 hours</option>'
        '<option value="86400" selected>day</option><option value="604800">week</option>'
        '</select></label><button type="submit">show</button></form>'
        '<div id="tiles" class="tiles"></div>'
        '<h2>Equivalent stress (tensile positive) and the allowable</h2>'
        '<div id="stress" class="chart"></div>'
        '<h2>Metal temperature</h2><div id="temperature" class="chart"></div>'
        '<h2>Life consumed in the range</h2>'
        '<p class="note">Fatigue: rainflow, Neuber, Manson–Coffin–Basquin with Morrow\'s '
        'mean stress and the ASME design factors; creep: Larson–Miller time fraction '
        '(docs/rotor.md).</p><table id="life" class="wide"></table>'
        '<h2>Per day</h2><table id="days" class="wide"></table>'
        '<h2>Ramp advice</h2><form id="advise" class="controls"><label>to load <input '
        'id="advice-to" size="4" value="30"> % of rated</label><label>hold after <input '
        'id="advice-hold" size="5" value="60"> min</label><button type="submit">advise'
        '</button></form><p id="advice-note" class="note"></p>'
        '<table id="advice" class="wide"></table>'), unit, "rotor")
