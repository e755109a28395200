"""Chip flight in fieldsim: the ballistic arc, its bounces, and where each camera draws it."""

from __future__ import annotations

import itertools
import math

import pytest

from fieldsim.ball_physics import MIN_BOUNCE_MPS, apex, flight_time
from fieldsim.bodies import Ball
from fieldsim.cameras import make_cameras
from fieldsim.config import SimConfig
from fieldsim.protocol import CommandHandler
from fieldsim.vision import Vision
from fieldsim.world import Team, World
from sslpb import ssl_simulation_robot_control_pb2 as rc_pb

G = 9.81


def chip_world(**overrides: object) -> World:
    """One blue robot at (-2, 0) facing +x with the ball at its kicker, nobody else near."""
    cfg = SimConfig(blue=1, yellow=0, **overrides)  # type: ignore[arg-type]
    w = World(cfg)
    w.teleport_robot(Team.BLUE, 0, -2.0, 0.0, 0.0)
    d = cfg.robot_radius_m + cfg.ball_radius_m + 0.002
    w.teleport_ball(-2.0 + d, 0.0)
    return w


def heights(w: World, seconds: float) -> list[tuple[float, float, float, float]]:
    """(t, x, z, vz) after every step for ``seconds``."""
    out = []
    for _ in range(round(seconds / w.dt)):
        w.step()
        out.append((w.t, w.ball.x, w.ball.z, w.ball.vz))
    return out


def test_flight_time_and_apex_of_a_chip_kick() -> None:
    w = chip_world()
    speed, angle = 5.0, math.radians(45)
    w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=speed, kick_angle=angle)
    w.step()
    t_kick = w.t
    vz = speed * math.sin(angle)
    assert w.ball.vz == pytest.approx(vz, abs=0.05)
    assert w.robot(Team.BLUE, 0) is not None and w.robot(Team.BLUE, 0).last_kick_chip  # type: ignore[union-attr]
    trace = heights(w, 3.0)
    # the first landing: the step where the vertical speed turns upwards again (a bounce)
    i_land = next(i for i in range(1, len(trace)) if trace[i][3] > trace[i - 1][3])
    landing = trace[i_land][0]
    # the ball lands within a step of 2 vz / g, at its apex vz^2 / 2g
    assert landing - t_kick == pytest.approx(2 * vz / G, abs=2 * w.dt)
    assert flight_time(vz, G) == pytest.approx(2 * vz / G)
    assert max(z for _, _, z, _ in trace) == pytest.approx(apex(vz, G), rel=0.02)
    # no rolling friction in the air: the ground speed is kept over the flight
    x_land = trace[i_land][1]
    x0 = -2.0 + w.config.robot_radius_m + w.config.ball_radius_m + 0.002
    assert x_land - x0 == pytest.approx(speed * math.cos(angle) * 2 * vz / G, rel=0.03)


def test_bounces_decrease_by_the_restitution_then_the_ball_rolls() -> None:
    w = chip_world(chip_bounce_restitution=0.5)
    w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=6.0, kick_angle=math.radians(60))
    trace = heights(w, 4.0)
    # apexes of the successive hops: local maxima of z
    apexes = [trace[i][2] for i in range(1, len(trace) - 1)
              if trace[i][2] > 0.0 and trace[i - 1][2] <= trace[i][2] > trace[i + 1][2]]
    assert len(apexes) >= 3
    for a, b in itertools.pairwise(apexes):
        # each hop leaves with half the vertical speed: a quarter of the height
        assert b == pytest.approx(a * 0.25, rel=0.1)
    # then it rolls (on the ground, friction), and stops
    assert trace[-1][2] == 0.0 and trace[-1][3] == 0.0
    assert w.ball.vx < 6.0 * math.cos(math.radians(60))


