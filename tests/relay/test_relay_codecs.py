"""Pure codec tests: no sockets, no event loop."""

from __future__ import annotations

import json
import math
import random
import struct
from collections.abc import Callable

import numpy as np
import pytest

from larcmacs_relay import codecs
from larcmacs_relay.codecs import BoxExtras, Command, CommandError
from larcmacs_relay.commands import CommandTable, RobotState
from larcmacs_relay.compat import MATRIX_BYTES, RefereeMapper, decode_command_matrix
from sslpb import (
    grsim_packet_pb2,
    ssl_gc_common_pb2,
    ssl_gc_referee_message_pb2,
    ssl_simulation_control_pb2,
    ssl_simulation_robot_control_pb2,
    ssl_vision_wrapper_pb2,
    touchline_pb2,
)
from tests.wire import f32, ld, uv

BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW
Ref = ssl_gc_referee_message_pb2.Referee


def make_detection_wrapper(frame: int = 1, camera: int = 0) -> bytes:
    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number = frame
    d.t_capture = 1.7e9
    d.t_sent = 1.7e9 + 0.001
    d.camera_id = camera
    b = d.balls.add()
    b.confidence, b.x, b.y, b.pixel_x, b.pixel_y = 0.9, 10.0, -20.0, 1.0, 2.0
    return w.SerializeToString()


def make_referee(
    command: int,
    counter: int,
    *,
    stage: int = Ref.NORMAL_FIRST_HALF,
    blue_positive: bool | None = None,
) -> bytes:
    r = Ref()
    r.packet_timestamp = 1_700_000_000_000_000
    r.stage = stage
    r.command = command
    r.command_counter = counter
    r.command_timestamp = 1_700_000_000_000_000
    for t in (r.yellow, r.blue):
        t.name = "x"
        t.score = t.red_cards = t.yellow_cards = t.timeouts = t.timeout_time = t.goalkeeper = 0
    if blue_positive is not None:
        r.blue_team_on_positive_half = blue_positive
    assert r.IsInitialized()
    return r.SerializeToString()


# ----------------------------------------------------------------- validation


def test_vision_and_referee_are_forwarded_without_decoding() -> None:
    """The backend decodes them once (and counts what does not parse); the relay refuses only
    an empty datagram, and parses a Referee only where it re-encodes it (compat, referee out)."""
    assert codecs.check_forwarded(make_detection_wrapper()) is None
    assert codecs.check_forwarded(b"\xff\xff\xff\xff garbage") is None
    assert codecs.check_forwarded(b"") == "empty datagram"
    ref, why = codecs.parse_referee(make_referee(Ref.HALT, 1))
    assert ref is not None and why is None and ref.command == Ref.HALT
    ref, why = codecs.parse_referee(uv(1, 5))  # only packet_timestamp
    assert ref is None and why is not None and "required" in why


# ----------------------------------------------------------------- wire compatibility


def test_sim_robot_control_matches_hand_built_wire_bytes() -> None:
    cmd = Command(
        BLUE,
        2,
        forward_mps=1.5,
        left_mps=-0.25,
        angular_radps=2.0,
        kick_speed_mps=4.0,
        chip=True,
        dribbler_rpm=1000.0,
    )
    got = codecs.encode_sim_robot_control([cmd], chip_angle_deg=45.0)
    local = f32(1, 1.5) + f32(2, -0.25) + f32(3, 2.0)  # MoveLocalVelocity forward, left, angular
    move = ld(2, local)  # RobotMoveCommand.local_velocity = 2
    robot = uv(1, 2) + ld(2, move) + f32(3, 4.0) + f32(4, 45.0) + f32(5, 1000.0)
    expected = ld(1, robot)  # RobotControl.robot_commands = 1
    assert got == expected


