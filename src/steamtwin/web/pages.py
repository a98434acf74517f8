"""The service's HTML pages (issue 22, item 2; the dashboard pages come later): a router the
app includes, and the static files (style sheet, later the charting library with its licence)
served from the package's ``static`` folder — the plant network has no CDN."""

from __future__ import annotations

from html import escape
from importlib import resources

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse

__all__ = ["STATIC_DIR", "router"]

STATIC_DIR = resources.files("steamtwin.web") / "static"

router = APIRouter(include_in_schema=False)


@router.get("/", response_class=HTMLResponse)
def landing(request: Request) -> HTMLResponse:
    """The landing page: the units and where the API is."""
    units = request.app.state.known_units()
    items = "".join(f"<li><code>{escape(name)}</code></li>" for name in units)
    return HTMLResponse(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
        "<title>steamtwin</title><link rel=\"stylesheet\" href=\"/static/style.css\"></head>"
        "<body><main><h1>steamtwin live twin</h1>"
        f"<h2>Units</h2><ul>{items or '<li>none yet</li>'}</ul>"
        "<p><a href=\"/docs\">API reference</a> · <a href=\"/health\">health</a> · "
        "<a href=\"/metrics\">metrics</a></p></main></body></html>")
