"""The live twin's HTTP service (issue 22): a FastAPI app on the service's DuckDB historian —
JSON API, server-sent events, /health, /metrics, an API reference at /docs — with bearer-token
access and security headers, run by ``steamtwin serve --http-port`` inside the service's own
event loop. The public objects, imported on first use:"""

from steamtwin.lazy import lazy_exports

_EXPORTS = {
    "create_app": "steamtwin.web.app",
    "WebSettings": "steamtwin.web.app",
    "ApiError": "steamtwin.web.app",
    "AccessPolicy": "steamtwin.web.access",
    "AccessError": "steamtwin.web.access",
    "load_tokens": "steamtwin.web.access",
    "HistorianReader": "steamtwin.web.queries",
    "LiveFeed": "steamtwin.web.events",
    "HttpSettings": "steamtwin.web.server",
    "http_companion": "steamtwin.web.server",
}

__all__ = [*_EXPORTS]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
