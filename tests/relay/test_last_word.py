"""The relay's last word: on every shutdown it can see (SIGTERM, SIGINT, an exception) the last
datagram each robot gets from it is a stop. The relay runs as its own process here, as under
the launcher, with its output pointed at UDP sockets this test reads as the simulator."""

from __future__ import annotations

import asyncio
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zmq
import zmq.asyncio

from larcmacs_relay import Relay, RelayConfig
from sslpb import grsim_packet_pb2, touchline_pb2
from sslpb import ssl_simulation_robot_control_pb2 as rc_pb
from tests.ports import free_udp_port, random_multicast_port

ROOT = Path(__file__).resolve().parents[2]


def _tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _moving(rid: int) -> list[bytes]:
    cmd = touchline_pb2.RobotCommand(team=touchline_pb2.TEAM_BLUE, id=rid, forward_mps=1.2,
                                     left_mps=0.3, angular_radps=0.5, dribbler_rpm=2000.0)
    return [b"commands", touchline_pb2.RobotCommandSet(commands=[cmd]).SerializeToString()]


def _speeds(data: bytes) -> dict[int, float]:
    out = {}
    for c in rc_pb.RobotControl.FromString(data).robot_commands:
        lv = c.move_command.local_velocity
        out[c.id] = abs(lv.forward) + abs(lv.left) + abs(lv.angular) + c.dribbler_speed
    return out


def _drain(sock: socket.socket) -> list[bytes]:
    got = []
    while True:
        try:
            got.append(sock.recv(65536))
        except BlockingIOError:
            return got


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_a_stopped_relay_leaves_every_robot_a_stop(sig: signal.Signals) -> None:
    blue = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    blue.bind(("127.0.0.1", 0))
    blue.setblocking(False)
    sub_port = _tcp_port()
    proc = subprocess.Popen([
        sys.executable, "-m", "larcmacs_relay",
        "--vision", f"224.5.23.2:{random_multicast_port()}",
        "--referee", f"224.5.23.1:{random_multicast_port()}",
        "--pub", f"tcp://127.0.0.1:{_tcp_port()}", "--sub", f"tcp://127.0.0.1:{sub_port}",
        "--sim-blue-port", str(blue.getsockname()[1]),
        "--sim-yellow-port", str(free_udp_port()), "--sim-control-port", str(free_udp_port()),
        "--hold-time", "30",
    ], cwd=ROOT)
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    pub.connect(f"tcp://127.0.0.1:{sub_port}")
    try:
        # drive robots 2 and 5 until the relay repeats non-zero commands for both
        deadline = time.monotonic() + 15
        seen: set[int] = set()
        while seen != {2, 5}:
            assert time.monotonic() < deadline, "the relay never drove the robots"
            assert proc.poll() is None, "the relay exited"
            pub.send_multipart(_moving(2))
            pub.send_multipart(_moving(5))
            time.sleep(0.02)
            for d in _drain(blue):
                seen |= {rid for rid, s in _speeds(d).items() if s > 0}
        pub.send_multipart(_moving(2))
        proc.send_signal(sig)
        assert proc.wait(timeout=10) == 0
        last: dict[int, float] = {}
        for d in _drain(blue):
            last.update(_speeds(d))
        assert last == {2: 0.0, 5: 0.0}, f"the last datagrams were not a stop: {last}"
    finally:
        if proc.poll() is None:
            proc.kill()
        pub.close()
        ctx.term()
        blue.close()


async def test_an_exception_in_the_relay_still_leaves_a_stop() -> None:
    blue = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    blue.bind(("127.0.0.1", 0))
    blue.setblocking(False)
    cfg = RelayConfig(vision_port=random_multicast_port(), referee_port=random_multicast_port(),
                      pub_endpoint="tcp://127.0.0.1:0", sub_endpoint="tcp://127.0.0.1:0",
                      sim_blue_port=blue.getsockname()[1], sim_yellow_port=free_udp_port(),
                      sim_control_port=free_udp_port(), stats_interval_s=0.05)
    relay = Relay(cfg)
    boom = asyncio.Event()
    real_stats = relay.stats

    def stats(now: float | None = None) -> touchline_pb2.RelayStats:
        if boom.is_set():
            raise RuntimeError("a bug in the stats loop")
        return real_stats(now)
    relay.stats = stats  # type: ignore[method-assign]
    task = asyncio.create_task(relay.run())
    await asyncio.wait_for(relay.ready.wait(), 5)
    ctx = zmq.asyncio.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    pub.connect(relay.sub_address)
    try:
        deadline = time.monotonic() + 5
        while not any(s > 0 for d in _drain(blue) for s in _speeds(d).values()):
            assert time.monotonic() < deadline, "the relay never drove robot 3"
            await pub.send_multipart(_moving(3))
            await asyncio.sleep(0.02)
        boom.set()
        with pytest.raises(RuntimeError, match="a bug in the stats loop"):
            await asyncio.wait_for(task, 5)
        last: dict[int, float] = {}
        for d in _drain(blue):
            last.update(_speeds(d))
        assert last == {3: 0.0}
    finally:
        pub.close()
        ctx.term()
        blue.close()


