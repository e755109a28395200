"""Who may do what (backend.access, docs/security.md): the operator token (file mode 0600,
the environment's override, rotation), constant-time comparison, the rate limit on wrong
tokens, and the roles per route class on the real app: operator-only changes, viewer reads,
the emergency-stop rule, the login cookie and the websocket."""

from __future__ import annotations

import json
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from starlette.testclient import WebSocketDenialResponse

import backend.access as access
from backend.access import (
    COOKIE,
    NEED_OPERATOR,
    AccessRule,
    RateLimiter,
    TokenStore,
    base_url,
    credential,
    is_loopback,
    print_login,
)
from backend.api import create_app
from backend.config import Settings
from backend.station import Station
from launcher.supervisor import free_tcp_port


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    return Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                    relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                    state_dir=tmp_path / "state", allowed_hosts=["testserver"], **kw)


def _client(tmp_path: Path, clock: Clock | None = None, **kw: Any) -> TestClient:
    cfg = _settings(tmp_path, **kw)
    rule = AccessRule.from_settings(cfg.host, cfg.state_dir, cfg.require_token,
                                    cfg.view_token, cfg.estop_for_all)
    if clock is not None:
        rule.limiter = RateLimiter(max_failures=10, window_s=60.0, block_s=60.0, clock=clock)
    # the page's header: what is tested here is the token, not the CSRF rule
    return TestClient(create_app(cfg, Station(cfg), access=rule),
                      headers={"X-Touchline": "1"})


@pytest.fixture
def guarded(tmp_path: Path) -> Iterator[TestClient]:
    with _client(tmp_path, require_token=True) as c:
        yield c


def _token(c: TestClient) -> str:
    rule: AccessRule = c.app.state.access  # type: ignore[attr-defined]
    return rule.operator.token


def _bearer(token: str) -> dict[str, str]:
    return {"authorization": f"Bearer {token}"}


TARGET = ("/api/robots/blue/1/target", {"x": 100, "y": 200})


# ------------------------------------------------------------------------------- the token

def test_the_token_is_made_once_private_and_kept(tmp_path: Path) -> None:
    path = tmp_path / "var" / "token"
    a = TokenStore(path, environ={})
    assert path.exists() and stat.S_IMODE(path.stat().st_mode) == 0o600
    assert len(a.token) >= 43 and path.read_text().strip() == a.token  # token_urlsafe(32)
    assert TokenStore(path, environ={}).token == a.token  # the next start: the same token
    path.chmod(0o644)  # a copy that was left readable is made private again
    assert TokenStore(path, environ={}).token == a.token
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_the_environment_overrides_the_file_and_is_not_rotated(tmp_path: Path) -> None:
    path = tmp_path / "token"
    t = TokenStore(path, environ={"TOUCHLINE_TOKEN": "from-the-env"})
    assert t.token == "from-the-env" and t.matches("from-the-env") and not path.exists()
    with pytest.raises(ValueError, match="TOUCHLINE_TOKEN"):
        t.rotate()
    assert t.token == "from-the-env"


def test_rotation_writes_a_new_private_token_and_the_old_one_stops_matching(
        tmp_path: Path) -> None:
    path = tmp_path / "token"
    t = TokenStore(path, environ={})
    old = t.token
    new = t.rotate()
    assert new != old and t.token == new and path.read_text().strip() == new
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert t.matches(new) and not t.matches(old)
    assert TokenStore(path, environ={}).token == new


def test_tokens_are_compared_in_constant_time(monkeypatch: pytest.MonkeyPatch,
                                              tmp_path: Path) -> None:
    calls: list[tuple[bytes, bytes]] = []
    real = access.hmac.compare_digest

    def spy(a: bytes, b: bytes) -> bool:
        calls.append((a, b))
        return real(a, b)
    monkeypatch.setattr(access.hmac, "compare_digest", spy)
    t = TokenStore(tmp_path / "token", environ={})
    assert t.matches(t.token) and not t.matches(t.token[:-1]) and not t.matches("")
    assert len(calls) == 3
    # a role check compares with both tokens, whichever matches (no early exit)
    rule = AccessRule(operator=t, viewer=TokenStore(None, environ={}), required=True)
    calls.clear()
    assert rule.role_of(t.token) == "operator" and len(calls) == 2


