"""The relay in-process with real multicast, UDP and ZeroMQ on loopback (random ports)."""

from __future__ import annotations

import asyncio
import math
import socket
import time
from functools import partial

import pytest
import zmq

from larcmacs_relay import RelayConfig
from larcmacs_relay.codecs import Command
from larcmacs_relay.commands import RobotState
from sslnet.multicast import open_multicast_receiver
from sslpb import (
    grsim_packet_pb2,
    ssl_gc_common_pb2,
    ssl_gc_referee_message_pb2,
    ssl_simulation_control_pb2,
    ssl_simulation_robot_control_pb2,
    ssl_simulation_robot_feedback_pb2,
    touchline_pb2,
)
from tests.relay.conftest import (
    CycleLog,
    Harness,
    drain_udp,
    recv_udp,
    recv_udp_from,
    running_relay,
    subscribed,
)
from tests.relay.test_relay_codecs import make_detection_wrapper, make_referee
from tests.waiting import until

BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW
Ref = ssl_gc_referee_message_pb2.Referee


def command_set(
    *cmds: touchline_pb2.RobotCommand, stop_all: bool = False, source_ns: int = 0
) -> list[bytes]:
    s = touchline_pb2.RobotCommandSet(
        commands=list(cmds), stop_all=stop_all, source_receive_time_ns=source_ns
    )
    return [b"commands", s.SerializeToString()]


async def connect_commands(h: Harness) -> zmq.asyncio.Socket:
    """A PUB connected to the relay SUB; returns once the relay has seen a message from it."""
    pub = h.publisher()
    probe = [b"commands", touchline_pb2.RobotCommandSet().SerializeToString()]
    counter = h.relay.streams["commands"]
    deadline = time.monotonic() + 3.0
    while counter.packets == 0:
        assert time.monotonic() < deadline, "relay SUB never received the probe"
        await pub.send_multipart(probe)
        await asyncio.sleep(0.02)
    return pub


async def probe(h: Harness, pub: zmq.asyncio.Socket) -> None:
    """An empty command set, returned from once the relay has handled it: everything the
    relay's loop had to do before it has run."""
    counter = h.relay.streams["commands"]
    seen = counter.packets
    await pub.send_multipart([b"commands", touchline_pb2.RobotCommandSet().SerializeToString()])
    await until(lambda: counter.packets > seen, what="the probe handled")


def decode_rc(data: bytes) -> ssl_simulation_robot_control_pb2.RobotControl:
    msg = ssl_simulation_robot_control_pb2.RobotControl.FromString(data)
    assert msg.IsInitialized()
    return msg


# ----------------------------------------------------------------- inputs


async def test_vision_and_referee_forwarded_unchanged_with_reuse() -> None:
    async with running_relay() as h:
        # A second program on the same port: must also get the datagrams (SO_REUSEPORT).
        other = open_multicast_receiver(h.config.vision_group, h.config.vision_port, "127.0.0.1")
        try:
            sub = h.subscriber(b"vision", b"referee")
            first = await subscribed(sub, lambda: h.send_vision(make_detection_wrapper(0)))
            assert first[0] == b"vision"
            before_ns = time.time_ns()
            frames = [make_detection_wrapper(i, camera=i % 4) for i in range(1, 21)]
            for f in frames:
                h.send_vision(f)
            got: list[touchline_pb2.Envelope] = []
            while len(got) < len(frames):
                topic, body = await asyncio.wait_for(sub.recv_multipart(), 2.0)
                env = touchline_pb2.Envelope.FromString(body)
                if topic == b"vision" and env.payload in frames:
                    got.append(env)
            after_ns = time.time_ns()
            assert [e.payload for e in got] == frames
            seqs = [e.sequence for e in got]
            assert seqs == list(range(seqs[0], seqs[0] + len(frames)))
            for e in got:
                assert e.stream == touchline_pb2.STREAM_VISION
                assert before_ns <= e.receive_time_ns <= after_ns
                assert e.source.startswith("127.0.0.1:")
            # the other receiver got them too
            loop = asyncio.get_running_loop()
            seen = set()
            while not set(frames) <= seen:
                seen.add(await asyncio.wait_for(loop.sock_recv(other, 65536), 2.0))

            ref = make_referee(Ref.STOP, 7)
            h.send_referee(ref)
            while True:
                topic, body = await asyncio.wait_for(sub.recv_multipart(), 2.0)
                if topic == b"referee":
                    break
            env = touchline_pb2.Envelope.FromString(body)
            assert env.payload == ref and env.stream == touchline_pb2.STREAM_REFEREE
            assert env.sequence == 1
        finally:
            other.close()


