"""touchline.lib: the built-in strategy's pieces for a team's plays, over the Game snapshot
(our frame), and usable from a play in its worker."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

from touchline import Ball, FieldSize, Game, Referee, Robot, Target
from touchline.lib import (
    attacker,
    best_shot,
    defender_spots,
    geometry,
    goalkeeper,
    kick_ball,
    plan_path,
)

from .helpers import answer, game, started, write

F = FieldSize()
HL = F.half_length


def snap(ours: list[Robot], theirs: list[Robot], ball: Ball | None,
         keeper: int | None = None) -> Game:
    return Game(1, 0.0, "blue", "negative-x", tuple(ours), tuple(theirs), ball,
                Referee(goalkeeper=keeper), F, mine=tuple(r.id for r in ours))


def seg_dist(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    return float(geometry.point_segment_distance(p, a, b))


def test_plan_path_goes_around_a_robot_in_the_way() -> None:
    g = snap([Robot(1, -2000.0, 0.0, 0.0)], [Robot(4, 0.0, 0.0, math.pi)], None)
    pts = plan_path(g, 1, 2000.0, 0.0)
    assert len(pts) >= 2 and pts[-1] == (2000.0, 0.0)
    route = [(-2000.0, 0.0), *pts]
    clearance = 90.0 + 60.0 + 90.0  # their body + margin + ours
    assert all(seg_dist((0.0, 0.0), a, b) >= clearance - 1.0
               for a, b in itertools.pairwise(route))
    # nothing in the way: straight
    assert plan_path(g, 1, -2000.0, 1500.0) == [(-2000.0, 1500.0)]
    # a robot not on the field: the goal itself
    assert plan_path(g, 9, 10.0, 20.0) == [(10.0, 20.0)]


def test_plan_path_keeps_out_of_our_area_unless_the_goalkeeper() -> None:
    start, goal = (-HL + 1500.0, -1500.0), (-HL + 1500.0, 1500.0)
    ours = [Robot(0, *start, 0.0)]
    crossing = snap(ours, [], None)  # straight line crosses nothing: it passes the area
    assert plan_path(crossing, 0, *goal) == [goal]
    start2 = (-HL + 300.0, -1500.0)
    g = snap([Robot(0, *start2, 0.0)], [], None, keeper=None)
    pts = plan_path(g, 0, -HL + 300.0, 1500.0)
    route = [start2, *pts]
    area = (-HL, -F.penalty_area_width / 2, -HL + F.penalty_area_depth,
            F.penalty_area_width / 2)
    assert len(pts) >= 2  # around the area
    for a, b in itertools.pairwise(route):
        mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
        assert not (area[0] < mid[0] < area[2] and area[1] < mid[1] < area[3])
    keeper = snap([Robot(0, *start2, 0.0)], [], None, keeper=0)
    assert plan_path(keeper, 0, -HL + 300.0, 1500.0) == [(-HL + 300.0, 1500.0)]


def test_goalkeeper_defenders_attacker_shot() -> None:
    slow = snap([Robot(0, -HL + 200.0, 0.0, 0.0), Robot(1, -1000.0, 0.0, 0.0)], [],
                Ball(-1000.0, 300.0), keeper=0)
    k = goalkeeper(slow)
    assert isinstance(k, Target) and k.x == -HL + 90.0 + 30.0
    # a slow ball: on the bisector of the angle the mouth makes at it, which divides the
    # mouth as the ball's distances to the posts (at the keeper's line): a little up
    h, dx = F.goal_width / 2, -1000.0 - k.x
    d1, d2 = math.hypot(dx, 300.0 - h), math.hypot(dx, 300.0 + h)
    assert math.isclose(k.y, h * (d2 - d1) / (d1 + d2)) and 0.0 < k.y < 300.0
    assert k.role == "goalkeeper"
    towards = snap(slow.ours, [], Ball(-1000.0, 0.0, -2000.0, -100.0), keeper=0)
    k2 = goalkeeper(towards)
    expect = 0.0 + (k2.x - -1000.0) * -100.0 / -2000.0  # where its path crosses
    assert math.isclose(k2.y, expect)
    spots = defender_spots(slow, 3)
    assert len(spots) == 3 and len(set(spots)) == 3
    for x, y in spots:
        assert not F.in_our_defense_area(x, y) and x > -HL + F.penalty_area_depth
    a = attacker(slow, 1)
    assert a.x < -1000.0 and a.role == "attacker"  # behind the ball, towards their goal
    (aim, angle) = best_shot(slow)
    assert aim[0] == HL and abs(aim[1]) < 10.0 and angle > 0.0
    blocked = snap(slow.ours, [Robot(3, HL - 300.0, 0.0, math.pi)], slow.ball)
    aim2, angle2 = best_shot(blocked)
    assert abs(aim2[1]) > 100.0 and 0.0 < angle2 < angle
    assert kick_ball(slow, 9, (0.0, 0.0), 3.0).role == "kicker"  # no such robot: no crash


async def test_a_play_uses_the_library_in_its_worker(tmp_path: Path) -> None:
    write(tmp_path, "lib_user.py",
          "from touchline import Target\n"
          "from touchline.lib import defender_spots, goalkeeper, plan_path\n"
          "def play(game):\n"
          "    keeper, *rest = sorted(game.mine)\n"
          "    out = {keeper: goalkeeper(game, rid=keeper)}\n"
          "    for rid, (x, y) in zip(rest, defender_spots(game, len(rest))):\n"
          "        out[rid] = Target(x, y, 0.0, role='defender')\n"
          "    way = plan_path(game, keeper, 500.0, 0.0)\n"
          "    end = f'{way[-1][0]:.0f},{way[-1][1]:.0f}'\n"
          "    out[keeper] = Target(out[keeper].x, out[keeper].y, role=f'{len(way)}:{end}')\n"
          "    return out\n")
    r = await started(tmp_path, "lib_user.py")
    try:
        p = await answer(r.send(game((1, 2, 3)), None, 5.0))
        assert r.run.error is None, r.run.error
        assert p.output is not None and [o[1] for o in p.output] == [1, 2, 3]
        roles = [o[10] for o in p.output]
        assert roles[1:] == ["defender", "defender"]
        n, end = roles[0].split(":")
        assert int(n) >= 2 and end == "500,0"  # robots 2 and 3 stand on the straight way
    finally:
        await r.close()
