"""Arming (a relay driving real robots): the station starts disarmed; POST /api/arm is refused
with 409 and the reason without vision, with the e-stop active or in replay; disarming always
works; the e-stop disarms; the publisher repeats the state to the relay."""

from __future__ import annotations

import asyncio
import errno
import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zmq
import zmq.asyncio
from fastapi.testclient import TestClient

from backend import topics
from backend.api import create_app
from backend.arming import ArmingStore
from backend.bus import DataBus
from backend.config import Settings
from backend.processors import CommandPublisher
from backend.station import Station
from backend.world.state import BallState, RobotState, WorldState
from launcher.supervisor import free_tcp_port
from sslpb import touchline_pb2 as tl


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    return Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                    relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                    state_dir=tmp_path / "state", allowed_hosts=["testserver"], **kw)


@pytest.fixture
def armable(tmp_path: Path) -> Iterator[tuple[TestClient, Station]]:
    st = Station(_settings(tmp_path, require_arming=True))
    with TestClient(create_app(st.settings, st), headers={"X-Touchline": "1"}) as c:
        # the world _vision writes counts as vision for the longest the rules allow: a
        # loaded machine took more than the default 0.3 s from the write to the arm request
        assert c.patch("/api/params", json={"safety": {"vision_stale_s": 2.0}}).status_code == 200
        yield c, st


def _fresh_world() -> WorldState:
    robots = (RobotState("blue", 3, 0.0, 0.0, 0.0, t_seen=10.0),)
    return WorldState(10.0, time.time_ns(), BallState(1.0, 2.0, t_seen=10.0), robots)


def _vision(st: Station) -> None:
    st.call_sync(st.world_topic.write, _fresh_world())


def test_the_station_starts_disarmed_and_says_so(armable: tuple[TestClient, Station]) -> None:
    c, _ = armable
    w = c.get("/api/world").json()
    assert w["armed"] is False and w["arming_required"] is True
    assert w["arming"]["required"] and not w["arming"]["armed"]
    assert "vision" in w["arming"]["refusal"]
    h = c.get("/api/health").json()
    assert h["arming"]["armed"] is False and h["arming"]["required"] is True
    assert c.get("/api/arm").json()["armed"] is False


def test_arming_is_refused_without_vision(armable: tuple[TestClient, Station]) -> None:
    c, st = armable
    r = c.post("/api/arm", json={"armed": True})
    assert r.status_code == 409
    assert "vision is missing" in r.json()["detail"]
    assert not st.safety.armed


def test_arming_with_vision_then_disarming(armable: tuple[TestClient, Station]) -> None:
    c, st = armable
    _vision(st)
    r = c.post("/api/arm", json={"armed": True})
    assert r.status_code == 200, r.text
    assert r.json()["armed"] is True and "operator" in r.json()["by"]
    assert c.get("/api/world").json()["armed"] is True
    r = c.post("/api/arm", json={"armed": False})
    assert r.status_code == 200 and r.json()["armed"] is False
    assert not st.safety.armed


def test_arming_is_refused_while_the_estop_is_active_and_a_press_disarms(
        armable: tuple[TestClient, Station]) -> None:
    c, st = armable
    _vision(st)
    assert c.post("/api/arm", json={"armed": True}).status_code == 200
    assert c.post("/api/estop", json={"active": True}).status_code == 200
    assert not st.safety.armed
    w = c.get("/api/world").json()
    assert w["armed"] is False and w["arming"]["by"].startswith("e-stop")
    _vision(st)
    r = c.post("/api/arm", json={"armed": True})
    assert r.status_code == 409 and "emergency stop" in r.json()["detail"]
    # disarming always works
    assert c.post("/api/arm", json={"armed": False}).status_code == 200
    assert c.post("/api/estop", json={"active": False, "confirm": True}).status_code == 200
    assert not st.safety.armed  # a release does not re-arm
    _vision(st)
    assert c.post("/api/arm", json={"armed": True}).status_code == 200


def test_arming_is_refused_in_replay(tmp_path: Path) -> None:
    st = Station(_settings(tmp_path, require_arming=True))
    st.world_topic.write(_fresh_world())
    assert st.safety.arm_refusal() is None
    st.replay.player.log = object()  # type: ignore[assignment]
    why = st.safety.set_armed(True, "t")
    assert why is not None and "replaying a log" in why
    assert not st.safety.armed
    st.replay.player.log = None
    assert st.safety.set_armed(True, "t") is None and st.safety.armed


def test_bad_bodies_are_refused(armable: tuple[TestClient, Station]) -> None:
    c, _ = armable
    assert c.post("/api/arm", json={}).status_code == 422
    assert c.post("/api/arm", json={"armed": True, "extra": 1}).status_code == 422


