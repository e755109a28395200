"""Hostile vision through the real processes (relay + backend, no simulator): a test program
is the camera (real multicast) and the simulator (it reads the relay's RobotControl datagrams
on the blue port). The defect: one frame from an hour ahead froze the world while commands
kept flowing. Now that frame is dropped and counted, the world keeps following the camera,
and a camera whose every frame is out of range stops the robots (the lost-vision stop)."""

from __future__ import annotations

import math
import socket
import threading
import time
from dataclasses import dataclass, field

import httpx

from sslnet.multicast import open_multicast_sender
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from .conftest import StationHandle, arm, wait_until
from .standins import frame


@dataclass
class Camera:
    """Sends camera 0's frames at 60 Hz: blue 0 driving along x at 0.5 m/s, blue 1 still.
    ``mode``: "normal"; "future-once" (the next frame is an hour ahead, then normal again);
    "scattered" (every frame hours off, each by another amount: nothing to re-sync to)."""

    group: str
    port: int
    mode: str = "normal"
    x0: float = -2000.0
    frames: int = 0
    x: float = 0.0
    stop: threading.Event = field(default_factory=threading.Event)

    def run(self) -> None:
        sock = open_multicast_sender("127.0.0.1")
        t_start = time.time()
        try:
            while not self.stop.is_set() and time.time() - t_start < 120:  # bounded
                now = time.time()
                self.x = self.x0 + 500.0 * (now - t_start)
                t_cap, x = now, self.x
                if self.mode == "future-once":
                    t_cap, x, self.mode = now + 3600.0, -2465.0, "normal"
                elif self.mode == "scattered":
                    t_cap = now + 3600.0 * (1 + self.frames % 5) * (-1) ** self.frames
                sock.sendto(frame(self.frames, t_cap, blue=[(0, x, 0.0), (1, 1000.0, 0.0)],
                                  ball=(0.0, 1500.0)), (self.group, self.port))
                self.frames += 1
                self.stop.wait(1 / 60)
        finally:
            sock.close()


class Robots:
    """The simulator's side: the newest command per blue robot."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.sock.settimeout(0.05)

    def latest(self, rid: int, window_s: float = 0.15) -> list[float]:
        """Speeds (m/s) commanded to ``rid`` in the next ``window_s``."""
        speeds: list[float] = []
        end = time.monotonic() + window_s
        while time.monotonic() < end:
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            for c in RobotControl.FromString(data).robot_commands:
                if c.id == rid:
                    lv = c.move_command.local_velocity
                    speeds.append(math.hypot(lv.forward, lv.left))
        return speeds


def _blue0(st: StationHandle) -> dict | None:  # type: ignore[type-arg]
    return next((r for r in st.get("/api/world")["robots"]
                 if r["team"] == "blue" and r["id"] == 0), None)


def test_a_frame_from_the_future_neither_freezes_the_world_nor_drives_blind(
        bare: StationHandle) -> None:
    p = bare.ports
    cam = Camera(p["vision_group"], p["vision"])
    sender = threading.Thread(target=cam.run, daemon=True)
    robots = Robots(p["sim_blue"])
    sender.start()
    try:
        wait_until(lambda: _blue0(bare), 20, what="blue 0 seen")
        # health is ok only with the relay's statistics (once a second): a loaded machine
        # may not have them yet
        wait_until(lambda: bare.get("/api/health")["relay"], 10, what="relay statistics")
        arm(bare)  # an external simulator: the station starts disarmed
        r = httpx.post(bare.url + "/api/robots/blue/0/target", json={"x": 3000.0, "y": 0.0})
        assert r.status_code == 200, r.text
        wait_until(lambda: any(s > 0.1 for s in robots.latest(0)), 10,
                   what="blue 0 commanded to drive")

        # one frame an hour ahead: dropped, counted; the world keeps following the camera
        cam.mode = "future-once"
        wait_until(lambda: bare.get("/api/health")["world"]["rejected"]
                   .get("time out of range", 0) >= 1, 5, what="the future frame counted")
        def follows() -> bool:
            b = _blue0(bare)
            return b is not None and abs(b["raw_x"] - cam.x) < 100.0
        wait_until(follows, 5, what=f"blue 0 following the camera (camera at {cam.x:.0f})")
        n = cam.frames  # the camera drives on: the world must still follow 20 frames later
        wait_until(lambda: cam.frames >= n + 20, 5, what="20 more frames sent")
        wait_until(follows, 2, what="blue 0 still following the camera")
        h = bare.get("/api/health")
        assert h["ok"], h["warnings"]
        assert any("time out of range" in w for w in h["warnings"]), h["warnings"]
        assert any(s > 0.1 for s in robots.latest(0))

        # every frame out of range, each differently: nothing merges, the robots stop
        cam.mode = "scattered"
        wait_until(lambda: bare.get("/api/world")["halt_reason"].startswith("no vision"), 5,
                   what="the lost-vision stop")
        wait_until(lambda: (s := robots.latest(0, 0.3)) and max(s) == 0.0, 5,
                   what="blue 0 commanded to zero")
        h = bare.get("/api/health")
        assert not h["ok"]
        assert any(w.startswith("world not updated") for w in h["warnings"]), h["warnings"]

        # good frames again: the station drives again
        cam.mode = "normal"
        wait_until(lambda: any(s > 0.1 for s in robots.latest(0)), 10,
                   what="blue 0 driving again with good frames")
        assert bare.get("/api/world")["halt_reason"] == ""
    finally:
        cam.stop.set()
        sender.join(5)
        robots.sock.close()


def test_undecodable_datagrams_are_counted_once_by_the_backend(bare: StationHandle) -> None:
    """The relay forwards vision undecoded; the backend is the one decoder: what does not parse
    is counted there by reason (shown in health), the relay counts nothing for it, and good
    frames around it still reach the world."""
    p = bare.ports
    cam = Camera(p["vision_group"], p["vision"])
    sender = threading.Thread(target=cam.run, daemon=True)
    bad = open_multicast_sender("127.0.0.1")
    sender.start()
    try:
        wait_until(lambda: _blue0(bare), 20, what="blue 0 seen")
        good = SSL_WrapperPacket()
        d = good.detection
        d.frame_number, d.t_capture, d.t_sent, d.camera_id = 1, time.time(), time.time(), 0
        whole = good.SerializeToString()

        def reasons() -> dict[str, int]:
            h = bare.get("/api/health")
            return h["streams"]["vision"]["errors_by_reason"]  # type: ignore[no-any-return]

        before = reasons()

        def counted() -> bool:
            for data in (whole[:-3], b"\xff\xfe not a wrapper"):
                bad.sendto(data, (p["vision_group"], p["vision"]))
            now = reasons()
            return all(now.get(k, 0) > before.get(k, 0) for k in ("truncated", "not protobuf"))
        wait_until(counted, 10, what="the backend counting truncated and not-protobuf vision")
        relay_vision = bare.get("/api/health")["streams"]["relay.vision"]
        assert relay_vision["errors_by_reason"] == {}, relay_vision
        n = cam.frames
        wait_until(lambda: cam.frames >= n + 10, 5, what="10 more good frames")
        wait_until(lambda: (b := _blue0(bare)) is not None and abs(b["raw_x"] - cam.x) < 100.0,
                   5, what="blue 0 following the camera")
    finally:
        cam.stop.set()
        sender.join(5)
        bad.close()