def test_a_slow_bounce_ends_the_flight() -> None:
    cfg = SimConfig(blue=0, yellow=0, chip_bounce_restitution=0.5)
    w = World(cfg)
    w.teleport_ball(0.0, 0.0, 0.0, 0.0, z=0.0, vz=1.2 * MIN_BOUNCE_MPS / 0.5)
    heights(w, 1.0)
    assert w.ball.z == 0.0 and w.ball.vz == 0.0


def test_a_chip_through_the_simulation_protocol() -> None:
    w = chip_world()
    h = CommandHandler(w)
    msg = rc_pb.RobotControl()
    cmd = msg.robot_commands.add(id=0, kick_speed=4.0, kick_angle=30.0)  # degrees on the wire
    cmd.move_command.local_velocity.forward = 0.0
    cmd.move_command.local_velocity.left = 0.0
    cmd.move_command.local_velocity.angular = 0.0
    h.robot_control(Team.BLUE, msg.SerializeToString())
    w.step()
    assert w.ball.vz == pytest.approx(4.0 * math.sin(math.radians(30)), abs=0.05)
    assert math.hypot(w.ball.vx, w.ball.vy) == pytest.approx(4.0 * math.cos(math.radians(30)),
                                                             abs=0.05)


def test_each_camera_draws_a_flying_ball_at_its_ground_projection() -> None:
    cfg = SimConfig(blue=0, yellow=0, cameras=4, noise_mm=0.0, miss_prob=0.0)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    cams = make_cameras(cfg, w.geometry)
    # in the overlap near the centre: all four cameras see the ball, 0.2 m up
    w.teleport_ball(0.1, 0.05, z=0.2)
    w.ball.vz = 0.0
    seen = {}
    for cam in cams:
        frame = v.detect(cam.camera_id, w, 1000.0).detection
        assert len(frame.balls) == 1
        b = frame.balls[0]
        assert not b.HasField("z") or b.z == 0.0  # no height, like SSL-Vision
        seen[cam.camera_id] = (b.x, b.y)
        # the ray from the camera through the ball meets the ground there
        k = cam.height / (cam.height - 200.0)
        assert b.x == pytest.approx(cam.cx + (100.0 - cam.cx) * k, abs=1e-3)
        assert b.y == pytest.approx(cam.cy + (50.0 - cam.cy) * k, abs=1e-3)
    # the cameras disagree, by about their distance times z / (H - z)
    spread = max(math.dist(seen[a], seen[b]) for a in seen for b in seen)
    assert spread > 200.0
    # the geometry packet says where the cameras are
    calib = {c.camera_id: c for c in v.geometry_packet().geometry.calib}
    for cam in cams:
        c = calib[cam.camera_id]
        assert (c.derived_camera_world_tx, c.derived_camera_world_ty,
                c.derived_camera_world_tz) == pytest.approx((cam.cx, cam.cy, cam.height))


def test_a_ball_on_the_ground_is_drawn_where_it_is() -> None:
    cam = make_cameras(SimConfig(), World(SimConfig(blue=0, yellow=0)).geometry)[0]
    assert cam.ground_point(-1234.0, 567.0, 0.0) == (-1234.0, 567.0)


def test_other_balls_are_seen_and_stay() -> None:
    cfg = SimConfig(blue=0, yellow=0, noise_mm=0.0, miss_prob=0.0, other_balls=[(1.0, 1.0)])
    w = World(cfg)
    w.teleport_ball(-1.0, -1.0)
    extra = w.add_ball(2.0, -1.5)
    assert isinstance(extra, Ball) and len(w.other_balls) == 2
    v = Vision(cfg, w.geometry)
    for _ in range(20):
        w.step()
    xs = sorted((round(b.x), round(b.y)) for k in range(4)
                for b in v.detect(k, w, 1000.0 + w.t).detection.balls)
    assert (-1000, -1000) in xs and (1000, 1000) in xs and (2000, -1500) in xs
    assert w.truth()["other_balls"][0] == {"x": 1000.0, "y": 1000.0, "z": 0.0}
    assert w.clear_other_balls() == 2 and not w.other_balls
    with pytest.raises(ValueError):
        w.add_ball(math.nan, 0.0)
