"""Rules for a stopped game that the whole strategy (plays + navigation) must keep, on many
random scenes: the 0.2 m from the opponents' defence area during STOP and free kicks, and our
ball placer fetching a ball from inside a defence area."""

from __future__ import annotations

import math
import random

import pytest

from backend.params.model import StrategyParams
from backend.strategy.core import StrategyCore
from backend.strategy.model import ROBOT_RADIUS_MM as R
from backend.world.referee import RefereeState
from backend.world.state import BallState, RobotState, WorldState

GEOM = {"field_length": 9000.0, "field_width": 6000.0, "goal_width": 1000.0,
        "goal_depth": 180.0, "penalty_area_depth": 1000.0, "penalty_area_width": 2000.0}
HL = 4500.0
# blue defends -x (our side negative): their defence area in the field frame
THEIRS = (HL - 1000.0, -1000.0, HL, 1000.0)


def rect_dist(p: tuple[float, float], r: tuple[float, float, float, float]) -> float:
    dx = max(r[0] - p[0], 0.0, p[0] - r[2])
    dy = max(r[1] - p[1], 0.0, p[1] - r[3])
    return math.hypot(dx, dy)


def referee(command: str, designated: tuple[float, float] | None = None) -> RefereeState:
    team = {"goalkeeper": 0}
    return RefereeState(command, "NORMAL_FIRST_HALF", 1, None, team, team, designated, None, 0)


def scene(rnd: random.Random) -> WorldState:
    """Robots anywhere, several of them close to the opponents' defence area; the ball in
    front of that area."""
    robots = []
    for team in ("blue", "yellow"):
        for i in range(6):
            if team == "blue" and i >= 3:  # near their defence area, outside 0.2 m + R
                x, y = rnd.uniform(2800.0, 3100.0), rnd.uniform(-1500.0, 1500.0)
            else:
                x, y = rnd.uniform(-4000.0, 4000.0), rnd.uniform(-2700.0, 2700.0)
            robots.append(RobotState(team, i, x, y, rnd.uniform(-math.pi, math.pi)))
    ball = BallState(rnd.uniform(2300.0, 3300.0), rnd.uniform(-1500.0, 1500.0), 0.0, 0.0)
    return WorldState(0.0, 0, ball, tuple(robots))


def closest_to_their_area(command: str | None, seeds: range) -> float:
    """The smallest distance (mm) from any planned point of any blue robot that started
    outside the rules' zone to the opponents' defence area, minus the robot radius."""
    worst = math.inf
    for seed in seeds:
        rnd = random.Random(seed)
        world = scene(rnd)
        core = StrategyCore()
        ref = referee(command) if command else None
        prep = core.prepare(world, GEOM, ref, StrategyParams(play="match"), "blue", True, False,
                            0.0)
        moves = core.decide(prep)
        for r in world.robots:
            if r.team != "blue" or rect_dist((r.x, r.y), THEIRS) < R + 200.0:
                continue
            m = moves[r.id]
            for p in (*m.path, (m.x, m.y)):
                worst = min(worst, rect_dist(p, THEIRS) - R)
    return worst


@pytest.mark.parametrize("command", ["STOP", "DIRECT_FREE_YELLOW", "DIRECT_FREE_BLUE"])
def test_stopped_game_keeps_0_2_m_from_their_defence_area(command: str) -> None:
    assert closest_to_their_area(command, range(40)) >= 200.0


def test_running_play_may_come_closer_to_their_defence_area() -> None:
    """The same scenes in running play use the normal margin: the stopped-game margin above
    is what keeps the robots away, not the scenes."""
    assert closest_to_their_area(None, range(40)) < 200.0


@pytest.mark.parametrize("ball", [(HL - 300.0, 300.0), (-HL + 300.0, -300.0)])
def test_our_placer_goes_into_a_defence_area_for_the_ball(ball: tuple[float, float]) -> None:
    robots = tuple(RobotState("blue", i, -1000.0 + 300.0 * i, 1500.0, 0.0) for i in range(1, 6))
    world = WorldState(0.0, 0, BallState(ball[0], ball[1], 0.0, 0.0), robots)
    core = StrategyCore()
    mark = (0.0, 0.0)
    prep = core.prepare(world, GEOM, referee("BALL_PLACEMENT_BLUE", mark),
                        StrategyParams(play="match"), "blue", True, False, 0.0)
    moves = core.decide(prep)
    (placer,) = [m for m in moves.values() if m.role == "placer"]
    # behind the ball as seen from the mark: inside the area, not stopped at its edge
    area = THEIRS if ball[0] > 0 else (-HL, -1000.0, -HL + 1000.0, 1000.0)
    assert rect_dist((placer.x, placer.y), area) == 0.0
    assert math.dist((placer.x, placer.y), ball) < 300.0