def test_loopback_binds() -> None:
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1")
    assert is_loopback("127.0.1.1") and is_loopback("[::1]")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.5")
    assert not is_loopback("::")


def test_the_credential_from_bearer_cookie_or_the_websocket_query() -> None:
    http = {"type": "http", "query_string": b"token=q"}
    ws = {"type": "websocket", "query_string": b"token=q"}
    cookie = {"cookie": f'a="x; b=[; {COOKIE}=tok'}  # one http.cookies would give up on
    assert credential(http, {"authorization": "Bearer abc"}) == "abc"
    assert credential(http, {"authorization": "Basic abc"}) is None
    assert credential(http, cookie) == "tok"
    assert credential(http, {}) is None  # ?token= only on the websocket
    assert credential(ws, {}) == "q" and credential(ws, cookie) == "q"
    # an explicit token wins over the browser's cookie
    assert credential(http, {**cookie, "authorization": "Bearer abc"}) == "abc"


# ---------------------------------------------------------------------------- the rate limit

def test_the_rate_limiter_blocks_after_n_distinct_failures_then_forgives() -> None:
    clock = Clock()
    lim = RateLimiter(max_failures=3, window_s=60, block_s=60, clock=clock)
    assert not lim.fail("10.0.0.9", "a") and not lim.fail("10.0.0.9", "a")  # once
    assert not lim.fail("10.0.0.9", "b")
    assert lim.blocked("10.0.0.9") == 0
    assert lim.fail("10.0.0.9", "c") and lim.blocked("10.0.0.9") == 60
    assert lim.blocked("10.0.0.8") == 0  # per address
    clock.t += 59
    assert lim.blocked("10.0.0.9") == pytest.approx(1)
    clock.t += 2
    assert lim.blocked("10.0.0.9") == 0
    # failures older than the window are forgotten
    lim.fail("10.0.0.9", "d")
    lim.fail("10.0.0.9", "e")
    clock.t += 61
    assert not lim.fail("10.0.0.9", "f") and lim.blocked("10.0.0.9") == 0
    assert lim.total == 6


def test_wrong_tokens_get_429_after_ten_then_the_right_one_works_after_the_window(
        tmp_path: Path) -> None:
    clock = Clock()
    with _client(tmp_path, clock, require_token=True) as c:
        good = _token(c)
        for i in range(9):
            r = c.post(TARGET[0], json=TARGET[1], headers=_bearer(f"guess-{i}"))
            assert r.status_code == 401, r.text
        r = c.get("/login?token=guess-9", follow_redirects=False)  # the tenth, by the login
        assert r.status_code == 401
        r = c.post(TARGET[0], json=TARGET[1], headers=_bearer(good))
        assert r.status_code == 429 and "try again in 60 s" in r.json()["detail"]
        assert c.get(f"/login?token={good}", follow_redirects=False).status_code == 429
        # viewing without a token is no attempt: still open
        assert c.get("/api/world").status_code == 200
        clock.t += 61
        r = c.post(TARGET[0], json=TARGET[1], headers=_bearer(good))
        assert r.status_code == 200, r.text
        rule: AccessRule = c.app.state.access  # type: ignore[attr-defined]
        assert rule.limiter.total == 10 and rule.refused["wrong token"] == 10


def test_a_stale_cookie_sent_again_and_again_counts_once(tmp_path: Path) -> None:
    with _client(tmp_path, Clock(), require_token=True) as c:
        c.cookies.set(COOKIE, "an-old-token")
        for _ in range(30):
            assert c.post(TARGET[0], json=TARGET[1]).status_code == 401
        assert c.post(TARGET[0], json=TARGET[1],
                      headers=_bearer(_token(c))).status_code == 200


