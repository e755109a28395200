"""A camera that can fall silent and a simulator that stamps every command it gets: for the
all-vision-lost stop through the real processes (tests/integration/test_vision_lost.py and
bench/vision_loss_bench.py). Real multicast SSL_WrapperPacket datagrams out, the relay's real
RobotControl datagrams in, stamped by the kernel on arrival."""

from __future__ import annotations

import math
import select
import socket
import threading
import time
from dataclasses import dataclass, field

from sslnet.kerneltime import enable_kernel_timestamps, kernel_time_ns
from sslnet.multicast import open_multicast_sender
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl

from .standins import frame


@dataclass
class Camera:
    """Camera 0 at ``hz``: blue 0 at (-2000, 0), blue 1 at (1000, 0), a ball. ``silence``
    stops it between two frames and says when the last one was sent (this machine's clock,
    read before the send: the relay received it later); ``resume`` starts it again."""

    group: str
    port: int
    hz: float = 60.0
    frames: int = 0
    last_sent_ns: int = 0
    stop: threading.Event = field(default_factory=threading.Event)
    _sending: threading.Event = field(default_factory=threading.Event)
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def __post_init__(self) -> None:
        self._sending.set()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _packet(self, now: float) -> bytes:
        return frame(self.frames, now, blue=[(0, -2000.0, 0.0), (1, 1000.0, 0.0)],
                     ball=(0.0, 1500.0))

    def _run(self) -> None:
        sock = open_multicast_sender("127.0.0.1")
        period = 1.0 / self.hz
        end = time.monotonic() + 600  # bounded
        nxt = time.monotonic()
        try:
            while not self.stop.is_set() and time.monotonic() < end:
                if not self._sending.wait(0.1):
                    nxt = time.monotonic()
                    continue
                with self._lock:
                    if self._sending.is_set():
                        self.last_sent_ns = time.time_ns()
                        sock.sendto(self._packet(self.last_sent_ns / 1e9),
                                    (self.group, self.port))
                        self.frames += 1
                nxt = max(nxt + period, time.monotonic())  # paced, no catching up in bursts
                self.stop.wait(max(0.0, nxt - time.monotonic()))
        finally:
            sock.close()

    def silence(self) -> int:
        """Stops sending; returns the last frame's send time (ns, Unix)."""
        with self._lock:
            self._sending.clear()
            return self.last_sent_ns

    def resume(self) -> None:
        self._sending.set()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)


@dataclass
class Command:
    arrival_ns: int  # the kernel's stamp
    speeds: dict[int, float]  # robot id -> |v| + |w| of every robot in the datagram


class Simulator:
    """The blue port of a simulator: every RobotControl datagram with its arrival stamp."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self.sock.bind(("127.0.0.1", port))
        self.sock.setblocking(False)
        enable_kernel_timestamps(self.sock)
        self.trace: list[Command] = []  # what stop_after read, for a failure's message

    def describe(self, t_ns: int) -> str:
        """The datagrams ``stop_after`` read: ms after ``t_ns``, robot: speed."""
        return "; ".join(
            f"{(c.arrival_ns - t_ns) / 1e6:.1f} ms " + " ".join(
                f"{i}:{v:.2f}" for i, v in sorted(c.speeds.items())) for c in self.trace)

    def read(self, timeout_s: float = 0.0) -> list[Command]:
        """Every datagram waiting (after up to ``timeout_s`` for the first)."""
        out: list[Command] = []
        if timeout_s > 0:
            select.select([self.sock], [], [], timeout_s)
        while True:
            try:
                data, anc, _, _ = self.sock.recvmsg(65536, 64)
            except BlockingIOError:
                return out
            t = kernel_time_ns(anc) or time.time_ns()
            speeds = {}
            for c in RobotControl.FromString(data).robot_commands:
                lv = c.move_command.local_velocity
                speeds[c.id] = math.hypot(lv.forward, lv.left) + abs(lv.angular)
            out.append(Command(t, speeds))

    def driving(self, rid: int = 0, timeout_s: float = 0.2) -> bool:
        """``rid`` commanded to move in what arrives now."""
        return any(c.speeds.get(rid, 0.0) > 0.05 for c in self.read(timeout_s))

    def stop_after(self, t_ns: int, rid: int = 0, hold_s: float = 0.4,
                   timeout_s: float = 5.0) -> tuple[Command, Command | None]:
        """The stop after ``t_ns``: the first datagram commanding zero to every robot in it,
        ``rid`` among them, after which nothing but zeros came for ``hold_s`` (a zero for
        another reason that the robots drove on from, such as a strategy stalled for a
        moment on a loaded machine, is not it); and the last datagram before it that drove
        ``rid`` (None: none after ``t_ns``). Bounded by ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        drove: Command | None = None
        stop: Command | None = None
        self.trace = []
        while time.monotonic() < deadline:
            for c in self.read(0.05):
                if c.arrival_ns < t_ns:
                    continue
                self.trace.append(c)
                if all(s == 0.0 for s in c.speeds.values()):
                    if stop is None and rid in c.speeds:
                        stop = c
                    continue
                stop = None  # driven again: that zero was not the stop
                if c.speeds.get(rid, 0.0) > 0.0:
                    drove = c
            if stop is not None and time.time_ns() - stop.arrival_ns > hold_s * 1e9:
                return stop, drove
        raise AssertionError(f"no stop for robot {rid} within {timeout_s} s")

    def close(self) -> None:
        self.sock.close()
