"""Role geometry: the widest open angle on goal, keeper, defenders, helpers."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from backend.geometry import goalkeeper_target
from backend.strategy.model import BALL_RADIUS_MM, ROBOT_RADIUS_MM, Ball, Bot
from backend.strategy.paths import Obstacles, point_is_free
from backend.strategy.roles import (
    attacker,
    best_shot,
    defender_points,
    goalkeeper,
    in_own_defense,
    keeper_y,
    kick_ball,
    push_out_of_capsule,
    push_out_of_circle,
)
from domain.field import DIVISION_B

FS = DIVISION_B
R = ROBOT_RADIUS_MM


def _open(ball: tuple[float, float], blockers: list[tuple[float, float]],
          y: float) -> bool:
    """Brute force: is the straight shot from ball to (goal x, y) clear of every blocker?"""
    gx = FS.half_length
    for cx, cy in blockers:
        if cx <= ball[0] or cx > gx + R:
            continue
        # distance from the blocker centre to the ray ball -> aim
        dx, dy = gx - ball[0], y - ball[1]
        t = ((cx - ball[0]) * dx + (cy - ball[1]) * dy) / (dx * dx + dy * dy)
        if t <= 0:
            continue
        px, py = ball[0] + dx * t, ball[1] + dy * t
        if math.hypot(cx - px, cy - py) < R + BALL_RADIUS_MM - 1e-6:
            return False
    return True


@settings(max_examples=150, deadline=None)
@given(bx=st.floats(-3000, 3500), by=st.floats(-2500, 2500),
       blockers=st.lists(st.tuples(st.floats(-1000, 4400), st.floats(-1500, 1500)),
                         max_size=5))
def test_best_shot_aims_through_the_widest_free_gap(
        bx: float, by: float, blockers: list[tuple[float, float]]) -> None:
    ball = (bx, by)
    blockers = [b for b in blockers if math.dist(b, ball) > R + BALL_RADIUS_MM + 1]
    aim, angle = best_shot(ball, blockers, FS)
    assert aim[0] == FS.half_length
    half = FS.goal_width / 2
    assert -half <= aim[1] <= half
    # sample the goal mouth: the widest run of open directions, by brute force
    ys = np.linspace(-half + BALL_RADIUS_MM + 20, half - BALL_RADIUS_MM - 20, 400)
    opens = [_open(ball, blockers, float(y)) for y in ys]
    angles = [math.atan2(float(y) - by, FS.half_length - bx) for y in ys]
    best = 0.0
    start = None
    for k, ok in enumerate(opens):
        if ok and start is None:
            start = k
        if (not ok or k == len(opens) - 1) and start is not None:
            end = k if ok else k - 1
            best = max(best, angles[end] - angles[start])
            start = None
    step = max(abs(angles[1] - angles[0]), 1e-9)
    assert abs(angle - best) <= 3 * step + 1e-6
    if angle > 3 * step:
        assert _open(ball, blockers, aim[1])  # the aim itself is clear


def test_best_shot_avoids_the_keeper_side() -> None:
    aim, angle = best_shot((3000.0, 0.0), [(4400.0, 300.0)], FS)
    assert aim[1] < 0 and angle > 0.1
    _, angle2 = best_shot((3000.0, 0.0), [(4400.0, 0.0), (4300.0, 350.0),
                                             (4300.0, -350.0)], FS)
    assert angle2 < angle


def test_kick_ball_approaches_from_behind_then_drives_through_with_the_kicker_armed() -> None:
    ball = Ball(1000.0, 0.0)
    far = Bot(1, -500.0, 800.0, 0.0)
    it = kick_ball(ball, (4500.0, 0.0), 5.0, "attacker", far)
    assert it.kick_speed_mps == 0.0 and it.x < ball.x and abs(it.y) < 1e-6
    assert it.avoid_ball_mm > 0  # circles the ball instead of pushing it sideways
    ready = Bot(1, ball.x - R - BALL_RADIUS_MM - 60.0, 0.0, 0.0)
    it2 = kick_ball(ball, (4500.0, 0.0), 5.0, "attacker", ready)
    assert it2.kick_speed_mps == 5.0 and it2.x > ball.x and not it2.plan


def test_attacker_passes_from_deep_and_shoots_when_close() -> None:
    deep = attacker(Ball(-3500.0, 0.0), Bot(1, -3700.0, 0.0, 0.0), [], FS, 5.5, 3.0)
    close = attacker(Ball(2500.0, 0.0), Bot(1, 2300.0, 0.0, 0.0), [], FS, 5.5, 3.0)
    assert deep.kick_speed_mps == 3.0 and close.kick_speed_mps == 5.5


def test_goalkeeper_intercepts_a_ball_coming_towards_goal_and_mirrors_a_still_one() -> None:
    still = goalkeeper(Ball(-2000.0, 800.0), FS, None, 300.0, 3.0)
    assert still.own_defense_ok and still.x < -FS.half_length + 200
    assert 0 < still.y <= FS.goal_width / 2
    # a shot from (-2000, 800) towards (-4500, -200): crosses the keeper line low
    v = (-2500.0, -1000.0)
    shot = goalkeeper(Ball(-2000.0, 800.0, *v), FS, None, 300.0, 3.0)
    gx = -FS.half_length + R + 30.0
    y_line = 800.0 + (gx + 2000.0) * v[1] / v[0]
    assert abs(shot.y - max(-FS.goal_width / 2 + R / 2, y_line)) < 1e-6
    # a precomputed spot (the compute engine's) is used as given
    eng = goalkeeper(Ball(-2000.0, 800.0, *v), FS, (-4300.0, 123.0), 300.0, 3.0)
    assert (eng.x, eng.y) == (-4300.0, 123.0)


def test_goalkeeper_clears_a_slow_ball_in_our_defence_area() -> None:
    it = goalkeeper(Ball(-4000.0, 300.0), FS, None, 300.0, 3.0,
                    Bot(0, -4400.0, 0.0, 0.0))
    assert it.own_defense_ok and it.role == "goalkeeper"
    assert in_own_defense((it.x, it.y), FS, 300.0)


def test_defenders_stand_outside_the_defence_area_between_ball_and_goal() -> None:
    for ball in (Ball(0.0, 0.0), Ball(-2000.0, 2500.0), Ball(-4400.0, 2800.0),
                 Ball(-3000.0, -200.0)):
        pts = defender_points(3, ball, FS, 120.0)
        assert len(pts) == 3
        for p in pts:
            assert not in_own_defense(p, FS, 120.0 + R)
        for a in pts:
            for b in pts:
                if a is not b:
                    assert math.dist(a, b) >= 2 * R


@given(bx=st.floats(-4400.0, 4400.0), by=st.floats(-2900.0, 2900.0),
       n=st.integers(2, 5), robot_margin=st.sampled_from([0.0, 60.0, 150.0]))
@settings(max_examples=60, deadline=None)
def test_each_defender_spot_is_free_of_its_neighbours_for_the_path_planner(
        bx: float, by: float, n: int, robot_margin: float) -> None:
    # the planner's own test (navigation: every other robot a disc of R + margin, the robot
    # a point grown by R): a spot inside a neighbour's disc makes both escape and plan again
    # on every tick (2 R + 40 mm apart did, with the default margin of 60 mm)
    pts = defender_points(n, Ball(bx, by), FS, 120.0, robot_margin)
    for i, p in enumerate(pts):
        others = Obstacles.build(robots=[q for j, q in enumerate(pts) if j != i],
                                 robot_radius=R + robot_margin)
        assert point_is_free(p, others, R)


def test_push_helpers_move_points_out_exactly_to_the_radius() -> None:
    p = push_out_of_circle((100.0, 0.0), (0.0, 0.0), 650.0)
    assert math.isclose(math.hypot(*p), 650.0) and p[0] > 0
    q = push_out_of_capsule((500.0, 100.0), (0.0, 0.0), (1000.0, 0.0), 650.0)
    assert math.isclose(q[1], 650.0) and math.isclose(q[0], 500.0)
    far = (3000.0, 3000.0)
    assert push_out_of_capsule(far, (0.0, 0.0), (1000.0, 0.0), 650.0) == far


@settings(max_examples=400, deadline=None)
@given(bx=st.floats(-7000, 7000), by=st.floats(-5000, 5000),
       vx=st.one_of(st.just(0.0), st.floats(-8000, 8000), st.floats(-1e-300, 1e-300)),
       vy=st.floats(-8000, 8000), min_speed=st.sampled_from([0.0, 100.0, 300.0]),
       margin=st.sampled_from([0.0, 45.0, 900.0]))
def test_keeper_y_is_goalkeeper_target_bit_for_bit(bx: float, by: float, vx: float, vy: float,
                                                   min_speed: float, margin: float) -> None:
    gx = -FS.half_length + R + 30.0
    want = goalkeeper_target((bx, by), (vx, vy), gx, FS.goal_width, margin=margin,
                             min_speed=min_speed)
    got = keeper_y(bx, by, vx, vy, gx, FS.goal_width, margin, min_speed)
    assert float(want[0]) == gx
    assert math.copysign(1.0, got) == math.copysign(1.0, float(want[1]))
    assert got.hex() == float(want[1]).hex()