def test_sim_robot_parts_joined_are_the_whole_message() -> None:
    """The relay keeps each robot's encoded part and joins them: byte for byte the message
    of all of them."""
    cmds = [Command(BLUE, 1, 1.0, 0.5, -0.2, 3.0, True, 500.0), Command(BLUE, 4),
            Command(BLUE, 9, -1.5, 0.0, 2.0)]
    joined = b"".join(codecs.encode_sim_robot_command(c, 45.0) for c in cmds)
    assert joined == codecs.encode_sim_robot_control(cmds, 45.0)


def test_sim_robot_part_by_struct_is_protobufs_encoding() -> None:
    """A robot's part is written by struct: byte for byte what protobuf makes of it, for
    every id, signed zeros, float32 rounding, denormals, the float32 edge, values beyond it
    (protobuf's infinity, through the fallback), chips with and without a kick."""
    rng = random.Random(5)
    values = [0.0, -0.0, 0.1, -1.5, 1e-40, 3.4e38, -3.4028235e38, 1e39, -1e300,
              1.0000000001, 2.5e-7]
    for k in range(5000):
        v = [rng.choice(values) if rng.random() < 0.5 else rng.uniform(-20, 20)
             for _ in range(5)]
        c = Command(rng.choice([BLUE, YELLOW]), rng.randint(0, 15), v[0], v[1], v[2],
                    abs(v[3]), rng.random() < 0.5, v[4])
        angle = rng.choice([0.0, 45.0, 60.5])
        assert codecs.encode_sim_robot_command(c, angle) == \
            codecs.encode_sim_robot_control([c], angle), (k, c, angle)
    # an id beyond one varint byte (not a valid robot, but the encoding must still agree)
    c = Command(BLUE, 300, 1.0)
    assert codecs.encode_sim_robot_command(c, 45.0) == codecs.encode_sim_robot_control([c], 45.0)


def test_sim_robot_control_straight_kick_angle_zero() -> None:
    got = codecs.encode_sim_robot_control([Command(YELLOW, 15, kick_speed_mps=3.0)], 45.0)
    msg = ssl_simulation_robot_control_pb2.RobotControl.FromString(got)
    rc = msg.robot_commands[0]
    assert rc.id == 15 and rc.kick_speed == 3.0 and rc.kick_angle == 0.0


# ----------------------------------------------------------------- robot box


def test_robot_box_bytes_native_command() -> None:
    # forward 2.0 m/s -> 40, left -1.0 m/s -> -20, angular 4 rad/s -> 20 (sent inverted: -20)
    cmd = Command(
        BLUE,
        7,
        forward_mps=2.0,
        left_mps=-1.0,
        angular_radps=4.0,
        kick_speed_mps=3.0,
        chip=False,
        dribbler_rpm=5000.0,
    )
    got = codecs.encode_robot_box(cmd, kick_mps_per_volt=0.5, dribbler_rpm_per_unit=1000.0)
    expected = bytes(
        [
            1,  # opcode
            7,  # robot number
            256 - 20,  # speedY = left power -20 as int8
            40,  # speedX = forward power 40
            256 - 20,  # speedR = -(angular power 20)
            5,  # dribbler speed 5000 rpm / 1000
            6,  # kicker voltage 3 m/s / 0.5
            0,  # kickUp
            1,  # kickForward
            0,  # beep
            1,  # dribbler enable
            1,  # kicker-charge enable
            0,  # autoKick
        ]
    )
    assert got == expected
    assert len(got) == 13


def test_robot_box_clamps_and_zero_and_compat_passthrough() -> None:
    fast = Command(YELLOW, 3, forward_mps=10.0, angular_radps=-50.0)
    got = codecs.encode_robot_box(fast)
    assert got[2] == 0 and got[3] == 100 and got[4] == 100  # norm clipped; -(-100)
    assert codecs.encode_robot_box(fast.zero()) == bytes([1, 3] + [0] * 11)
    box = BoxExtras(
        kick_up=1,
        kick_forward=0,
        auto_kick=1,
        kicker_voltage=12,
        dribbler_enable=1,
        dribbler_speed=9,
        kicker_charge_enable=1,
        beep=1,
    )
    c = Command(BLUE, 4, forward_mps=0.5, left_mps=0.25, angular_radps=-1.0, box=box)
    assert codecs.encode_robot_box(c) == bytes([1, 4, 5, 10, 5, 9, 12, 1, 0, 1, 1, 1, 1])


