"""Who may talk to the console: an ASGI middleware checking Host, Origin and the token.

A console on ``127.0.0.1`` is reachable by every web page the user opens: a page can send
"simple" requests (a form POST, a ``fetch`` with ``Content-Type: text/plain``) and open
WebSockets to any address without asking, and by DNS rebinding (a name of the attacker's
that resolves to 127.0.0.1) even read the answers. :class:`Guard` refuses, before the app
sees them:

- **any request or WebSocket whose ``Host`` is not allowed** (:attr:`Policy.allowed_hosts`,
  names without port): a rebound name arrives with the attacker's name in ``Host``;
- **a state-changing request (any method but GET, HEAD, OPTIONS) or a WebSocket from
  another origin**: a browser sends ``Origin`` with both; it must be this server itself
  (scheme ``http``/``https``, the same host and port as ``Host``; a ``Host`` without a
  port matches the default port of the origin's scheme, as behind a TLS proxy).
  ``Origin: null`` (a sandboxed frame, a ``data:`` page, a redirect) is refused. Without
  ``Origin`` (curl, a script) ``Sec-Fetch-Site``, when sent, must be ``same-origin`` or
  ``none``;
- **with a token** (:attr:`Policy.token`): any ``/api/`` request or ``/ws/`` socket without
  ``Authorization: Bearer <token>``. A browser cannot set headers on a WebSocket, so there
  the token may come as the subprotocol ``gcu-async.bearer.<token>`` offered beside
  :data:`WS_PROTOCOL` (which the app then accepts).

Refusals are JSON ``{"error", "kind"}`` (403 ``ForbiddenHost`` / ``ForbiddenOrigin``, 401
``Unauthorized``); a refused WebSocket handshake gets HTTP 403. The page and its static
files need no token (they hold no secret); the page reads the token from its URL fragment.
"""

from __future__ import annotations

import hmac
import json
import logging
import re
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

LOOPBACK_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})
"""The host names allowed by default: the loopback addresses and ``localhost``."""
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
"""Methods that change nothing: no Origin check (answers stay unreadable cross-origin:
the app sends no CORS headers)."""
PROTECTED_PREFIXES = ("/api/", "/ws/")
"""Paths that need the token when one is set."""
WS_PROTOCOL = "gcu-async.telemetry"
"""The WebSocket subprotocol the app accepts when a client offers it."""
WS_TOKEN_PREFIX = "gcu-async.bearer."
"""A WebSocket subprotocol carrying the token (for browsers, which cannot set headers)."""
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9._~-]{16,256}")
"""A token: 16–256 URL-safe characters (``secrets.token_urlsafe()`` makes one); the set
fits a URL fragment, a header and a WebSocket subprotocol unescaped."""
log = logging.getLogger("gcu_async.examples.web")

_DEFAULT_PORTS = {"http": 80, "https": 443}


def check_token(token: str | None) -> str | None:
    """``token`` if usable (``None``: no token), else ``ValueError`` naming the rule (never
    the secret itself, only its length)."""
    if token is None:
        return None
    if not TOKEN_PATTERN.fullmatch(token):
        raise ValueError(f"token: expected 16 to 256 characters from A-Z a-z 0-9 . _ ~ -, "
                         f"got {len(token)} characters"
                         f"{'' if token.isascii() else ' (not all ASCII)'}")  # fmt: skip
    return token


def normalize_host(name: str) -> str:
    """A host name as compared: lower case, no brackets, no trailing dot."""
    return name.strip().lower().removeprefix("[").removesuffix("]").rstrip(".")


@dataclass(frozen=True)
class Policy:
    """What :class:`Guard` lets through."""

    allowed_hosts: frozenset[str] = LOOPBACK_HOSTS
    """Host names (no port) a request's ``Host`` may carry."""
    token: str | None = None
    """The bearer token ``/api/`` and ``/ws/`` need (``None``: none)."""

    @classmethod
    def make(cls, allowed_hosts: Iterable[str] | None = None,
             token: str | None = None) -> Policy:  # fmt: skip
        """A checked policy: host names normalized (``ValueError`` for an empty or
        port-carrying one), the token checked by :func:`check_token`."""
        hosts = LOOPBACK_HOSTS if allowed_hosts is None else frozenset(allowed_hosts)
        names = set()
        for host in hosts:
            name = normalize_host(host)
            if not name or any(c in name for c in "/@ ") or name.count(":") == 1:
                raise ValueError(f"allowed host: {host!r} is not a host name or address "
                                 "(give it without scheme or port)")  # fmt: skip
            names.add(name)
        return cls(frozenset(names), check_token(token))


def _split_host(value: str) -> tuple[str, int | None] | None:
    """``(name, port)`` of a ``Host`` header or an origin's netloc; ``None`` if malformed."""
    try:
        parts = urlsplit(f"//{value}")
        port = parts.port
    except ValueError:
        return None
    if parts.hostname is None or parts.username is not None or parts.path:
        return None
    return normalize_host(parts.hostname), port


