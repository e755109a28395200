"""The director's I/O: fieldsim's truth in (ZeroMQ SUB, topic b"truth", JSON), the Referee
multicast out (10 Hz and at once on every change) and ball teleports out (SSL simulation
protocol SimulatorCommand to fieldsim's control port). Synchronous and single-threaded."""

from __future__ import annotations

import json
import logging
import socket
import time
from collections.abc import Callable
from typing import Any

import zmq

from match.director import Director, TeleportBall
from sslnet.multicast import open_multicast_sender
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand, SimulatorResponse

log = logging.getLogger("touchline.match")

REFEREE_HZ = 10.0


def teleport_datagram(t: TeleportBall) -> bytes:
    """SimulatorCommand that puts the ball at rest at (x, y) mm (the protocol is in metres)."""
    cmd = SimulatorCommand()
    tb = cmd.control.teleport_ball
    tb.x, tb.y, tb.z = t.x / 1000.0, t.y / 1000.0, 0.0
    tb.vx, tb.vy, tb.vz = 0.0, 0.0, 0.0
    return cmd.SerializeToString()


class DirectorShell:
    def __init__(
        self,
        director: Director,
        *,
        truth_endpoint: str,
        referee_group: str,
        referee_port: int,
        sim_control: tuple[str, int],
        interface: str = "127.0.0.1",
        clock: Callable[[], float] = time.monotonic,
        wallclock: Callable[[], float] = time.time,
    ) -> None:
        self.director = director
        self.truth_endpoint = truth_endpoint
        self.referee_addr = (referee_group, referee_port)
        self.sim_control = sim_control
        self.interface = interface
        self.clock = clock
        self.wallclock = wallclock
        self.truth_frames = 0
        self.truth_errors = 0
        self.last_truth_mono: float | None = None
        self.referee_sent = 0
        self.referee_errors = 0
        self.teleports_sent = 0
        self.sim_errors: list[str] = []
        self._ctx: zmq.Context[zmq.Socket[bytes]] | None = None
        self._sub: zmq.Socket[bytes] | None = None
        self._ref_sock: socket.socket | None = None
        self._sim_sock: socket.socket | None = None
        self._sent_revision = -1
        self._sent_at = -1e9

    # -- lifecycle -----------------------------------------------------------------------------

    def open(self) -> None:
        self._ctx = zmq.Context()
        sub = self._ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.RCVHWM, 10_000)
        sub.setsockopt(zmq.SUBSCRIBE, b"truth")
        sub.connect(self.truth_endpoint)
        self._sub = sub
        self._ref_sock = open_multicast_sender(self.interface)
        sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sim.setblocking(False)
        self._sim_sock = sim

    def close(self) -> None:
        if self._sub is not None:
            self._sub.close(linger=0)
            self._sub = None
        if self._ctx is not None:
            self._ctx.term()
            self._ctx = None
        for s in (self._ref_sock, self._sim_sock):
            if s is not None:
                s.close()
        self._ref_sock = self._sim_sock = None

    def __enter__(self) -> DirectorShell:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- I/O -----------------------------------------------------------------------------------

    def receive(self, timeout_s: float) -> list[dict[str, Any]]:
        """Truth frames that arrived within ``timeout_s`` (all of them, in order)."""
        assert self._sub is not None
        out: list[dict[str, Any]] = []
        if not self._sub.poll(int(max(0.0, timeout_s) * 1000)):
            return out
        while True:
            try:
                frames = self._sub.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                break
            if len(frames) != 2:
                self.truth_errors += 1
                continue
            try:
                truth = json.loads(frames[1])
            except ValueError:
                self.truth_errors += 1
                continue
            if isinstance(truth, dict):
                out.append(truth)
        if out:
            self.truth_frames += len(out)
            self.last_truth_mono = self.clock()
        return out

    def step(self, truths: list[dict[str, Any]]) -> None:
        """Tick the director with every new truth frame (or once without one), send what it
        asks for, and the Referee message if it changed or 0.1 s passed."""
        now = self.clock()
        actions: list[TeleportBall] = []
        if truths:
            for truth in truths:
                actions.extend(self.director.tick(now, truth))
        else:
            actions.extend(self.director.tick(now, None))
        for a in actions:
            self.send_teleport(a)
        self.send_referee(force=False)
        self._drain_sim_replies()

    def send_referee(self, force: bool) -> None:
        now = self.clock()
        d = self.director
        if not force and d.revision == self._sent_revision and \
                now - self._sent_at < 1.0 / REFEREE_HZ:
            return
        assert self._ref_sock is not None
        try:
            self._ref_sock.sendto(d.encode(int(self.wallclock() * 1e6)), self.referee_addr)
            self.referee_sent += 1
        except OSError as exc:
            self.referee_errors += 1
            log.warning("referee send failed: %s", exc)
        self._sent_revision = d.revision
        self._sent_at = now

    def send_teleport(self, t: TeleportBall) -> None:
        assert self._sim_sock is not None
        try:
            self._sim_sock.sendto(teleport_datagram(t), self.sim_control)
            self.teleports_sent += 1
        except OSError as exc:
            log.warning("teleport send failed: %s", exc)

    def _drain_sim_replies(self) -> None:
        assert self._sim_sock is not None
        while True:
            try:
                data = self._sim_sock.recv(65536)
            except OSError:  # nothing more (BlockingIOError) or the port is gone
                return
            try:
                reply = SimulatorResponse.FromString(data)
            except Exception:  # a malformed reply is the simulator's problem, not ours
                continue
            for err in reply.errors:
                self.sim_errors.append(f"{err.code}: {err.message}")
                log.warning("simulator refused a teleport: %s %s", err.code, err.message)
