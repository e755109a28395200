"""The web edge's guard, one ASGI middleware in front of every route (HTTP and websocket):

* **Host allowlist** (DNS rebinding): the Host header must name this station: the address
  it is bound to, a loopback name, or a name given with ``--allow-host``; anything else gets
  400, a websocket upgrade too (refused before it is accepted, with the same JSON reason).
  ``--allow-host '*'`` turns it off.
* **Origin**: a request that carries an Origin (every browser request that changes state,
  every websocket) must come from an allowed host or a configured dev origin (Vite); the
  request's own Host is never trusted for it. Else 403.
* **Cross-site requests** (CSRF): a state-changing request (POST, PUT, PATCH, DELETE) must
  carry ``Content-Type: application/json`` or the header ``X-Touchline: 1``. Neither can be
  sent cross-site by a browser without a CORS preflight, which this server never grants; a
  form or ``text/plain`` post is refused with 415 / 403.
* **Bodies**: at most ``MAX_BODY_BYTES`` (413) and at most ``MAX_JSON_DEPTH`` levels of
  nesting (400, whatever the content type), checked in linear time before any route parses
  them, so no body, whatever its shape or size, reaches a parser that could fail with a 500.

Every refusal answers JSON ``{"detail": reason}`` and is logged once per reason (rate-limited).
The model is Jupyter's: local names by default, remote names only when given."""

from __future__ import annotations

import json
import logging
import re
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from typing import Any
from urllib.parse import urlsplit

import numpy as np

from sslnet.ratelog import RateLimitedLog

log = logging.getLogger("touchline.security")
_ratelog = RateLimitedLog(log, interval_s=10.0)

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

MAX_BODY_BYTES = 1 << 20
MAX_JSON_DEPTH = 32
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
STATE_CHANGING = frozenset({"POST", "PUT", "PATCH", "DELETE"})
CSRF_HEADER = "x-touchline"


def host_name(host_header: str) -> str:
    """The name in a Host header or an origin's netloc, without the port, lower case
    ("[::1]:8000" -> "::1")."""
    h = host_header.strip().lower()
    if h.startswith("["):
        return h[1:h.find("]")] if "]" in h else h[1:]
    if h.count(":") == 1:
        return h.split(":", 1)[0]
    return h


def allowed_hosts(bound: str, extra: Iterable[str]) -> frozenset[str] | None:
    """The names the Host header may carry; None: any (``*`` given)."""
    names = {n.strip().lower() for n in extra if n.strip()}
    if "*" in names:
        return None
    names.update(LOOPBACK_NAMES)
    b = host_name(bound)
    if b and b not in ("0.0.0.0", "::"):
        names.add(b)
    return frozenset(names)


#: a JSON string; one left open runs to the end of the body. Possessive, and a match at a
#: quote never fails: a failed match retried at every later quote made ``"\"\"\"...`` take
#: quadratic time (32 KiB: seconds, holding the GIL the station's loop needs)
_STRING = re.compile(rb'"(?:[^"\\]++|\\.)*+(?:"|\\?\Z)', re.DOTALL)
_NOT_BRACKET = bytes(c for c in range(256) if c not in b"[]{}")
#: an opening bracket goes a level deeper (+1), a closing one a level up (-1 as int8)
_STEP = bytes.maketrans(b"[{]}", b"\x01\x01\xff\xff")


def json_depth(raw: bytes) -> int:
    """How deeply ``raw`` nests arrays and objects (brackets inside strings not counted; a
    closing bracket too many counts as none); linear in the size, without recursion and
    without a Python loop over the body, whatever the input."""
    brackets = _STRING.sub(b"", raw).translate(None, _NOT_BRACKET)
    if not brackets:
        return 0
    level = np.cumsum(np.frombuffer(brackets.translate(_STEP), dtype=np.int8), dtype=np.int64)
    # depth never below 0: the level minus the lowest level reached so far (if below 0)
    floor = np.minimum.accumulate(np.minimum(level, 0))
    return int((level - floor).max())


