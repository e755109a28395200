"""Who may do what (docs/security.md): the operator token, the viewer token and the rule.

* On loopback nothing is asked: the station is the operator's own machine.
* Listening on any other address (``--host``), or with ``--require-token``, every request
  that changes something (POST, PUT, PATCH, DELETE on ``/api/*``) needs the **operator
  token**: ``Authorization: Bearer <token>``, or the cookie ``GET /login?token=...`` sets
  (HttpOnly, SameSite=Strict). The websocket takes the cookie, or ``?token=`` on its URL.
* Viewing (GET on ``/api/*``, the websocket) stays open unless ``--view-token`` is set: then
  the viewer token or the operator token is needed for those too. The page's own files and
  ``/login`` are always served (the page shows how to log in).
* The emergency stop (``POST /api/estop``) is the operator's; a viewer may press it (never
  release it) only on a station started with ``--estop-for-all``.

Tokens are compared in constant time; failed attempts are counted per client address and,
after ``max_failures`` distinct wrong tokens within ``window_s``, that address gets 429 for
``block_s`` (the same stale cookie sent again and again counts once).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import logging
import os
import secrets
import time
from collections import deque
from collections.abc import Callable, Iterable, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal
from urllib.parse import parse_qs

from sslnet.ratelog import RateLimitedLog

from .contract import AccessHealth
from .security import ASGIApp, Receive, Scope, Send, _answer

log = logging.getLogger("touchline.access")
_ratelog = RateLimitedLog(log, interval_s=30.0)

Role = Literal["operator", "viewer"]
COOKIE = "touchline_token"
TOKEN_ENV = "TOUCHLINE_TOKEN"
VIEW_TOKEN_ENV = "TOUCHLINE_VIEW_TOKEN"
#: the key in the ASGI scope where the guard leaves the caller's role for the routes
ROLE_KEY = "touchline.role"
LOOPBACK_BINDS = ("localhost", "::1")

NEED_OPERATOR = ("this station requires the operator token: open the URL printed at start "
                 "(http://HOST:PORT/login?token=...), or send Authorization: Bearer <token>")
NEED_VIEWER = ("this station requires a token to view: open the URL printed at start "
               "(http://HOST:PORT/login?token=...), or send Authorization: Bearer <token>")
ESTOP_REFUSED = ("the emergency stop needs the operator token on this station (a station "
                 "started with --estop-for-all lets every viewer press it)")
ESTOP_RELEASE_REFUSED = "releasing the emergency stop needs the operator token"


def is_loopback(host: str) -> bool:
    h = host.strip().lower().strip("[]")
    return h in LOOPBACK_BINDS or h.startswith("127.")


def new_token() -> str:
    return secrets.token_urlsafe(32)


def same(candidate: str, token: str) -> bool:
    """Constant-time comparison (the time does not tell how much of a guess was right)."""
    return hmac.compare_digest(candidate.encode("utf-8", "surrogatepass"),
                               token.encode("utf-8", "surrogatepass"))


def _write_private(path: Path, text: str) -> None:
    """Writes ``text`` to ``path`` readable by its owner only (0600), atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        os.fchmod(fd, 0o600)  # whatever the umask or a stale file left
        os.write(fd, (text + "\n").encode())
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, path)


class TokenStore:
    """One token: from the environment variable ``env`` if set, else the file ``path`` (made
    on first use, mode 0600), else (no path) generated for this run only."""

    def __init__(self, path: Path | None, env: str = TOKEN_ENV,
                 environ: MutableMapping[str, str] | None = None) -> None:
        self.path = path
        self.env = env
        environ = os.environ if environ is None else environ
        given = environ.get(env, "").strip()
        self.from_env = bool(given)
        self.token = given or self._load_or_create()

    def _load_or_create(self) -> str:
        if self.path is None:
            return new_token()
        try:
            text = self.path.read_text().strip()
        except FileNotFoundError:
            text = ""
        if text:
            if self.path.stat().st_mode & 0o077:
                log.warning("%s was readable by others: made private (0600)", self.path)
                self.path.chmod(0o600)
            return text
        token = new_token()
        _write_private(self.path, token)
        log.info("a new token was written to %s", self.path)
        return token

    def rotate(self) -> str:
        """A new token, written; the old one (and every cookie holding it) stops working."""
        if self.from_env:
            raise ValueError(f"the token comes from the environment ({self.env}): change it "
                             "there and restart")
        token = new_token()
        if self.path is not None:
            _write_private(self.path, token)
        self.token = token
        return token

    def matches(self, candidate: str) -> bool:
        return same(candidate, self.token)