async def test_undecodable_datagrams_forwarded_for_the_backend_to_count() -> None:
    """The backend is the one decoder (and counts what does not parse): the relay forwards
    every datagram unchanged, refusing only what it can judge without decoding."""
    async with running_relay(max_datagram_bytes=1000) as h:
        sub = h.subscriber(b"vision")
        await subscribed(sub, lambda: h.send_vision(make_detection_wrapper(0)))
        vision = h.relay.streams["vision"]
        garbage = b"\xff\xfe garbage \x00\x07"
        h.send_vision(b"\x00" * 1001)  # oversized: dropped
        h.send_vision(garbage)  # forwarded unchanged
        good = make_detection_wrapper(42)
        h.send_vision(good)
        seen: list[bytes] = []
        while good not in seen:
            _, body = await asyncio.wait_for(sub.recv_multipart(), 2.0)
            seen.append(touchline_pb2.Envelope.FromString(body).payload)
        assert garbage in seen and all(len(p) <= 1000 for p in seen)
        await until(lambda: vision.by_reason.get("oversized") == 1, what="oversized counted")
        assert vision.errors == 1


async def test_stats_published() -> None:
    # one command, then its zeros for the hold time: cycles at the output rate throughout
    async with running_relay(hold_time_s=30.0) as h:
        sub = h.subscriber(b"stats")
        topic, body = await asyncio.wait_for(sub.recv_multipart(), 3.0)
        st = touchline_pb2.RelayStats.FromString(body)
        assert topic == b"stats" and st.output_mode == "sim"
        names = {s.name for s in st.streams}
        assert {"vision", "referee", "tracker", "commands", "output", "sim_responses"} <= names
        pub = await connect_commands(h)
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=1)))
        # wait for a stats message with a full second of cycles behind it (bounded: a slow
        # machine fails here with the rate it reached instead of hanging CI)
        deadline = time.monotonic() + 10.0
        while st.output_rate_hz < 100:
            assert time.monotonic() < deadline, \
                f"output rate stayed at {st.output_rate_hz:.0f} Hz (< 100) for 10 s"
            _, body = await asyncio.wait_for(sub.recv_multipart(), 3.0)
            st = touchline_pb2.RelayStats.FromString(body)
        assert st.output_rate_hz < 140


async def test_idle_relay_sends_nothing_and_wakes_on_a_command() -> None:
    """No robot known (or every one idle): no output cycle at all, not even empty ones; the
    next command set goes out at once."""
    async with running_relay(hold_time_s=0.05) as h:
        relay = h.relay
        pub = await connect_commands(h)  # empty command sets: nothing to send
        cycles = relay.cycles

        def asleep() -> bool:
            """The relay's own schedule: no output timer armed, no cycle due (it never wakes
            by itself until a command comes)."""
            return relay._timer is None and not math.isfinite(relay._next_cycle)

        # a round trip through the relay's command path after the first sets: had it cycled
        # idle, a timer would be armed or a cycle counted by now (no sleep and hope)
        await probe(h, pub)
        assert asleep() and cycles.total == 0 and drain_udp(h.sim_blue) == 0
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=4)))
        data, _ = await recv_udp(h.sim_blue)
        assert [r.id for r in decode_rc(data).robot_commands] == [4]
        # command timeout (0.1 s) then zeros for the hold time (0.05 s), then idle: silent
        await until(lambda: relay.table.count(RobotState.IDLE) == 1, what="robot idle")
        await until(asleep, what="no output timer once every robot is idle")
        drain_udp(h.sim_blue)
        total = cycles.total
        await probe(h, pub)
        assert asleep() and cycles.total == total and drain_udp(h.sim_blue) == 0


