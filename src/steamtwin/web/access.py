"""Who may reach the HTTP service, and what every response carries (issue 22, item 3).

* **Bind address**: loopback (127.0.0.0/8, ::1, ``localhost``) by default; any other address
  only with tokens (:func:`check_bind`), so a service reachable from the plant network never
  answers an anonymous request.
* **Tokens**: a TOML token file (:func:`load_tokens`)::

      [[tokens]]
      name = "control-room"      # who: stored as the acknowledging operator
      role = "ack"               # "read" (GET only) or "ack" (may also acknowledge alarms)
      token = "…"                # ≥ 32 characters, e.g. `python -c "import secrets;
                                 #   print(secrets.token_urlsafe(32))"`

  With tokens every request needs ``Authorization: Bearer <token>`` (RFC 6750 §2.1); a
  missing or wrong one gets 401 with ``WWW-Authenticate: Bearer`` (RFC 6750 §3). The token is
  compared in constant time against every configured token (``hmac.compare_digest`` of
  SHA-256 digests, so neither the length nor the first differing byte leaks; the loop does not
  stop at a match).
* **Page shells**: a ``GET`` of a dashboard page (``/``, ``/units/…``), of a static file
  (``/static/…``, ``/vendor/…``) or of the API reference (``/docs``, ``/openapi.json``)
  needs no token (:func:`is_page_shell`): a browser cannot add a header to a navigation, and
  these carry no data — a unit page's shell is the same for any name in the path (the unit is
  not looked up, so the shells do not even tell which units exist); the pages' scripts fetch
  every figure from ``/api`` with the token the operator typed, kept in the tab's
  ``sessionStorage`` and sent as the ``Authorization`` header. Deliberately no login page and
  no session cookie: a cookie is sent by the browser on its own, so the acknowledge ``POST``
  would need cross-site request forgery defences (OWASP CSRF Prevention Cheat Sheet), and a
  token in the URL (query or path) would land in the history and in proxy logs (RFC 6750
  §5.3: "Don't pass bearer tokens in page URLs"); a header sent by the page's own script has
  neither problem. ``/health`` and ``/metrics`` (last-sample times, alarm counts) need the
  token like ``/api`` (a Prometheus scrape job can send one: ``authorization`` in its
  ``scrape_config``).
* **Security headers** on every response, errors included (OWASP Secure Headers Project):
  ``Content-Security-Policy: default-src 'self'; …`` (no inline script, no other origin: the
  pages and their scripts come from the package; W3C CSP Level 3), ``X-Content-Type-Options:
  nosniff``, ``X-Frame-Options: DENY``, ``Referrer-Policy: no-referrer``, and
  ``Cache-Control: no-store`` unless the response sets its own.
"""

from __future__ import annotations

import hashlib
import hmac
import ipaddress
import json
import logging
import tomllib
from dataclasses import dataclass
from pathlib import Path

from starlette.types import ASGIApp, Receive, Scope, Send

from steamtwin.errors import SteamtwinError
from steamtwin.textfile import read_utf8_text

__all__ = ["ROLES", "SECURITY_HEADERS", "AccessError", "AccessPolicy", "SecurityMiddleware",
           "Token", "check_bind", "is_loopback", "is_page_shell", "load_tokens"]

ROLES = ("read", "ack")
LOG = logging.getLogger("steamtwin.web")
MIN_TOKEN_CHARS = 32
"""Shortest accepted token: 32 URL-safe characters ≈ 190 bits (``secrets.token_urlsafe(32)``
gives 43)."""

SECURITY_HEADERS: tuple[tuple[bytes, bytes], ...] = (
    (b"content-security-policy",
     b"default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
     b"object-src 'none'; base-uri 'none'; frame-ancestors 'none'; form-action 'self'"),
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
    (b"cache-control", b"no-store"),  # live data: never from a cache (OWASP)
)


class AccessError(SteamtwinError, ValueError):
    """A token file or bind address the service refuses (names the file or the address)."""


@dataclass(frozen=True)
class Token:
    """One accepted bearer token: its holder's ``name`` and ``role`` ("read" or "ack")."""

    name: str
    role: str
    digest: bytes

    @property
    def may_acknowledge(self) -> bool:
        """Whether the holder may acknowledge alarms."""
        return self.role == "ack"


def _digest(text: str) -> bytes:
    return hashlib.sha256(text.encode("utf-8")).digest()


@dataclass(frozen=True)
class AccessPolicy:
    """The accepted ``tokens`` (empty: open access, loopback only)."""

    tokens: tuple[Token, ...] = ()

    @property
    def required(self) -> bool:
        """Whether every request needs a token."""
        return bool(self.tokens)

    def authenticate(self, authorization: str | None) -> Token | None:
        """The token an ``Authorization`` header value presents, None if it presents none
        that is accepted (constant time in the token compared: see the module docstring)."""
        if not authorization:
            return None
        scheme, _, credentials = authorization.strip().partition(" ")
        if scheme.lower() != "bearer" or not credentials.strip():
            return None
        presented = _digest(credentials.strip())
        found = None
        for token in self.tokens:  # no early exit: every token is compared
            if hmac.compare_digest(presented, token.digest):
                found = token
        return found