@dataclass
class RateLimiter:
    """Failed attempts per client address: after ``max_failures`` distinct wrong tokens in
    ``window_s``, the address is refused for ``block_s``. ``clock``: injectable (tests)."""

    max_failures: int = 10
    window_s: float = 60.0
    block_s: float = 60.0
    clock: Callable[[], float] = time.monotonic
    _fails: dict[str, deque[tuple[float, str]]] = field(default_factory=dict)
    _blocked: dict[str, float] = field(default_factory=dict)
    total: int = 0  # failures counted, for health and the tests

    def blocked(self, client: str) -> float:
        """Seconds the client is still refused (0: not)."""
        until = self._blocked.get(client)
        if until is None:
            return 0.0
        left = until - self.clock()
        if left <= 0:
            del self._blocked[client]
            return 0.0
        return left

    def blocked_count(self) -> int:
        """Addresses refused now (read only: called from the station's thread too)."""
        now = self.clock()
        return sum(1 for until in list(self._blocked.values()) if until > now)

    def fail(self, client: str, candidate: str) -> bool:
        """Counts a wrong token; True when the client is now blocked."""
        now = self.clock()
        digest = hashlib.sha256(candidate.encode("utf-8", "surrogatepass")).hexdigest()[:16]
        q = self._fails.setdefault(client, deque())
        while q and now - q[0][0] > self.window_s:
            q.popleft()
        if any(d == digest for _, d in q):
            return False  # the same wrong token again (a stale cookie): counted once
        q.append((now, digest))
        self.total += 1
        if len(q) >= self.max_failures:
            self._blocked[client] = now + self.block_s
            q.clear()
            return True
        return False

    def forget(self) -> None:
        """Drops clients whose failures are all older than the window (bounded memory)."""
        now = self.clock()
        for c in [c for c, q in self._fails.items() if not q or now - q[-1][0] > self.window_s]:
            del self._fails[c]


@dataclass
class AccessRule:
    """What the guard enforces; built from the settings (``from_settings``) or by tests."""

    operator: TokenStore
    viewer: TokenStore | None = None  # set: viewing needs a token too
    required: bool = False  # operator token needed for changes
    estop_for_all: bool = False
    limiter: RateLimiter = field(default_factory=RateLimiter)
    refused: dict[str, int] = field(default_factory=dict)  # by reason, for health

    @classmethod
    def from_settings(cls, host: str, state_dir: Path | None, require_token: bool,
                      view_token: bool, estop_for_all: bool) -> AccessRule:
        viewer = None
        if view_token:
            viewer = TokenStore(state_dir / "view-token" if state_dir else None,
                                env=VIEW_TOKEN_ENV)
        return cls(operator=TokenStore(state_dir / "token" if state_dir else None),
                   viewer=viewer, required=require_token or view_token or not is_loopback(host),
                   estop_for_all=estop_for_all)

    def role_of(self, candidate: str) -> Role | None:
        # both compared, whichever matches: no early exit telling which one was tried
        op = self.operator.matches(candidate)
        view = self.viewer.matches(candidate) if self.viewer is not None else False
        return "operator" if op else "viewer" if view else None

    def failed(self, client: str, candidate: str, where: str) -> bool:
        """Counts a wrong token from ``client`` (logged once per client and interval); True
        when the client is now blocked."""
        blocked = self.limiter.fail(client, candidate)
        self.limiter.forget()
        self.refused["wrong token"] = self.refused.get("wrong token", 0) + 1
        _ratelog.warning(f"token-{client}", "wrong token from %s (%s)%s", client, where,
                         ": refused for a while" if blocked else "")
        return blocked

    def health(self) -> AccessHealth:
        return {"token_required": self.required, "view_token": self.viewer is not None,
                "estop_for_all": self.estop_for_all, "refused": dict(self.refused),
                "blocked_clients": self.limiter.blocked_count()}

    def login_urls(self, base: str) -> list[tuple[str, str]]:
        out = [("operator", f"{base}/login?token={self.operator.token}")]
        if self.viewer is not None:
            out.append(("viewer", f"{base}/login?token={self.viewer.token}"))
        return out


