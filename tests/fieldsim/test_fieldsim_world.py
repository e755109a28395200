"""Pure physics of fieldsim.world: no sockets, no clock."""

from __future__ import annotations

import math
import random

import pytest

from fieldsim.config import SimConfig
from fieldsim.world import Team, World


def lone_world(**overrides: object) -> World:
    cfg = SimConfig(blue=1, yellow=0, **overrides)  # type: ignore[arg-type]
    w = World(cfg)
    w.teleport_robot(Team.BLUE, 0, -2.0, 0.0, 0.0)
    w.teleport_ball(3.0, 2.0)
    return w


def drive(w: World, seconds: float, forward: float, left: float = 0.0, angular: float = 0.0,
          rid: int = 0, team: Team = Team.BLUE) -> list[tuple[float, float, float]]:
    """Command at every physics step (like a 200 Hz sender); returns (t, vx, vy) per step."""
    out = []
    for _ in range(round(seconds / w.dt)):
        w.set_command(team, rid, forward, left, angular)
        w.step()
        r = w.robot(team, rid)
        assert r is not None
        out.append((w.t, r.vx, r.vy))
    return out


def test_forward_reaches_speed_and_distance() -> None:
    w = lone_world()
    a = w.config.robot_max_accel
    trace = drive(w, 2.0, 1.0)
    r = w.robot(Team.BLUE, 0)
    assert r is not None
    ramp = 1.0 / a
    # still accelerating just before the ramp ends, at speed just after
    before = [vx for t, vx, _ in trace if t <= ramp - 0.05]
    after = [vx for t, vx, _ in trace if t >= ramp + 0.02]
    assert max(before) < 0.9
    assert min(after) == pytest.approx(1.0, abs=1e-6)
    expected = 1.0 * 2.0 - 1.0 / (2 * a)
    assert r.x - (-2.0) == pytest.approx(expected, abs=0.01)
    assert abs(r.y) < 1e-9


def test_local_frame_left_and_heading() -> None:
    w = lone_world()
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, math.pi / 2)  # facing +y
    drive(w, 1.0, 0.0, 1.0)  # "left" of a robot facing +y is -x
    r = w.robot(Team.BLUE, 0)
    assert r is not None
    assert r.x < -0.6
    assert abs(r.y) < 1e-6


def test_generation1_gain_scales_speed() -> None:
    w = lone_world(generation=1, gains=[0.5])
    drive(w, 1.0, 1.0)
    r = w.robot(Team.BLUE, 0)
    assert r is not None
    assert r.gain == 0.5
    assert r.vx == pytest.approx(0.5, abs=1e-6)


def test_generation1_drawn_gains_unequal_and_seeded() -> None:
    cfg = SimConfig(generation=1, seed=7)
    gains = [r.gain for r in World(cfg).robots.values()]
    assert len(set(gains)) == len(gains)
    assert all(0.6 <= g <= 1.4 for g in gains)
    assert gains == [r.gain for r in World(SimConfig(generation=1, seed=7)).robots.values()]
    assert gains != [r.gain for r in World(SimConfig(generation=1, seed=8)).robots.values()]
    assert all(r.gain == 1.0 for r in World(SimConfig(generation=2)).robots.values())


def test_acceleration_limit_never_exceeded() -> None:
    w = lone_world()
    rng = random.Random(3)
    a = w.config.robot_max_accel
    prev = (0.0, 0.0)
    cmd = (3.0, -3.0, 5.0)
    for _ in range(400):
        if rng.random() < 0.05:
            cmd = (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-5, 5))
        w.set_command(Team.BLUE, 0, *cmd)
        w.teleport_ball(3.0, 2.0)
        w.step()
        r = w.robot(Team.BLUE, 0)
        assert r is not None
        dv = math.hypot(r.vx - prev[0], r.vy - prev[1])
        assert dv <= a * w.dt + 1e-9
        assert math.hypot(r.vx, r.vy) <= w.config.robot_max_speed + 1e-9
        prev = (r.vx, r.vy)


def test_robot_stops_after_command_timeout() -> None:
    w = lone_world()
    drive(w, 1.0, 1.0)
    t_last = w.t
    w.set_command(Team.BLUE, 0, 1.0, 0.0, 0.0)
    r = w.robot(Team.BLUE, 0)
    assert r is not None
    speeds = []
    while w.t < t_last + 1.0:
        w.step()
        speeds.append((w.t - t_last, r.vx))
    # keeps the last command for the timeout, then brakes at the accel limit
    assert all(v == pytest.approx(1.0) for t, v in speeds if t < 0.19)
    stop_by = 0.2 + 1.0 / w.config.robot_max_accel + 0.02
    assert all(v == 0.0 for t, v in speeds if t > stop_by)
    assert any(0.0 < v < 1.0 for t, v in speeds)


def test_ball_friction_decelerates() -> None:
    w = lone_world()
    w.teleport_ball(0.0, 0.0, 2.0, 0.0)
    for _ in range(round(1.0 / w.dt)):
        w.step()
    assert w.ball.vx == pytest.approx(2.0 - w.config.ball_rolling_decel, abs=0.01)
    assert w.ball.x == pytest.approx(2.0 - w.config.ball_rolling_decel / 2, abs=0.02)
    for _ in range(round(6.0 / w.dt)):
        w.step()
    assert w.ball.vx == 0.0


