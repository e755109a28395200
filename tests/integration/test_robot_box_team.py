"""The wrong robot, through the real processes: the station in robot-box mode (the seed's
13-byte datagram per robot, no team field) with a test socket as the robot box and a test
camera. A target for yellow 3 is refused with the reason; one for blue 3 drives robot 3; no
datagram for robot 3 ever comes from a yellow target."""

from __future__ import annotations

import socket
import time

import httpx

from .conftest import StationHandle, arm, next_relay_stats, wait_until
from .standins import RobotBoxCamera, box_ids


def test_a_target_for_their_robot_never_drives_ours(
        box_station: tuple[StationHandle, socket.socket]) -> None:
    station, box = box_station
    cam = RobotBoxCamera(station.ports)
    try:
        wait_until(lambda: len(station.get("/api/world")["robots"]) == 2, 20,
                   what="blue 3 and yellow 3 seen")
        # the strategy must not move robot 3 by itself meanwhile
        assert httpx.patch(station.url + "/api/params",
                           json={"strategy": {"play": "idle"}}).status_code == 200
        wait_until(lambda: station.get("/api/health")["relay"] is not None, 10,
                   what="relay stats")
        arm(station)  # real robots: the station starts disarmed

        def robot3_still() -> bool:  # the play's last commands stale and zeroed by the relay
            got = [sx for rid, sx in box_ids(box) if rid == 3]
            time.sleep(0.15)
            got += [sx for rid, sx in box_ids(box) if rid == 3]
            return all(sx == 0 for sx in got)
        wait_until(robot3_still, 10, what="robot 3 at rest before the test")
        r = httpx.post(station.url + "/api/robots/yellow/3/target", json={"x": 3000, "y": 0})
        assert r.status_code == 422, r.text
        assert "robot-box" in r.json()["detail"][0]["msg"]
        # an observation window by the relay's own clock (its statistics stamped 0.3 s
        # later at least): nothing in it may drive robot 3
        next_relay_stats(station, 0.3)
        assert all(sx == 0 for rid, sx in box_ids(box) if rid == 3)
        r = httpx.post(station.url + "/api/robots/blue/3/target", json={"x": 3000, "y": 0})
        assert r.status_code == 200, r.text
        wait_until(lambda: any(rid == 3 and sx != 0 for rid, sx in box_ids(box)), 10,
                   what="our robot 3 driven")
    finally:
        httpx.delete(station.url + "/api/robots/blue/3/target", headers={"X-Touchline": "1"})
        cam.stop()