async def test_a_command_set_moves_the_output_timer_with_the_schedule() -> None:
    """A command set goes out at once and re-phases the repeats a period later: the one
    output timer moves there, it does not stay at the old time to wake the loop for
    nothing."""
    async with running_relay(output_rate_hz=100.0) as h:
        pub = await connect_commands(h)
        relay = h.relay
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=4)))
        await recv_udp(h.sim_blue)
        first = relay._last_cycle
        await until(lambda: time.monotonic() > first + 0.002, what="2 ms after the cycle")
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=4,
                                                                        forward_mps=0.5)))
        while True:  # the new command's datagram (a repeat of the old one may come first)
            data, _ = await recv_udp(h.sim_blue)
            if decode_rc(data).robot_commands[0].move_command.local_velocity.forward > 0.4:
                break
        timer = relay._timer
        assert timer is not None and math.isfinite(relay._next_cycle)
        loop = asyncio.get_running_loop()
        due = loop.time() + (relay._next_cycle - time.monotonic())
        assert abs(timer.when() - due) <= 0.0006


# ----------------------------------------------------------------- commands, sim mode


def drain_datagrams(sock: socket.socket, into: list[bytes]) -> None:
    """Every datagram waiting on ``sock`` appended to ``into`` (non-blocking)."""
    while True:
        try:
            into.append(sock.recv(65536))
        except BlockingIOError:
            return


async def test_commands_repeated_then_stale_then_silent() -> None:
    """Every output cycle sends the robot's latest command while it is younger than the
    command timeout, zero velocity from the first cycle past it (counted once in
    stale_stops) for the hold time, then nothing at all (no cycle left armed).

    Judged on the relay's own clock: each command's arrival and each cycle's ``now`` are
    recorded and every datagram is checked against what that cycle had to send. The relay
    runs in this test's process, so a loaded machine that stops the process for 0.1 s
    delays the relay's cycles and the test's commands alike (a command may even go stale
    between two of them, as it must): wall-clock bounds on the test's side failed then.
    The commands are paced by the relay's cycles (two repeats after each one), not by a
    sleep."""
    hold_s = 0.3
    async with running_relay(hold_time_s=hold_s) as h:
        relay, cfg = h.relay, h.config
        pub = await connect_commands(h)
        cmd = touchline_pb2.RobotCommand(
            team=BLUE,
            id=2,
            forward_mps=1.25,
            left_mps=-0.5,
            angular_radps=0.75,
            kick_speed_mps=3.0,
            chip=True,
            dribbler_rpm=500.0,
        )
        # what happened, in order, on the relay's clock: ("command", arrival) or
        # ("cycle", now, the next cycle it planned: inf when nothing was due)
        events: list[tuple[str, float, float]] = []
        update_all, run_cycle = relay.table.update_all, relay._run_cycle

        def recording_update_all(commands: list[Command], now: float) -> None:
            update_all(commands, now)
            if commands:
                events.append(("command", now, math.nan))

        def recording_run_cycle(now: float) -> None:
            run_cycle(now)
            events.append(("cycle", now, relay._next_cycle))

        relay.table.update_all = recording_update_all  # type: ignore[method-assign]
        relay._run_cycle = recording_run_cycle  # type: ignore[method-assign]
        datagrams: list[bytes] = []

        def three_cycles_since(mark: int) -> bool:
            drain_datagrams(h.sim_blue, datagrams)
            return sum(1 for e in events[mark:] if e[0] == "cycle") >= 3

        n_commands = 40
        for _ in range(n_commands):
            mark = len(events)
            await pub.send_multipart(command_set(cmd))
            # its arrival, the cycle it kicks at once and two repeats of it
            await until(partial(three_cycles_since, mark), what="three cycles after a command")
        await until(lambda: relay.table.count(RobotState.IDLE) == 1, timeout_s=5.0,
                       what="the robot idle after its stop was held")
        # idle: no cycle is armed, so nothing can be sent any more (without a new command)
        assert relay._timer is None and relay._next_cycle == math.inf
        drain_datagrams(h.sim_blue, datagrams)
        table_stale_stops = relay.table.stale_stops

        # The rule, replayed over the recorded events: what each cycle had to send.
        period = 1.0 / cfg.output_rate_hz
        arrival = zero_since = math.nan
        state = "none"
        expected: list[str] = []  # per datagram: "command" or "zero"
        stale_count = 0
        for kind, t, next_cycle in events:
            if kind == "command":
                state, arrival = "active", t
                continue
            if state == "active" and t - arrival > cfg.command_timeout_s:
                state, zero_since = "zero", t
                stale_count += 1
            if state == "zero" and t - zero_since >= hold_s:
                state = "idle"
            if state in ("active", "zero"):
                expected.append("command" if state == "active" else "zero")
                # cycles keep coming: the next one planned at most a period later
                assert next_cycle <= t + period + 0.0005, (t, next_cycle)
            else:
                assert next_cycle == math.inf  # nothing due: no cycle armed
        assert state == "idle"
        sent = []
        for data in datagrams:
            rc = decode_rc(data).robot_commands
            assert len(rc) == 1 and rc[0].id == 2
            r = rc[0]
            lv = r.move_command.local_velocity
            if (lv.forward, lv.left, lv.angular) == (1.25, -0.5, 0.75):
                assert (r.kick_speed, r.kick_angle, r.dribbler_speed) == (3.0, 45.0, 500.0)
                sent.append("command")
            else:
                assert (lv.forward, lv.left, lv.angular, r.kick_speed) == (0, 0, 0, 0)
                sent.append("zero")
        assert sent == expected
        # repeated: each command went out at once (its own cycle) and the timer's cycles
        # followed (two at least before the next command), sending it again unless it had
        # gone stale; the last one did go stale
        cycles = sum(1 for e in events if e[0] == "cycle")
        assert cycles >= 3 * n_commands
        assert sent.count("command") >= n_commands and expected[-1] == "zero"
        assert stale_count >= 1 and table_stale_stops == stale_count
        stats = relay.stats()
        assert stats.stale_stops == stale_count and stats.active_robots == 0


