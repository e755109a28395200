"""Arming through the real processes: the station in robot-box mode (real robots) with a test
socket as the robot box and a test camera. Disarmed, the box receives nothing at all, even
with a target set and vision arriving; armed, the robot is driven; after an e-stop only stops
(or nothing) arrive and the station and the relay say disarmed."""

from __future__ import annotations

import socket

import httpx

from .conftest import StationHandle, arm, next_relay_stats, wait_until
from .standins import RobotBoxCamera, box_ids


def _post(st: StationHandle, path: str, body: dict) -> httpx.Response:  # type: ignore[type-arg]
    return httpx.post(st.url + path, json=body, headers={"X-Touchline": "1"}, timeout=5)


def _disarmed_drops(health: dict) -> int:  # type: ignore[type-arg]
    n: int = (health["streams"].get("relay.commands", {})
              .get("errors_by_reason", {}).get("disarmed", 0))
    return n


def _robots_held(st: StationHandle) -> int:
    """Robots the relay sends anything to (commands, or zeros for the hold time), from its
    latest statistics."""
    relay = st.get("/api/health")["relay"]
    n: int = relay["active_robots"] + relay["stale_robots"]
    return n


def test_nothing_reaches_the_robots_until_armed_and_the_estop_disarms(
        box_station: tuple[StationHandle, socket.socket]) -> None:
    station, box = box_station
    cam = RobotBoxCamera(station.ports)
    try:
        wait_until(lambda: len(station.get("/api/world")["robots"]) == 2, 20,
                   what="blue 3 and yellow 3 seen")
        w = station.get("/api/world")
        assert w["arming_required"] is True and w["armed"] is False
        wait_until(lambda: (station.get("/api/health")["relay"] or {}).get("arming_required"),
                   10, what="relay stats")
        h = station.get("/api/health")
        assert h["relay"]["armed"] is False and h["arming"]["armed"] is False
        # a target and a play that drives, vision arriving: still nothing leaves the relay
        assert httpx.patch(station.url + "/api/params", headers={"X-Touchline": "1"},
                           json={"strategy": {"play": "idle"}}).status_code == 200
        assert _post(station, "/api/robots/blue/3/target",
                     {"x": 3000, "y": 0}).status_code == 200
        # the relay drops each set when it takes it (it would send at once otherwise): once
        # its statistics count more drops than those stamped after the target was set,
        # sets with the target were taken, and nothing can be on its way to the box
        dropped = _disarmed_drops(next_relay_stats(station, 0.0))
        wait_until(lambda: _disarmed_drops(station.get("/api/health")) > dropped, 10,
                   what="the dropped command sets counted")
        assert box_ids(box) == []

        # armed: robot 3 is driven
        state = arm(station)
        assert state["armed"] is True and state["required"] is True
        wait_until(lambda: any(rid == 3 and sx != 0 for rid, sx in box_ids(box)), 10,
                   what="our robot 3 driven once armed")
        wait_until(lambda: station.get("/api/health")["relay"]["armed"], 5,
                   what="the relay armed")

        # the e-stop: disarmed, only stops (or nothing) from 0.2 s after the press
        assert _post(station, "/api/estop", {"active": True}).status_code == 200
        wait_until(lambda: station.get("/api/estop")["relay_latched"], 5,
                   what="the relay latched")
        box_ids(box)  # sent before the relay latched
        next_relay_stats(station, 1.0)  # a second of the relay's own time, latched
        got = box_ids(box)
        assert all(sx == 0 for _, sx in got), got
        w = station.get("/api/world")
        assert w["armed"] is False and w["estop"] is True
        wait_until(lambda: station.get("/api/health")["relay"]["armed"] is False, 5,
                   what="the relay disarmed")
        r = _post(station, "/api/arm", {"armed": True})
        assert r.status_code == 409 and "emergency stop" in r.json()["detail"]

        # released: still disarmed, nothing drives until armed again
        assert _post(station, "/api/estop", {"active": False, "confirm": True}).status_code \
            == 200
        # the zeros' hold time is 1 s: then the relay holds no robot and sends nothing
        wait_until(lambda: _robots_held(station) == 0, 10, what="the zeros' hold over")
        box_ids(box)
        next_relay_stats(station, 0.5)
        assert _robots_held(station) == 0 and box_ids(box) == []
        assert station.get("/api/world")["armed"] is False
    finally:
        httpx.delete(station.url + "/api/robots/blue/3/target", headers={"X-Touchline": "1"})
        _post(station, "/api/arm", {"armed": False})
        cam.stop()