class EdgeGuard:
    """The ASGI middleware; see the module text."""

    def __init__(self, app: ASGIApp, *, bound_host: str, allow_hosts: Iterable[str] = (),
                 dev_origins: Iterable[str] = ()) -> None:
        self.app = app
        self.hosts = allowed_hosts(bound_host, allow_hosts)
        self.dev_origins = frozenset(o.rstrip("/").lower() for o in dev_origins)
        self.refused: dict[str, int] = {}  # by reason, for health

    def host_ok(self, host_header: str) -> bool:
        return self.hosts is None or host_name(host_header) in self.hosts

    def origin_ok(self, origin: str) -> bool:
        o = origin.rstrip("/").lower()
        if o in self.dev_origins:
            return True
        parts = urlsplit(o)
        return parts.scheme in ("http", "https") and self.host_ok(parts.netloc)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        method = scope.get("method", "GET") if kind == "http" else "WEBSOCKET"
        why = self._check(kind, method, headers)
        if why is not None:
            status, reason = why
            self._refuse(reason, scope, headers)
            if kind == "websocket":
                if "websocket.http.response" in scope.get("extensions", {}):
                    # the same answer as HTTP (status and JSON reason) to the upgrade request
                    await _answer(send, status, reason, prefix="websocket.")
                else:  # a server without the denial extension: a plain refusal
                    await send({"type": "websocket.close", "code": 1008,
                                "reason": reason[:120]})
                return
            await _answer(send, status, reason)
            return
        if kind == "http" and method in STATE_CHANGING:
            body = await _read_body(receive, MAX_BODY_BYTES)
            if body is None:
                self._refuse("body too large", scope, headers)
                await _answer(send, 413, f"request body larger than {MAX_BODY_BYTES} bytes")
                return
            # whatever its content type: a route may parse any body as JSON
            if body and json_depth(body) > MAX_JSON_DEPTH:
                self._refuse("JSON too deep", scope, headers)
                await _answer(send, 400, f"JSON nested deeper than {MAX_JSON_DEPTH} levels")
                return
            await self.app(scope, _replay(body, receive), send)
            return
        await self.app(scope, receive, send)

    def _check(self, kind: str, method: str,
               headers: dict[str, str]) -> tuple[int, str] | None:
        host = headers.get("host", "")
        if not self.host_ok(host):
            return 400, (f"host {host!r} is not allowed: use the station's address or "
                         "localhost, or start it with --allow-host NAME")
        origin = headers.get("origin")
        if origin is not None and origin != "null" and (
                kind == "websocket" or method in STATE_CHANGING) and not self.origin_ok(origin):
            return 403, f"origin {origin!r} is not allowed"
        if origin == "null" and (kind == "websocket" or method in STATE_CHANGING):
            return 403, "origin 'null' is not allowed"
        if kind == "http" and method in STATE_CHANGING and not _is_json(headers) \
                and headers.get(CSRF_HEADER) != "1":
            ctype = headers.get("content-type", "")
            if ctype:
                return 415, (f"content type {ctype!r} refused: send application/json "
                             f"(or the header X-Touchline: 1)")
            return 403, "state-changing request without the header X-Touchline: 1"
        cl = headers.get("content-length")
        if cl is not None and cl.isdigit() and int(cl) > MAX_BODY_BYTES:
            return 413, f"request body larger than {MAX_BODY_BYTES} bytes"
        return None

    def _refuse(self, reason: str, scope: Scope, headers: dict[str, str]) -> None:
        key = reason.split(":")[0].split("'")[0].strip()
        self.refused[key] = self.refused.get(key, 0) + 1
        client = scope.get("client") or ("?", 0)
        _ratelog.warning(f"edge-{key}", "refused %s %s from %s (host %r, origin %r): %s",
                         scope.get("method", "websocket"), scope.get("path", ""), client[0],
                         headers.get("host"), headers.get("origin"), reason)


def _is_json(headers: dict[str, str]) -> bool:
    ctype = headers.get("content-type", "").split(";")[0].strip().lower()
    return ctype == "application/json"


async def _read_body(receive: Receive, limit: int) -> bytes | None:
    chunks: list[bytes] = []
    size = 0
    while True:
        msg = await receive()
        if msg["type"] == "http.disconnect":
            break
        chunk = msg.get("body", b"")
        size += len(chunk)
        if size > limit:
            return None
        chunks.append(chunk)
        if not msg.get("more_body", False):
            break
    return b"".join(chunks)


def _replay(body: bytes, then: Receive) -> Receive:
    """The body read already, once; then the client's own messages (its disconnect)."""
    sent = False

    async def receive() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await then()
    return receive


async def _answer(send: Send, status: int, reason: str, prefix: str = "") -> None:
    body = json.dumps({"detail": reason}).encode()
    await send({"type": f"{prefix}http.response.start", "status": status, "headers": [
        (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": f"{prefix}http.response.body", "body": body})
