"""The generated code against bytes built by hand from the official field numbers.

The same vectors are checked in TypeScript (frontend/src/proto/wire.test.ts), so Python and
the browser agree with the league's definitions byte for byte."""

from __future__ import annotations

from sslpb import touchline_pb2 as tl
from sslpb.grsim_packet_pb2 import grSim_Packet
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand
from sslpb.ssl_simulation_robot_control_pb2 import RobotControl
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from tests.wire import f32, f64, ld, uv

# SSL_WrapperPacket{detection{frame_number=7, t_capture=1.5, t_sent=1.75, camera_id=2,
#   balls[{confidence=0.5, x=100, y=-200, pixel_x=1, pixel_y=2}],
#   robots_blue[{confidence=1, robot_id=3, x=10, y=20, orientation=0.25, pixel_x=0, pixel_y=0}]}}
BALL = f32(1, 0.5) + f32(3, 100.0) + f32(4, -200.0) + f32(6, 1.0) + f32(7, 2.0)
ROBOT = f32(1, 1.0) + uv(2, 3) + f32(3, 10.0) + f32(4, 20.0) + f32(5, 0.25) + f32(6, 0) + f32(7, 0)
DETECTION = uv(1, 7) + f64(2, 1.5) + f64(3, 1.75) + uv(4, 2) + ld(5, BALL) + ld(7, ROBOT)
WRAPPER = ld(1, DETECTION)

# RobotControl{robot_commands[{id=3, move_command{local_velocity{forward=1, left=-0.5,
#   angular=2}}, kick_speed=4}]}
LOCAL = f32(1, 1.0) + f32(2, -0.5) + f32(3, 2.0)
ROBOT_CONTROL = ld(1, uv(1, 3) + ld(2, ld(2, LOCAL)) + f32(3, 4.0))


def test_wrapper_decodes_hand_built_bytes() -> None:
    p = SSL_WrapperPacket()
    p.ParseFromString(WRAPPER)
    assert p.IsInitialized()
    d = p.detection
    assert (d.frame_number, d.t_capture, d.t_sent, d.camera_id) == (7, 1.5, 1.75, 2)
    assert (d.balls[0].x, d.balls[0].y) == (100.0, -200.0)
    r = d.robots_blue[0]
    assert (r.robot_id, r.x, r.y, r.orientation) == (3, 10.0, 20.0, 0.25)
    assert p.SerializeToString() == WRAPPER  # and encodes to the same bytes


def test_robot_control_encodes_to_hand_built_bytes() -> None:
    m = RobotControl()
    c = m.robot_commands.add(id=3, kick_speed=4.0)
    c.move_command.local_velocity.forward = 1.0
    c.move_command.local_velocity.left = -0.5
    c.move_command.local_velocity.angular = 2.0
    assert m.SerializeToString() == ROBOT_CONTROL


def test_teleport_robot_field_numbers() -> None:
    # SimulatorCommand{control{teleport_robot[{id{id=1, team=BLUE(2)}, x=0.5, orientation=3}]}}
    want = ld(1, ld(2, ld(1, uv(1, 1) + uv(2, 2)) + f32(2, 0.5) + f32(4, 3.0)))
    m = SimulatorCommand()
    t = m.control.teleport_robot.add(x=0.5, orientation=3.0)
    t.id.id, t.id.team = 1, 2
    assert m.SerializeToString() == want


def test_grsim_command_field_numbers() -> None:
    cmd = (uv(1, 5) + f32(2, 0) + f32(3, 0) + f32(4, 1.0) + f32(5, 0.5) + f32(6, -1.0)
           + uv(7, 0) + uv(8, 0))
    want = ld(1, f64(1, 2.0) + uv(2, 1) + ld(3, cmd))
    m = grSim_Packet()
    m.commands.timestamp, m.commands.isteamyellow = 2.0, True
    m.commands.robot_commands.add(id=5, kickspeedx=0, kickspeedz=0, veltangent=1.0,
                                  velnormal=0.5, velangular=-1.0, spinner=False,
                                  wheelsspeed=False)
    assert m.SerializeToString() == want


def test_referee_required_fields_and_command() -> None:
    team = ld(1, b"A") + uv(2, 1) + uv(3, 0) + uv(5, 2) + uv(6, 4) + uv(7, 300) + uv(8, 0)
    raw = (uv(1, 1000) + uv(2, 1) + uv(4, 16) + uv(5, 9) + uv(6, 999) + ld(7, team)
           + ld(8, team) + ld(9, f32(1, 1500.0) + f32(2, -250.0)) + uv(10, 1))
    m = Referee()
    m.ParseFromString(raw)
    assert m.IsInitialized()
    assert m.command == Referee.BALL_PLACEMENT_YELLOW and m.stage == Referee.NORMAL_FIRST_HALF
    assert (m.designated_position.x, m.designated_position.y) == (1500.0, -250.0)
    assert m.blue_team_on_positive_half is True and m.yellow.yellow_cards == 2
    # missing required fields parse without error: the station must check IsInitialized()
    partial = Referee()
    partial.ParseFromString(uv(1, 1000))
    assert not partial.IsInitialized()


def test_touchline_command_set_layout() -> None:
    cmd = uv(1, 2) + uv(2, 4) + f32(3, 1.0) + f32(5, -2.0)
    want = uv(1, 10) + uv(3, 1) + ld(4, cmd) + uv(5, 1)
    m = tl.RobotCommandSet(created_time_ns=10, sequence=1, stop_all=True)
    m.commands.add(team=tl.TEAM_BLUE, id=4, forward_mps=1.0, angular_radps=-2.0)
    assert m.SerializeToString() == want


def test_robot_feedback_and_grsim_status_field_numbers() -> None:
    from sslpb.grsim_robot_status_pb2 import Robots_Status
    from sslpb.ssl_simulation_robot_feedback_pb2 import RobotControlResponse

    # RobotControlResponse{feedback[{id=5, dribbler_ball_contact=true}]}: 0x12 = field 2 LEN
    want = b"\x12\x04\x08\x05\x10\x01"
    assert ld(2, uv(1, 5) + uv(2, 1)) == want
    m = RobotControlResponse()
    m.feedback.add(id=5, dribbler_ball_contact=True)
    assert m.SerializeToString() == want
    # Robots_Status{robots_status[{robot_id=2, infrared=true, flat_kick=false, chip_kick=true}]}
    want = ld(1, uv(1, 2) + uv(2, 1) + uv(3, 0) + uv(4, 1))
    s = Robots_Status()
    s.robots_status.add(robot_id=2, infrared=True, flat_kick=False, chip_kick=True)
    assert s.SerializeToString() == want
