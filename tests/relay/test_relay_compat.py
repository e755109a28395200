"""Compat mode: this test plays the seed strategy-bridge against the relay's LARCmaCS sockets."""

from __future__ import annotations

import asyncio
import json
import time

import numpy as np
import zmq
import zmq.asyncio

from sslpb import ssl_gc_referee_message_pb2, ssl_simulation_robot_control_pb2
from tests.ports import free_udp_port
from tests.relay.conftest import (
    Harness,
    drain_udp,
    recv_udp,
    running_relay,
    subscribed,
)
from tests.relay.test_relay_codecs import make_detection_wrapper, make_referee
from tests.waiting import until

Ref = ssl_gc_referee_message_pb2.Referee


async def _send_until_received(h: Harness, bridge: zmq.asyncio.Socket,
                               m: np.ndarray) -> float:
    """Sends the matrix until the relay has one (a slow joiner: the bridge repeats it every
    cycle anyway); returns the deadline (3 s) for what the test waits for next."""
    counter = h.relay.streams["compat_commands"]
    deadline = time.monotonic() + 3.0
    while counter.packets == 0:
        assert time.monotonic() < deadline, "relay never received the matrix"
        await bridge.send(m.tobytes())
        await asyncio.sleep(0.02)
    return deadline


async def test_compat_mode_like_the_seed_strategy_bridge() -> None:
    ctx = zmq.asyncio.Context()
    bridge = ctx.socket(zmq.PUB)  # stands in for the strategy-bridge's tcp://*:5667
    bridge.setsockopt(zmq.LINGER, 0)
    port = free_udp_port()
    bridge.bind(f"tcp://127.0.0.1:{port}")
    try:
        async with running_relay(compat=True, compat_commands=f"tcp://127.0.0.1:{port}") as h:
            # --- vision: raw datagram, one frame, no topic
            vsub = ctx.socket(zmq.SUB)
            vsub.setsockopt(zmq.LINGER, 0)
            vsub.setsockopt(zmq.SUBSCRIBE, b"")
            vsub.connect(h.relay.compat_vision_address)
            probe = make_detection_wrapper(0)
            first = await subscribed(vsub, lambda: h.send_vision(probe))
            assert first == [probe]
            frame = make_detection_wrapper(77, camera=3)
            h.send_vision(frame)
            while True:
                msg = await asyncio.wait_for(vsub.recv_multipart(), 2.0)
                assert len(msg) == 1
                if msg[0] == frame:
                    break

            # --- referee JSON
            rsub = ctx.socket(zmq.SUB)
            rsub.setsockopt(zmq.LINGER, 0)
            rsub.setsockopt(zmq.SUBSCRIBE, b"")
            rsub.connect(h.relay.compat_referee_address)
            halt = make_referee(Ref.HALT, 1)
            msg = await subscribed(rsub, lambda: h.send_referee(halt))
            assert len(msg) == 1
            assert json.loads(msg[0]) == {"state": 0, "team": 0, "is_left": 1}

            async def next_json(data: bytes) -> dict[str, int]:
                h.send_referee(data)
                while True:
                    (raw,) = await asyncio.wait_for(rsub.recv_multipart(), 2.0)
                    out: dict[str, int] = json.loads(raw)
                    if out != {"state": 0, "team": 0, "is_left": 1}:
                        return out

            kick = make_referee(Ref.PREPARE_KICKOFF_BLUE, 2, blue_positive=True)
            assert await next_json(kick) == {"state": 5, "team": 1, "is_left": 0}
            start = make_referee(Ref.NORMAL_START, 3, blue_positive=True)
            assert await next_json(start) == {"state": 6, "team": 1, "is_left": 0}
            free = make_referee(Ref.DIRECT_FREE_YELLOW, 4)
            assert await next_json(free) == {"state": 9, "team": 2, "is_left": 1}

            # --- commands: 32x13 float64 matrix, row 3 valid
            m = np.zeros((32, 13), dtype=np.float64)
            m[3, :12] = [1, 40, -20, 25, 0, 1, 0, 8, 1, 3, 1, 0]
            await _send_until_received(h, bridge, m)
            data, _ = await recv_udp(h.sim_blue)
            rc = ssl_simulation_robot_control_pb2.RobotControl.FromString(data).robot_commands
            r = next(c for c in rc if c.id == 3)
            lv = r.move_command.local_velocity
            assert (lv.forward, lv.left, lv.angular) == (2.0, -1.0, 5.0)
            assert (r.kick_speed, r.kick_angle, r.dribbler_speed) == (4.0, 0.0, 3000.0)

            # --- a wrong-size matrix is an error, not fatal
            counter = h.relay.streams["compat_commands"]
            before = counter.errors
            await bridge.send(b"\x00" * 100)
            await until(lambda: counter.errors == before + 1, what="size error")
            await bridge.send(m.tobytes())
            packets = counter.packets
            await until(lambda: counter.packets > packets, what="relay still alive")
    finally:
        ctx.destroy(linger=0)