class Refusal(Exception):
    """A request the policy refuses: HTTP status, ``kind`` and message."""

    def __init__(self, status: int, kind: str, message: str) -> None:
        super().__init__(message)
        self.status = status
        self.kind = kind


def _headers(scope: Scope) -> dict[str, str]:
    """The request headers (the first of each name), names lower case, latin-1 decoded."""
    headers: dict[str, str] = {}
    for raw_name, raw_value in scope.get("headers", ()):
        headers.setdefault(raw_name.decode("latin-1").lower(), raw_value.decode("latin-1"))
    return headers


def check(policy: Policy, scope: Scope) -> None:
    """Raise :class:`Refusal` unless ``policy`` lets this HTTP request or WebSocket in."""
    headers = _headers(scope)
    host = _check_host(policy, headers.get("host"))
    websocket = scope["type"] == "websocket"
    if websocket or scope.get("method", "GET") not in SAFE_METHODS:
        _check_origin(headers, host)
    if policy.token is not None and scope.get("path", "").startswith(PROTECTED_PREFIXES):
        _check_token(policy.token, headers, websocket)


def _check_host(policy: Policy, value: str | None) -> tuple[str, int | None]:
    if value is None:
        raise Refusal(403, "ForbiddenHost", "no Host header: the console answers only "
                      f"requests for {', '.join(sorted(policy.allowed_hosts))}")  # fmt: skip
    host = _split_host(value)
    if host is None or host[0] not in policy.allowed_hosts:
        allowed = ", ".join(sorted(policy.allowed_hosts))
        raise Refusal(403, "ForbiddenHost",
                      f"Host {value[:100]!r} is not allowed (allowed: {allowed}; see "
                      "--allowed-host)")  # fmt: skip
    return host


def _check_origin(headers: dict[str, str], host: tuple[str, int | None]) -> None:
    origin = headers.get("origin")
    if origin is None:
        site = headers.get("sec-fetch-site")
        if site is not None and site not in ("same-origin", "none"):
            raise Refusal(403, "ForbiddenOrigin", f"a {site} request without Origin is refused")
        return
    try:
        parts = urlsplit(origin) if origin != "null" else None
    except ValueError:  # "http://[" and the like
        parts = None
    allowed = False
    if parts is not None and parts.scheme in ("http", "https") and parts.path == "":
        theirs = _split_host(parts.netloc)
        if theirs is not None and theirs[0] == host[0]:
            port = theirs[1] or _DEFAULT_PORTS[parts.scheme]
            # Host without a port: the default of the scheme the browser used (behind a
            # TLS proxy the app sees http, the page is https)
            allowed = port == (host[1] or _DEFAULT_PORTS[parts.scheme])
    if not allowed:
        raise Refusal(403, "ForbiddenOrigin",
                      f"Origin {origin[:100]!r} is not this console: requests that change "
                      "state and WebSockets must come from its own page")  # fmt: skip


def _check_token(token: str, headers: dict[str, str], websocket: bool) -> None:
    offered: list[str] = []
    scheme, _, credential = headers.get("authorization", "").partition(" ")
    if scheme.lower() == "bearer":
        offered.append(credential.strip())
    if websocket:
        for protocol in headers.get("sec-websocket-protocol", "").split(","):
            protocol = protocol.strip()
            if protocol.startswith(WS_TOKEN_PREFIX):
                offered.append(protocol.removeprefix(WS_TOKEN_PREFIX))
    expected = token.encode()
    # compare_digest on every candidate: the time taken does not depend on the secret
    if not any([hmac.compare_digest(o.encode("latin-1"), expected) for o in offered]):
        what = "missing" if not offered else "wrong"
        raise Refusal(401, "Unauthorized",
                      f"the bearer token is {what}: send 'Authorization: Bearer <token>' "
                      "(the page: open it as /#token=<token>)")  # fmt: skip


class Guard:
    """ASGI middleware applying a :class:`Policy` to every HTTP request and WebSocket."""

    def __init__(self, app: ASGIApp, policy: Policy) -> None:
        self.app = app
        self.policy = policy

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] in ("http", "websocket"):
            try:
                check(self.policy, scope)
            except Refusal as refusal:
                # INFO, not WARNING: any page the user opens may cause these
                log.info("refused %s %s: %s", scope.get("method", "WEBSOCKET"),
                         scope.get("path", ""), refusal)  # fmt: skip
                await _refuse(scope, send, refusal)
                return
        await self.app(scope, receive, send)


async def _refuse(scope: Scope, send: Send, refusal: Refusal) -> None:
    if scope["type"] == "websocket":  # closing before accepting: the server answers 403
        await send({"type": "websocket.close", "code": 1008, "reason": str(refusal)[:120]})
        return
    body = json.dumps({"error": str(refusal), "kind": refusal.kind}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if refusal.status == 401:
        headers.append((b"www-authenticate", b"Bearer"))
    await send({"type": "http.response.start", "status": refusal.status, "headers": headers})
    await send({"type": "http.response.body", "body": body})