def test_power_conversions() -> None:
    assert codecs.power_to_si(60, 80, 50) == pytest.approx((3.0, 4.0, 10.0))
    fx, fy, fr = codecs.power_to_si(300, 400, -250)  # norm 500 -> clipped to 100
    assert (fx, fy, fr) == pytest.approx((3.0, 4.0, -20.0))
    assert codecs.si_to_power(3.0, 4.0, 10.0) == (60, 80, 50)


# ----------------------------------------------------------------- grSim


def test_grsim_commands_fields() -> None:
    cmds = [Command(YELLOW, 1, 1.0, 0.5, -2.0, 4.0, True, 100.0), Command(YELLOW, 2, 0.1)]
    pkt = grsim_packet_pb2.grSim_Packet.FromString(
        codecs.encode_grsim_commands(cmds, True, 123.5, 45.0)
    )
    assert pkt.IsInitialized()
    gc = pkt.commands
    assert gc.timestamp == 123.5 and gc.isteamyellow
    r = gc.robot_commands[0]
    assert (r.id, r.veltangent, r.velnormal, r.velangular) == (1, 1.0, 0.5, -2.0)
    assert r.kickspeedx == pytest.approx(4.0 * math.sqrt(0.5), rel=1e-6)
    assert r.kickspeedz == pytest.approx(4.0 * math.sqrt(0.5), rel=1e-6)
    assert r.spinner and not r.wheelsspeed
    r2 = gc.robot_commands[1]
    assert r2.kickspeedx == 0 and r2.kickspeedz == 0 and not r2.spinner


def test_teleport_translation_to_grsim() -> None:
    cmd = ssl_simulation_control_pb2.SimulatorCommand()
    cmd.control.teleport_ball.x = 1.25
    cmd.control.teleport_ball.y = -0.5
    tr = cmd.control.teleport_robot.add()
    tr.id.id = 3
    tr.id.team = ssl_gc_common_pb2.YELLOW
    tr.x, tr.y, tr.orientation, tr.present = -2.0, 1.0, math.pi / 2, True
    pkt = grsim_packet_pb2.grSim_Packet.FromString(codecs.sim_command_to_grsim(cmd) or b"")
    assert pkt.IsInitialized()
    ball = pkt.replacement.ball
    assert (ball.x, ball.y) == (1.25, -0.5)
    r = pkt.replacement.robots[0]
    assert (r.x, r.y, r.id, r.yellowteam, r.turnon) == (-2.0, 1.0, 3, True, True)
    assert r.dir == pytest.approx(90.0, abs=1e-4)
    assert codecs.sim_command_to_grsim(ssl_simulation_control_pb2.SimulatorCommand()) is None


# ----------------------------------------------------------------- commands


def test_command_validation() -> None:
    good = touchline_pb2.RobotCommand(team=BLUE, id=2, forward_mps=1.0)
    assert codecs.command_from_proto(good) == Command(BLUE, 2, forward_mps=1.0)
    for bad in (
        touchline_pb2.RobotCommand(team=BLUE, id=20),
        touchline_pb2.RobotCommand(team=touchline_pb2.TEAM_UNSPECIFIED, id=1),
        touchline_pb2.RobotCommand(team=BLUE, id=1, forward_mps=math.nan),
        touchline_pb2.RobotCommand(team=BLUE, id=1, angular_radps=math.inf),
    ):
        with pytest.raises(CommandError):
            codecs.command_from_proto(bad)


F32_MAX = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]  # the largest finite float32
F32_TINY = struct.unpack("<f", b"\x01\x00\x00\x00")[0]  # the smallest denormal