async def test_stop_all_zeroes_every_robot_and_latency() -> None:
    async with running_relay(command_timeout_s=1.0) as h:
        pub = await connect_commands(h)
        cmds = [
            touchline_pb2.RobotCommand(team=BLUE, id=1, forward_mps=1.0),
            touchline_pb2.RobotCommand(team=YELLOW, id=4, left_mps=1.0),
        ]
        sent_at = time.monotonic()  # the relay takes them later: they are fresh until 1 s after
        await pub.send_multipart(command_set(*cmds, source_ns=time.time_ns() - 5_000_000))

        def moving(sock_data: bytes) -> bool:
            lv = decode_rc(sock_data).robot_commands[0].move_command.local_velocity
            return lv.forward != 0 or lv.left != 0

        data, _ = await recv_udp(h.sim_blue)
        assert moving(data)
        data, _ = await recv_udp(h.sim_yellow)
        assert moving(data)
        stats = h.relay.stats()
        assert stats.active_robots == 2
        assert 5.0 <= stats.command_latency_ms < 500.0

        cycles = CycleLog(h.relay)
        await pub.send_multipart(command_set(stop_all=True))
        await until(lambda: h.relay.stats().stale_robots == 2, what="both zeroed")
        t_stop = time.monotonic()
        drain_udp(h.sim_blue)
        drain_udp(h.sim_yellow)
        for sock in (h.sim_blue, h.sim_yellow):
            data, _ = await recv_udp(sock)
            assert not moving(data)
        # still zero 0.2 s later although the old commands would not be stale yet: every
        # cycle the relay ran after the stop, by its own clock, until they would be
        fresh_until = sent_at + 1.0
        await until(lambda: any(t >= t_stop + 0.2 for t, _ in cycles.cycles),
                       what="the relay's cycles 0.2 s past the stop")
        window = [(t, sent) for t, sent in cycles.after(t_stop) if t < fresh_until]
        assert any(t >= t_stop + 0.2 for t, _ in window), \
            "no cycle 0.2-1 s after the commands: the relay's loop was starved"
        assert {c.id for _, sent in window for c in sent} == {1, 4}
        assert all(c.is_zero for _, sent in window for c in sent), \
            [(round(t - t_stop, 3), sent) for t, sent in window if not all(c.is_zero for c in sent)]
        # a newer non-stop command revives the robot
        await pub.send_multipart(command_set(cmds[0]))

        async def blue_moving() -> None:
            while not moving((await recv_udp(h.sim_blue))[0]):
                pass

        await asyncio.wait_for(blue_moving(), 2.0)


