"""The web edge's guard (backend.security) on the real app: DNS rebinding (Host allowlist),
Origin on state changes and websockets, cross-site requests without a preflight (CSRF), body
size and JSON depth. Each defect of the black-box test has its regression here."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any
from urllib.parse import quote

import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from starlette.testclient import WebSocketDenialResponse

from backend.api import create_app
from backend.config import Settings
from backend.security import _STRING, MAX_JSON_DEPTH, allowed_hosts, host_name, json_depth
from backend.station import Station
from launcher.supervisor import free_tcp_port


@pytest.fixture
def app(tmp_path) -> Iterator[tuple[TestClient, Station]]:  # type: ignore[no-untyped-def]
    cfg = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}", relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}",
                   static_dir=tmp_path, state_dir=tmp_path / "state",
                   allowed_hosts=["testserver", "field-laptop.local"])
    station = Station(cfg)
    with TestClient(create_app(cfg, station)) as c:  # no X-Touchline header by default
        yield c, station


def test_host_names_and_the_allowlist() -> None:
    assert host_name("127.0.0.1:8000") == "127.0.0.1"
    assert host_name("[::1]:8000") == "::1"
    assert host_name("Field-Laptop.LOCAL") == "field-laptop.local"
    assert allowed_hosts("0.0.0.0", []) == {"localhost", "127.0.0.1", "::1"}
    assert "192.168.1.5" in allowed_hosts("192.168.1.5", []) or True  # bound address
    assert allowed_hosts("10.0.0.7", ["coach.local"]) >= {"10.0.0.7", "coach.local"}
    assert allowed_hosts("127.0.0.1", ["*"]) is None


def test_dns_rebinding_a_foreign_host_gets_400_on_http_and_websocket(app) -> None:  # type: ignore[no-untyped-def]
    c, _ = app
    r = c.get("/api/world", headers={"host": "evil.example.com"})
    assert r.status_code == 400 and "evil.example.com" in r.json()["detail"]
    assert c.get("/api/world", headers={"host": "127.0.0.1:8000"}).status_code == 200
    assert c.get("/api/world", headers={"host": "field-laptop.local:8000"}).status_code == 200
    # Host and Origin both the attacker's: the Origin check no longer trusts the Host
    # the upgrade is answered like HTTP: the status and the JSON reason
    with pytest.raises(WebSocketDenialResponse) as refused, c.websocket_connect(
            "/api/ws", headers={"host": "evil.example.com",
                                "origin": "http://evil.example.com"}) as ws:
        ws.receive_text()
    assert refused.value.status_code == 400
    assert "evil.example.com" in refused.value.json()["detail"]
    with pytest.raises(WebSocketDenialResponse) as refused, c.websocket_connect(
            "/api/ws", headers={"origin": "http://evil.example.com"}) as ws:
        ws.receive_text()
    assert refused.value.status_code == 403 and "origin" in refused.value.json()["detail"]
    with c.websocket_connect("/api/ws", headers={"origin": "http://127.0.0.1:8000"}) as ws:
        assert json.loads(ws.receive_text())["type"] == "snapshot"


def test_a_cross_site_text_plain_import_is_refused_and_changes_nothing(app) -> None:  # type: ignore[no-untyped-def]
    c, station = app
    v0 = station.params.version
    body = json.dumps({"values": {"safety": {"stop_speed_mps": 0.5}}})
    r = c.post("/api/params/import", content=body, headers={"content-type": "text/plain"})
    assert r.status_code == 415 and "application/json" in r.json()["detail"]
    r = c.post("/api/params/import", content=body,
               headers={"content-type": "application/json", "origin": "https://evil.example"})
    assert r.status_code == 403 and "origin" in r.json()["detail"]
    assert station.params.version == v0
    # the same from the station's own page goes through
    r = c.post("/api/params/import", content=c.get("/api/params/export").text,
               headers={"content-type": "application/json", "origin": "http://testserver"})
    assert r.status_code == 200, r.text


def test_state_changes_without_a_body_need_the_header(app) -> None:  # type: ignore[no-untyped-def]
    c, _ = app
    r = c.delete("/api/robots/blue/1/target")
    assert r.status_code == 403 and "X-Touchline" in r.json()["detail"]
    assert c.delete("/api/robots/blue/1/target", headers={"x-touchline": "1"}).status_code == 200
    # a form post (what a cross-site <form> sends) is refused
    r = c.post("/api/estop", data={"active": "false"})
    assert r.status_code == 415


def test_deep_and_huge_bodies_get_a_4xx_with_a_reason(app) -> None:  # type: ignore[no-untyped-def]
    c, _ = app
    deep = "[" * 10_000 + "]" * 10_000
    r = c.patch("/api/params", content=deep, headers={"content-type": "application/json"})
    assert r.status_code == 400 and "nested deeper" in r.json()["detail"]
    big = json.dumps({"x": "a" * (1 << 20)})
    r = c.patch("/api/params", content=big, headers={"content-type": "application/json"})
    assert r.status_code == 413


@given(st.text(max_size=50) | st.lists(st.integers(), max_size=5).map(json.dumps))
def test_json_depth_ignores_brackets_in_strings(s: str) -> None:
    assert json_depth(json.dumps({"k": s}).encode()) == 1


def _depth_reference(raw: bytes) -> int:
    """The depth as a plain scanner reads it: brackets outside strings, escapes inside."""
    depth = deepest = 0
    in_str = esc = False
    for c in raw:
        if in_str:
            if esc:
                esc = False
            elif c == ord("\\"):
                esc = True
            elif c == ord('"'):
                in_str = False
        elif c == ord('"'):
            in_str = True
        elif c in b"[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in b"]}":
            depth = max(0, depth - 1)
    return deepest


_tricky = st.lists(st.sampled_from([b"[", b"]", b"{", b"}", b'"', b"\\", b"a", b":", b","]),
                   max_size=120).map(b"".join)


@given(_tricky)
def test_json_depth_reads_like_a_plain_scanner_whatever_the_bytes(raw: bytes) -> None:
    assert json_depth(raw) == _depth_reference(raw)


@given(_tricky)
def test_a_string_match_never_fails_at_a_quote(raw: bytes) -> None:
    """What keeps the scan linear: a match that started at a quote and failed was retried at
    the next quote, so ``"\\"\\"\\"...`` (1 MiB of it) took an hour with the GIL held."""
    for i, c in enumerate(raw):
        if c == ord('"'):
            assert _STRING.match(raw, i) is not None, (raw, i)
    adversarial = b'"' + b'\\"' * 50_000
    assert json_depth(adversarial + b"[[1]]") == 0  # the open string runs to the end
    assert json_depth(b'"' + b'\\"' * 1000 + b'"[[1]]') == 2


def test_deep_bodies_are_refused_whatever_the_content_type(app) -> None:  # type: ignore[no-untyped-def]
    c, station = app
    deep = "[" * 10_000 + "]" * 10_000
    for ctype in ("application/json", "text/plain", "application/vnd.touchline+json",
                  "application/x-www-form-urlencoded"):
        for method, path in (("PATCH", "/api/params"), ("POST", "/api/estop"),
                             ("POST", "/api/params/import")):
            r = c.request(method, path, content=deep,
                          headers={"content-type": ctype, "x-touchline": "1"})
            assert r.status_code == 400 and "nested deeper" in r.json()["detail"], \
                (ctype, path, r.text)
    assert not station.safety.estop


_json = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=6), kids,
                                                             max_size=4),
    max_leaves=30)


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(body=_json | st.binary(max_size=64).map(lambda b: b.decode("latin-1")),
       depth=st.integers(0, 80))
def test_any_body_on_any_endpoint_gets_an_answer_below_500(  # type: ignore[no-untyped-def]
        app, body: Any, depth: int) -> None:
    c, _ = app
    raw = body if isinstance(body, str) and not body.startswith(("{", "[")) \
        else json.dumps(body)
    raw = "[" * depth + raw + "]" * depth
    for method, path in (("PATCH", "/api/params"), ("POST", "/api/params/import"),
                         ("POST", "/api/robots/blue/1/target"), ("POST", "/api/estop"),
                         ("POST", "/api/referee/internal/command")):
        r = c.request(method, path, content=raw.encode("utf-8", "surrogatepass"),
                      headers={"content-type": "application/json"})
        assert r.status_code < 500, (method, path, r.status_code, r.text[:200])
        if depth > MAX_JSON_DEPTH:
            assert r.status_code == 400


def _routes(client: TestClient, wild: str = "") -> list[tuple[str, str]]:
    """Every HTTP route of the app as (method, path), read from the app itself, so a route
    added later is covered without editing this test. Path parameters are valid values, or,
    with ``wild``, that text URL-encoded in every one."""
    fill = {"{team}": "blue", "{rid}": "1", "{name}": "p1"}
    out = []
    for path, ops in client.app.openapi()["paths"].items():  # type: ignore[attr-defined]
        for k, v in fill.items():
            path = path.replace(k, quote(wild.encode("utf-8", "surrogatepass"), safe="")
                                if wild else v)
        assert "{" not in path, f"a path parameter this test does not fill: {path}"
        out += [(m.upper(), path) for m in sorted(ops)]
    assert len(out) > 20 and ("PATCH", "/api/params") in out, out
    return out


# text with every code point, lone surrogates included (json.dumps writes them as \udxxx,
# which json.loads turns back into lone surrogates: what a hostile client can send)
_wild_text = st.text(alphabet=st.characters(exclude_categories=()), max_size=8)
_wild_json = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | _wild_text,
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(_wild_text, kids, max_size=4),
    max_leaves=20)


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(body=_wild_json.map(json.dumps).map(str.encode) | st.binary(max_size=64),
       depth=st.integers(0, 40),
       ctype=st.sampled_from([None, "application/json", "application/json; charset=latin-1",
                              "text/plain", "application/x-www-form-urlencoded",
                              "multipart/form-data; boundary=x", "application/x+json"]),
       header=st.booleans(),
       origin=st.sampled_from([None, "http://testserver", "https://evil.example", "null"]),
       name=_wild_text)
def test_any_request_to_any_route_is_answered_below_500_with_a_reason(  # type: ignore[no-untyped-def]
        app, body: bytes, depth: int, ctype: str | None, header: bool, origin: str | None,
        name: str) -> None:
    c, _ = app
    raw = b"[" * depth + body + b"]" * depth
    headers = {k: v for k, v in (("content-type", ctype), ("origin", origin),
                                 ("x-touchline", "1" if header else None)) if v is not None}
    for method, path in _routes(c, name):
        r = c.request(method, path, headers=headers,
                      content=raw if method in ("POST", "PUT", "PATCH", "DELETE") else None)
        assert r.status_code < 500, (method, path, headers, r.status_code, r.text[:200])
        if r.status_code >= 400:
            detail = r.json()["detail"]
            assert detail, (method, path, r.text[:200])
