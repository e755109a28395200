"""The world estimate as tracked vision: units, team numbers, visibility, round trip."""

from __future__ import annotations

import math

import pytest

from backend.world.state import BallState, KickedBall, RobotState, WorldState
from backend.world.tracked import tracked_packet
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket
from tests.wire import read_fields


def world() -> WorldState:
    return WorldState(
        t_capture=1700000000.25,
        receive_time_ns=1700000000_300_000_000,
        ball=BallState(x=1500.0, y=-250.0, vx=2000.0, vy=-500.0),
        robots=(
            RobotState("yellow", 3, x=-1000.0, y=2000.0, orientation=1.5, vx=100.0, vy=-300.0,
                       omega=-2.0),
            RobotState("blue", 7, x=500.0, y=0.0, orientation=-math.pi / 2, predicted=True),
            RobotState("blue", 0, x=0.0, y=0.0, orientation=0.0, visible=False, lost=True,
                       t_seen=1700000000.25 - 0.3),  # lost, not seen for 0.3 s
        ),
    )


def decode(data: bytes) -> TrackerWrapperPacket:
    p = TrackerWrapperPacket()
    p.ParseFromString(data)
    assert p.IsInitialized()
    return p


def test_values_are_converted_to_metres() -> None:
    p = decode(tracked_packet(world(), "station-1", 42))
    assert (p.uuid, p.source_name) == ("station-1", "Touchline")
    f = p.tracked_frame
    assert f.frame_number == 42 and f.timestamp == 1700000000.25
    [b] = f.balls
    assert (b.pos.x, b.pos.y, b.pos.z) == pytest.approx((1.5, -0.25, 0.0))
    assert (b.vel.x, b.vel.y, b.vel.z) == pytest.approx((2.0, -0.5, 0.0))
    assert b.visibility == 1.0
    y3 = f.robots[0]
    assert (y3.robot_id.id, y3.robot_id.team) == (3, 1)  # YELLOW = 1
    assert (y3.pos.x, y3.pos.y) == pytest.approx((-1.0, 2.0))
    assert (y3.vel.x, y3.vel.y) == pytest.approx((0.1, -0.3))
    assert y3.orientation == pytest.approx(1.5) and y3.vel_angular == pytest.approx(-2.0)
    assert y3.visibility == 1.0
    b7 = f.robots[1]
    assert (b7.robot_id.id, b7.robot_id.team) == (7, 2)  # BLUE = 2
    assert b7.orientation == pytest.approx(-math.pi / 2)
    assert b7.visibility == 0.5  # extrapolated
    assert f.robots[2].visibility == 0.0  # lost
    assert list(f.capabilities) == [] and not f.HasField("kicked_ball")


def test_a_robot_lost_for_longer_than_half_a_second_is_left_out() -> None:
    """The game controller counts every robot of the frame (visibility aside): a robot lifted
    off the field must leave the frame soon, or the lift after a yellow card is a foul."""
    from dataclasses import replace

    from backend.world.tracked import LOST_ROBOT_SENT_S, tracked_packet_pb

    w = world()
    gone = RobotState("yellow", 5, x=100.0, y=-2900.0, orientation=0.0, visible=False,
                      lost=True, t_seen=w.t_capture - LOST_ROBOT_SENT_S - 0.01)
    just = replace(gone, id=6, t_seen=w.t_capture - LOST_ROBOT_SENT_S + 0.01)
    w = replace(w, robots=(*w.robots, gone, just))
    data = tracked_packet(w, "u", 1)
    ids = [(r.robot_id.team, r.robot_id.id) for r in decode(data).tracked_frame.robots]
    assert ids == [(1, 3), (2, 7), (2, 0), (1, 6)]
    assert data == tracked_packet_pb(w, "u", 1)


def test_team_numbers_on_the_wire() -> None:
    """RobotId.team is field 2 of RobotId (field 1 of TrackedRobot, field 4 of the frame)."""
    data = tracked_packet(world(), "u", 1, source_name="x")
    frame = next(v for n, _, v in read_fields(data) if n == 3)
    assert isinstance(frame, bytes)
    robots = [v for n, _, v in read_fields(frame) if n == 4]
    teams = []
    for r in robots:
        assert isinstance(r, bytes)
        rid = next(v for n, _, v in read_fields(r) if n == 1)
        assert isinstance(rid, bytes)
        teams.append(dict((n, v) for n, _, v in read_fields(rid)))
    assert teams == [{1: 3, 2: 1}, {1: 7, 2: 2}, {1: 0, 2: 2}]


KICK = KickedBall(("blue", 7), start_x=400.0, start_y=-100.0, start_t=1700000000.125,
                  vx=3000.0, vy=-400.0, stop_x=11700.0, stop_y=-1600.0, stop_t=1700000007.7)