async def test_bad_commands_rejected_and_counted() -> None:
    async with running_relay() as h:
        pub = await connect_commands(h)
        counter = h.relay.streams["commands"]
        before = counter.errors
        await pub.send_multipart(
            command_set(
                touchline_pb2.RobotCommand(team=BLUE, id=20, forward_mps=1.0),
                touchline_pb2.RobotCommand(team=BLUE, id=3, forward_mps=math.nan),
                touchline_pb2.RobotCommand(team=touchline_pb2.TEAM_UNSPECIFIED, id=3),
            )
        )
        await pub.send_multipart([b"commands", b"\xff\xff\xff"])
        await until(lambda: counter.errors >= before + 4, what="four command errors")
        assert h.relay.table.known == 0
        # nothing is sent for rejected commands
        with pytest.raises(TimeoutError):
            await recv_udp(h.sim_blue, timeout=0.2)


async def test_messages_of_one_or_three_parts_are_counted_and_those_around_them_whole() -> None:
    """A message on the command SUB must be [topic, body]: one of one part or of three is an
    error ("bad frames") and is not used; the messages before and after it are read whole and
    in order (a part left over would be taken for the next message's topic)."""
    async with running_relay() as h:
        pub = await connect_commands(h)
        counter = h.relay.streams["commands"]
        packets = counter.packets

        def cmd(v: float) -> list[bytes]:
            return command_set(touchline_pb2.RobotCommand(team=BLUE, id=1, forward_mps=v))

        await pub.send_multipart(cmd(0.125))
        await pub.send_multipart([b"commands"])
        await pub.send_multipart(cmd(0.25))
        await pub.send_multipart([b"commands", cmd(9.0)[1], cmd(8.0)[1]])
        await pub.send_multipart(cmd(0.375))
        await until(lambda: counter.packets >= packets + 3, what="three command sets")
        await until(lambda: counter.by_reason.get("bad frames", 0) >= 2, what="two errors")
        speeds = []
        while not speeds or speeds[-1] != 0.375:
            data, _ = await recv_udp(h.sim_blue)
            speeds.append(ssl_simulation_robot_control_pb2.RobotControl.FromString(data)
                          .robot_commands[0].move_command.local_velocity.forward)
        # in order (one cycle may cover several sets: a speed can be skipped, never undone)
        assert set(speeds) <= {0.125, 0.25, 0.375} and speeds == sorted(speeds)
        assert counter.packets == packets + 3
        assert counter.by_reason == {"bad frames": 2}


async def test_sim_topic_forwarded_and_responses_counted() -> None:
    async with running_relay() as h:
        pub = await connect_commands(h)
        cmd = ssl_simulation_control_pb2.SimulatorCommand()
        cmd.control.teleport_ball.x = 1.0
        body = cmd.SerializeToString()
        await pub.send_multipart([b"sim", body])
        data, _ = await recv_udp(h.sim_control)
        assert data == body
        # answer with an error to the sender's address, like a simulator
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=0)))
        _, _, addr = await recv_udp_from(h.sim_blue)
        resp = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
        e = resp.errors.add()
        e.code, e.message = "E1", "robot 0 unknown"
        h.sim_blue.sendto(resp.SerializeToString(), addr)
        counter = h.relay.streams["sim_responses"]
        await until(lambda: counter.errors == 1, what="sim response error")
        assert "E1" in counter.last_error and counter.packets == 1


# ----------------------------------------------------------------- grsim and robot-box


async def test_grsim_mode_commands_and_teleport() -> None:
    async with running_relay(output="grsim") as h:
        pub = await connect_commands(h)
        await pub.send_multipart(
            command_set(
                touchline_pb2.RobotCommand(
                    team=YELLOW,
                    id=6,
                    forward_mps=0.5,
                    left_mps=0.25,
                    angular_radps=-1.0,
                    kick_speed_mps=2.0,
                    dribbler_rpm=300.0,
                )
            )
        )
        data, _ = await recv_udp(h.sim_blue)  # grsim_port is the sim_blue socket here
        pkt = grsim_packet_pb2.grSim_Packet.FromString(data)
        assert pkt.IsInitialized() and pkt.HasField("commands")
        gc = pkt.commands
        assert gc.isteamyellow and abs(gc.timestamp - time.time()) < 5
        r = gc.robot_commands[0]
        assert (r.id, r.veltangent, r.velnormal, r.velangular) == (6, 0.5, 0.25, -1.0)
        assert (r.kickspeedx, r.kickspeedz, r.spinner, r.wheelsspeed) == (2.0, 0.0, True, False)

        cmd = ssl_simulation_control_pb2.SimulatorCommand()
        tr = cmd.control.teleport_robot.add()
        tr.id.id, tr.id.team = 2, ssl_gc_common_pb2.BLUE
        tr.x, tr.y, tr.orientation, tr.present = 1.5, -1.0, -math.pi, True
        await pub.send_multipart([b"sim", cmd.SerializeToString()])
        while True:
            data, _ = await recv_udp(h.sim_blue)
            pkt = grsim_packet_pb2.grSim_Packet.FromString(data)
            if pkt.HasField("replacement"):
                break
        assert pkt.IsInitialized()
        rr = pkt.replacement.robots[0]
        assert (rr.id, rr.yellowteam, rr.x, rr.y, rr.turnon) == (2, False, 1.5, -1.0, True)
        assert rr.dir == pytest.approx(-180.0, abs=1e-4)


