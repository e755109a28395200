import json
import time
from collections.abc import Iterator
from typing import Any

import pytest
import zmq
from fastapi.testclient import TestClient
from starlette.testclient import WebSocketDenialResponse

from backend import topics
from backend.api import create_app
from backend.config import Settings
from backend.messages import OperatorTarget
from backend.station import Station
from backend.world.state import BallState, RobotState, WorldState
from launcher.supervisor import free_tcp_port
from tests.waiting import wait_until


@pytest.fixture
def client(tmp_path) -> Iterator[tuple[TestClient, Station]]:  # type: ignore[no-untyped-def]
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state",
                        allowed_hosts=["testserver"])  # the test client's Host header
    st = Station(settings)
    # the page's header (backend.security refuses state changes without it or JSON)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        yield c, st


def _world(n: int = 2) -> WorldState:
    robots = tuple(RobotState("blue", i, 100.0 * i, -50.0, 0.5, t_seen=10.0) for i in range(n))
    return WorldState(10.0, 10_000_000_000, BallState(1.0, 2.0, t_seen=10.0), robots)


def test_world_reports_robots_in_mm_and_rad(client) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    assert c.get("/api/world").json()["robots"] == []
    st.call_sync(st.world_topic.write, _world(3))  # the station thread is the only writer
    w = c.get("/api/world").json()
    assert [(r["team"], r["id"], r["x"], r["y"]) for r in w["robots"]] == [
        ("blue", 0, 0.0, -50.0), ("blue", 1, 100.0, -50.0), ("blue", 2, 200.0, -50.0)]
    assert w["ball"]["x"] == 1.0 and w["robots"][0]["orientation"] == 0.5


def test_target_is_queued_on_the_bus(client) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    r = c.post("/api/robots/blue/3/target", json={"x": 1000, "y": -500, "orientation": 1.0})
    assert r.status_code == 200, r.text
    rec = st.operator_targets.latest_value()
    assert isinstance(rec, OperatorTarget)
    assert (rec.team, rec.id, rec.target.x, rec.target.y) == ("blue", 3, 1000.0, -500.0)


@pytest.mark.parametrize("path,body,field", [
    ("/api/robots/green/1/target", {"x": 0, "y": 0}, "team"),
    ("/api/robots/blue/16/target", {"x": 0, "y": 0}, "rid"),
    ("/api/robots/blue/-1/target", {"x": 0, "y": 0}, "rid"),
    ("/api/robots/blue/1/target", {"x": "left", "y": 0}, "x"),
    ("/api/robots/blue/1/target", {"y": 0}, "x"),
    ("/api/robots/blue/1/target", {"x": 0, "y": 0, "speed": 3}, "speed"),
    ("/api/robots/blue/1/target", {"x": 99999, "y": 0}, "x"),
])
def test_bad_targets_get_422_with_field_and_reason(client, path, body, field) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    r = c.post(path, json=body)
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert any(field in d["loc"] for d in detail), detail
    assert all(d["msg"] for d in detail)
    assert st.operator_targets.seq == 0  # nothing applied


@pytest.mark.parametrize("raw", ['{"x": NaN, "y": 0}', '{"x": 0, "y": Infinity}',
                                 '{"x": 0, "y": 0, "orientation": -Infinity}'])
def test_nan_and_infinity_are_rejected_cleanly(client, raw: str) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    r = c.post("/api/robots/blue/1/target", content=raw,
               headers={"content-type": "application/json"})
    assert r.status_code == 422, r.text
    assert "finite" in json.dumps(r.json())
    assert st.operator_targets.seq == 0