def test_without_arming_required_the_station_is_armed(tmp_path: Path) -> None:
    st = Station(_settings(tmp_path))
    with TestClient(create_app(st.settings, st), headers={"X-Touchline": "1"}) as c:
        w = c.get("/api/world").json()
        assert w["armed"] is True and w["arming_required"] is False
        assert w["arming"]["refusal"] is None


def test_the_relay_saying_it_requires_arming_is_enough(tmp_path: Path) -> None:
    st = Station(_settings(tmp_path))
    assert st.safety.armed
    st.relay_stats.write({"received_mono": time.monotonic(), "arming_required": True,
                          "armed": False})
    assert st.safety.arming_required and not st.safety.armed


def test_operator_actions_are_recorded(armable: tuple[TestClient, Station]) -> None:
    c, st = armable
    actions: list[tuple[str, str]] = []
    st.operator_action = lambda a, by="", d=None: actions.append((a, by))  # type: ignore[method-assign]
    _vision(st)
    assert c.post("/api/arm", json={"armed": True}).status_code == 200
    assert c.post("/api/arm", json={"armed": False}).status_code == 200
    assert [a for a, _ in actions] == ["arm", "disarm"]


async def test_the_publisher_repeats_the_arming_state() -> None:
    bus = DataBus({})
    ctx = zmq.asyncio.Context()
    try:
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.SUBSCRIBE, b"arming")
        port = sub.bind_to_random_port("tcp://127.0.0.1")
        pub = ctx.socket(zmq.PUB)
        pub.connect(f"tcp://127.0.0.1:{port}")
        p = CommandPublisher(bus, pub)
        p.attach(pub)
        armed = [False]
        p.armed = lambda: armed[0]
        p.armed_by = lambda: "op"
        # the publisher's schedule on a clock of the test's own (``_arming(now)``, what
        # ``tick`` calls with the monotonic time): counts, not scheduling luck
        now = 0.0

        async def received(timeout_s: float = 3.0) -> tl.Arming:
            _, body = await asyncio.wait_for(sub.recv_multipart(), timeout_s)
            return tl.Arming.FromString(body)

        # ZeroMQ's slow joiner: repeats (0.5 s apart on that clock) until one arrives
        deadline = time.monotonic() + 5.0
        while not await sub.poll(20):
            assert time.monotonic() < deadline, "the subscription never received anything"
            now += 0.5
            p._arming(now)
        while await sub.poll(0):
            await sub.recv_multipart()
        sent_at = now
        for k in range(1, 61):  # 1.2 s on its clock, a pass every 20 ms
            p._arming(sent_at + 0.02 * k)
        armed[0] = True
        p._arming(sent_at + 1.21)  # a change: at once, not at the next repeat
        got = [await received()]
        while not got[-1].armed:
            got.append(await received())
        assert [m.armed for m in got] == [False, False, True]  # every 0.5 s, then the change
        assert got[-1].by == "op"
        pub.close(0)
        sub.close(0)
    finally:
        ctx.destroy(0)
    assert bus.of(topics.ESTOP).latest_value() is None


@pytest.mark.parametrize("output,status", [("sim", 200), ("grsim", 200), ("robot-box", 409)])
def test_teleports_go_to_a_simulator_only_so_arming_does_not_gate_them(
        tmp_path: Path, output: str, status: int) -> None:
    """An external simulator under --require-arming takes teleports disarmed (nothing physical
    moves); real robots (robot-box) never take one, armed or not (docs/api.md)."""
    st = Station(_settings(tmp_path, require_arming=True, relay_output=output))
    with TestClient(create_app(st.settings, st), headers={"X-Touchline": "1"}) as c:
        for armed in (False, True):
            if armed:
                _vision(st)
                assert c.post("/api/arm", json={"armed": True}).status_code == 200
            assert st.safety.armed is armed
            ball = c.post("/api/sim/ball", json={"x": 0, "y": 0})
            robot = c.post("/api/sim/robots/blue/3", json={"x": 0, "y": 0})
            assert (ball.status_code, robot.status_code) == (status, status), ball.text
            if status == 409:
                assert "robot-box" in ball.json()["detail"]


# ---- arming persisted (backend/arming.py): the operator's decision survives the supervisor's
# restart after a crash (--restarted), not a start anew; the e-stop wins over it ----


def _on_disk(st: Station) -> Station:
    """``st`` once the state files asked for so far are written: the station writes them on
    its writer thread, in order (a crash within that millisecond forgets the last change)."""
    assert st.params.writer is not None
    st.params.writer.submit(lambda: None).result(timeout=10)
    return st


def _armed_station(tmp_path: Path, **kw: Any) -> Station:
    st = Station(_settings(tmp_path, require_arming=True, **kw))
    st.world_topic.write(_fresh_world())
    assert st.safety.set_armed(True, "operator at 127.0.0.1") is None
    return _on_disk(st)