async def test_robot_box_mode_datagram() -> None:
    async with running_relay(output="robot-box") as h:
        pub = await connect_commands(h)
        await pub.send_multipart(
            command_set(
                touchline_pb2.RobotCommand(
                    team=BLUE,
                    id=9,
                    forward_mps=-1.0,
                    left_mps=0.5,
                    angular_radps=-2.0,
                    kick_speed_mps=2.0,
                    chip=True,
                )
            )
        )
        data, _ = await recv_udp(h.out_box)
        expected = bytes([1, 9, 10, 256 - 20, 10, 0, 4, 1, 0, 0, 0, 1, 0])
        assert data == expected


async def test_robot_box_mode_never_drives_a_robot_for_the_other_team() -> None:
    """A robot-box datagram has no team field: a command for yellow 3 would drive our robot
    3. The relay drops it, counts it ("other team") and sends nothing for it."""
    async with running_relay(output="robot-box", our_team="blue") as h:
        pub = await connect_commands(h)
        commands = h.relay.streams["commands"]
        await pub.send_multipart(command_set(
            touchline_pb2.RobotCommand(team=YELLOW, id=3, forward_mps=1.0)))
        await until(lambda: commands.by_reason.get("other team") == 1, what="dropped")
        assert "yellow 3 dropped" in commands.last_error
        # only our robot's datagram ever arrives, and it is robot 4's
        await pub.send_multipart(command_set(
            touchline_pb2.RobotCommand(team=BLUE, id=4, forward_mps=1.0)))
        data, _ = await recv_udp(h.out_box)
        assert data[1] == 4
        drain_udp(h.out_box)
        assert h.relay.table.known == 1


async def test_tracker_input_when_enabled() -> None:
    from tests.ports import random_multicast_port

    async with running_relay(tracker_enabled=True, tracker_port=random_multicast_port()) as h:
        sub = h.subscriber(b"tracker")
        payload = b"\x0a\x03abc\x12\x02ts"  # wire-valid: uuid "abc", source_name "ts"
        dest = (h.config.tracker_group, h.config.tracker_port)
        topic, body = await subscribed(sub, lambda: h.sender.sendto(payload, dest))
        env = touchline_pb2.Envelope.FromString(body)
        assert topic == b"tracker" and env.stream == touchline_pb2.STREAM_TRACKER
        assert env.payload == payload
        h.sender.sendto(b"\x0a\xff", dest)  # truncated length-delimited field
        counter = h.relay.streams["tracker"]
        await until(lambda: counter.errors == 1, what="tracker error")


async def test_burst_is_forwarded_completely_in_order() -> None:
    async with running_relay() as h:
        sub = h.subscriber(b"vision")
        await subscribed(sub, lambda: h.send_vision(make_detection_wrapper(0)))
        frames = [make_detection_wrapper(1000 + i, camera=i % 8) for i in range(600)]
        for f in frames:  # > MAX_BATCH back to back
            h.send_vision(f)
        got: list[bytes] = []
        while len(got) < len(frames):
            _, body = await asyncio.wait_for(sub.recv_multipart(), 2.0)
            payload = touchline_pb2.Envelope.FromString(body).payload
            if payload in frames:
                got.append(payload)
        assert got == frames


# ----------------------------------------------------------------- internal referee out


