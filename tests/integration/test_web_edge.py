"""The web edge through the real processes (relay + backend started by the launcher, no
simulator): what a black-box test of the running station found. A Referee whose team name is
not UTF-8 and a geometry packet with NaN and a bad name arrive as real multicast through the
relay; a foreign Host (DNS rebinding), a foreign Origin, a cross-site text/plain post and an
oversized websocket message arrive on the real HTTP port; the Vite dev and preview servers
proxy to the station as a developer runs them."""

from __future__ import annotations

import base64
import json
import os
import socket
import subprocess
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect
from websockets.typing import Origin

from launcher.supervisor import free_tcp_port
from sslnet.multicast import open_multicast_sender
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from .conftest import ROOT, StationHandle, launched, stop_process, wait_until

ALLOWED = "field-laptop.local"


@pytest.fixture(scope="module")
def station() -> Iterator[StationHandle]:
    with launched("--sim", "none", "--allow-host", ALLOWED) as st:
        yield st


def _strict(text: str | bytes, where: str) -> Any:
    if isinstance(text, bytes):
        text = text.decode("utf-8")  # strict: raises on anything that is not UTF-8
    text.encode("utf-8")  # no lone surrogates
    return json.loads(text, parse_constant=lambda s: pytest.fail(f"{s} in {where}"))


def _ws(st: StationHandle, max_size: int | None = 1 << 20) -> ClientConnection:
    return connect(st.url.replace("http://", "ws://") + "/api/ws", open_timeout=10,
                   max_size=max_size)