def test_command_validation_of_every_float_field() -> None:
    """Each float field refused when it is a NaN or an infinity of either sign (the others
    finite), accepted at float32's extremes (the fields are float); the command carries every
    field as sent, is a Command, and equals one made by its constructor."""
    fields = ("forward_mps", "left_mps", "angular_radps", "kick_speed_mps", "dribbler_rpm")
    for name in fields:
        for bad in (math.nan, math.inf, -math.inf):
            pc = touchline_pb2.RobotCommand(team=YELLOW, id=7, **{name: bad})
            with pytest.raises(CommandError, match="non-finite"):
                codecs.command_from_proto(pc)
        for good in (F32_MAX, F32_TINY, -F32_MAX, -0.0):
            if name == "kick_speed_mps" and good < 0:
                continue
            c = codecs.command_from_proto(touchline_pb2.RobotCommand(team=YELLOW, id=7,
                                                                     **{name: good}))
            assert getattr(c, name) == good and type(c) is Command
            assert c == Command(YELLOW, 7, **{name: good})
    pc = touchline_pb2.RobotCommand(team=BLUE, id=15, forward_mps=1.5, left_mps=-0.25,
                                    angular_radps=2.0, kick_speed_mps=3.0, chip=True,
                                    dribbler_rpm=900.0)
    c = codecs.command_from_proto(pc)
    assert c == Command(BLUE, 15, 1.5, -0.25, 2.0, 3.0, True, 900.0, None)
    assert c.zero() == Command(BLUE, 15) and type(c.zero()) is Command and c.zero().is_zero


def test_command_table_stale_hold_and_stop_all() -> None:
    t = CommandTable(timeout_s=0.1, hold_time_s=1.0)
    c = Command(BLUE, 2, forward_mps=1.0)
    t.update(c, 10.0)
    assert t.due(10.05) == [c]
    assert t.due(10.2) == [c.zero()] and t.stale_stops == 1
    assert t.count(RobotState.STALE) == 1
    assert t.due(11.1) == [c.zero()]
    assert t.due(11.25) == [] and t.count(RobotState.IDLE) == 1
    assert t.stale_stops == 1
    t.update(c, 12.0)
    other = Command(YELLOW, 5, left_mps=0.3)
    t.update(other, 12.0)
    t.stop_all(12.01)
    assert t.due(12.02) == [other.zero(), c.zero()]  # sorted by (team, id)
    assert t.stale_stops == 1  # stop_all is not a stale stop
    t.update(c, 12.5)
    assert t.due(12.51) == [other.zero(), c]


# ----------------------------------------------------------------- compat


def test_referee_mapper_states() -> None:
    m = RefereeMapper("blue")
    R = ssl_gc_referee_message_pb2.Referee

    def state(cmd: int, counter: int, **kw: object) -> dict[str, int]:
        return m.state(R.FromString(make_referee(cmd, counter, **kw)))  # type: ignore[arg-type]

    assert state(R.HALT, 1) == {"state": 0, "team": 0, "is_left": 1}
    assert state(R.PREPARE_KICKOFF_YELLOW, 2) == {"state": 5, "team": 2, "is_left": 1}
    assert state(R.PREPARE_KICKOFF_YELLOW, 2)["state"] == 5  # repeated packet, same counter
    assert state(R.NORMAL_START, 3) == {"state": 6, "team": 2, "is_left": 1}
    assert state(R.NORMAL_START, 3)["state"] == 6
    assert state(R.PREPARE_PENALTY_BLUE, 4)["state"] == 7
    assert state(R.NORMAL_START, 5) == {"state": 8, "team": 1, "is_left": 1}
    assert state(R.STOP, 6)["state"] == 1
    assert state(R.NORMAL_START, 7)["state"] == 2
    assert state(R.FORCE_START, 8)["state"] == 2
    assert state(R.GOAL_BLUE, 9) == {"state": 1, "team": 0, "is_left": 1}
    assert state(R.DIRECT_FREE_BLUE, 10, blue_positive=True) == {
        "state": 9,
        "team": 1,
        "is_left": 0,
    }
    assert state(R.INDIRECT_FREE_YELLOW, 11)["state"] == 10
    assert state(R.BALL_PLACEMENT_YELLOW, 12)["state"] == 11
    assert state(R.TIMEOUT_BLUE, 13) == {"state": 3, "team": 1, "is_left": 1}
    assert state(R.HALT, 14, stage=R.POST_GAME)["state"] == 4
    ym = RefereeMapper("yellow")
    out = json.loads(ym.encode(R.FromString(make_referee(R.STOP, 1, blue_positive=True))))
    assert out == {"state": 1, "team": 0, "is_left": 1}