async def test_referee_out_is_multicast_and_comes_back_as_referee_input() -> None:
    async with running_relay() as h:
        listener = open_multicast_receiver(h.config.referee_group, h.config.referee_port,
                                           "127.0.0.1")
        try:
            sub = h.subscriber(b"referee")
            pub = h.publisher()
            ref = make_referee(Ref.FORCE_START, 3)
            first = await subscribed(sub, lambda: asyncio.ensure_future(
                pub.send_multipart([b"referee-out", ref])))
            assert first[0] == b"referee"
            assert touchline_pb2.Envelope.FromString(first[1]).payload == ref
            loop = asyncio.get_running_loop()
            assert await asyncio.wait_for(loop.sock_recv(listener, 65536), 2.0) == ref
            # an incomplete Referee is refused, counted, and not sent
            sent = h.relay.streams["referee_out"].packets
            await pub.send_multipart([b"referee-out", b"\x08\x01"])
            await until(lambda: h.relay.streams["referee_out"].errors == 1,
                           what="referee-out error")
            assert h.relay.streams["referee_out"].packets == sent
        finally:
            listener.close()


async def test_referee_out_is_off_on_a_non_loopback_interface_unless_asked() -> None:
    cfg = RelayConfig(interface="192.0.2.10")
    assert not cfg.referee_out_enabled
    assert RelayConfig(interface="192.0.2.10", referee_out=True).referee_out_enabled
    assert RelayConfig().referee_out_enabled


async def test_datagram_errors_are_counted_by_reason_and_published() -> None:
    """Every stream counts its refused datagrams by reason (sslnet.streams), not only the
    last error, and RelayStats carries the counts to the backend's health. (What does not
    decode is forwarded and counted by the backend:
    tests/backend/processors/test_ingest_reasons.py.)"""
    async with running_relay() as h:
        sub = h.subscriber(b"stats")
        vision = h.relay.streams["vision"]
        good = make_detection_wrapper(7)
        h.send_vision(good[: len(good) // 2])  # cut short: forwarded, the backend counts it
        h.send_vision(b"")  # nothing in it
        h.send_vision(good + b"\x00" * 40000)  # larger than the stream's limit
        await until(lambda: vision.errors >= 2, what="two errors")
        await until(lambda: vision.packets >= 1, what="the cut one forwarded")
        assert vision.by_reason == {"no content": 1, "oversized": 1}
        h.send_referee(b"")
        await until(lambda: h.relay.streams["referee"].errors == 1, what="referee error")
        assert h.relay.streams["referee"].by_reason == {"no content": 1}
        deadline = time.monotonic() + 5
        while True:
            assert time.monotonic() < deadline, "no stats with the reasons"
            _, body = await asyncio.wait_for(sub.recv_multipart(), 3.0)
            st = touchline_pb2.RelayStats.FromString(body)
            by = {s.name: dict(s.errors_by_reason) for s in st.streams}
            if by.get("vision", {}).get("oversized") == 1 and by.get("referee"):
                break
        assert by["referee"] == {"no content": 1}


async def test_the_estop_is_latched_in_the_relay_until_an_explicit_release() -> None:
    async with running_relay() as h:
        pub = await connect_commands(h)
        go = command_set(touchline_pb2.RobotCommand(team=BLUE, id=1, forward_mps=1.0))

        def speed(data: bytes) -> float:
            lv = decode_rc(data).robot_commands[0].move_command.local_velocity
            return abs(lv.forward)
        await pub.send_multipart(go)
        data, _ = await recv_udp(h.sim_blue)
        assert speed(data) > 0
        press = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.PRESS, by="t")
        await pub.send_multipart([b"estop", press.SerializeToString()])
        await until(lambda: h.relay.estop_latched, what="latched")
        assert h.relay.stats().estop_latched and h.relay.stats().estop_by == "t"
        # whatever arrives now, robot 1 gets zeros
        for _ in range(5):
            await pub.send_multipart(go)
            await asyncio.sleep(0.02)
        drain_udp(h.sim_blue)
        for _ in range(5):
            data, _ = await recv_udp(h.sim_blue)
            assert speed(data) == 0
        release = touchline_pb2.EmergencyStop(action=touchline_pb2.EmergencyStop.RELEASE)
        await pub.send_multipart([b"estop", release.SerializeToString()])
        await until(lambda: not h.relay.estop_latched, what="released")
        await pub.send_multipart(go)

        async def moving() -> bool:
            data, _ = await recv_udp(h.sim_blue)
            return speed(data) > 0
        deadline = time.monotonic() + 3
        while not await moving():
            assert time.monotonic() < deadline, "no motion after the release"
            await pub.send_multipart(go)