# ------------------------------------------------------------------------- roles per route

def test_on_loopback_nothing_changes(tmp_path: Path) -> None:
    with _client(tmp_path) as c:
        assert c.post(*TARGET[:1], json=TARGET[1]).status_code == 200
        assert c.post("/api/estop", json={"active": True}).status_code == 200
        assert c.post("/api/estop", json={"active": False, "confirm": True}).status_code == 200
        with c.websocket_connect("/api/ws") as ws:
            assert json.loads(ws.receive_text())["type"] == "snapshot"


def test_another_address_requires_the_token_without_the_flag(tmp_path: Path) -> None:
    cfg = _settings(tmp_path, host="0.0.0.0")
    rule = AccessRule.from_settings(cfg.host, cfg.state_dir, False, False, False)
    assert rule.required
    with TestClient(create_app(cfg, Station(cfg), access=rule)) as c:
        r = c.post(TARGET[0], json=TARGET[1])
        assert r.status_code == 401 and r.json()["detail"] == NEED_OPERATOR


def _changing_routes(c: TestClient) -> list[tuple[str, str]]:
    fill = {"{team}": "blue", "{rid}": "1", "{name}": "p1"}
    out = []
    for path, ops in c.app.openapi()["paths"].items():  # type: ignore[attr-defined]
        for k, v in fill.items():
            path = path.replace(k, v)
        out += [(m.upper(), path) for m in ops if m.upper() in ("POST", "PUT", "PATCH",
                                                                  "DELETE")]
    return out


def test_every_change_is_the_operators_and_reading_stays_open(guarded: TestClient) -> None:
    c = guarded
    routes = _changing_routes(c)
    assert ("POST", "/api/token/rotate") in routes and len(routes) > 12
    v0 = c.get("/api/params").json()["version"]
    for method, path in routes:
        r = c.request(method, path, json={"active": True} if path == "/api/estop" else {})
        if path == "/api/estop":  # the e-stop rule: 403 (below)
            assert r.status_code == 403, r.text
            continue
        assert r.status_code == 401, (method, path, r.status_code)
        assert "operator token" in r.json()["detail"]
        assert "Authorization: Bearer" in r.json()["detail"]
    assert c.get("/api/params").json()["version"] == v0
    assert c.get("/api/estop").json()["active"] is False
    for path in ("/api/world", "/api/health", "/api/params", "/api/referee", "/api/estop",
                 "/api/player", "/api/logs", "/api/presets"):
        assert c.get(path).status_code == 200, path
    with c.websocket_connect("/api/ws") as ws:
        assert json.loads(ws.receive_text())["type"] == "snapshot"
    # with the token, a change goes through
    r = c.patch("/api/params", json={"strategy": {"play": "idle"}}, headers=_bearer(_token(c)))
    assert r.status_code == 200 and r.json()["version"] == v0 + 1