def _ws_until(ws: ClientConnection, cond: Any, what: str, timeout_s: float = 20.0) -> Any:
    """Messages until ``cond`` holds (health comes twice a second); each must be strict JSON."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = _strict(ws.recv(timeout=max(0.1, deadline - time.monotonic())), "the websocket")
        if cond(msg):
            return msg
    raise AssertionError(f"timed out waiting for {what} on the websocket")


def _referee_datagram() -> bytes:
    """A valid Referee whose yellow team name is not UTF-8 (the black-box test's packet)."""
    now_us = time.time_ns() // 1000
    m = Referee(source_identifier="gc-bad-name", packet_timestamp=now_us,
                stage=Referee.NORMAL_FIRST_HALF, command=Referee.STOP, command_counter=1,
                command_timestamp=now_us)
    for t, name in ((m.yellow, "YNAME"), (m.blue, "Blue")):
        t.name, t.score, t.red_cards, t.yellow_cards = name, 0, 0, 0
        t.timeouts, t.timeout_time, t.goalkeeper = 4, 300_000_000, 0
    return m.SerializeToString().replace(b"YNAME", b"Y\xff\xfeNA")


def _geometry_datagram() -> bytes:
    pkt = SSL_WrapperPacket()
    f = pkt.geometry.field
    f.field_length, f.field_width, f.goal_width, f.goal_depth, f.boundary_width = \
        9000, 6000, 1000, 180, 300
    f.ball_radius = float("nan")
    for name, x in (("NanLine", float("nan")), ("BADNAME", 0.0), ("Good", 0.0)):
        ln = f.field_lines.add()
        ln.name, ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness = name, x, 0, 1000, 0, 10
    return pkt.SerializeToString().replace(b"BADNAME", b"Bad\xffame")


def test_a_referee_name_that_is_not_utf8_through_the_relay_breaks_nothing(
        station: StationHandle) -> None:
    p = station.ports
    sender = open_multicast_sender("127.0.0.1")
    with _ws(station) as ws:
        assert _strict(ws.recv(timeout=10), "the snapshot")["type"] == "snapshot"

        def sent_and_seen() -> Any:
            sender.sendto(_referee_datagram(), (p["referee_group"], p["referee"]))
            ref = station.get("/api/world")["referee"]
            return ref if ref and ref["source_identifier"] == "gc-bad-name" else None
        ref = wait_until(sent_and_seen, 20, what="the referee with the bad name")
        sender.close()
        assert ref["yellow"]["name"] == "Y\ufffd\ufffdNA" and ref["blue"]["name"] == "Blue"
        for path in ("/api/world", "/api/referee", "/api/health", "/api/strategy"):
            r = httpx.get(station.url + path, timeout=5)
            assert r.status_code == 200, (path, r.text[:300])
            _strict(r.content, path)
        referee = station.get("/api/health")["streams"]["referee"]
        assert referee["errors_by_reason"].get("bad string", 0) >= 1, referee
        assert "yellow team name" in referee["last_error"]
        # the websocket opened before the bad message is still streaming
        _ws_until(ws, lambda m: m["type"] == "health" and m["health"]["streams"]["referee"]
                  ["errors_by_reason"].get("bad string", 0) >= 1, "health after the bad name")
    with _ws(station) as ws:  # and a new page gets its snapshot
        snap = _strict(ws.recv(timeout=10), "the snapshot")
        assert snap["world"]["referee"]["yellow"]["name"] == "Y\ufffd\ufffdNA"


def test_geometry_with_nan_and_a_bad_name_through_the_relay_reaches_http_and_websocket(
        station: StationHandle) -> None:
    p = station.ports
    sender = open_multicast_sender("127.0.0.1")
    try:
        with _ws(station) as ws:
            _strict(ws.recv(timeout=10), "the snapshot")
            deadline = time.monotonic() + 20
            msg = None
            while msg is None and time.monotonic() < deadline:
                sender.sendto(_geometry_datagram(), (p["vision_group"], p["vision"]))
                try:
                    msg = _ws_until(ws, lambda m: m["type"] == "geometry", "geometry", 1.0)
                except AssertionError:
                    continue  # the relay joins the group a little after it starts
            assert msg is not None, "no geometry message on the websocket"
    finally:
        sender.close()
    g = msg["geometry"]
    assert [ln["name"] for ln in g["lines"]] == ["Bad\ufffdame", "Good"]
    assert g["ball_radius"] == 21.5
    r = httpx.get(station.url + "/api/geometry", timeout=5)
    assert r.status_code == 200 and _strict(r.content, "/api/geometry") == g
    vision = station.get("/api/health")["streams"]["vision"]
    assert vision["errors_by_reason"].get("bad string", 0) >= 1, vision


def _upgrade(st: StationHandle, host: str, origin: str | None) -> str:
    """The status line the station answers a websocket upgrade with (a raw client, so the
    Host header is exactly what a rebinding browser would send)."""
    port = st.ports["http"]
    key = base64.b64encode(os.urandom(16)).decode()
    lines = ["GET /api/ws HTTP/1.1", f"Host: {host}", "Upgrade: websocket",
             "Connection: Upgrade", f"Sec-WebSocket-Key: {key}", "Sec-WebSocket-Version: 13"]
    if origin is not None:
        lines.append(f"Origin: {origin}")
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        reply = b""
        while b"\r\n" not in reply:
            chunk = s.recv(4096)
            if not chunk:
                break
            reply += chunk
    return reply.split(b"\r\n", 1)[0].decode()


def test_hosts_origins_and_cross_site_posts_on_the_real_port(station: StationHandle) -> None:
    port = station.ports["http"]
    url = station.url
    # DNS rebinding: a foreign Host gets 400 with the reason, on HTTP and the websocket
    r = httpx.get(url + "/api/world", headers={"host": "evil.example.com"}, timeout=5)
    assert r.status_code == 400 and "evil.example.com" in r.json()["detail"]
    assert " 400 " in _upgrade(station, "evil.example.com", "http://evil.example.com")
    assert " 101 " in _upgrade(station, f"127.0.0.1:{port}", f"http://127.0.0.1:{port}")
    # the Origin is checked against the allowlist, not against the request's own Host
    assert " 403 " in _upgrade(station, f"127.0.0.1:{port}", "http://evil.example.com")
    # a name given to the launcher with --allow-host reaches the backend
    for host in (f"{ALLOWED}:{port}", f"localhost:{port}", f"[::1]:{port}"):
        r = httpx.get(url + "/api/world", headers={"host": host}, timeout=5)
        assert r.status_code == 200, (host, r.text[:200])
    assert " 101 " in _upgrade(station, f"{ALLOWED}:{port}", f"http://{ALLOWED}:{port}")

    # CSRF: a cross-site text/plain import is refused and changes nothing
    before = station.get("/api/params")
    body = json.dumps({"values": {"safety": {"stop_speed_mps": 0.3}}})
    r = httpx.post(url + "/api/params/import", content=body, timeout=5,
                   headers={"content-type": "text/plain", "origin": "https://evil.example"})
    assert r.status_code in (403, 415) and r.json()["detail"]
    r = httpx.post(url + "/api/params/import", content=body, timeout=5,
                   headers={"content-type": "text/plain"})
    assert r.status_code == 415 and "application/json" in r.json()["detail"]
    r = httpx.post(url + "/api/params/import", content=body, timeout=5,
                   headers={"content-type": "application/json",
                            "origin": "https://evil.example"})
    assert r.status_code == 403 and "origin" in r.json()["detail"]
    assert station.get("/api/params")["version"] == before["version"]
    # deep JSON: a reason, not a 500
    r = httpx.patch(url + "/api/params", content="[" * 10_000 + "]" * 10_000, timeout=5,
                    headers={"content-type": "application/json"})
    assert r.status_code == 400 and "nested" in r.json()["detail"]


def test_an_oversized_websocket_message_closes_only_that_socket(
        station: StationHandle) -> None:
    closed: BaseException | None = None
    with _ws(station, max_size=None) as ws:
        _strict(ws.recv(timeout=10), "the snapshot")
        deadline = time.monotonic() + 10
        try:
            ws.send(b"x" * (2 << 20))
            while time.monotonic() < deadline:  # health keeps coming until it is closed
                ws.recv(timeout=10)
        except (ConnectionClosed, OSError) as exc:
            closed = exc
        # the server closes with 1009 while the client may still be sending the 2 MiB: then
        # the client sees a reset instead of the close frame; either way the socket is closed
        assert closed is not None, "the oversized message did not close the socket"
        if isinstance(closed, ConnectionClosed) and closed.rcvd is not None:
            assert closed.rcvd.code == 1009
    assert httpx.get(station.url + "/api/health", timeout=5).status_code == 200
    with _ws(station) as ws:
        assert _strict(ws.recv(timeout=10), "the snapshot")["type"] == "snapshot"


@pytest.mark.parametrize("mode", ["dev", "preview"])
def test_the_vite_servers_proxy_http_and_the_websocket_to_the_station(
        station: StationHandle, mode: str) -> None:
    """A developer's page on the Vite server: its proxy rewrites the Host to the station's and
    passes the page's Origin (http://127.0.0.1:<vite port>), both allowed."""
    vite = ROOT / "node_modules" / ".bin" / "vite"
    assert vite.exists(), "node_modules missing: run make setup"
    if mode == "preview":
        assert (ROOT / "frontend" / "dist" / "index.html").exists(), "run make build"
    port = free_tcp_port()
    args = [str(vite), *(["preview"] if mode == "preview" else []), "--config",
            "frontend/vite.config.ts", "--port", str(port), "--strictPort"]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "TOUCHLINE_BACKEND": station.url})
    page = f"http://127.0.0.1:{port}"
    try:
        def health() -> Any:
            try:
                r = httpx.get(page + "/api/health", timeout=2)
            except httpx.HTTPError:
                return None
            return r if r.status_code == 200 else None
        wait_until(health, 60, 0.2, what=f"the vite {mode} server proxying /api/health")
        r = httpx.patch(page + "/api/params", json={}, timeout=5,
                        headers={"origin": page, "x-touchline": "1"})
        assert r.status_code == 200, r.text[:300]
        with connect(page.replace("http://", "ws://") + "/api/ws", origin=Origin(page),
                     open_timeout=10) as ws:
            assert _strict(ws.recv(timeout=10), "the snapshot")["type"] == "snapshot"
    finally:
        stop_process(proc)