def test_arming_survives_a_restart_by_the_supervisor(tmp_path: Path) -> None:
    first = _armed_station(tmp_path)
    again = Station(_settings(tmp_path, require_arming=True, restarted=True))
    assert again.safety.armed and again.safety.arming_store.restored
    assert again.safety.armed_by == "operator at 127.0.0.1"
    assert again.safety.armed_since == pytest.approx(first.safety.armed_since)
    # and the publisher tells the relay so from its first step
    assert again.publisher.armed() is True


def test_a_start_anew_is_disarmed_and_forgets_the_last_arming(tmp_path: Path) -> None:
    _armed_station(tmp_path)
    fresh = Station(_settings(tmp_path, require_arming=True))
    assert not fresh.safety.armed and not fresh.safety.arming_store.restored
    assert not (tmp_path / "state" / "arming.json").exists()
    # a crash after that start does not bring the earlier arming back either
    assert not Station(_settings(tmp_path, require_arming=True, restarted=True)).safety.armed


def test_a_disarm_survives_a_restart_too(tmp_path: Path) -> None:
    st = _armed_station(tmp_path)
    st.safety.set_armed(False, "operator at 127.0.0.1")
    _on_disk(st)
    assert not Station(_settings(tmp_path, require_arming=True, restarted=True)).safety.armed


def test_the_estop_disarms_for_the_restart_and_wins_over_an_armed_file(tmp_path: Path) -> None:
    st = _armed_station(tmp_path)
    st.safety.set_estop(True, "operator at 127.0.0.1")
    _on_disk(st)
    again = Station(_settings(tmp_path, require_arming=True, restarted=True))
    assert again.safety.estop and not again.safety.armed
    # an armed file beside a pressed stop (written by hand, or a crash between the two): the
    # stop wins, and the file is made to say so
    (tmp_path / "state" / "arming.json").write_text(
        json.dumps({"armed": True, "since": 1.0, "by": "x"}))
    again = Station(_settings(tmp_path, require_arming=True, restarted=True))
    assert again.safety.estop and not again.safety.armed
    assert json.loads((tmp_path / "state" / "arming.json").read_text())["armed"] is False


@pytest.mark.parametrize("content", ["{not json", "[]", '{"armed": "true"}', '{"armed": 1}',
                                     '{"by": "x"}'])
def test_a_file_that_does_not_say_armed_is_disarmed(tmp_path: Path, content: str) -> None:
    (tmp_path / "state").mkdir()
    (tmp_path / "state" / "arming.json").write_text(content)
    st = Station(_settings(tmp_path, require_arming=True, restarted=True))
    assert not st.safety.armed
    assert "not readable" in st.safety.arming_store.warning


def test_a_disarm_that_cannot_be_written_removes_the_armed_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store = ArmingStore(tmp_path, restarted=True)
    store.set(True, "op")
    assert ArmingStore(tmp_path, restarted=True).state.armed

    def full_disk(path: Path, data: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr("backend.arming.atomic_write_json", full_disk)
    store.set(False, "op")
    assert store.warning == ""  # said by removing the file: no file is disarmed
    assert not (tmp_path / "arming.json").exists()
    assert not ArmingStore(tmp_path, restarted=True).state.armed
    store.set(True, "op")  # an arming not written: a restart comes up disarmed, and says so
    assert "arming not persisted" in store.warning


def test_an_unreadable_file_is_a_health_warning(tmp_path: Path) -> None:
    (tmp_path / "state").mkdir()
    (tmp_path / "state" / "arming.json").write_text("{not json")
    st = Station(_settings(tmp_path, require_arming=True, restarted=True))
    with TestClient(create_app(st.settings, st), headers={"X-Touchline": "1"}) as c:
        warnings = c.get("/api/health").json()["warnings"]
    assert any(w.startswith("arming.json is not readable") for w in warnings), warnings


def test_a_press_does_not_wait_for_the_disk(tmp_path: Path) -> None:
    """The stop is on the bus (and the arming gone) while the disk still holds the writer
    thread; the file follows once the disk is free, in order."""
    st = _armed_station(tmp_path)
    assert st.params.writer is not None
    disk_free = threading.Event()
    st.params.writer.submit(disk_free.wait, 10)  # a slow fsync: the writer thread busy
    try:
        st.safety.set_estop(True, "operator at 127.0.0.1")
        assert st.safety.estop and not st.safety.armed
        assert not (tmp_path / "state" / "estop.json").exists()  # not written yet
    finally:
        disk_free.set()
    _on_disk(st)
    assert json.loads((tmp_path / "state" / "estop.json").read_text())["active"] is True
    assert json.loads((tmp_path / "state" / "arming.json").read_text())["armed"] is False