def kicked(k: KickedBall = KICK) -> WorldState:
    w = world()
    return WorldState(w.t_capture, w.receive_time_ns, w.ball, w.robots, kicked_ball=k)


def test_a_kick_is_the_frames_kicked_ball_with_its_capability() -> None:
    f = decode(tracked_packet(kicked(), "u", 3)).tracked_frame
    assert list(f.capabilities) == [3]  # CAPABILITY_DETECT_KICKED_BALLS
    k = f.kicked_ball
    assert (k.pos.x, k.pos.y) == pytest.approx((0.4, -0.1))
    assert (k.vel.x, k.vel.y, k.vel.z) == pytest.approx((3.0, -0.4, 0.0))
    assert k.start_timestamp == 1700000000.125 and k.stop_timestamp == 1700000007.7
    assert (k.stop_pos.x, k.stop_pos.y) == pytest.approx((11.7, -1.6))
    assert (k.robot_id.id, k.robot_id.team) == (7, 2)
    unknown = decode(tracked_packet(kicked(KickedBall(None, 0, 0, 1, 1, 0, 2, 0, 3)), "u", 3))
    assert not unknown.tracked_frame.kicked_ball.HasField("robot_id")


def test_round_trip_and_no_ball() -> None:
    w = WorldState(t_capture=5.0, receive_time_ns=0, ball=None, robots=())
    data = tracked_packet(w, "u", 0, source_name="Touchline test")
    p = decode(data)
    assert len(p.tracked_frame.balls) == 0 and p.source_name == "Touchline test"
    assert p.SerializeToString() == data
    full = tracked_packet(world(), "u", 9)
    assert decode(full).SerializeToString() == full


def test_the_hand_encoder_writes_the_runtimes_bytes() -> None:
    """The fast encoder is byte for byte what the generated classes write, for worlds of
    every shape (no ball, many robots, big frame numbers, extreme values)."""
    from backend.world.tracked import tracked_packet_pb

    worlds = [world(), WorldState(t_capture=0.0, receive_time_ns=0, ball=None, robots=())]
    many = tuple(RobotState("blue" if i % 2 else "yellow", i % 16, x=i * 123.4 - 6000,
                            y=-i * 77.7, orientation=-3.1 + i * 0.2, vx=i * 40.0 - 900,
                            vy=1e6 if i == 3 else -i, omega=i * 0.5, visible=i % 5 != 0,
                            predicted=i % 3 == 0, lost=i % 7 == 0,
                            t_seen=1.8e9 - (0.2 if i % 2 else 0.9)) for i in range(22))
    worlds.append(WorldState(t_capture=1.8e9 + 0.123456, receive_time_ns=1, robots=many,
                             ball=BallState(x=-0.0, y=1e-30, vx=math.inf, vy=-1e38)))
    worlds.append(kicked())
    worlds.append(kicked(KickedBall(None, -0.0, 1e-30, 0.0, math.inf, -1e38, 1e6, -1e6, -1.0)))
    worlds.append(kicked(KickedBall(("yellow", 200), 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0)))
    for w in worlds:
        for frame in (0, 1, 127, 128, 300_000, 2**32 - 1):
            assert tracked_packet(w, "station-ü", frame) == tracked_packet_pb(w, "station-ü",
                                                                               frame)


def chipped() -> WorldState:
    """A chip in the air (camera positions known) with a second ball left on the field."""
    from dataclasses import replace

    from backend.world.state import OtherBall

    w = kicked(KickedBall(("blue", 2), 0.0, 0.0, 1.0, 2000.0, 0.0, 5000.0, 0.0, 4.0, chip=True,
                          vz=3000.0, land_x=1200.0, land_y=0.0, land_t=1.6))
    ball = replace(w.ball, z=450.0, vz=-1000.0, flying=True)  # type: ignore[arg-type]
    return replace(w, ball=ball, flying_balls=True,
                   other_balls=(OtherBall(-2000.0, 1000.0, 1.0, (1, 3), 50),))


def test_a_flying_ball_and_other_balls_on_the_wire() -> None:
    f = decode(tracked_packet(chipped(), "u", 3)).tracked_frame
    assert list(f.capabilities) == [1, 2, 3]  # FLYING, MULTIPLE, KICKED
    assert len(f.balls) == 2
    b, o = f.balls
    assert (b.pos.z, b.vel.z) == pytest.approx((0.45, -1.0))
    assert (o.pos.x, o.pos.y, o.pos.z) == pytest.approx((-2.0, 1.0, 0.0))
    assert o.visibility == 1.0 and not o.HasField("vel")
    assert f.kicked_ball.vel.z == pytest.approx(3.0)
    from backend.world.tracked import tracked_packet_pb
    for frame in (0, 300):
        assert tracked_packet(chipped(), "s", frame) == tracked_packet_pb(chipped(), "s", frame)
