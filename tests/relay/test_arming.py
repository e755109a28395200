"""--require-arming: a relay driving real robots (or an external simulator) starts disarmed and
sends nothing but stops until the backend arms it; an e-stop press disarms it."""

from __future__ import annotations

import asyncio
import math
import time

import zmq

from larcmacs_relay.__main__ import build_parser, config_from_args
from larcmacs_relay.commands import RobotState
from sslpb import ssl_simulation_control_pb2, touchline_pb2
from tests.relay.conftest import (
    CycleLog,
    Harness,
    drain_udp,
    recv_udp,
    running_relay,
    subscribed,
)
from tests.relay.test_relay_codecs import make_detection_wrapper
from tests.relay.test_relay_io import command_set
from tests.waiting import until

BLUE = touchline_pb2.TEAM_BLUE
GO = command_set(touchline_pb2.RobotCommand(team=BLUE, id=3, forward_mps=1.0))


def arming(armed: bool, by: str = "t") -> list[bytes]:
    return [b"arming", touchline_pb2.Arming(armed=armed, time_ns=time.time_ns(),
                                             by=by).SerializeToString()]


async def connect(h: Harness) -> zmq.asyncio.Socket:
    """A PUB to the relay's SUB; returns once a (dropped) command set has reached it."""
    pub = h.publisher()
    counter = h.relay.streams["commands"]
    deadline = time.monotonic() + 3.0
    while counter.packets + counter.errors == 0:
        assert time.monotonic() < deadline, "relay SUB never received the probe"
        await pub.send_multipart(command_set())
        await asyncio.sleep(0.02)
    return pub


async def handled(h: Harness, pub: zmq.asyncio.Socket, frames: list[bytes]) -> None:
    """Sends a command set; returns once the relay has taken it (sent, or dropped and
    counted): whatever it makes the relay send at once is in the box by then."""
    counter = h.relay.streams["commands"]
    seen = counter.packets + counter.errors
    await pub.send_multipart(frames)
    await until(lambda: counter.packets + counter.errors > seen, what="the set taken")


def asleep(h: Harness) -> bool:
    """The relay's own schedule: no output timer armed, no cycle due."""
    return h.relay._timer is None and not math.isfinite(h.relay._next_cycle)


def in_box(h: Harness) -> list[bytes]:
    out = []
    while True:
        try:
            out.append(h.out_box.recv(64))
        except BlockingIOError:
            return out


async def sends_nothing(h: Harness, pub: zmq.asyncio.Socket) -> list[bytes]:
    """GO taken by the relay, which stays asleep: what reached the box (nothing, unless
    disarming failed). No waiting for time to pass: a relay that sends anything for GO does
    so when it takes it, or arms its timer for it."""
    cycles = h.relay.cycles.total
    await handled(h, pub, GO)
    assert asleep(h) and h.relay.cycles.total == cycles
    return in_box(h)


def test_the_flag_sets_require_arming() -> None:
    args = build_parser().parse_args(["--require-arming", "--output", "robot-box"])
    assert config_from_args(args).require_arming
    assert not config_from_args(build_parser().parse_args([])).require_arming


async def test_disarmed_nothing_is_sent_and_the_sets_are_counted() -> None:
    async with running_relay(output="robot-box", require_arming=True) as h:
        assert not h.relay.armed
        st = h.relay.stats()
        assert st.arming_required and not st.armed
        pub = await connect(h)
        for _ in range(10):
            await handled(h, pub, GO)
        assert h.relay.streams["commands"].by_reason.get("disarmed", 0) >= 10
        assert asleep(h) and h.relay.cycles.total == 0 and in_box(h) == []
        assert h.relay.table.known == 0


async def test_armed_commands_are_sent_and_a_disarm_leaves_only_zeros() -> None:
    async with running_relay(output="robot-box", require_arming=True) as h:
        pub = await connect(h)
        await pub.send_multipart(arming(True, "op"))
        await until(lambda: h.relay.armed, what="armed")
        assert h.relay.stats().armed
        await pub.send_multipart(GO)
        data, _ = await recv_udp(h.out_box)
        assert data[1] == 3 and data[3] != 0
        await pub.send_multipart(arming(False))
        await until(lambda: not h.relay.armed, what="disarmed")
        log = CycleLog(h.relay)  # every cycle from here on, by the relay's clock
        drain_udp(h.out_box)
        for _ in range(5):
            await handled(h, pub, GO)
        await until(lambda: len(log.cycles) >= 3, what="cycles after the disarm")
        got = in_box(h)
        assert got and all(d[3] == 0 and d[2] == 0 for d in got)  # stops only
        assert all(c.is_zero for _, sent in log.cycles for c in sent), log.cycles
        assert h.relay.streams["commands"].by_reason.get("disarmed", 0) >= 5
        # the zeros last the hold time, then nothing, whatever command sets keep arriving
        # (sent every 50 ms as the backend does, until the relay's table says idle)
        deadline = time.monotonic() + h.config.hold_time_s + 5.0
        while h.relay.table.count(RobotState.IDLE) < 1 or not asleep(h):
            assert time.monotonic() < deadline, "the disarmed robot never went idle"
            await pub.send_multipart(GO)
            await pub.send_multipart(arming(False))  # the backend repeats it
            await asyncio.sleep(0.05)  # the sender's pace, not a wait for the relay
        assert all(c.is_zero for _, sent in log.cycles for c in sent)
        drain_udp(h.out_box)
        assert await sends_nothing(h, pub) == []


