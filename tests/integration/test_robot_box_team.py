"""The wrong robot, through the real processes: the station in robot-box mode (the seed's
13-byte datagram per robot, no team field) with a test socket as the robot box and a test
camera. A target for yellow 3 is refused with the reason; one for blue 3 drives robot 3; no
datagram for robot 3 ever comes from a yellow target."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import httpx
import pytest

from sslnet.multicast import open_multicast_sender
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from .conftest import StationHandle, arm, launched, next_relay_stats, wait_until


@pytest.fixture(scope="module")
def box() -> Iterator[socket.socket]:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.setblocking(False)
    yield s
    s.close()


@pytest.fixture(scope="module")
def station(box: socket.socket) -> Iterator[StationHandle]:
    port = box.getsockname()[1]
    with launched("--sim", "none", "--output", "robot-box",
                  f"--relay-arg=--robot-box=127.0.0.1:{port}") as st:
        yield st


def _camera(st: StationHandle, stop: threading.Event) -> None:
    sock = open_multicast_sender("127.0.0.1")
    p = st.ports
    try:
        for k in range(6000):  # at most 100 s at 60 Hz
            if stop.is_set():
                return
            pkt = SSL_WrapperPacket()
            d = pkt.detection
            d.frame_number, d.t_capture, d.t_sent, d.camera_id = k, time.time(), time.time(), 0
            for team, x in ((d.robots_blue, -1000.0), (d.robots_yellow, 1000.0)):
                r = team.add()
                r.confidence, r.robot_id, r.x, r.y, r.pixel_x, r.pixel_y = 0.9, 3, x, 0, 0, 0
            sock.sendto(pkt.SerializeToString(), (p["vision_group"], p["vision"]))
            stop.wait(1 / 60)
    finally:
        sock.close()


def _box_ids(box: socket.socket) -> list[tuple[int, int]]:
    """(robot id, speedX byte) of every datagram waiting."""
    out = []
    while True:
        try:
            d = box.recv(64)
        except BlockingIOError:
            return out
        out.append((d[1], d[3]))


def test_a_target_for_their_robot_never_drives_ours(station: StationHandle,
                                                     box: socket.socket) -> None:
    stop = threading.Event()
    cam = threading.Thread(target=_camera, args=(station, stop), daemon=True)
    cam.start()
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
            got = [sx for rid, sx in _box_ids(box) if rid == 3]
            time.sleep(0.15)
            got += [sx for rid, sx in _box_ids(box) if rid == 3]
            return all(sx == 0 for sx in got)
        wait_until(robot3_still, 10, what="robot 3 at rest before the test")
        r = httpx.post(station.url + "/api/robots/yellow/3/target", json={"x": 3000, "y": 0})
        assert r.status_code == 422, r.text
        assert "robot-box" in r.json()["detail"][0]["msg"]
        # an observation window by the relay's own clock (its statistics stamped 0.3 s
        # later at least): nothing in it may drive robot 3
        next_relay_stats(station, 0.3)
        assert all(sx == 0 for rid, sx in _box_ids(box) if rid == 3)
        r = httpx.post(station.url + "/api/robots/blue/3/target", json={"x": 3000, "y": 0})
        assert r.status_code == 200, r.text
        wait_until(lambda: any(rid == 3 and sx != 0 for rid, sx in _box_ids(box)), 10,
                   what="our robot 3 driven")
    finally:
        httpx.delete(station.url + "/api/robots/blue/3/target", headers={"X-Touchline": "1"})
        stop.set()
        cam.join(5)
