"""The HTTP service run inside the live service's event loop (``steamtwin serve --http-port``).

:func:`http_companion` gives :func:`~steamtwin.live.runner.run_service` a companion: given the
service's open historian it builds the app on connections of that same database (one process:
DuckDB allows one writer process; the app's readers are connections of the same instance,
see :mod:`steamtwin.web.queries`) and runs uvicorn's ``Server.serve()`` as a task of the same
asyncio loop until the service stops. The socket is bound here first, so a port in use or a
refused bind address is a clear :class:`HttpServiceError` before anything runs, and port 0
(any free port) reports the one taken through ``on_bound``; the socket is closed when the
server stops. Uvicorn's own signal capture is
switched off: the service owns SIGINT/SIGTERM and stops the server through its stop event.
Uvicorn logs through :mod:`logging` (``uvicorn.error``, ``uvicorn.access``).
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
from collections.abc import Awaitable, Callable, Generator
from dataclasses import dataclass, field

import uvicorn

from steamtwin.errors import SteamtwinError
from steamtwin.live.config import ServiceConfig
from steamtwin.live.historian import LiveHistorian
from steamtwin.web.access import AccessPolicy, check_bind
from steamtwin.web.app import WebSettings, create_app

__all__ = ["HttpServiceError", "HttpSettings", "bind_socket", "http_companion"]


class HttpServiceError(SteamtwinError, OSError):
    """The HTTP service cannot start (names the address and why)."""


@dataclass(frozen=True)
class HttpSettings:
    """Where to listen (``host``, ``port``; 0: any free port), who may ask (``access``) and
    the API's limits (``web``)."""

    host: str = "127.0.0.1"
    port: int = 8080
    access: AccessPolicy = field(default_factory=AccessPolicy)
    web: WebSettings = field(default_factory=WebSettings)


def bind_socket(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host``:``port`` (IPv6 when the host is an IPv6 address)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host.strip("[]"), port))
        sock.listen(2048)
    except OSError as error:
        sock.close()
        raise HttpServiceError(f"cannot listen on {host}:{port}: {error.strerror or error}"
                               ) from None
    sock.setblocking(False)
    return sock


class _ServiceServer(uvicorn.Server):
    """Uvicorn without its signal capture (the live service owns the signals)."""

    @contextlib.contextmanager
    def capture_signals(self) -> Generator[None, None, None]:
        yield


def http_companion(settings: HttpSettings, config: ServiceConfig | None = None,
                   on_bound: Callable[[str, int], None] | None = None
                   ) -> Callable[[LiveHistorian, asyncio.Event], Awaitable[None]]:
    """A companion for :func:`~steamtwin.live.runner.run_service`: serves the app on the
    service's historian until ``done`` is set. Refuses (AccessError) a non-loopback host
    without tokens and (HttpServiceError) an address it cannot bind: here, before the
    service starts; ``on_bound(host, port)`` then tells the port taken."""
    check_bind(settings.host, settings.access)
    sock = bind_socket(settings.host, settings.port)
    if on_bound is not None:
        on_bound(settings.host, sock.getsockname()[1])

    async def serve(historian: LiveHistorian, done: asyncio.Event) -> None:
        app = create_app(historian.connection.cursor, config, settings.access, settings.web)
        server = _ServiceServer(uvicorn.Config(
            app, log_config=None, access_log=False, timeout_graceful_shutdown=2,
            lifespan="on"))
        task = asyncio.create_task(server.serve(sockets=[sock]))
        waiter = asyncio.create_task(done.wait())
        try:
            await asyncio.wait({task, waiter}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            server.should_exit = True
            waiter.cancel()
            await task
            sock.close()

    return serve
