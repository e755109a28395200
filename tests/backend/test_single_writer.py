"""The one writer (docs/architecture.md, "Rules of the structure"): the parameters and the
operators are station state, changed on the station thread only; the web side submits each
change to the station's queue, and one e-stop press is one queued call.

Where a call runs is seen through the parts' own hooks: the parameter store's listeners
(called where a change is made) and the operators' injected wall clock (read where a session,
a driving hold or an action is made)."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from backend.api import create_app
from backend.config import Settings
from backend.station import Station
from launcher.supervisor import free_tcp_port

#: the station loop's thread (backend/station_loop.py)
STATION_THREAD = "station"


@pytest.fixture
def station(tmp_path) -> Iterator[tuple[TestClient, Station]]:  # type: ignore[no-untyped-def]
    settings = Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state", allowed_hosts=["testserver"])
    st = Station(settings)
    with TestClient(create_app(settings, st), headers={"X-Touchline": "1"}) as c:
        yield c, st


def _threads_of_param_changes(st: Station) -> list[str]:
    seen: list[str] = []
    st.params.subscribe(lambda _p, _v: seen.append(threading.current_thread().name))
    return seen


def test_every_parameter_change_is_made_on_the_station_thread(station) -> None:  # type: ignore[no-untyped-def]
    c, st = station
    seen = _threads_of_param_changes(st)
    r = c.patch("/api/params", json={"safety": {"vision_stale_s": 0.4}})
    assert r.status_code == 200, r.text
    # answered once the change is on disk (written by the store's own thread, in order)
    on_disk = json.loads((st.settings.state_dir / "params.json").read_text())  # type: ignore[operator]
    assert on_disk["version"] == r.json()["version"]
    assert on_disk["values"]["safety"]["vision_stale_s"] == 0.4
    assert c.put("/api/presets/p1").status_code == 200
    assert c.post("/api/params/import",
                  json={"values": {"safety": {"vision_stale_s": 0.5}}}).status_code == 200
    assert c.post("/api/presets/p1/load").status_code == 200
    assert c.post("/api/recording", json={"action": "stop"}).status_code == 200
    assert c.get("/api/params").json()["values"]["recording"]["enabled"] is False
    assert seen == [STATION_THREAD] * 4, seen


def test_a_refused_or_stale_change_is_refused_on_the_station_thread_too(station) -> None:  # type: ignore[no-untyped-def]
    c, st = station
    seen = _threads_of_param_changes(st)
    v0 = c.get("/api/params").json()["version"]
    assert c.patch("/api/params", json={"safety": {"vision_stale_s": 0.4}}).status_code == 200
    r = c.patch(f"/api/params?version={v0}", json={"safety": {"vision_stale_s": 0.6}})
    assert r.status_code == 409 and r.json()["detail"][0]["type"] == "stale_version", r.text
    r = c.patch("/api/params", json={"safety": {"vision_stale_s": -1}})
    assert r.status_code == 422, r.text
    r = c.patch("/api/params", headers={"x-touchline-params-version": "x"}, json={})
    assert r.status_code == 422 and r.json()["detail"][0]["type"] == "int_parsing"
    assert seen == [STATION_THREAD]


def _threads_reading(st: Station) -> list[str]:
    seen: list[str] = []
    wall = st.operators.wall

    def recording_wall() -> float:
        seen.append(threading.current_thread().name)
        return wall()
    st.operators.wall = recording_wall
    return seen


def test_the_operators_are_changed_on_the_station_thread(station) -> None:  # type: ignore[no-untyped-def]
    c, st = station
    seen = _threads_reading(st)
    alice = {"cookie": "touchline_name=alice"}
    with c.websocket_connect("/api/ws", headers=alice) as ws:
        ws.receive_text()  # the snapshot: the session is listed
        assert [s["name"] for s in c.get("/api/operators").json()["operators"]] == ["alice"]
        assert c.post("/api/robots/blue/1/target", json={"x": 0, "y": 0},
                      headers=alice).status_code == 200
        bob = {"cookie": "touchline_name=bob"}
        assert c.post("/api/driving/blue/request", headers=bob).status_code == 200
        assert c.post("/api/driving/blue/give", headers=alice).status_code == 200
        assert c.post("/api/driving/blue/take", json={"confirm": True},
                      headers=alice).status_code == 200
        assert c.post("/api/driving/blue/release", headers=alice).status_code == 200
        assert c.patch("/api/params", json={"strategy": {"play": "idle"}},
                       headers=bob).status_code == 200
    deadline = time.monotonic() + 5
    while c.get("/api/operators").json()["operators"]:  # the session ends with the socket
        assert time.monotonic() < deadline, "the websocket session was not ended"
        threading.Event().wait(0.01)
    assert len(seen) >= 10 and set(seen) == {STATION_THREAD}, seen


def _count_queued(st: Station) -> list[str]:
    """Every call queued on the station (its command queue) while the list is kept."""
    queued: list[str] = []
    command: Callable[..., Any] = st.loop.command

    def counting(fn: Callable[..., Any], *args: Any) -> Any:
        queued.append(getattr(fn, "__name__", repr(fn)))
        return command(fn, *args)
    st.loop.command = counting  # type: ignore[method-assign]
    return queued


def test_one_estop_press_is_one_queued_call(station) -> None:  # type: ignore[no-untyped-def]
    c, st = station
    queued = _count_queued(st)
    r = c.post("/api/estop", json={"active": True})
    assert r.status_code == 200 and r.json()["active"] is True, r.text
    assert len(queued) == 1, queued
    assert st.safety.estop and st.operators.actions()[0]["action"] == "estop"
    queued.clear()
    r = c.post("/api/estop", json={"active": False, "confirm": True, "reason": "clear"})
    assert r.status_code == 200 and r.json()["active"] is False, r.text
    assert len(queued) == 1, queued
    assert st.operators.actions()[0]["action"] == "estop-release"
