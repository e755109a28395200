"""fieldsim answers like grSim / ER-Force: a RobotFeedback per robot commanded, with
dribbler_ball_contact while the ball touches the robot's kicker face."""

from __future__ import annotations

import math

from fieldsim.config import SimConfig
from fieldsim.protocol import CommandHandler
from fieldsim.world import Team, World
from tests.wire import f32, key, ld, read_fields, varint


def robot_control(*ids: int) -> bytes:
    """RobotControl {1 robot_commands: RobotCommand {1 id, 2 move: {2 local_velocity}}}."""
    local = f32(1, 0.0) + f32(2, 0.0) + f32(3, 0.0)
    return b"".join(ld(1, key(1, 0) + varint(i) + ld(2, ld(2, local))) for i in ids)


def contacts(reply: bytes) -> dict[int, bool]:
    """RobotControlResponse.feedback (2) read by hand: RobotFeedback {1 id, 2 contact}."""
    out: dict[int, bool] = {}
    for f, _, v in read_fields(reply):
        if f == 2 and isinstance(v, bytes):
            inner = {ff: vv for ff, _, vv in read_fields(v)}
            assert isinstance(inner[1], int)
            out[inner[1]] = bool(inner.get(2, 0))
    return out


def setup(ball_dx: float, ball_dy: float, theta: float = 0.0) -> tuple[World, CommandHandler]:
    w = World(SimConfig(blue=2, yellow=1))
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, theta)
    w.teleport_robot(Team.BLUE, 1, -2.0, 1.0, 0.0)
    w.teleport_robot(Team.YELLOW, 0, 2.0, 1.0, 0.0)
    w.teleport_ball(ball_dx, ball_dy)
    w.step()
    return w, CommandHandler(w)


def touch_distance(w: World) -> float:
    return w.config.robot_radius_m + w.config.ball_radius_m


def test_ball_at_the_kicker_face_is_contact() -> None:
    w, h = setup(0.0, 0.0)
    d = touch_distance(w) + 0.003  # a few mm in front of the kicker face
    w.teleport_ball(d, 0.0)
    w.step()
    assert contacts(h.robot_control(Team.BLUE, robot_control(0, 1))) == {0: True, 1: False}


def test_answers_only_the_robots_commanded() -> None:
    _, h = setup(0.5, 0.5)
    assert contacts(h.robot_control(Team.BLUE, robot_control(1))) == {1: False}
    assert contacts(h.robot_control(Team.YELLOW, robot_control(0, 7))) == {0: False}  # 7 absent


def test_no_contact_behind_aside_or_too_far() -> None:
    w, h = setup(0.0, 0.0, theta=math.pi / 2)  # facing +y
    d = touch_distance(w) + 0.003
    for bx, by in ((0.0, -d), (d, 0.0), (0.0, d + 0.03),
                   (d * math.cos(math.radians(90 + 60)), d * math.sin(math.radians(90 + 60)))):
        w.teleport_ball(bx, by)
        w.step()
        assert contacts(h.robot_control(Team.BLUE, robot_control(0))) == {0: False}, (bx, by)
    w.teleport_ball(0.0, d)  # in front of the turned robot
    w.step()
    assert contacts(h.robot_control(Team.BLUE, robot_control(0))) == {0: True}


# -- grSim's Robots_Status ----------------------------------------------------------------------


def grsim_command(yellow: bool, rid: int, kick: float = 0.0, chip: float = 0.0) -> bytes:
    """grSim_Packet {1 commands {1 timestamp, 2 isteamyellow, 3 robot_commands {1 id,
    2 kickspeedx, 3 kickspeedz, 4 veltangent, 5 velnormal, 6 velangular, 7 spinner,
    8 wheelsspeed}}}."""
    rc = (key(1, 0) + varint(rid) + f32(2, kick) + f32(3, chip) + f32(4, 0.0) + f32(5, 0.0)
          + f32(6, 0.0) + key(7, 0) + varint(0) + key(8, 0) + varint(0))
    commands = key(1, 1) + b"\x00" * 8 + key(2, 0) + varint(int(yellow)) + ld(3, rc)
    return ld(1, commands)


def statuses(data: bytes) -> dict[int, tuple[bool, bool, bool]]:
    """Robots_Status {1 robots_status {1 robot_id, 2 infrared, 3 flat_kick, 4 chip_kick}}."""
    out: dict[int, tuple[bool, bool, bool]] = {}
    for f, _, v in read_fields(data):
        assert f == 1 and isinstance(v, bytes)
        s = {ff: vv for ff, _, vv in read_fields(v)}
        assert isinstance(s[1], int)
        out[s[1]] = (bool(s[2]), bool(s[3]), bool(s[4]))
    return out


def test_grsim_status_on_change_with_kicks() -> None:
    w, h = setup(0.5, 0.5)
    assert h.grsim_packet(grsim_command(False, 0)) is Team.BLUE
    first = h.grsim_status(Team.BLUE)
    assert first is not None
    assert statuses(first) == {0: (False, False, False), 1: (False, False, False)}
    assert h.grsim_status(Team.BLUE) is None  # nothing changed: nothing sent
    d = touch_distance(w) + 0.003
    w.teleport_ball(d, 0.0)
    w.step()
    changed = h.grsim_status(Team.BLUE)
    assert changed is not None and statuses(changed)[0] == (True, False, False)
    h.grsim_packet(grsim_command(False, 0, kick=3.0, chip=3.0))  # a chip
    w.step()
    kicked = h.grsim_status(Team.BLUE)
    assert kicked is not None and statuses(kicked)[0][2] is True
    after = h.grsim_status(Team.BLUE)
    assert after is not None and statuses(after)[0][1:] == (False, False)
    assert h.grsim_packet(b"\xff") is None
