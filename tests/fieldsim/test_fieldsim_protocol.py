"""Protocol decoder (pure): arbitrary bytes never crash it; replies always parse."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldsim.config import SimConfig
from fieldsim.protocol import ERR_INVALID_VALUE, ERR_UNKNOWN_ROBOT, CommandHandler
from fieldsim.world import Team, World
from sslpb import grsim_packet_pb2 as grsim_pb
from sslpb import ssl_gc_common_pb2 as common_pb
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb

HANDLER = CommandHandler(World(SimConfig()))


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=200))
def test_arbitrary_bytes_never_crash(data: bytes) -> None:
    r = fb_pb.RobotControlResponse()
    r.ParseFromString(HANDLER.robot_control(Team.BLUE, data))
    s = control_pb.SimulatorResponse()
    s.ParseFromString(HANDLER.simulator_command(data))
    HANDLER.grsim_packet(data)
    assert r.IsInitialized() and s.IsInitialized()
    for robot in HANDLER.world.robots.values():
        assert math.isfinite(robot.x) and math.isfinite(robot.y)
    assert math.isfinite(HANDLER.world.ball.x)


def test_teleport_errors_and_units() -> None:
    world = World(SimConfig())
    h = CommandHandler(world)
    cmd = control_pb.SimulatorCommand()
    tr = cmd.control.teleport_robot.add()
    tr.id.id = 5
    tr.id.team = common_pb.BLUE
    tr.x, tr.y, tr.orientation = 1.0, -2.0, 1.0
    cmd.control.teleport_ball.x = math.inf
    resp = control_pb.SimulatorResponse()
    resp.ParseFromString(h.simulator_command(cmd.SerializeToString()))
    assert [e.code for e in resp.errors] == [ERR_INVALID_VALUE]
    r = world.robot(Team.BLUE, 5)
    assert r is not None and (r.x, r.y) == (1.0, -2.0) and abs(r.theta - 1.0) < 1e-6
    # a robot that is not on the field and not added -> UNKNOWN_ROBOT
    tr.id.id = 9
    cmd.control.ClearField("teleport_ball")
    resp.ParseFromString(h.simulator_command(cmd.SerializeToString()))
    assert [e.code for e in resp.errors] == [ERR_UNKNOWN_ROBOT]
    assert world.robot(Team.BLUE, 9) is None


def test_grsim_units_degrees_and_kick() -> None:
    world = World(SimConfig())
    h = CommandHandler(world)
    pkt = grsim_pb.grSim_Packet()
    pkt.replacement.robots.add(x=0.0, y=0.0, dir=180.0, id=0, yellowteam=False)
    pkt.replacement.ball.x = -0.115  # touching the front
    pkt.replacement.ball.y = 0.0
    h.grsim_packet(pkt.SerializeToString())
    r = world.robot(Team.BLUE, 0)
    assert r is not None and abs(abs(r.theta) - math.pi) < 1e-6
    cmds = grsim_pb.grSim_Packet()
    cmds.commands.timestamp = 0.0
    cmds.commands.isteamyellow = False
    cmds.commands.robot_commands.add(id=0, kickspeedx=3.0, kickspeedz=0.0, veltangent=0.0,
                                     velnormal=0.0, velangular=0.0, spinner=False,
                                     wheelsspeed=False)
    h.grsim_packet(cmds.SerializeToString())
    for _ in range(40):
        world.step()
    assert world.ball.vx < -2.5  # kicked along the heading (-x)