def test_decode_command_matrix() -> None:
    m = np.zeros((32, 13), dtype=np.float64)
    m[3, :12] = [1, 60, -80, 50, 0, 1, 0, 10, 1, 4, 1, 0]
    m[20, 0] = 1  # yellow 4, all zero
    m[21, 0] = 0  # invalid: ignored
    m[22, :4] = [1, math.nan, 0, 0]
    res = decode_command_matrix(m.tobytes())
    assert len(res.errors) == 1
    assert [(c.team, c.id) for c in res.commands] == [(BLUE, 3), (YELLOW, 4)]
    c = res.commands[0]
    assert (c.forward_mps, c.left_mps, c.angular_radps) == pytest.approx((3.0, -4.0, 10.0))
    assert c.kick_speed_mps == pytest.approx(5.0) and not c.chip
    assert c.dribbler_rpm == pytest.approx(4000.0)
    assert len(m.tobytes()) == MATRIX_BYTES
    with pytest.raises(ValueError):
        decode_command_matrix(b"\x00" * 100)


# ----------------------------------------------------------------- properties

from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

finite = st.floats(allow_nan=False, allow_infinity=False, width=32)


@given(finite, finite, finite, st.floats(0, 100), st.booleans(), st.floats(0, 1e5))
def test_robot_box_always_13_bytes_in_range(
    fwd: float, left: float, ang: float, kick: float, chip: bool, rpm: float
) -> None:
    data = codecs.encode_robot_box(Command(BLUE, 5, fwd, left, ang, kick, chip, rpm))
    assert len(data) == 13 and data[0] == 1 and data[1] == 5
    sy, sx, sr = struct.unpack("3b", data[2:5])
    assert all(-100 <= v <= 100 for v in (sx, sy, sr))
    assert math.hypot(sx, sy) <= 101.5  # norm clipped to 100 before rounding


@given(st.integers(-100, 100), st.integers(-100, 100), st.integers(-100, 100))
def test_power_round_trip(px: int, py: int, pr: int) -> None:
    if math.hypot(px, py) <= 100:
        assert codecs.si_to_power(*codecs.power_to_si(px, py, pr)) == (px, py, pr)


def test_validation_failures_are_classified_by_reason() -> None:
    """The reason a refused datagram is counted under (sslnet.streams names)."""
    from larcmacs_relay.codecs import check_forwarded, classify, validate_tracker
    from sslnet import streams

    def kind(validate: Callable[[bytes], str | None], data: bytes) -> str:
        reason = validate(data)
        assert reason is not None, data
        return classify(reason, data)

    assert kind(check_forwarded, b"") == streams.NO_CONTENT
    ref = make_referee(Ref.HALT, 1)
    for cut, expected in ((ref[:-1], streams.TRUNCATED), (b"\x08\x01", streams.MISSING_FIELD)):
        why = codecs.parse_referee(cut)[1]
        assert why is not None and classify(why, cut) == expected
    assert kind(validate_tracker, b"") == streams.NO_CONTENT
    assert kind(validate_tracker, b"\x0f\x01") == streams.NOT_PROTOBUF