def test_ball_bounces_off_wall() -> None:
    w = lone_world()
    wall = w.geometry.wall_x / 1000.0
    w.teleport_ball(wall - 0.3, 1.5, 3.0, 0.0)  # beside the goal, not into it
    seen_reverse = False
    for _ in range(200):
        w.step()
        assert w.ball.x <= wall - w.config.ball_radius_m + 1e-9
        if w.ball.vx < 0:
            seen_reverse = True
    assert seen_reverse
    assert w.ball.vx < -1.0  # damped but reversed
    assert w.stats.ball_wall_bounces == 1


def test_kick_along_heading() -> None:
    w = lone_world()
    for heading in (0.0, math.pi / 2, -2.5):
        w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, heading)
        d = w.config.robot_radius_m + w.config.ball_radius_m + 0.005
        w.teleport_ball(d * math.cos(heading), d * math.sin(heading))
        w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=5.0)
        w.step()
        speed = math.hypot(w.ball.vx, w.ball.vy)
        assert speed == pytest.approx(5.0, abs=0.01)
        assert math.atan2(w.ball.vy, w.ball.vx) == pytest.approx(heading, abs=1e-6)


def test_no_kick_from_behind_or_unarmed() -> None:
    w = lone_world()
    d = w.config.robot_radius_m + w.config.ball_radius_m + 0.005
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, 0.0)
    w.teleport_ball(-d, 0.0)  # behind
    w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=5.0)
    w.step()
    assert math.hypot(w.ball.vx, w.ball.vy) < 0.01
    w.teleport_ball(d, 0.0)  # in front, kicker not armed
    w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0)
    w.step()
    assert math.hypot(w.ball.vx, w.ball.vy) < 0.01


def test_chip_kick_ground_speed() -> None:
    w = lone_world()
    d = w.config.robot_radius_m + w.config.ball_radius_m + 0.005
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, 0.0)
    w.teleport_ball(d, 0.0)
    w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=4.0, kick_angle=math.radians(45))
    w.step()
    assert w.ball.vx == pytest.approx(4.0 * math.cos(math.radians(45)), abs=0.01)
    assert w.ball.vz > 2.0
    peak = 0.0
    for _ in range(400):
        w.step()
        peak = max(peak, w.ball.z)
    assert peak > 0.3
    assert w.ball.z == 0.0


def test_robots_do_not_overlap() -> None:
    w = World(SimConfig(blue=6, yellow=6))
    # everybody drives to the centre
    for _ in range(round(4.0 / w.dt)):
        for r in w.robots.values():
            dx, dy = -r.x, -r.y
            n = math.hypot(dx, dy) or 1.0
            c, s = math.cos(r.theta), math.sin(r.theta)
            w.set_command(r.team, r.id, 2.0 * (c * dx + s * dy) / n, 2.0 * (-s * dx + c * dy) / n,
                          0.0)
        w.step()
    robots = list(w.robots.values())
    two_r = 2 * w.config.robot_radius_m
    worst = min(
        math.hypot(a.x - b.x, a.y - b.y) for i, a in enumerate(robots) for b in robots[i + 1:]
    )
    assert worst >= two_r - 0.005
    # they did reach the crowd in the middle
    assert max(math.hypot(r.x, r.y) for r in robots) < 0.8


def test_ball_pushed_slowly_does_not_pass_through() -> None:
    w = lone_world()
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, 0.0)
    w.teleport_ball(0.2, 0.0)
    drive(w, 3.0, 0.4)
    r = w.robot(Team.BLUE, 0)
    assert r is not None
    assert r.x > 0.8  # the robot moved well past the ball's start
    assert w.ball.x > r.x + w.config.robot_radius_m  # ball still in front


def test_ball_bounces_off_robot() -> None:
    w = lone_world()
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, 0.0)
    w.teleport_ball(-1.0, 0.0, 2.0, 0.0)
    for _ in range(200):
        w.step()
        assert math.hypot(w.ball.x, w.ball.y) >= 0.09 + 0.0215 - 1e-9
    assert w.ball.vx < 0.0


def test_teleport_and_remove() -> None:
    w = World(SimConfig())
    assert w.remove_robot(Team.YELLOW, 2)
    assert w.robot(Team.YELLOW, 2) is None
    assert not w.teleport_robot(Team.YELLOW, 2, 1.0, 1.0, add=False)
    assert w.teleport_robot(Team.YELLOW, 2, 1.0, 1.0, 0.5, add=True)
    r = w.robot(Team.YELLOW, 2)
    assert r is not None and (r.x, r.y, r.theta) == (1.0, 1.0, 0.5)
    with pytest.raises(ValueError):
        w.set_command(Team.YELLOW, 2, math.nan, 0.0, 0.0)
    with pytest.raises(ValueError):
        w.add_robot(Team.BLUE, 16, 0.0, 0.0, 0.0)


def test_start_formation_on_own_halves() -> None:
    w = World(SimConfig(blue=11, yellow=11))
    assert len(w.robots) == 22
    assert all(r.x < 0 for r in w.robots.values() if r.team is Team.BLUE)
    assert all(r.x > 0 for r in w.robots.values() if r.team is Team.YELLOW)
    w2 = World(SimConfig(blue_on_positive_half=True))
    assert all(r.x > 0 for r in w2.robots.values() if r.team is Team.BLUE)