def credential(scope: Scope, headers: dict[str, str]) -> str | None:
    """The token a request presents, the first of: ``Authorization: Bearer``, ``?token=``
    (websocket only), the cookie. An explicit one wins over the browser's cookie, so a wrong
    explicit token is refused even where a cookie would do."""
    auth = headers.get("authorization", "")
    if auth[:7].lower() == "bearer " and auth[7:].strip():
        return auth[7:].strip()
    if scope["type"] == "websocket":
        qs: str = bytes(scope.get("query_string", b"")).decode("latin-1")
        given = [t for t in parse_qs(qs).get("token", []) if t]
        if given:
            return given[0]
    # by hand: http.cookies gives up on the whole header at the first cookie it dislikes
    for part in headers.get("cookie", "").split(";"):
        name, eq, value = part.strip().partition("=")
        if eq and name == COOKIE and value.strip('" '):
            return value.strip('" ')
    return None


def client_of(scope: Scope) -> str:
    client = scope.get("client")
    return str(client[0]) if client else "?"


class AccessGuard:
    """The ASGI middleware in front of every route (behind the EdgeGuard: Host, Origin and
    the JSON/X-Touchline rule are checked first): reads the credential once, counts wrong
    tokens, answers 429 to a blocked address, refuses a websocket without a token where
    viewing needs one (before it is accepted), and leaves the caller's role in
    ``scope[ROLE_KEY]`` (None: no or a wrong token). What a role may do on a route is that
    route's dependency (``backend.routes.deps``)."""

    def __init__(self, app: ASGIApp, *, rule: AccessRule) -> None:
        self.app = app
        self.rule = rule

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        path: str = scope.get("path", "")
        rule = self.rule
        if not rule.required:
            scope[ROLE_KEY] = "operator"
            await self.app(scope, receive, send)
            return
        if not path.startswith("/api/") or path == "/login":
            # the page's files and the login page (which checks its token itself)
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        client = client_of(scope)
        role: Role | None = None
        presented = credential(scope, headers)
        if presented is not None:
            left = rule.limiter.blocked(client)
            if left > 0:
                await self._refuse(scope, send, 429, f"too many wrong tokens from {client}: "
                                   f"try again in {left:.0f} s", "rate-limited")
                return
            role = rule.role_of(presented)
            if role is None:
                rule.failed(client, presented, path)
        if kind == "websocket" and role is None and rule.viewer is not None:
            # refused before it is accepted, with the JSON reason (the route's VIEWER
            # dependency could only close an accepted socket)
            await self._refuse(scope, send, 401, NEED_VIEWER, "no viewer token")
            return
        scope[ROLE_KEY] = role
        await self.app(scope, receive, send)

    async def _refuse(self, scope: Scope, send: Send, status: int, reason: str,
                      key: str) -> None:
        self.rule.refused[key] = self.rule.refused.get(key, 0) + 1
        _ratelog.warning(f"access-{key}", "refused %s %s from %s: %s",
                         scope.get("method", "websocket"), scope.get("path", ""),
                         client_of(scope), reason)
        if scope["type"] == "websocket":
            if "websocket.http.response" in scope.get("extensions", {}):
                await _answer(send, status, reason, prefix="websocket.")
            else:
                await send({"type": "websocket.close", "code": 1008, "reason": reason[:120]})
            return
        await _answer(send, status, reason)


def estop_refusal(role: Any, rule: AccessRule, active: bool) -> str | None:
    """Why this caller may not press (``active``) or release the emergency stop, or None."""
    if role == "operator" or not rule.required:
        return None
    if not active:
        return ESTOP_RELEASE_REFUSED
    return None if rule.estop_for_all else ESTOP_REFUSED


def print_login(rule: AccessRule, base: str, out: Callable[[str], None] | None = None) -> None:
    """Prints the URLs to open once per laptop (and a machine-readable line for scripts)."""
    say = out or (lambda s: print(s, flush=True))  # noqa: T201
    for role, url in rule.login_urls(base):
        say(f"\n  Touchline {role} login (open once on each laptop): {url}\n")
        say(f"TOUCHLINE_LOGIN {json.dumps({'role': role, 'url': url})}")


def base_url(host: str, port: int, names: Iterable[str] = ()) -> str:
    """The URL to print: an --allow-host name when bound to every address, else the bound
    address."""
    h = host
    if h in ("0.0.0.0", "::", ""):
        h = next((n for n in names if n != "*"), "localhost")
    if ":" in h and not h.startswith("["):
        h = f"[{h}]"
    return f"http://{h}:{port}"