def load_tokens(path: str | Path) -> AccessPolicy:
    """Read a token file (TOML, see the module docstring); AccessError naming the file and
    the entry for every mistake."""
    path = Path(path)
    try:
        document = tomllib.loads(read_utf8_text(path, "token file", "TOML", AccessError))
    except tomllib.TOMLDecodeError as error:
        raise AccessError(f"{path}: not valid TOML: {error}") from None
    entries = document.get("tokens")
    if set(document) - {"tokens"} or not isinstance(entries, list) or not entries:
        raise AccessError(f"{path}: expected only [[tokens]] tables with name, role and token")
    tokens, names, digests = [], set(), set()
    for k, entry in enumerate(entries):
        where = f"{path}: tokens[{k}]"
        if not isinstance(entry, dict) or set(entry) != {"name", "role", "token"}:
            raise AccessError(f"{where}: expected exactly the keys name, role and token")
        name, role, text = entry["name"], entry["role"], entry["token"]
        if not isinstance(name, str) or not name.strip() or name in names:
            raise AccessError(f"{where}.name = {name!r}: expected a unique non-empty string")
        if role not in ROLES:
            raise AccessError(f"{where}.role = {role!r}: expected one of {ROLES}")
        if not isinstance(text, str) or len(text.strip()) < MIN_TOKEN_CHARS:
            raise AccessError(f"{where}.token: expected at least {MIN_TOKEN_CHARS} characters "
                              "(e.g. python -c \"import secrets; "
                              "print(secrets.token_urlsafe(32))\")")
        digest = _digest(text.strip())
        if digest in digests:
            raise AccessError(f"{where}.token is used twice")
        names.add(name)
        digests.add(digest)
        tokens.append(Token(name, role, digest))
    return AccessPolicy(tuple(tokens))


def is_loopback(host: str) -> bool:
    """Whether ``host`` (an address or ``localhost``) is a loopback address."""
    if host.strip().lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip().strip("[]")).is_loopback
    except ValueError:
        return False  # a host name: it may resolve to anything


def check_bind(host: str, policy: AccessPolicy) -> None:
    """Refuse (AccessError) to bind a non-loopback ``host`` without tokens."""
    if not is_loopback(host) and not policy.required:
        raise AccessError(f"--bind {host}: binding an address other than loopback "
                          "(127.0.0.1, ::1) needs --token-file; every request must then bring "
                          "a bearer token")


PAGE_PREFIXES = ("/units/", "/static/", "/vendor/")
PAGE_PATHS = ("/", "/docs", "/openapi.json")


def is_page_shell(method: str, path: str) -> bool:
    """Whether a request fetches a data-free page shell, static file or the API reference
    (module docstring)."""
    return method in ("GET", "HEAD") and (path in PAGE_PATHS or path.startswith(PAGE_PREFIXES))


async def _send_json(send, status: int, message: str, extra: tuple = ()) -> None:
    body = json.dumps({"error": message}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"),
                            (b"content-length", str(len(body)).encode()), *extra]})
    await send({"type": "http.response.body", "body": body})


class SecurityMiddleware:
    """ASGI middleware, the outermost layer: the security headers on every response; when
    ``policy`` requires tokens, the bearer check before the application sees the request (the
    accepted :class:`Token` is put in ``scope["state"]["token"]``); and any exception the
    application lets through is logged and answered with a JSON 500 without the traceback.
    Pure ASGI rather than Starlette's ``BaseHTTPMiddleware``, whose task handling gets in the
    way of streamed (SSE) responses."""

    def __init__(self, app: ASGIApp, policy: AccessPolicy) -> None:
        self.app = app
        self.policy = policy

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        started = False

        async def with_headers(message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
                names = {name.lower() for name, _ in message.get("headers", [])}
                extra = [(n, v) for n, v in SECURITY_HEADERS if n not in names]
                message["headers"] = [*message.get("headers", []), *extra]
            await send(message)

        token = None
        if self.policy.required and not is_page_shell(scope.get("method", ""),
                                                       scope.get("path", "")):
            header = dict(scope.get("headers", [])).get(b"authorization", b"")
            token = self.policy.authenticate(header.decode("latin-1"))
            if token is None:
                await _send_json(with_headers, 401, "a valid bearer token is required "
                                 "(Authorization: Bearer <token>)",
                                 ((b"www-authenticate", b'Bearer realm="steamtwin"'),))
                return
        scope.setdefault("state", {})["token"] = token
        try:
            await self.app(scope, receive, with_headers)
        except Exception:  # logged here; the client gets a message, never the traceback
            LOG.exception("%s %s failed", scope.get("method"), scope.get("path"))
            if not started:
                await _send_json(with_headers, 500, "internal error; the service log has the "
                                 "details")
