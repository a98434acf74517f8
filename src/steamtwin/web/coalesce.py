"""One answer for many identical polls (issue 22: 200 clients polling at 1 Hz on 2 cores).

Every open Unit page polls the same few URLs each second — the last minute of a signal
(``span_s``), the active alarms, /health. :class:`ResponseCoalescer`, an ASGI middleware,
answers an identical GET (same path and query) within ``max_age_s`` from the answer computed
first, and lets concurrent identical requests wait for that one computation instead of
repeating it (the "single flight" of request coalescing, as in Go's
``golang.org/x/sync/singleflight`` or a CDN's request collapsing). The answers are at most
``max_age_s`` older than the database, which the live feed (server-sent events) does not share;
any other method (an acknowledgement) empties the store. Only JSON 200 answers of the
``prefixes`` are kept, never the event stream or a download.
"""

from __future__ import annotations

import asyncio
import time
from collections import OrderedDict

from starlette.types import ASGIApp, Receive, Scope, Send

__all__ = ["ResponseCoalescer"]

MAX_BODY = 1 << 20
"""Largest answer kept (bytes)."""


class ResponseCoalescer:
    """ASGI middleware (see the module docstring): ``max_age_s`` (s; 0 turns it off),
    ``prefixes`` of the paths it may answer, ``size`` answers kept at most."""

    def __init__(self, app: ASGIApp, max_age_s: float,
                 prefixes: tuple[str, ...] = ("/api/", "/health"),
                 excluded: tuple[str, ...] = ("/api/events", "/download"),
                 size: int = 256) -> None:
        self.app = app
        self.max_age_s = max_age_s
        self.prefixes = prefixes
        self.excluded = excluded
        self.size = size
        self._kept: OrderedDict[tuple[str, bytes], tuple[float, list[dict]]] = OrderedDict()
        self._running: dict[tuple[str, bytes], asyncio.Future] = {}

    def _eligible(self, scope) -> bool:
        path = scope.get("path", "")
        return (self.max_age_s > 0.0 and scope.get("method") == "GET"
                and path.startswith(self.prefixes)
                and not any(part in path for part in self.excluded))

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        if scope.get("method") not in ("GET", "HEAD"):
            self._kept.clear()  # e.g. an acknowledgement: what was kept may be out of date
        if not self._eligible(scope):
            await self.app(scope, receive, send)
            return
        key = (scope["path"], scope.get("query_string", b""))
        kept = self._kept.get(key)
        if kept is not None and time.monotonic() - kept[0] <= self.max_age_s:
            await self._replay(kept[1], send)
            return
        running = self._running.get(key)
        if running is not None:
            messages = await asyncio.shield(running)
            if messages is not None:
                await self._replay(messages, send)
                return
        future = asyncio.get_running_loop().create_future()
        self._running[key] = future
        messages: list[dict] = []

        async def capture(message) -> None:
            messages.append(message)
            await send(message)

        try:
            await self.app(scope, receive, capture)
        finally:
            del self._running[key]
            reusable = self._reusable(messages)
            future.set_result(messages if reusable else None)
            if reusable:
                self._kept[key] = (time.monotonic(), messages)
                self._kept.move_to_end(key)
                while len(self._kept) > self.size:
                    self._kept.popitem(last=False)

    @staticmethod
    def _reusable(messages: list[dict]) -> bool:
        if not messages or messages[0].get("status") != 200:
            return False
        headers = dict(messages[0].get("headers", []))
        body = sum(len(m.get("body", b"")) for m in messages[1:])
        return headers.get(b"content-type", b"").startswith(b"application/json") and (
            body <= MAX_BODY)

    @staticmethod
    async def _replay(messages: list[dict], send) -> None:
        for message in messages:  # copies: the layers outside add headers to what they send
            copy = dict(message)
            if "headers" in copy:
                copy["headers"] = list(copy["headers"])
            await send(copy)