async def test_the_estop_disarms_and_arming_is_refused_while_latched() -> None:
    async with running_relay(output="robot-box", require_arming=True) as h:
        pub = await connect(h)
        await pub.send_multipart(arming(True))
        await until(lambda: h.relay.armed, what="armed")
        press = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.PRESS, by="t")
        await pub.send_multipart([b"estop", press.SerializeToString()])
        await until(lambda: h.relay.estop_latched, what="latched")
        assert not h.relay.armed
        await pub.send_multipart(arming(True))
        await until(lambda: h.relay.streams["commands"].by_reason.get("arming refused", 0)
                       == 1, what="refused")
        assert not h.relay.armed
        release = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.RELEASE)
        await pub.send_multipart([b"estop", release.SerializeToString()])
        await until(lambda: not h.relay.estop_latched, what="released")
        assert not h.relay.armed  # a release does not re-arm
        assert await sends_nothing(h, pub) == []


async def test_a_restarted_relay_starts_disarmed() -> None:
    async with running_relay(output="robot-box", require_arming=True) as h:
        pub = await connect(h)
        await pub.send_multipart(arming(True))
        await until(lambda: h.relay.armed, what="armed")
    async with running_relay(output="robot-box", require_arming=True) as h:
        assert not h.relay.armed and not h.relay.stats().armed
        pub = await connect(h)
        assert await sends_nothing(h, pub) == []


async def test_without_the_flag_it_is_always_armed() -> None:
    async with running_relay(output="robot-box") as h:
        st = h.relay.stats()
        assert st.armed and not st.arming_required
        pub = await connect(h)
        await pub.send_multipart(arming(False))  # ignored: nothing to arm
        await pub.send_multipart(GO)
        data, _ = await recv_udp(h.out_box)
        assert data[1] == 3 and data[3] != 0
        assert h.relay.armed


async def test_a_teleport_never_reaches_real_robots_armed_or_not() -> None:
    """Why teleports need no arming (docs/api.md): only a simulator takes them. In robot-box
    mode the backend refuses them (409) and the relay drops one that comes all the same."""
    cmd = ssl_simulation_control_pb2.SimulatorCommand()
    cmd.control.teleport_ball.x, cmd.control.teleport_ball.y = 1.0, 0.5
    async with running_relay(output="robot-box", require_arming=True) as h:
        pub = await connect(h)
        counter = h.relay.streams["sim_commands"]
        for armed in (False, True):
            await pub.send_multipart(arming(armed))
            await until(lambda a=armed: h.relay.armed == a, what=f"armed={armed}")
            before = counter.errors
            await pub.send_multipart([b"sim", cmd.SerializeToString()])
            await until(lambda b=before: counter.errors > b,
                           what="the teleport dropped and counted")
            # dropped when taken: nothing went out then, and nothing is scheduled
            assert asleep(h) and h.relay.cycles.total == 0 and in_box(h) == []
        assert counter.by_reason.get("rejected", 0) == 2


async def test_an_arming_change_is_acknowledged_by_statistics_at_once() -> None:
    """The backend's reply to an operator waits for the relay's statistics to show the
    change: they go out on the change, not on the stats timer (a minute here)."""
    async with running_relay(output="robot-box", require_arming=True,
                             stats_interval_s=60.0) as h:
        sub = h.subscriber(b"stats", b"vision")
        await subscribed(sub, lambda: h.send_vision(make_detection_wrapper(0)))
        pub = await connect(h)

        async def next_stats() -> touchline_pb2.RelayStats:
            while True:
                topic, body = await asyncio.wait_for(sub.recv_multipart(), 3.0)
                if topic == b"stats":
                    return touchline_pb2.RelayStats.FromString(body)
        await pub.send_multipart(arming(True, "op"))
        assert (await next_stats()).armed
        await pub.send_multipart(arming(True, "op"))  # the repeat: no change, no stats
        await pub.send_multipart(arming(False))
        assert not (await next_stats()).armed
