"""The relay forwards what simulators and robots answer ("feedback" topic) with the team it
came for and what it had sent: real UDP and ZeroMQ on loopback."""

from __future__ import annotations

import asyncio
import socket
import time

import zmq.asyncio

from sslpb import grsim_robot_status_pb2, ssl_simulation_robot_feedback_pb2, touchline_pb2
from tests.relay.conftest import recv_udp_from, running_relay
from tests.relay.test_relay_io import command_set, connect_commands
from tests.waiting import until

BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW


async def next_feedback(sub: zmq.asyncio.Socket,
                        timeout: float = 2.0) -> touchline_pb2.RobotFeedbackEnvelope:
    while True:
        topic, body = await asyncio.wait_for(sub.recv_multipart(), timeout)
        if topic == b"feedback":
            return touchline_pb2.RobotFeedbackEnvelope.FromString(body)


async def test_sim_responses_forwarded_with_team_and_sent() -> None:
    async with running_relay() as h:
        sub = h.subscriber(b"feedback")
        pub = await connect_commands(h)
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=YELLOW, id=3,
                                                                        forward_mps=0.1)))
        _, _, addr = await recv_udp_from(h.sim_yellow)
        resp = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
        resp.feedback.add(id=3, dribbler_ball_contact=True)
        data = resp.SerializeToString()
        before = time.time_ns()
        # the ZeroMQ slow joiner: answer until the subscriber hears one
        env = None
        for _ in range(100):
            h.sim_yellow.sendto(data, addr)
            if await sub.poll(30):
                env = await next_feedback(sub)
                break
        assert env is not None, "no feedback forwarded"
        assert env.kind == touchline_pb2.FEEDBACK_SIM_RESPONSE
        assert env.team == YELLOW and env.payload == data
        assert env.receive_time_ns >= before and env.sequence >= 1
        assert env.source.startswith("127.0.0.1:")
        assert [s.id for s in env.sent] == [3]
        assert env.sent[0].commands_sent >= 1 and 0 < env.sent[0].last_sent_time_ns <= \
            env.receive_time_ns
        # a blue answer on the blue port is blue; the yellow robot's sends are not in it
        h.sim_blue.sendto(data, addr)
        env = await next_feedback(sub)
        assert env.team == BLUE and list(env.sent) == []


async def test_bad_sim_response_counted_by_reason_not_forwarded() -> None:
    async with running_relay() as h:
        sub = h.subscriber(b"feedback")
        pub = await connect_commands(h)
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=0)))
        _, _, addr = await recv_udp_from(h.sim_blue)
        counter = h.relay.streams["sim_responses"]
        h.sim_blue.sendto(b"\x12\x05\x08", addr)  # feedback (2, LEN) of 5 bytes, 1 there
        h.sim_blue.sendto(b"\x12\x02\x10\x01", addr)  # RobotFeedback without its id
        await until(lambda: counter.errors == 2, what="two bad answers counted")
        assert counter.by_reason == {"truncated": 1, "missing required field": 1}
        assert not await sub.poll(200)


async def test_grsim_status_forwarded_bad_counted() -> None:
    async with running_relay(output="grsim") as h:
        ports = h.relay.grsim_status_ports
        assert set(ports) == {"blue", "yellow"} and all(ports.values())
        sub = h.subscriber(b"feedback")
        status = grsim_robot_status_pb2.Robots_Status()
        status.robots_status.add(robot_id=2, infrared=True, flat_kick=False, chip_kick=True)
        data = status.SerializeToString()
        grsim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            env = None
            for _ in range(100):
                grsim.sendto(data, ("127.0.0.1", ports["yellow"]))
                if await sub.poll(30):
                    env = await next_feedback(sub)
                    break
            assert env is not None, "no grSim status forwarded"
            assert env.kind == touchline_pb2.FEEDBACK_GRSIM_STATUS
            assert env.team == YELLOW and env.payload == data
            grsim.sendto(data, ("127.0.0.1", ports["blue"]))
            while (env := await next_feedback(sub)).team != BLUE:
                pass
            counter = h.relay.streams["grsim_status"]
            bad = b"\x0a\x02\x08\x02"  # Robot_Status with only its robot_id
            grsim.sendto(bad, ("127.0.0.1", ports["blue"]))
            grsim.sendto(b"\x0a\x09", ("127.0.0.1", ports["blue"]))  # cut short
            await until(lambda: counter.errors == 2, what="bad status counted")
            assert counter.by_reason == {"missing required field": 1, "truncated": 1}
        finally:
            grsim.close()