def _udp() -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.setblocking(False)
    return s


def _command(team: int, rid: int) -> touchline_pb2.RobotCommand:
    return touchline_pb2.RobotCommand(team=team, id=rid, forward_mps=1.2, left_mps=-0.3,
                                      angular_radps=0.5, kick_speed_mps=3.0,
                                      dribbler_rpm=2000.0)


BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW


def _decode(output: str, team: int | None, data: bytes) -> dict[tuple[int, int], tuple[float, ...]]:
    """Every robot in one output datagram: (team, id) -> what would make it move or kick."""
    if output == "sim":
        assert team is not None
        return {(team, c.id): (c.move_command.local_velocity.forward,
                               c.move_command.local_velocity.left,
                               c.move_command.local_velocity.angular, c.kick_speed,
                               c.dribbler_speed)
                for c in rc_pb.RobotControl.FromString(data).robot_commands}
    if output == "grsim":
        gc = grsim_packet_pb2.grSim_Packet.FromString(data).commands
        t = YELLOW if gc.isteamyellow else BLUE
        return {(t, c.id): (c.veltangent, c.velnormal, c.velangular, c.kickspeedx, c.kickspeedz,
                            float(c.spinner))
                for c in gc.robot_commands}
    # robot box: 13 bytes, the robot number then speeds, dribbler, kicker, charge, ...
    assert len(data) == 13 and data[0] == 1
    return {(BLUE, data[1]): tuple(float(b) for b in data[2:])}


@pytest.mark.parametrize("output", ["sim", "grsim", "robot-box"])
async def test_the_last_word_reaches_every_robot_on_every_output(output: str) -> None:
    """The stop goes out on whichever output the relay drives: both teams of the simulation
    protocol (two ports), both teams of grSim (one port, a packet per team), the robot box
    (one datagram per robot, our team only); kick and dribbler are off in it as well."""
    blue, yellow, control, box = _udp(), _udp(), _udp(), _udp()
    port = {s: s.getsockname()[1] for s in (blue, yellow, control, box)}
    cfg = RelayConfig(vision_port=random_multicast_port(), referee_port=random_multicast_port(),
                      pub_endpoint="tcp://127.0.0.1:0", sub_endpoint="tcp://127.0.0.1:0",
                      output=output, sim_blue_port=port[blue], sim_yellow_port=port[yellow],
                      sim_control_port=port[control], grsim_port=port[blue],
                      # the robot status ports of its own (grSim's 30011/30012 may be taken
                      # by a station running beside the tests: "Address already in use")
                      grsim_status_host="127.0.0.1", grsim_status_blue_port=0,
                      grsim_status_yellow_port=0,
                      robot_box_port=port[box], hold_time_s=30.0, command_timeout_s=1.0)
    robots = ([(BLUE, 2), (BLUE, 4)] if output == "robot-box"
              else [(BLUE, 2), (YELLOW, 4), (YELLOW, 7)])
    readers: list[tuple[socket.socket, int | None]] = (
        [(box, None)] if output == "robot-box" else [(blue, None)] if output == "grsim"
        else [(blue, BLUE), (yellow, YELLOW)])

    def received() -> list[dict[tuple[int, int], tuple[float, ...]]]:
        return [_decode(output, team, d) for sock, team in readers for d in _drain(sock)]

    relay = Relay(cfg)
    task = asyncio.create_task(relay.run())
    ctx = zmq.asyncio.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    try:
        # ready, or the relay's own error (not a timeout hiding it)
        ready = asyncio.ensure_future(relay.ready.wait())
        await asyncio.wait([ready, task], timeout=5, return_when=asyncio.FIRST_COMPLETED)
        ready.cancel()
        if task.done():
            task.result()
        assert relay.ready.is_set(), "the relay did not start within 5 s"
        pub.connect(relay.sub_address)
        body = touchline_pb2.RobotCommandSet(
            commands=[_command(t, i) for t, i in robots]).SerializeToString()
        moving: set[tuple[int, int]] = set()
        deadline = time.monotonic() + 5
        while moving != set(robots):
            assert time.monotonic() < deadline, f"the relay drove only {moving}"
            await pub.send_multipart([b"commands", body])
            await asyncio.sleep(0.02)
            for got in received():
                moving |= {k for k, v in got.items() if all(x != 0 for x in v[:3])}
        relay.stop()
        await asyncio.wait_for(task, 5)
        last: dict[tuple[int, int], tuple[float, ...]] = {}
        for got in received():
            last.update(got)
        assert set(last) == set(robots)
        assert all(not any(v) for v in last.values()), f"the last datagrams were not a stop: {last}"
    finally:
        if not task.done():
            relay.stop()
            await asyncio.wait_for(task, 5)
        pub.close()
        ctx.term()
        for s in (blue, yellow, control, box):
            s.close()
