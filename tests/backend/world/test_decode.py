"""decode_detection against a plain reference (math.isfinite, HasField for the orientation):
robots without an id, ids over 15, non-finite positions and orientations, non-finite balls."""

from __future__ import annotations

import itertools
import math

from backend.world.decode import decode_detection
from backend.world.state import CameraFrame, RawBall, RawRobot, Team
from sslpb.ssl_vision_detection_pb2 import SSL_DetectionFrame

ODD = (0.0, -0.0, 1.5, -2500.25, 1e30, math.inf, -math.inf, math.nan)


def reference(frame: SSL_DetectionFrame, receive_time_ns: int) -> CameraFrame:
    robots: list[RawRobot] = []
    team: Team
    for team, dets in (("yellow", frame.robots_yellow), ("blue", frame.robots_blue)):
        for d in dets:
            if not d.HasField("robot_id") or d.robot_id > 15:
                continue
            if not (math.isfinite(d.x) and math.isfinite(d.y)):
                continue
            ori = d.orientation if d.HasField("orientation") else 0.0
            robots.append(RawRobot(team, d.robot_id, d.x, d.y,
                                   ori if math.isfinite(ori) else 0.0, d.confidence))
    balls = [RawBall(b.x, b.y, b.confidence) for b in frame.balls
             if math.isfinite(b.x) and math.isfinite(b.y)]
    return CameraFrame(frame.camera_id, frame.frame_number, frame.t_capture, frame.t_sent,
                       receive_time_ns, tuple(balls), tuple(robots))


def frame_with_odd_values() -> SSL_DetectionFrame:
    f = SSL_DetectionFrame(frame_number=7, t_capture=100.5, t_sent=100.51, camera_id=3)
    for k, (x, y, ori) in enumerate(itertools.product(ODD, ODD, (*ODD, None))):
        r = (f.robots_blue if k % 2 else f.robots_yellow).add(
            confidence=0.5, x=x, y=y, pixel_x=0.0, pixel_y=0.0)
        if k % 7:  # every seventh without an id; ids 0..17 (16 and 17: out of range)
            r.robot_id = k % 18
        if ori is not None:
            r.orientation = ori
    for x, y in itertools.product(ODD, ODD):
        f.balls.add(confidence=0.25, x=x, y=y, pixel_x=0.0, pixel_y=0.0)
    return f


def same(a: object, b: object) -> bool:
    """Equal, with NaN equal to NaN and -0.0 told from 0.0 (repr of every float)."""
    return repr(a) == repr(b)


def test_decode_matches_the_reference_for_odd_values() -> None:
    f = frame_with_odd_values()
    got, want = decode_detection(f, 123), reference(f, 123)
    assert same(got, want)
    assert got.robots and got.balls  # something is kept, and something dropped
    assert len(got.robots) < len(f.robots_blue) + len(f.robots_yellow)
    assert len(got.balls) < len(f.balls)
    assert all(math.isfinite(v) for r in got.robots for v in (r.x, r.y, r.orientation))
    assert all(math.isfinite(v) for b in got.balls for v in (b.x, b.y))
    assert all(r.id <= 15 for r in got.robots)


def test_decoded_detections_read_by_name() -> None:
    f = SSL_DetectionFrame(frame_number=1, t_capture=2.0, t_sent=2.0, camera_id=0)
    f.robots_blue.add(confidence=0.9, robot_id=4, x=10.0, y=-20.0, pixel_x=0, pixel_y=0)
    f.balls.add(confidence=0.8, x=1.0, y=2.0, pixel_x=0, pixel_y=0)
    got = decode_detection(f, 5)
    (r,), (b,) = got.robots, got.balls
    assert (r.team, r.id, r.x, r.y, r.orientation, r.confidence) == \
        ("blue", 4, 10.0, -20.0, 0.0, r.confidence)
    assert math.isclose(r.confidence, 0.9, rel_tol=1e-6)
    assert type(r) is RawRobot and type(b) is RawBall
    assert (b.x, b.y) == (1.0, 2.0)
    assert repr(r).startswith("RawRobot(team='blue', id=4, x=10.0, y=-20.0, orientation=0.0")
    assert got.receive_time_ns == 5 and got.camera_id == 0