def test_estop_is_reported_in_the_world(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    assert c.post("/api/estop", json={"active": True}).json()["estop"] is True
    assert c.get("/api/world").json()["estop"] is True
    c.post("/api/estop", json={"active": False, "confirm": True})
    assert c.get("/api/world").json()["estop"] is False


def test_estop_release_must_be_confirmed_and_the_stop_survives_a_restart(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The defect: the stop lived only in memory, so a restarted backend (the launcher
    restarts it after a crash) was released without anyone pressing anything."""
    def app() -> tuple[TestClient, Station]:
        settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                            relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                            state_dir=tmp_path / "state", allowed_hosts=["testserver"])
        st = Station(settings)
        return TestClient(create_app(settings, st)), st

    c, _ = app()
    with c:
        assert c.post("/api/estop", json={"active": True}).status_code == 200
    c, _ = app()  # a fresh backend on the same state folder
    with c:
        assert c.get("/api/world").json()["estop"] is True
        info = c.get("/api/estop").json()
        assert info["active"] is True and "(operator at " in info["by"]  # name (role at address)
        with c.websocket_connect("/api/ws") as ws:  # every page is told at once
            assert json.loads(ws.receive_text())["world"]["estop"] is True
        r = c.post("/api/estop", json={"active": False})
        assert r.status_code == 409 and "confirm" in r.json()["detail"]
        assert c.get("/api/world").json()["estop"] is True
        r = c.post("/api/estop", json={"active": False, "confirm": True, "reason": "field clear"})
        assert r.status_code == 200 and r.json()["estop"] is False
    c, _ = app()
    with c:
        assert c.get("/api/world").json()["estop"] is False


def test_an_unreadable_estop_file_is_a_pressed_stop(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from backend.estop import EstopLatch

    (tmp_path / "estop.json").write_text("{not json")
    latch = EstopLatch(tmp_path)
    assert latch.active and "not readable" in latch.warning


def test_health_lists_processors_and_topics(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    h = c.get("/api/health").json()
    names = {p["name"] for p in h["processors"]}
    assert {"relay-ingest", "vision-ingest", "referee-ingest", "world-model", "strategy",
            "control", "command-publisher"} <= names
    topics = {t["name"]: t for t in h["topics"]}
    assert topics["robot-commands"]["capacity"] == 20
    assert h["ok"] is False  # no vision, no relay
    assert h["warnings"] == ["no vision received", "no relay statistics received"]
    assert h["referee"] is None  # none heard yet: nothing to say about it


def test_websocket_snapshot_then_world(client) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    with c.websocket_connect("/api/ws") as ws:
        snap = ws.receive_json()
        assert snap["type"] == "snapshot" and "health" in snap
        st.world_topic.write(_world(4))
        for _ in range(20):
            msg = ws.receive_json()
            if msg["type"] == "world" and len(msg["world"]["robots"]) == 4:
                break
        else:
            raise AssertionError("no world with 4 robots")


def test_websocket_from_a_foreign_origin_is_refused(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    with pytest.raises(WebSocketDenialResponse) as exc, \
            c.websocket_connect("/api/ws", headers={"origin": "http://evil.example"}) as ws:
        ws.receive_json()
    assert exc.value.status_code == 403 and "evil.example" in exc.value.json()["detail"]


def test_geometry_404_before_first_packet(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    r = c.get("/api/geometry")
    assert r.status_code == 404 and "geometry" in r.json()["detail"]


def test_params_patch_applies_live_and_reaches_every_client(client) -> None:  # type: ignore[no-untyped-def]
    c, st = client
    with c.websocket_connect("/api/ws") as a, c.websocket_connect("/api/ws") as b:
        for ws in (a, b):
            snap = ws.receive_json()
            assert snap["params"]["values"]["processors"]["strategy_hz"] == 20.0
        r = c.patch("/api/params", json={"processors": {"strategy_hz": 5},
                                         "bus": {"world": 7}})
        assert r.status_code == 200, r.text
        version = r.json()["version"]
        for ws in (a, b):
            for _ in range(50):
                msg = ws.receive_json()
                if msg["type"] == "params":
                    break
            else:
                raise AssertionError("no params message")
            assert msg["version"] == version
            assert msg["values"]["processors"]["strategy_hz"] == 5
    # applied to the running processors and the bus
    assert st.strategy.trigger.hz == 5
    assert st.bus.of(topics.WORLD).capacity == 7
    assert c.get("/api/params").json()["values"]["bus"]["world"] == 7


def test_params_bad_value_422_names_field_and_reason(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    v0 = c.get("/api/params").json()["version"]
    r = c.patch("/api/params", content='{"strategy": {"formation_period_s": NaN}}',
                headers={"content-type": "application/json"})
    assert r.status_code == 422
    d = r.json()["detail"][0]
    assert d["loc"] == ["body", "strategy", "formation_period_s"] and "finite" in d["msg"]
    r = c.patch("/api/params", json={"strategy": {"formation_period_s": 400}})
    assert r.status_code == 422 and "less than or equal" in r.json()["detail"][0]["msg"]
    assert c.get("/api/params").json()["version"] == v0


def test_schema_preset_and_export_routes(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    schema = c.get("/api/params/schema").json()
    assert {"team", "filters", "control"} <= set(schema["properties"])
    c.patch("/api/params", json={"strategy": {"formation_period_s": 4.0}})
    assert c.put("/api/presets/match day").json() == {"presets": ["match day"]}
    p = c.get("/api/presets/match day").json()
    assert p["diff_from_defaults"] == [
        {"path": "strategy.formation_period_s", "from": 5.0, "to": 4.0}]
    exported = c.get("/api/params/export")
    assert "attachment" in exported.headers["content-disposition"]
    c.patch("/api/params", json={"strategy": {"formation_period_s": 1.0}})
    assert c.post("/api/params/import", json=exported.json()).json()["values"]["strategy"][
        "formation_period_s"] == 4.0
    assert c.post("/api/presets/nope/load").status_code == 404
    assert c.put("/api/presets/..%2Fx").status_code in (404, 422)


def test_internal_referee_commands_and_validation(client) -> None:  # type: ignore[no-untyped-def]
    c, _ = client
    r = c.post("/api/referee/internal/command", json={"command": "STOP"})
    assert r.status_code == 200, r.text
    assert r.json()["internal"]["enabled"] is True and r.json()["internal"]["command"] == "STOP"
    bad = c.post("/api/referee/internal/command", json={"command": "BALL_PLACEMENT_BLUE"})
    assert bad.status_code == 422 and "designated position" in bad.json()["detail"][0]["msg"]
    far = c.post("/api/referee/internal/command", json={
        "command": "BALL_PLACEMENT_BLUE", "designated_position": {"x": 1e6, "y": 0}})
    assert far.status_code == 422
    assert c.get("/api/referee").json()["internal"]["command"] == "STOP"


def test_teleport_goes_to_the_simulator_in_metres(client) -> None:  # type: ignore[no-untyped-def]
    from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

    c, st = client
    assert c.post("/api/sim/ball", json={"x": 1500, "y": -250}).status_code == 200
    cmd = SimulatorCommand.FromString(st.sim_commands.latest_value())
    assert (cmd.control.teleport_ball.x, cmd.control.teleport_ball.y) == (1.5, -0.25)
    assert c.post("/api/sim/robots/yellow/2", json={"x": 0, "y": 1000, "orientation": 1}
                  ).status_code == 200
    cmd = SimulatorCommand.FromString(st.sim_commands.latest_value())
    t = cmd.control.teleport_robot[0]
    assert (t.id.id, t.id.team, t.y, t.orientation, t.present) == (2, 1, 1.0, 1.0, True)
    assert c.post("/api/sim/ball", json={"x": "NaN", "y": 0}).status_code == 422


# ---- a silent referee: packets through the relay's ZeroMQ stream, the watch's clock injected ----

class _Clock:
    def __init__(self) -> None:
        self.t = 5000.0

    def __call__(self) -> float:
        return self.t


def _referee_envelope(command: str, source: str, seq: int) -> bytes:
    from sslpb import touchline_pb2 as tl
    from sslpb.ssl_gc_referee_message_pb2 import Referee

    now_us = time.time_ns() // 1000
    m = Referee(source_identifier=source, packet_timestamp=now_us,
                stage=Referee.NORMAL_FIRST_HALF, command=Referee.Command.Value(command),
                command_counter=1, command_timestamp=now_us)
    for t in (m.yellow, m.blue):
        t.name, t.score, t.red_cards, t.yellow_cards = "t", 0, 0, 0
        t.timeouts, t.timeout_time, t.goalkeeper = 4, 300_000_000, 0
    return tl.Envelope(stream=tl.STREAM_REFEREE, receive_time_ns=time.time_ns(), sequence=seq,
                       source="127.0.0.1:10003", payload=m.SerializeToString()
                       ).SerializeToString()


class _Relay:
    """Plays the relay's PUB side: referee envelopes on the ZeroMQ stream the station reads."""

    def __init__(self, endpoint: str) -> None:
        self.ctx = zmq.Context()
        self.sock = self.ctx.socket(zmq.PUB)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.bind(endpoint)
        self.seq = 0

    def referee(self, command: str, source: str) -> None:
        self.seq += 1
        self.sock.send_multipart([b"referee", _referee_envelope(command, source, self.seq)])

    def close(self) -> None:
        self.sock.close()
        self.ctx.term()


@pytest.fixture
def relay(client) -> Iterator[_Relay]:  # type: ignore[no-untyped-def]
    _, st = client
    r = _Relay(st.settings.relay_pub)
    yield r
    r.close()


def _fresh(c: TestClient, st: Station, path: str) -> Any:
    """``path`` after a no-op command: the station publishes fresh views after each command,
    so this sees every change made before (here: the test's clock moved)."""
    st.call_sync(lambda: None)
    return c.get(path).json()


def _fresh_text(c: TestClient, st: Station, path: str) -> str:
    st.call_sync(lambda: None)
    return c.get(path).text


def _health_when(c: TestClient, relay: _Relay, command: str, source: str, cond) -> Any:  # type: ignore[no-untyped-def]
    """Sends referee packets until the station's health satisfies ``cond`` (a subscriber
    connecting to a PUB socket misses what was sent before it joined)."""
    def step() -> Any:
        relay.referee(command, source)
        h = c.get("/api/health").json()
        return h if cond(h) else None
    return wait_until(step, 10.0, 0.02, f"health after {command} from {source}")


def test_health_flags_a_silent_game_controller_and_clears_when_it_speaks(  # type: ignore[no-untyped-def]
        client, relay) -> None:
    c, st = client
    clock = _Clock()
    st.referee_watch.clock = clock
    h = _fresh(c, st, "/api/health")
    assert h["referee"] is None and not any("referee" in w for w in h["warnings"])
    h = _health_when(c, relay, "STOP", "gc-test", lambda h: h["referee"] is not None)
    assert h["referee"] == {"last_heard_s": 0.0, "source_identifier": "gc-test",
                            "command": "STOP", "obeyed": True, "silent": False,
                            "silent_after_s": 3.0, "source": "game-controller"}
    ok_heard = h["ok"]

    clock.t += 3.0  # at the threshold: not yet
    assert _fresh(c, st, "/api/health")["referee"]["silent"] is False
    clock.t += 0.5
    h = _fresh(c, st, "/api/health")
    assert h["referee"]["silent"] is True and h["referee"]["last_heard_s"] == 3.5
    assert "referee silent 3 s: still obeying STOP from gc-test" in h["warnings"]
    assert h["ok"] == ok_heard  # a warning, not a broken loop (docs/api.md)
    # the station keeps obeying the last command
    assert st.control.active_referee() is not None
    assert _fresh(c, st, "/api/world")["referee"]["command"] == "STOP"

    h = _health_when(c, relay, "FORCE_START", "gc-test",
                     lambda h: h["referee"]["command"] == "FORCE_START")
    assert h["referee"]["silent"] is False and h["referee"]["last_heard_s"] == 0.0
    assert not any("referee" in w for w in h["warnings"])


def test_the_internal_referee_switched_off_is_no_silent_referee(  # type: ignore[no-untyped-def]
        client, relay) -> None:
    c, st = client
    clock = _Clock()
    st.referee_watch.clock = clock
    assert c.post("/api/referee/internal/command", json={"command": "STOP"}).status_code == 200
    own = st.referee_state.source_identifier
    # the relay loops the internal referee's multicast back to the station
    _health_when(c, relay, "STOP", own, lambda h: h["referee"] is not None)
    clock.t += 10.0
    h = _fresh(c, st, "/api/health")
    assert h["referee"]["source"] == "internal" and h["referee"]["silent"] is True
    assert c.post("/api/referee/internal/enabled", json={"enabled": False}).status_code == 200
    h = _fresh(c, st, "/api/health")
    assert h["referee"]["obeyed"] is False and h["referee"]["silent"] is False
    assert not any("referee" in w for w in h["warnings"])


def test_a_referee_name_that_is_not_utf8_breaks_no_endpoint_and_no_stream(  # type: ignore[no-untyped-def]
        client, relay) -> None:
    """The defect: a valid Referee whose team name is not UTF-8 made /api/world, /api/referee
    and /api/health answer 500 and closed every websocket. Strings from the wire are decoded
    with replacement at the edge; the message is used, and counted as a bad string."""
    c, st = client
    good = _referee_envelope("STOP", "gc", 1)
    from sslpb import touchline_pb2 as tl

    env = tl.Envelope.FromString(good)
    env.payload = env.payload.replace(b"\x0a\x01t", b"\x0a\x01\xff", 1)  # blue/yellow name "t"
    bad = env.SerializeToString()

    def step() -> Any:
        relay.sock.send_multipart([b"referee", bad])
        ref = st.referee_topic.latest_value()
        return ref if ref is not None else None
    ref = wait_until(step, 10.0, 0.02, "the referee message with a bad name")
    assert "\ufffd" in ref.yellow["name"] + ref.blue["name"]
    for path in ("/api/world", "/api/referee", "/api/health"):
        r = c.get(path)
        assert r.status_code == 200, (path, r.text)
    assert "bad string" in _fresh(c, st, "/api/health")["streams"]["referee"]["last_error"]
    with c.websocket_connect("/api/ws") as ws:
        snap = json.loads(ws.receive_text())
        assert snap["type"] == "snapshot"
        assert "\ufffd" in json.dumps(snap["world"]["referee"], ensure_ascii=False)


def test_geometry_with_nan_reaches_neither_http_nor_the_websocket_as_nan(  # type: ignore[no-untyped-def]
        client, relay) -> None:
    c, st = client
    env = _geometry_envelope(1, a="Good")  # and a line with NaN, and NaN as the ball radius

    def step() -> Any:
        relay.sock.send_multipart([b"vision", env])
        return st.browser.geometry()
    wait_until(step, 10.0, 0.02, "the geometry")
    st.call_sync(lambda: None)  # fresh views: the geometry as published
    r = c.get("/api/geometry")
    assert r.status_code == 200
    g = json.loads(r.text, parse_constant=lambda s: pytest.fail(f"{s} in /api/geometry"))
    assert [ln["name"] for ln in g["lines"]] == ["Good"] and g["ball_radius"] == 21.5
    with c.websocket_connect("/api/ws") as ws:
        snap = json.loads(ws.receive_text(),
                          parse_constant=lambda s: pytest.fail(f"{s} in the websocket"))
        assert snap["geometry"]["field_length"] == 9000


def _strict(text: str, where: str) -> Any:
    """``text`` as strict JSON (no NaN, no lone surrogate), else the test fails."""
    text.encode("utf-8")
    return json.loads(text, parse_constant=lambda s: pytest.fail(f"{s} in {where}"))


def _ws_until(ws, cond, what: str, timeout_s: float = 10.0) -> Any:  # type: ignore[no-untyped-def]
    """Receives websocket messages until ``cond(message)`` holds (health arrives twice a
    second, so each receive returns); every message must be strict JSON."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = _strict(ws.receive_text(), "the websocket")
        if cond(msg):
            return msg
    raise AssertionError(f"timed out waiting for {what} on the websocket")


def _geometry_envelope(seq: int, **names: str) -> bytes:
    """A geometry packet with NaN in a line and in the ball radius, and a line named after
    each keyword; the name BADNAME is made invalid UTF-8 on the wire."""
    from sslpb import touchline_pb2 as tl
    from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

    pkt = SSL_WrapperPacket()
    f = pkt.geometry.field
    f.field_length, f.field_width, f.goal_width, f.goal_depth, f.boundary_width = \
        9000, 6000, 1000, 180, 300
    f.ball_radius = float("nan")
    ln = f.field_lines.add()
    ln.name, ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness = "Nan", float("nan"), 0, 1, 0, 10
    for i, name in enumerate(names.values()):
        ln = f.field_lines.add()
        ln.name, ln.p1.x, ln.p1.y, ln.p2.x, ln.p2.y, ln.thickness = name, 0, i, 1, i, 10
    payload = pkt.SerializeToString().replace(b"BADNAME", b"Bad\xffame")  # same length
    return tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=time.time_ns(), sequence=seq,
                       source="127.0.0.1:10020", payload=payload).SerializeToString()


def test_geometry_arriving_while_a_page_is_connected_reaches_it_clean(  # type: ignore[no-untyped-def]
        client, relay) -> None:
    """The websocket's geometry message (pushed when the field changes) is cleaned like
    the snapshot: no NaN, names decoded with replacement, counted as bad strings."""
    c, st = client
    with c.websocket_connect("/api/ws") as ws:
        assert _strict(ws.receive_text(), "the snapshot")["geometry"] is None
        seq = 0

        def step() -> Any:
            nonlocal seq
            seq += 1
            relay.sock.send_multipart([b"vision", _geometry_envelope(seq, a="Good",
                                                                     b="BADNAME")])
            return st.browser.geometry()
        wait_until(step, 10.0, 0.02, "the geometry")
        msg = _ws_until(ws, lambda m: m["type"] == "geometry", "the geometry message")
    g = msg["geometry"]
    assert [ln["name"] for ln in g["lines"]] == ["Good", "Bad\ufffdame"]
    assert g["ball_radius"] == 21.5
    assert _strict(_fresh_text(c, st, "/api/geometry"), "/api/geometry") == g
    vision = _fresh(c, st, "/api/health")["streams"]["vision"]
    assert vision["errors_by_reason"]["bad string"] >= 1
    assert "field line name" in vision["last_error"]


def test_values_that_cannot_be_json_break_no_endpoint_and_no_stream(  # type: ignore[no-untyped-def]
        client, caplog) -> None:
    """The last line of defence (backend.jsonsafe): should a value that JSON cannot carry get
    past the decoders (bytes, a lone surrogate, NaN, an object), every endpoint still answers
    200 with strict JSON, an open websocket keeps streaming, and it is logged once."""
    import dataclasses
    import logging

    from backend.world.referee import RefereeState

    c, st = client
    with c.websocket_connect("/api/ws") as ws:
        _strict(ws.receive_text(), "the snapshot")
        ref = RefereeState("STOP", "NORMAL_FIRST_HALF", 1, None, {"name": b"\xffblue"},
                           {"name": "yellow\udcff"}, None, None, 0, source_identifier="gc")
        with caplog.at_level(logging.WARNING, logger="touchline.json"):
            st.referee_topic.write(dataclasses.replace(
                ref, game_events=({"id": object(), "created_s": float("nan")},)))
            st.relay_stats.write({"time_ns": 0, "received_mono": time.monotonic(),
                                  "output_mode": b"\xfe", "streams": {}})
            st.geometry_topic.write({"field_length": 9000, "field_width": 6000,
                                     "boundary_width": 300, "lines": [{"name": b"\xff"}],
                                     "ball_radius": float("inf")})
            st.world_topic.write(_world(1))
            got: dict[str, Any] = {}

            def seen(m: dict[str, Any]) -> bool:
                if m["type"] != "world" or m["world"]["referee"]:  # the world with the referee
                    got.setdefault(m["type"], m)
                return {"world", "geometry"} <= got.keys() and bool(
                    got.get("health", {}).get("health", {}).get("relay"))
            _ws_until(ws, seen, "world, geometry and health")
            ref_out = got["world"]["world"]["referee"]
            assert ref_out["blue"]["name"] == "\ufffdblue"
            assert ref_out["yellow"]["name"] == "yellow\ufffd"
            assert ref_out["game_events"] == [{"id": None, "created_s": None}]
            g = got["geometry"]["geometry"]
            assert g["lines"] == [{"name": "\ufffd"}] and g["ball_radius"] is None
            assert got["health"]["health"]["relay"]["output_mode"] == "\ufffd"
            for path in ("/api/world", "/api/referee", "/api/health", "/api/strategy",
                         "/api/geometry"):
                r = c.get(path)
                assert r.status_code == 200, (path, r.text)
                _strict(r.text, path)
            for _ in range(3):
                assert c.get("/api/world").status_code == 200
            # the stream is still open and carries the next world
            st.world_topic.write(_world(2))
            _ws_until(ws, lambda m: m["type"] == "world" and len(m["world"]["robots"]) == 2,
                      "the next world")
    logged = [r.getMessage() for r in caplog.records if r.name == "touchline.json"]
    # once per kind of message (world, referee, health, ...), not once per request
    kinds = [line.split(" message:")[0] for line in logged]
    assert len(kinds) == len(set(kinds)) and "world" in kinds, logged
    assert any("$.world.referee.blue.name: bytes" in line for line in logged), logged


@pytest.mark.parametrize("output,other_param,status", [
    ("robot-box", True, 422),  # never, whatever the parameter says
    ("sim", False, 422),  # a simulator, but the operator has not said so
    ("sim", True, 200),
    (None, True, 422),  # the relay's output not known yet: the safe side
])
def test_the_other_team_is_commanded_only_where_it_can_be_addressed(  # type: ignore[no-untyped-def]
        tmp_path, output: str | None, other_param: bool, status: int) -> None:
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state", allowed_hosts=["testserver"],
                        relay_output=output)
    st = Station(settings)
    with TestClient(create_app(settings, st)) as c:
        if other_param:
            assert c.patch("/api/params", json={"safety": {"other_team_in_simulator": True}}
                           ).status_code == 200
        r = c.post("/api/robots/yellow/3/target", json={"x": 0, "y": 0})
        assert r.status_code == status, r.text
        if status == 422:
            assert r.json()["detail"][0]["loc"] == ["path", "team"]
            if output == "robot-box":
                assert "would drive our (blue) robot 3" in r.json()["detail"][0]["msg"]
        assert c.post("/api/robots/blue/3/target", json={"x": 0, "y": 0}).status_code == 200
        teleport = c.post("/api/sim/robots/yellow/3", json={"x": 0, "y": 0})
        assert teleport.status_code == (409 if output == "robot-box" else 200), teleport.text
        assert st.safety.drives_other_team() == (status == 200)


def test_a_player_change_while_the_next_world_waits_reaches_the_page(client) -> None:  # type: ignore[no-untyped-def]
    """Worlds go out at most ws_max_hz; a player message published while the next world waits
    for its turn is sent too (it used to be taken for sent with the newer world, and lost: the
    page stayed at "indexing 0 %" of a log that was open)."""
    c, st = client
    assert c.patch("/api/params", json={"stream": {"ws_max_hz": 1}}).status_code == 200
    with c.websocket_connect("/api/ws") as ws:
        _strict(ws.receive_text(), "the snapshot")
        st.call_sync(st.world_topic.write, _world(1))  # sent: the next world waits ~1 s
        _ws_until(ws, lambda m: m["type"] == "world", "the first world")
        st.call_sync(st.world_topic.write, _world(2))
        time.sleep(0.2)  # the client's loop is in the world's wait now

        def player_changed() -> None:
            st.replay.player.error = "marker"
            st.replay.player.serial += 1
        st.call_sync(player_changed)
        msg = _ws_until(ws, lambda m: m["type"] == "player", "the player message", 5.0)
    assert msg["player"]["error"] == "marker"
