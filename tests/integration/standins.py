"""What the integration tests stand in for when they are the camera, the simulator or the
robot box (``--sim none``): camera frames, the commands a simulator port receives, the robot
box's datagrams. Real multicast SSL_WrapperPacket datagrams out, the relay's real datagrams
in."""

from __future__ import annotations

import math
import select
import socket
import threading
import time
from collections.abc import Iterable, Mapping
from typing import Any

from sslnet.kerneltime import enable_kernel_timestamps, kernel_time
from sslnet.multicast import open_multicast_receiver, open_multicast_sender
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

#: a robot in a frame: (id, x mm, y mm), heading 0
Spot = tuple[int, float, float]


def frame(number: int, t: float, blue: Iterable[Spot] = (), yellow: Iterable[Spot] = (),
          ball: tuple[float, float] | None = None) -> bytes:
    """Camera 0's detection frame ``number``, captured and sent at ``t`` (Unix seconds)."""
    pkt = SSL_WrapperPacket()
    d = pkt.detection
    d.frame_number, d.t_capture, d.t_sent, d.camera_id = number, t, t, 0
    for team, spots in ((d.robots_blue, blue), (d.robots_yellow, yellow)):
        for rid, x, y in spots:
            r = team.add()
            r.confidence, r.robot_id, r.x, r.y, r.orientation = 0.9, rid, x, y, 0.0
            r.pixel_x = r.pixel_y = 0.0
    if ball is not None:
        b = d.balls.add()
        b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, ball[0], ball[1], 0.0, 0.0
    return pkt.SerializeToString()


class CommandLog:
    """A simulator's blue port: every command of every RobotControl datagram, as (arrival
    on the monotonic clock, robot id, speed + |turn|), recorded on a thread of its own."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.sock.settimeout(0.05)
        self.log: list[tuple[float, int, float]] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        end = time.monotonic() + 300  # bounded
        while not self.stop.is_set() and time.monotonic() < end:
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            now = time.monotonic()
            for c in RobotControl.FromString(data).robot_commands:
                lv = c.move_command.local_velocity
                self.log.append((now, c.id, math.hypot(lv.forward, lv.left) + abs(lv.angular)))

    def since(self, t: float, rid: int) -> list[float]:
        """The speeds commanded to ``rid`` since ``t`` (monotonic), oldest first."""
        return [s for ts, i, s in list(self.log) if ts >= t and i == rid]

    def moving_since(self, t: float, rid: int = 0) -> bool:
        return any(s > 0.05 for s in self.since(t, rid))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        self.sock.close()


class Arrivals:
    """Every datagram on a multicast group and port (tracked vision, a camera's frames): the
    kernel's receive time (wall clock, s), read on a thread of its own."""

    def __init__(self, group: str, port: int, rcvbuf: int = 1 << 21,
                 keep_data: bool = False) -> None:
        self.sock = open_multicast_receiver(group, port, "127.0.0.1", rcvbuf=rcvbuf)
        enable_kernel_timestamps(self.sock)
        self.times: list[float] = []
        #: with ``keep_data``: every datagram with its receive time, to be read afterwards
        self.datagrams: list[tuple[float, bytes]] | None = [] if keep_data else None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            if not select.select([self.sock], [], [], 0.1)[0]:
                continue
            while True:
                try:
                    data, anc, _, _ = self.sock.recvmsg(65536, 64)
                except BlockingIOError:
                    break
                t = kernel_time(anc) or time.time()
                self.times.append(t)
                if self.datagrams is not None:
                    self.datagrams.append((t, data))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.sock.close()


def robot_box_camera(ports: Mapping[str, Any], stop: threading.Event) -> None:
    """Camera 0 at 60 Hz until ``stop`` (100 s at most): blue 3 at (-1000, 0), yellow 3 at
    (1000, 0); for the robot-box tests, whose datagrams carry no team."""
    sock = open_multicast_sender("127.0.0.1")
    try:
        for k in range(6000):
            if stop.is_set():
                return
            sock.sendto(frame(k, time.time(), blue=[(3, -1000.0, 0.0)],
                              yellow=[(3, 1000.0, 0.0)]), (ports["vision_group"], ports["vision"]))
            stop.wait(1 / 60)
    finally:
        sock.close()


class RobotBoxCamera:
    """``robot_box_camera`` on a thread from its creation until ``stop``."""

    def __init__(self, ports: Mapping[str, Any]) -> None:
        self._stop = threading.Event()
        self._thread = threading.Thread(target=robot_box_camera, args=(ports, self._stop),
                                        daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(5)


def box_ids(box: socket.socket) -> list[tuple[int, int]]:
    """(robot id, speedX byte) of every robot-box datagram waiting."""
    out: list[tuple[int, int]] = []
    while True:
        try:
            d = box.recv(64)
        except BlockingIOError:
            return out
        out.append((d[1], d[3]))
