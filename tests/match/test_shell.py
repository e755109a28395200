"""The director's I/O shell over real sockets in one process: truth over ZeroMQ in, Referee
multicast and SimulatorCommand teleports out."""

from __future__ import annotations

import json
import random
import select
import socket
import time
from collections.abc import Iterator
from typing import Any

import pytest
import zmq

from launcher.supervisor import free_tcp_port
from match.config import MatchConfig
from match.director import Director, TeleportBall
from match.shell import DirectorShell
from sslnet.multicast import loopback_multicast_ok, open_multicast_receiver, open_udp_server
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

from .fake import FakeWorld

pytestmark = pytest.mark.skipif(not loopback_multicast_ok(),
                                reason="multicast on loopback is not set up")

GROUP = "224.5.23.1"


@pytest.fixture
def rig() -> Iterator[dict[str, Any]]:
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    endpoint = f"tcp://127.0.0.1:{free_tcp_port()}"
    pub.bind(endpoint)
    port = random.Random().randrange(40000, 50000)
    ref_rx = open_multicast_receiver(GROUP, port)
    sim = open_udp_server("127.0.0.1", 0)
    director = Director(MatchConfig(interludes=False), wall_offset_s=time.time() - time.monotonic())
    shell = DirectorShell(director, truth_endpoint=endpoint, referee_group=GROUP,
                          referee_port=port, sim_control=sim.getsockname())
    shell.open()
    try:
        yield {"pub": pub, "ref_rx": ref_rx, "sim": sim, "shell": shell, "director": director}
    finally:
        shell.close()
        ref_rx.close()
        sim.close()
        pub.close(linger=0)
        ctx.term()


def _referees(sock: socket.socket, timeout_s: float) -> list[Referee]:
    """Every Referee datagram waiting, waiting at most ``timeout_s`` for more."""
    out: list[Referee] = []
    deadline = time.monotonic() + timeout_s
    while True:
        ready, _, _ = select.select([sock], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            return out
        out.append(Referee.FromString(sock.recv(65536)))


def test_truth_in_referee_multicast_out_at_ten_hertz_and_on_change(
        rig: dict[str, Any]) -> None:
    shell: DirectorShell = rig["shell"]
    world = FakeWorld()
    frames: list[dict[str, Any]] = []
    deadline = time.monotonic() + 5.0
    while not frames and time.monotonic() < deadline:  # the SUB joins a moment after connect
        rig["pub"].send_multipart([b"truth", json.dumps(world.truth()).encode()])
        frames = shell.receive(0.05)
    assert frames and frames[0]["ball"]["x"] == 0.0
    rig["pub"].send_multipart([b"other", b"{}"])  # another topic is not delivered
    rig["pub"].send_multipart([b"truth", b"not json"])
    shell.step(frames)
    # the start: HALT now, STOP one second later (sent at once, not at the next 10 Hz slot)
    t_end = time.monotonic() + 1.6
    got: list[tuple[float, Referee]] = []
    while time.monotonic() < t_end:
        rig["pub"].send_multipart([b"truth", json.dumps(world.truth()).encode()])
        shell.step(shell.receive(1 / 60))
        got.extend((time.monotonic(), m) for m in _referees(rig["ref_rx"], 0.0))
    got.extend((time.monotonic(), m) for m in _referees(rig["ref_rx"], 0.2))
    assert shell.truth_errors == 1
    commands = [m.command for _, m in got]
    assert commands[0] == Referee.HALT and Referee.STOP in commands
    assert all(m.source_identifier == rig["director"].referee.source_identifier for _, m in got)
    # about 10 Hz (plus one on the change)
    assert 13 <= len(got) <= 20, len(got)
    first_stop = next(t for t, m in got if m.command == Referee.STOP)
    changed_at = rig["director"].command_since
    assert first_stop - changed_at < 0.1, [(round(t - changed_at, 3), m.command) for t, m in got]


def test_teleport_is_a_simulator_command_in_metres(rig: dict[str, Any]) -> None:
    shell: DirectorShell = rig["shell"]
    shell.send_teleport(TeleportBall(1500.0, -250.0))
    ready, _, _ = select.select([rig["sim"]], [], [], 2.0)
    assert ready
    data, _addr = rig["sim"].recvfrom(65536)
    cmd = SimulatorCommand.FromString(data)
    tb = cmd.control.teleport_ball
    assert (tb.x, tb.y, tb.z, tb.vx, tb.vy) == (pytest.approx(1.5), pytest.approx(-0.25), 0, 0, 0)
    assert shell.teleports_sent == 1
