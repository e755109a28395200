"""fieldsim over real UDP on loopback: in-process server on random ports, real sockets."""

from __future__ import annotations

import asyncio
import json
import math
import random
import socket
import statistics
import time
from collections.abc import AsyncIterator, Callable

import pytest

from fieldsim.config import SimConfig
from fieldsim.protocol import ERR_INVALID_VALUE, ERR_MALFORMED, ERR_UNKNOWN_ROBOT
from fieldsim.server import FieldSim, FieldSimThread
from fieldsim.world import Team
from sslnet.multicast import loopback_multicast_ok, open_multicast_receiver
from sslpb import grsim_packet_pb2 as grsim_pb
from sslpb import ssl_gc_common_pb2 as common_pb
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_simulation_error_pb2 as error_pb
from sslpb import ssl_simulation_robot_control_pb2 as rc_pb
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb
from sslpb import ssl_vision_wrapper_pb2 as wrapper_pb

pytestmark = pytest.mark.skipif(not loopback_multicast_ok(), reason="no multicast on loopback")

GROUP = "224.5.23.2"
Packet = wrapper_pb.SSL_WrapperPacket


def random_vision_port() -> int:
    return random.SystemRandom().randint(20000, 40000)


class Station:
    """The test's side of the wire: a vision receiver and a command socket."""

    def __init__(self, sim: FieldSim, rx: socket.socket) -> None:
        self.sim = sim
        self.rx = rx
        self.tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.tx.bind(("127.0.0.1", 0))
        self.tx.setblocking(False)

    def close(self) -> None:
        self.tx.close()
        self.rx.close()

    async def packet(self, pred: Callable[[Packet], bool], timeout: float = 3.0) -> Packet:
        """The first vision packet satisfying ``pred`` (fails after ``timeout``)."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while True:
            left = deadline - loop.time()
            if left <= 0:
                raise AssertionError("no matching vision packet in time")
            try:
                data = await asyncio.wait_for(loop.sock_recv(self.rx, 65536), left)
            except TimeoutError:
                continue
            p = Packet()
            p.ParseFromString(data)
            assert p.IsInitialized()
            if pred(p):
                return p

    async def request(self, port_name: str, data: bytes, timeout: float = 2.0) -> bytes:
        loop = asyncio.get_running_loop()
        self.tx.sendto(data, ("127.0.0.1", self.sim.ports[port_name]))
        return await asyncio.wait_for(loop.sock_recv(self.tx, 65536), timeout)

    def send(self, port_name: str, data: bytes) -> None:
        self.tx.sendto(data, ("127.0.0.1", self.sim.ports[port_name]))


def robot_in(p: Packet, team: str, rid: int) -> list[object]:
    if not p.HasField("detection"):
        return []
    rs = p.detection.robots_blue if team == "blue" else p.detection.robots_yellow
    return [r for r in rs if r.robot_id == rid]


@pytest.fixture
async def station() -> AsyncIterator[Station]:
    port = random_vision_port()
    rx = open_multicast_receiver(GROUP, port, "127.0.0.1")
    cfg = SimConfig(
        vision_port=port, control_port=0, blue_port=0, yellow_port=0, grsim_port=0,
        miss_prob=0.0, seed=11,
    )
    sim = FieldSim(cfg)
    await sim.start()
    st = Station(sim, rx)
    try:
        yield st
    finally:
        await sim.stop()
        st.close()


async def test_detection_and_geometry_arrive(station: Station) -> None:
    frames: dict[int, list[Packet]] = {k: [] for k in range(4)}
    geometry: list[Packet] = []

    def collect(p: Packet) -> bool:
        if p.HasField("geometry"):
            geometry.append(p)
        if p.HasField("detection"):
            frames[p.detection.camera_id].append(p)
        return bool(geometry) and all(len(f) >= 5 for f in frames.values())

    await station.packet(collect, timeout=5.0)
    now = time.time()
    for k, fs in frames.items():
        nums = [f.detection.frame_number for f in fs]
        assert nums == sorted(nums) and len(set(nums)) == len(nums), k
        for f in fs:
            d = f.detection
            assert d.t_sent >= d.t_capture - 1e-6
            assert abs(d.t_capture - now) < 2.0
            assert f.source == wrapper_pb.SSL_SOURCE_OTHER
    g = geometry[0].geometry
    assert g.field.field_length == 9000 and len(g.calib) == 4


async def test_robot_control_moves_robot(station: Station) -> None:
    first = await station.packet(lambda p: bool(robot_in(p, "blue", 0)))
    x0 = robot_in(first, "blue", 0)[0].x  # type: ignore[attr-defined]
    msg = rc_pb.RobotControl()
    cmd = msg.robot_commands.add(id=0)
    cmd.move_command.local_velocity.forward = 1.0
    cmd.move_command.local_velocity.left = 0.0
    cmd.move_command.local_velocity.angular = 0.0
    data = msg.SerializeToString()
    reply = fb_pb.RobotControlResponse()
    reply.ParseFromString(await station.request("blue", data))
    assert not reply.errors
    assert 0 in [f.id for f in reply.feedback]

    async def keep_sending() -> None:
        while True:
            station.send("blue", data)
            await asyncio.sleep(0.01)

    sender = asyncio.create_task(keep_sending())
    try:
        await station.packet(
            lambda p: any(r.x > x0 + 300 for r in robot_in(p, "blue", 0)),  # type: ignore[attr-defined]
            timeout=3.0,
        )
    finally:
        sender.cancel()
    # the robot keeps the last command for ~0.2 s, then brakes to a stop
    loop = asyncio.get_running_loop()
    t_stop = loop.time()
    truth = station.sim.world.robot(Team.BLUE, 0)
    assert truth is not None
    while truth.vx != 0.0:
        assert loop.time() - t_stop < 2.0, "robot did not stop"
        await asyncio.sleep(0.005)
    assert loop.time() - t_stop > 0.15
    t_still = time.time()
    xs: list[float] = []

    def settled(p: Packet) -> bool:
        if p.HasField("detection") and p.detection.t_capture > t_still:
            xs.extend(r.x for r in robot_in(p, "blue", 0))  # type: ignore[attr-defined]
        return len(xs) >= 10

    await station.packet(settled, timeout=3.0)
    assert max(xs) - min(xs) < 20  # noise only (2 mm sigma)


async def test_teleport_ball_and_remove_robot(station: Station) -> None:
    cmd = control_pb.SimulatorCommand()
    cmd.control.teleport_ball.x = 1.5
    cmd.control.teleport_ball.y = -1.0
    tr = cmd.control.teleport_robot.add()
    tr.id.id = 1
    tr.id.team = common_pb.YELLOW
    tr.present = False
    resp = control_pb.SimulatorResponse()
    resp.ParseFromString(await station.request("control", cmd.SerializeToString()))
    assert not resp.errors
    t_done = time.time()
    p = await station.packet(
        lambda p: p.HasField("detection") and p.detection.t_capture > t_done
        and any(abs(b.x - 1500) < 30 and abs(b.y + 1000) < 30 for b in p.detection.balls)
    )
    assert p.detection.camera_id == 3  # (+x, -y) quadrant
    seen_cams: set[int] = set()

    def no_yellow_1(p: Packet) -> bool:
        if p.HasField("detection") and p.detection.t_capture > t_done:
            assert not robot_in(p, "yellow", 1)
            seen_cams.add(p.detection.camera_id)
        return len(seen_cams) == 4

    await station.packet(no_yellow_1)
    # add it back
    tr.present = True
    tr.x, tr.y, tr.orientation = 2.0, 1.0, 0.0
    cmd.ClearField("control")
    cmd.control.teleport_robot.append(tr)
    resp.ParseFromString(await station.request("control", cmd.SerializeToString()))
    assert not resp.errors
    await station.packet(lambda p: any(abs(r.x - 2000) < 30 for r in robot_in(p, "yellow", 1)))  # type: ignore[attr-defined]


async def test_grsim_replacement_and_commands(station: Station) -> None:
    pkt = grsim_pb.grSim_Packet()
    rr = pkt.replacement.robots.add(x=0.5, y=0.5, dir=90.0, id=3, yellowteam=True)
    assert rr.IsInitialized()
    station.send("grsim", pkt.SerializeToString())
    p = await station.packet(
        lambda p: any(abs(r.x - 500) < 30 and abs(r.y - 500) < 30  # type: ignore[attr-defined]
                      for r in robot_in(p, "yellow", 3))
    )
    (r,) = robot_in(p, "yellow", 3)
    assert r.orientation == pytest.approx(math.pi / 2, abs=0.1)  # type: ignore[attr-defined]

    # legacy commands: yellow 3 drives forward (+y since it faces +y)
    cmds = grsim_pb.grSim_Packet()
    cmds.commands.timestamp = 0.0
    cmds.commands.isteamyellow = True
    cmds.commands.robot_commands.add(
        id=3, kickspeedx=0, kickspeedz=0, veltangent=1.0, velnormal=0, velangular=0,
        spinner=False, wheelsspeed=False,
    )
    data = cmds.SerializeToString()

    async def keep_sending() -> None:
        while True:
            station.send("grsim", data)
            await asyncio.sleep(0.01)

    sender = asyncio.create_task(keep_sending())
    try:
        await station.packet(
            lambda p: any(r.y > 800 for r in robot_in(p, "yellow", 3))  # type: ignore[attr-defined]
        )
    finally:
        sender.cancel()


async def test_malformed_and_invalid_datagrams(station: Station) -> None:
    stats = station.sim.handler.stats
    garbage = b"\xff\xff\xff\xff garbage \x00\x01"
    for name in ("blue", "yellow"):
        resp = fb_pb.RobotControlResponse()
        resp.ParseFromString(await station.request(name, garbage))
        assert [e.code for e in resp.errors] == [ERR_MALFORMED]
    resp_c = control_pb.SimulatorResponse()
    resp_c.ParseFromString(await station.request("control", garbage))
    assert [e.code for e in resp_c.errors] == [ERR_MALFORMED]
    station.send("grsim", garbage)
    # missing required field: a RobotCommand without id
    partial = rc_pb.RobotControl()
    partial.robot_commands.add().kick_speed = 1.0
    resp = fb_pb.RobotControlResponse()
    resp.ParseFromString(await station.request("blue", partial.SerializePartialToString()))
    assert [e.code for e in resp.errors] == [ERR_MALFORMED]
    # grSim packet missing required fields
    bad = grsim_pb.grSim_Packet()
    bad.commands.isteamyellow = True
    station.send("grsim", bad.SerializePartialToString())

    loop = asyncio.get_running_loop()
    deadline = loop.time() + 2.0
    while stats.malformed["grsim"] < 2:
        assert loop.time() < deadline, dict(stats.malformed)
        await asyncio.sleep(0.01)
    assert stats.malformed["blue"] == 2 and stats.malformed["yellow"] == 1
    assert stats.malformed["control"] == 1

    # unknown robot, NaN, wheel velocity -> errors; the robot with NaN stops
    msg = rc_pb.RobotControl()
    msg.robot_commands.add(id=12).move_command.local_velocity.forward = 1.0
    c = msg.robot_commands.add(id=0)
    c.move_command.local_velocity.forward = math.nan
    c.move_command.local_velocity.left = 0.0
    c.move_command.local_velocity.angular = 0.0
    w = msg.robot_commands.add(id=1).move_command.wheel_velocity
    w.front_right = w.back_right = w.back_left = w.front_left = 1.0
    msg.robot_commands[0].move_command.local_velocity.left = 0.0
    msg.robot_commands[0].move_command.local_velocity.angular = 0.0
    resp = fb_pb.RobotControlResponse()
    resp.ParseFromString(await station.request("blue", msg.SerializeToString()))
    codes = [e.code for e in resp.errors]
    assert codes[:2] == [ERR_UNKNOWN_ROBOT, ERR_INVALID_VALUE]
    assert resp.errors[2].unsupported_capability == (
        error_pb.SIMULATOR_CAPABILITY_MOVE_WHEEL_VELOCITY
    )
    robot0 = station.sim.world.robot(Team.BLUE, 0)
    assert robot0 is not None and robot0.command is not None and robot0.command.forward == 0.0

    # still alive and answering
    ok = control_pb.SimulatorCommand()
    ok.control.teleport_ball.x = 0.0
    resp_c.ParseFromString(await station.request("control", ok.SerializeToString()))
    assert not resp_c.errors
    await station.packet(lambda p: p.HasField("detection"))
    assert station.sim.running and station.sim.internal_errors == 0


async def test_truth_publisher() -> None:
    import zmq
    import zmq.asyncio

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    tcp_port = s.getsockname()[1]
    s.close()
    endpoint = f"tcp://127.0.0.1:{tcp_port}"
    cfg = SimConfig(
        vision_port=random_vision_port(), control_port=0, blue_port=0, yellow_port=0,
        grsim_port=0, truth_pub=endpoint, generation=1, seed=4,
    )
    ctx = zmq.asyncio.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, b"truth")
    async with FieldSim(cfg) as sim:
        sub.connect(endpoint)
        topic, body = await asyncio.wait_for(sub.recv_multipart(), 5.0)
        assert topic == b"truth"
        truth = json.loads(body)
        assert len(truth["robots"]) == 12
        gains = {(r["team"], r["id"]): r["C"] for r in truth["robots"]}
        assert gains[("blue", 0)] == sim.world.gain_of(Team.BLUE, 0)
        assert len(set(gains.values())) == 12
        assert {"x", "y", "vx", "vy"} <= set(truth["ball"])
    sub.close()
    ctx.term()


def test_thread_wrapper_and_rates() -> None:
    port = random_vision_port()
    rx = open_multicast_receiver(GROUP, port, "127.0.0.1")
    rx.setblocking(True)
    rx.settimeout(0.5)
    cfg = SimConfig(vision_port=port, control_port=0, blue_port=0, yellow_port=0, grsim_port=0)
    counts = {k: 0 for k in range(4)}
    with FieldSimThread(cfg) as handle:
        assert set(handle.ports) == {"control", "blue", "yellow", "grsim"}
        t_end = time.monotonic() + 1.0
        t_first: float | None = None
        while time.monotonic() < t_end:
            try:
                data = rx.recv(65536)
            except TimeoutError:
                continue
            p = Packet()
            p.ParseFromString(data)
            if p.HasField("detection"):
                if t_first is None:
                    t_first = time.monotonic()
                    t_end = t_first + 1.0
                counts[p.detection.camera_id] += 1
        n_robots = handle.call(lambda sim: len(sim.world.robots))
        assert n_robots == 12
    rx.close()
    # 60 Hz per camera; generous bounds for a shared 2-core machine
    assert all(45 <= c <= 65 for c in counts.values()), counts
    assert statistics.mean(counts.values()) > 50


async def test_grsim_status_sent_to_the_command_sender() -> None:
    """Like grSim: Robots_Status to the IP of the last grSim command's sender, on the status
    port of the team, when a value changes."""
    status_rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    status_rx.bind(("127.0.0.1", 0))
    status_rx.setblocking(False)
    cfg = SimConfig(vision_port=random_vision_port(), control_port=0, blue_port=0,
                    yellow_port=0, grsim_port=0, seed=3,
                    grsim_status_yellow_port=status_rx.getsockname()[1])
    sim = FieldSim(cfg)
    await sim.start()
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        pkt = grsim_pb.grSim_Packet()
        pkt.commands.timestamp = 0.0
        pkt.commands.isteamyellow = True
        pkt.commands.robot_commands.add(id=0, kickspeedx=0, kickspeedz=0, veltangent=0,
                                        velnormal=0, velangular=0, spinner=False,
                                        wheelsspeed=False)
        tx.sendto(pkt.SerializeToString(), ("127.0.0.1", sim.ports["grsim"]))
        loop = asyncio.get_running_loop()
        data = await asyncio.wait_for(loop.sock_recv(status_rx, 65536), 3.0)
        from sslpb.grsim_robot_status_pb2 import Robots_Status
        status = Robots_Status.FromString(data)
        assert status.IsInitialized()
        assert 0 in [s.robot_id for s in status.robots_status]
        assert sim.grsim_peers == {Team.YELLOW: "127.0.0.1"}
    finally:
        await sim.stop()
        tx.close()
        status_rx.close()


async def test_cameras_keep_their_phases_when_the_simulator_catches_up() -> None:
    """A stall longer than fieldsim's catch-up (its clock jumps 1 s: 200 physics steps, it
    takes 50 and skips the rest) leaves each camera on its own phase: after the skip the
    cameras still capture at instants of their own, not all at the skip's instant (which
    made every later frame of a spread run arrive as one burst, as --camera-phases together,
    for the rest of the run)."""
    port = random_vision_port()
    rx = open_multicast_receiver(GROUP, port, "127.0.0.1")
    jump = [0.0]
    cfg = SimConfig(vision_port=port, control_port=0, blue_port=0, yellow_port=0,
                    grsim_port=0, seed=11)
    sim = FieldSim(cfg, clock=lambda: time.monotonic() + jump[0])
    st = Station(sim, rx)
    await sim.start()
    try:
        instants: dict[float, set[int]] = {}

        def distinct_instants(n: int) -> Callable[[Packet], bool]:
            instants.clear()

            def take(p: Packet) -> bool:
                if p.HasField("detection"):
                    instants.setdefault(p.detection.t_capture, set()).add(
                        p.detection.camera_id)
                return len(instants) >= n

            return take

        await st.packet(distinct_instants(12), timeout=5.0)
        assert all(len(c) == 1 for c in instants.values())  # spread: one camera an instant
        jump[0] = 1.0  # the machine stalled for a second
        await st.packet(lambda p: sim.lag_resets > 0, timeout=5.0)
        await st.packet(lambda p: True)  # what was sent in the reset's turn
        await st.packet(distinct_instants(12), timeout=5.0)
        assert all(len(c) == 1 for c in instants.values()), instants
    finally:
        await sim.stop()
        st.close()