async def test_repeated_answers_coalesced_a_change_at_once() -> None:
    """The same bytes again and again go on as fewer envelopes whose sequence counts every
    answer; the last one held goes on by itself (the timer); a change goes on at once, after
    the held answers before it."""
    async with running_relay(feedback_interval_s=0.05) as h:
        sub = h.subscriber(b"feedback")
        pub = await connect_commands(h)
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=1)))
        _, _, addr = await recv_udp_from(h.sim_blue)

        def answer(contact: bool) -> bytes:
            resp = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
            resp.feedback.add(id=1, dribbler_ball_contact=contact)
            return resp.SerializeToString()

        no, yes = answer(False), answer(True)
        env = None
        for _ in range(100):  # the ZeroMQ slow joiner
            h.sim_blue.sendto(no, addr)
            if await sub.poll(30):
                env = await next_feedback(sub)
                break
        assert env is not None, "no feedback forwarded"
        # everything answered so far has been forwarded or is held: wait for the held one
        while env.sequence < h.relay.streams["sim_responses"].packets:
            env = await next_feedback(sub)
        first = env.sequence
        counter = h.relay.streams["sim_responses"]
        for _ in range(11):
            h.sim_blue.sendto(yes, addr)
        got = []
        while not got or got[-1].sequence < first + 11:
            got.append(await next_feedback(sub))
        assert all(e.payload == yes for e in got)
        assert got[0].sequence == first + 1  # a change: at once
        assert len(got) < 11 and got[-1].sequence == first + 11
        assert [s.id for s in got[-1].sent] == [1]
        # five more of the same, then no contact: the held ones go on first, then the change
        for _ in range(5):
            h.sim_blue.sendto(yes, addr)
        h.sim_blue.sendto(no, addr)
        got = []
        while not got or got[-1].payload != no:
            got.append(await next_feedback(sub))
        assert got[-2].payload == yes and got[-2].sequence == first + 16
        assert got[-1].sequence == first + 17
        assert counter.packets == first + 17 and counter.errors == 0


async def test_answers_read_by_the_output_cycles_with_the_kernels_arrival_time() -> None:
    """While the output cycles run, the loop does not wake for each of the simulator's answers:
    each cycle reads them before it sends, and an answer's receive time is the kernel's stamp
    of its arrival (within the simulator's sendto), not the later time it was read; once the
    output is idle, the loop watches the socket again."""
    async with running_relay(feedback_interval_s=0.0) as h:
        sub = h.subscriber(b"feedback")
        pub = await connect_commands(h)
        await pub.send_multipart(command_set(touchline_pb2.RobotCommand(team=BLUE, id=4)))
        _, _, addr = await recv_udp_from(h.sim_blue)
        await until(lambda: not h.relay._responses_watched, what="the cycles reading")
        resp = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
        resp.feedback.add(id=4, dribbler_ball_contact=True)
        data = resp.SerializeToString()
        env = None
        spans: list[tuple[int, int]] = []
        for _ in range(30):  # the ZeroMQ slow joiner: answer until the subscriber hears one
            before = time.time_ns()
            h.sim_blue.sendto(data, addr)
            spans.append((before, time.time_ns()))
            if await sub.poll(30):
                env = await next_feedback(sub)
                break
        assert env is not None, "no feedback forwarded"
        assert any(b <= env.receive_time_ns <= a for b, a in spans), (env.receive_time_ns, spans)
        assert env.sent[0].last_sent_time_ns <= env.receive_time_ns
        # the robot's command goes stale, then its zeros end: the output idles, the loop watches
        await until(lambda: h.relay._responses_watched, timeout_s=5.0,
                       what="the loop watching again")
        h.sim_blue.sendto(data, addr)
        env = await next_feedback(sub)
        assert env.payload == data
