"""Prometheus metrics of the HTTP service (issue 22, item 1), in the text exposition format
0.0.4 written by hand (Prometheus docs, "Exposition formats": ``# HELP``/``# TYPE`` lines,
``name{label="value"} number``, label values escaped ``\\`` → ``\\\\``, ``"`` → ``\\"``,
newline → ``\\n``; a histogram as cumulative ``_bucket{le=...}`` series ending in
``le="+Inf"``, with ``_sum`` and ``_count``). The bucket bounds are client_python's defaults.

:class:`RequestMetrics` is an ASGI middleware counting requests into :class:`RequestStats` by
route template (not the raw path: bounded label cardinality), method and status, and timing
them.
"""

from __future__ import annotations

import bisect
import time
from collections import defaultdict
from collections.abc import Iterable, Mapping

from starlette.types import ASGIApp, Receive, Scope, Send

__all__ = ["CONTENT_TYPE", "Family", "RequestMetrics", "RequestStats", "exposition"]

CONTENT_TYPE = "text/plain; version=0.0.4; charset=utf-8"
BUCKETS_S = (0.005, 0.01, 0.025, 0.05, 0.075, 0.1, 0.25, 0.5, 0.75, 1.0, 2.5, 5.0, 7.5, 10.0)
"""Histogram bucket bounds (s): prometheus/client_python ``Histogram.DEFAULT_BUCKETS``."""


def _escape(value: str) -> str:
    return value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")


def _labels(labels: Mapping[str, str]) -> str:
    if not labels:
        return ""
    return "{" + ",".join(f'{k}="{_escape(str(v))}"' for k, v in labels.items()) + "}"


def _number(value: float) -> str:
    if value != value:
        return "NaN"
    if value in (float("inf"), float("-inf")):
        return "+Inf" if value > 0 else "-Inf"
    return repr(float(value))


Family = tuple[str, str, str, Iterable[tuple[str, Mapping[str, str], float]]]
"""A metric family: name, type, help and samples (name suffix, labels, value)."""


def exposition(families: Iterable[Family]) -> str:
    """Text format of metric families (:data:`Family`)."""
    lines = []
    for name, kind, text, samples in families:
        lines.append(f"# HELP {name} {text.replace(chr(92), chr(92) * 2).replace(chr(10), ' ')}")
        lines.append(f"# TYPE {name} {kind}")
        for suffix, labels, value in samples:
            lines.append(f"{name}{suffix}{_labels(labels)} {_number(value)}")
    return "\n".join(lines) + "\n"


class RequestStats:
    """Request counts by (route, method, status) and duration histograms by route."""

    def __init__(self) -> None:
        self.requests: dict[tuple[str, str, str], int] = defaultdict(int)
        self.durations: dict[str, list[float]] = {}  # route → bucket counts (+Inf last), sum, count

    def observe(self, route: str, method: str, status: int, seconds: float) -> None:
        """Count one request and its duration (s)."""
        self.requests[(route, method, str(status))] += 1
        counts = self.durations.setdefault(route, [0.0] * (len(BUCKETS_S) + 3))
        counts[bisect.bisect_left(BUCKETS_S, seconds)] += 1  # le: upper bound inclusive
        counts[-2] += seconds
        counts[-1] += 1

    def families(self) -> list[Family]:
        """The request counter and duration histogram as metric families."""
        counter = [("", {"route": r, "method": m, "status": s}, float(n))
                   for (r, m, s), n in sorted(self.requests.items())]
        histogram = []
        for route, counts in sorted(self.durations.items()):
            cumulative = 0.0
            for bound, n in zip((*BUCKETS_S, float("inf")), counts[:-2], strict=True):
                cumulative += n
                label = "+Inf" if bound == float("inf") else repr(bound)
                histogram.append(("_bucket", {"route": route, "le": label}, cumulative))
            histogram.append(("_sum", {"route": route}, counts[-2]))
            histogram.append(("_count", {"route": route}, counts[-1]))
        return [("steamtwin_http_requests_total", "counter",
                 "HTTP requests answered, by route template, method and status.", counter),
                ("steamtwin_http_request_duration_seconds", "histogram",
                 "Time to answer an HTTP request (s), by route template.", histogram)]


class RequestMetrics:
    """ASGI middleware recording every HTTP request into ``stats``."""

    def __init__(self, app: ASGIApp, stats: RequestStats) -> None:
        self.app = app
        self.stats = stats

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = time.perf_counter()
        status = [500]

        async def recording(message) -> None:
            if message["type"] == "http.response.start":
                status[0] = message["status"]
            await send(message)

        try:
            await self.app(scope, receive, recording)
        finally:
            route = getattr(scope.get("route"), "path", None) or "unmatched"
            self.stats.observe(route, scope.get("method", ""), status[0],
                               time.perf_counter() - started)