async def test_the_estop_latch_holds_for_the_seed_commands_and_any_path() -> None:
    """The latch is the relay's, whatever path a command takes: the seed's matrices (which
    came in through their own socket and drove through a latched stop) get zeros, and the
    output cycle zeroes anything due while latched."""
    from larcmacs_relay.codecs import TEAM_BLUE, Command
    from sslpb import touchline_pb2

    ctx = zmq.asyncio.Context()
    bridge = ctx.socket(zmq.PUB)
    bridge.setsockopt(zmq.LINGER, 0)
    port = free_udp_port()
    bridge.bind(f"tcp://127.0.0.1:{port}")
    m = np.zeros((32, 13), dtype=np.float64)
    m[3, :12] = [1, 40, -20, 25, 0, 1, 0, 8, 1, 3, 1, 0]

    def speeds(data: bytes) -> dict[int, float]:
        rc = ssl_simulation_robot_control_pb2.RobotControl.FromString(data).robot_commands
        return {c.id: abs(c.move_command.local_velocity.forward) + c.kick_speed
                + c.dribbler_speed for c in rc}
    try:
        async with running_relay(compat=True, compat_commands=f"tcp://127.0.0.1:{port}") as h:
            deadline = await _send_until_received(h, bridge, m)
            while True:  # the seed drives robot 3
                assert time.monotonic() < deadline, "the seed's matrix never drove robot 3"
                await bridge.send(m.tobytes())
                data, _ = await recv_udp(h.sim_blue)
                if speeds(data).get(3, 0.0) > 0:
                    break
            pub = h.publisher()
            press = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.PRESS, by="t")
            deadline = time.monotonic() + 3.0
            while not h.relay.estop_latched:
                assert time.monotonic() < deadline, "the relay never latched"
                await pub.send_multipart([b"estop", press.SerializeToString()])
                await asyncio.sleep(0.02)
            # the seed keeps sending its matrix: robot 3 gets zeros only
            counter = h.relay.streams["compat_commands"]
            before = counter.packets
            deadline = time.monotonic() + 3.0
            while counter.packets < before + 5:
                assert time.monotonic() < deadline, "relay never received the matrices"
                await bridge.send(m.tobytes())
                await asyncio.sleep(0.02)
            drain_udp(h.sim_blue)
            for _ in range(10):
                await bridge.send(m.tobytes())
                data, _ = await recv_udp(h.sim_blue)
                assert speeds(data).get(3, 0.0) == 0.0, speeds(data)
            # a command in the table by any other path goes out as zero while latched
            h.relay.table.update(Command(TEAM_BLUE, 9, forward_mps=1.0, dribbler_rpm=500.0),
                                 time.monotonic())
            seen9 = False
            for _ in range(10):
                data, _ = await recv_udp(h.sim_blue)
                got = speeds(data)
                seen9 = seen9 or 9 in got
                assert got.get(9, 0.0) == 0.0, got
            assert seen9, "robot 9 never got its zero"
            release = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.RELEASE)
            await pub.send_multipart([b"estop", release.SerializeToString()])
            await until(lambda: not h.relay.estop_latched, what="released")
            deadline = time.monotonic() + 3.0
            while True:  # released: the seed's commands drive again
                assert time.monotonic() < deadline, "no motion after the release"
                await bridge.send(m.tobytes())
                data, _ = await recv_udp(h.sim_blue)
                if speeds(data).get(3, 0.0) > 0:
                    break
    finally:
        ctx.destroy(linger=0)