def test_the_login_url_sets_a_strict_httponly_cookie_that_carries_changes(
        guarded: TestClient) -> None:
    c = guarded
    bad = c.get("/login?token=nope", follow_redirects=False)
    assert bad.status_code == 401 and "URL printed" in bad.json()["detail"]
    r = c.get(f"/login?token={_token(c)}", follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == "/"
    cookie = r.headers["set-cookie"].lower()
    assert f"{COOKIE}=" in cookie and "httponly" in cookie and "samesite=strict" in cookie
    assert "path=/" in cookie
    assert c.post(TARGET[0], json=TARGET[1]).status_code == 200  # the cookie goes along
    # the cookie still needs the CSRF rule: JSON or X-Touchline
    r = c.post(TARGET[0], content=json.dumps(TARGET[1]),
               headers={"x-touchline": "0", "content-type": "text/plain"})
    assert r.status_code == 415


def test_rotation_needs_the_token_and_retires_the_old_one(guarded: TestClient,
                                                          tmp_path: Path) -> None:
    c = guarded
    old = _token(c)
    c.get(f"/login?token={old}")
    r = c.post("/api/token/rotate")
    assert r.status_code == 200, r.text
    new = _token(c)
    assert new != old and r.json()["login_url"].endswith(f"/login?token={new}")
    assert (tmp_path / "state" / "token").read_text().strip() == new
    assert c.post(TARGET[0], json=TARGET[1], headers=_bearer(old)).status_code == 401
    assert c.post(TARGET[0], json=TARGET[1], headers=_bearer(new)).status_code == 200
    assert c.post(TARGET[0], json=TARGET[1]).status_code == 200  # the answer's new cookie
    c.cookies.clear()
    c.cookies.set(COOKIE, old)  # another laptop's old cookie
    assert c.post(TARGET[0], json=TARGET[1]).status_code == 401


def test_the_websocket_takes_the_token_in_its_query_and_the_cookie(tmp_path: Path) -> None:
    with _client(tmp_path, view_token=True) as c:
        rule: AccessRule = c.app.state.access  # type: ignore[attr-defined]
        assert rule.viewer is not None
        with pytest.raises(WebSocketDenialResponse) as refused, \
                c.websocket_connect("/api/ws") as ws:
            ws.receive_text()
        assert refused.value.status_code == 401
        assert "token" in refused.value.json()["detail"]
        with c.websocket_connect(f"/api/ws?token={rule.viewer.token}") as ws:
            assert json.loads(ws.receive_text())["type"] == "snapshot"
        c.cookies.set(COOKIE, _token(c))
        with c.websocket_connect("/api/ws") as ws:
            assert json.loads(ws.receive_text())["type"] == "snapshot"


def test_a_view_token_guards_reading_and_gives_no_control(tmp_path: Path) -> None:
    with _client(tmp_path, view_token=True) as c:
        rule: AccessRule = c.app.state.access  # type: ignore[attr-defined]
        assert rule.viewer is not None and rule.required
        view = rule.viewer.token
        assert stat.S_IMODE((tmp_path / "state" / "view-token").stat().st_mode) == 0o600
        r = c.get("/api/world")
        assert r.status_code == 401 and "token to view" in r.json()["detail"]
        assert c.get("/api/world", headers=_bearer(view)).status_code == 200
        assert c.get("/api/world", headers=_bearer(_token(c))).status_code == 200
        r = c.post(TARGET[0], json=TARGET[1], headers=_bearer(view))
        assert r.status_code == 401 and r.json()["detail"] == NEED_OPERATOR
        assert c.post("/api/estop", json={"active": True}).status_code == 401  # no token
        assert c.post("/api/estop", json={"active": True},
                      headers=_bearer(view)).status_code == 403
        # the login page and the page's files are served to anyone (how to log in)
        assert c.get(f"/login?token={view}", follow_redirects=False).status_code == 303
        assert c.get("/api/world").status_code == 200  # by the viewer's cookie


def test_the_estop_is_the_operators_unless_estop_for_all(tmp_path: Path) -> None:
    with _client(tmp_path, require_token=True) as c:
        r = c.post("/api/estop", json={"active": True})
        assert r.status_code == 403 and "--estop-for-all" in r.json()["detail"]
        assert c.get("/api/estop").json()["active"] is False
        r = c.post("/api/estop", json={"active": True}, headers=_bearer(_token(c)))
        assert r.status_code == 200 and "(operator at " in r.json()["by"]
        r = c.post("/api/estop", json={"active": False, "confirm": True})
        assert r.status_code == 403 and c.get("/api/estop").json()["active"] is True
        r = c.post("/api/estop", json={"active": False, "confirm": True},
                   headers=_bearer(_token(c)))
        assert r.status_code == 200 and r.json()["active"] is False


def test_with_estop_for_all_a_viewer_presses_but_never_releases(tmp_path: Path) -> None:
    with _client(tmp_path / "b", require_token=True, estop_for_all=True) as c:
        r = c.post("/api/estop", json={"active": True})
        assert r.status_code == 200 and "(viewer at " in r.json()["by"]
        r = c.post("/api/estop", json={"active": False, "confirm": True})
        assert r.status_code == 403 and "operator token" in r.json()["detail"]
        assert c.get("/api/estop").json()["active"] is True
        # the rest stays the operator's
        assert c.post(TARGET[0], json=TARGET[1]).status_code == 401


def test_the_printed_login_urls(tmp_path: Path) -> None:
    assert base_url("192.168.1.20", 8000) == "http://192.168.1.20:8000"
    assert base_url("0.0.0.0", 8000, ["*", "field.local"]) == "http://field.local:8000"
    assert base_url("::", 8000) == "http://localhost:8000"
    assert base_url("fe80::1", 8000) == "http://[fe80::1]:8000"
    rule = AccessRule.from_settings("0.0.0.0", tmp_path, False, True, False)
    said: list[str] = []
    print_login(rule, "http://field.local:8000", said.append)
    logins = [json.loads(s.split(" ", 1)[1]) for s in said if s.startswith("TOUCHLINE_LOGIN ")]
    assert logins == [
        {"role": "operator", "url": f"http://field.local:8000/login?token={rule.operator.token}"},
        {"role": "viewer", "url": "http://field.local:8000/login?token="
                                 f"{rule.viewer.token if rule.viewer else ''}"}]


@pytest.mark.parametrize("method,path", [
    ("POST", "/api/robots/blue/1/target"), ("POST", "/api/estop"), ("PATCH", "/api/params"),
    ("POST", "/api/params/import"), ("POST", "/api/referee/internal/command"),
    ("POST", "/api/referee/internal/enabled"), ("POST", "/api/referee/internal/card"),
    ("POST", "/api/player"), ("POST", "/api/recording"), ("POST", "/api/sim/ball")])
def test_no_control_route_takes_a_form_body_even_from_an_operator(
        guarded: TestClient, method: str, path: str) -> None:
    """The cookie goes with a form a browser posts; a form without X-Touchline is refused by
    the edge (the CSRF rule), and with it no route reads a form as its body."""
    c = guarded
    c.get(f"/login?token={_token(c)}")
    form = {"content-type": "application/x-www-form-urlencoded"}
    r = c.request(method, path, content="active=true&x=1&y=2", headers={**form,
                                                                      "x-touchline": "0"})
    assert r.status_code == 415
    r = c.request(method, path, content="active=true&x=1&y=2", headers=form)
    assert r.status_code == 422, r.text  # the header (the client's default): still no form
    assert c.get("/api/estop").json()["active"] is False


def test_health_says_the_rule_and_counts_refusals_and_blocked_addresses(tmp_path: Path) -> None:
    clock = Clock()
    with _client(tmp_path, clock, require_token=True, estop_for_all=True) as c:
        a = c.get("/api/health").json()["access"]
        assert a == {"token_required": True, "view_token": False, "estop_for_all": True,
                     "refused": {}, "blocked_clients": 0}
        c.post(TARGET[0], json=TARGET[1])
        for i in range(10):
            c.post(TARGET[0], json=TARGET[1], headers=_bearer(f"guess-{i}"))
        h = c.get("/api/health").json()
        assert h["access"]["refused"]["no operator token"] == 11
        assert h["access"]["refused"]["wrong token"] == 10
        assert h["access"]["blocked_clients"] == 1
        assert any("wrong tokens" in w for w in h["warnings"])
        clock.t += 61
        assert c.get("/api/health").json()["access"]["blocked_clients"] == 0
