"""Obstacle avoidance for every move: each robot's intent becomes a path around the other
robots, the defence areas it may not enter, and the ball when it must keep clear of it.

Obstacles (our frame): every other robot (a disc of the robot radius plus a margin), the
opponents' defence area always and ours except for the keeper (grown by a margin), the ball
(a disc of ``Intent.avoid_ball_mm`` around it), and during the other team's ball placement
the whole corridor from the ball to the mark. ``plan_path`` inflates them by our robot's
radius, so the planned centre line keeps the robot's body clear.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from domain.field import Field

from .model import ROBOT_RADIUS_MM, Ball, Bot, Frame, Intent, Move, own_defense, their_defense
from .paths import (
    Obstacles,
    PathMemory,
    plan_path,
    straight_clear_of_circles,
    straight_clear_of_rest,
)

R = ROBOT_RADIUS_MM

#: another robot's centre this close ahead (within 60 deg of the way we go) caps our speed:
#: a crash above 1.5 m/s relative is a foul, and paths avoid robots where they are, not
#: where they will be
GUARD_MM = 650.0
GUARD_COS = 0.5
GUARD_SPEED_MPS = 0.75  # two robots driving at each other: 1.5 m/s relative at most


def _rect_grow(r: tuple[float, float, float, float], g: float) -> list[float]:
    return [r[0] - g, r[1] - g, r[2] + g, r[3] + g]


def _finite(*v: float) -> bool:
    return all(math.isfinite(x) for x in v)


def _valid_rows(c: NDArray[np.float64]) -> bool:
    """Circles (K, 3) as ``Obstacles`` takes them: finite, radii >= 0."""
    return bool(np.isfinite(c).all() and (c[:, 2] >= 0.0).all())


def _inside(p: tuple[float, float], r: Sequence[float], g: float) -> bool:
    return r[0] - g <= p[0] <= r[2] + g and r[1] - g <= p[1] <= r[3] + g


def navigate(intents: dict[int, Intent], ours: Sequence[Bot], theirs: Sequence[Bot],
             ball: Ball | None, fs: Field, frame: Frame, robot_margin_mm: float,
             defense_margin_mm: float,
             corridor: tuple[tuple[float, float], tuple[float, float], float] | None = None,
             their_defense_margin_mm: float | None = None,
             memory: PathMemory | None = None, now: float = 0.0,
             pause: Callable[[], None] | None = None,
             ) -> dict[int, Move]:
    """Paths for every intent, returned as moves in the field frame.

    ``corridor`` = (ball, mark, radius): keep clear of the capsule around that segment.
    ``their_defense_margin_mm``: how far the robots' bodies keep from the opponents' defence
    area (default ``defense_margin_mm``; the rules ask 0.2 m while the game is stopped).
    ``memory``: the robots' earlier searches, reused when they still hold (``now``: the
    tick's time, s); without it every robot plans afresh. ``pause``: called between two
    robots (the processor lets the station thread have the GIL there).
    """
    everyone = [("o", b) for b in ours] + [("t", b) for b in theirs]
    all_circles = np.array([[b.x, b.y, R + robot_margin_mm] for _, b in everyone],
                           dtype=np.float64).reshape(-1, 3)
    their_def = _rect_grow(their_defense(fs), defense_margin_mm
                           if their_defense_margin_mm is None else their_defense_margin_mm)
    own_def = _rect_grow(own_defense(fs), defense_margin_mm)
    extra_circles: list[list[float]] = []
    if corridor is not None:
        a, b, rad = corridor
        r = max(1.0, rad - R)
        # discs half a radius apart: the capsule's edge is covered to 3 % of the radius
        n = max(1, math.ceil(math.dist(a, b) / (0.5 * r)))
        for k in range(n + 1):
            t = k / n
            extra_circles.append([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, r])
    bounds = (-fs.half_length - 150.0, -fs.half_width - 150.0,
              fs.half_length + 150.0, fs.half_width + 150.0)
    extra_arr = np.array(extra_circles, dtype=np.float64).reshape(-1, 3)
    out: dict[int, Move] = {}
    searched: set[int] = set()
    mine = [idx for idx, (kind, bot) in enumerate(everyone)
            if kind == "o" and bot.id in intents]
    # the tick's arrays, checked once: each robot's obstacles are rows of them (its ball disc
    # aside), so they need no check of their own (else Obstacles checks, and refuses, as it
    # always did)
    rect_rows: dict[tuple[bool, bool], NDArray[np.float64]] = {}
    checked = _valid_rows(all_circles) and _valid_rows(extra_arr) \
        and all(_finite(*r) and r[0] <= r[2] and r[1] <= r[3] for r in (their_def, own_def))
    clear: dict[int, bool] = {}
    if memory is not None and mine:
        # the straight test against the robots and the corridor for all our robots in one
        # numpy pass (each robot's own ball disc, areas and bounds follow in plain floats)
        common = np.concatenate([all_circles, extra_arr])
        ends = np.array([[everyone[i][1].x, everyone[i][1].y,
                          intents[everyone[i][1].id].x, intents[everyone[i][1].id].y]
                         for i in mine], dtype=np.float64)
        ok = straight_clear_of_circles(ends[:, :2], ends[:, 2:], common, R,
                                       np.asarray(mine, dtype=np.int64))
        clear = dict(zip(mine, ok.tolist(), strict=True))
    for n, idx in enumerate(mine):
        if pause is not None and n:
            pause()
        bot = everyone[idx][1]
        it = intents[bot.id]
        goal = (it.x, it.y)
        rects = ([] if it.their_defense_ok else [their_def]) \
            + ([] if it.own_defense_ok else [own_def])
        plan = it.plan
        if not plan and any(_inside(goal, r, 0.0) for r in rects):
            plan = True  # a straight drive would end in a forbidden area: plan instead
        blocked = False
        pts: tuple[tuple[float, float], ...]
        ball_disc = [[ball.x, ball.y, max(1.0, it.avoid_ball_mm - R)]] \
            if it.avoid_ball_mm > 0.0 and ball is not None else []
        if plan and clear.get(idx) and _finite(goal[0], goal[1], bot.x, bot.y) \
                and straight_clear_of_rest(bot.xy, goal, ball_disc, rects, R, bounds):
            # the common case: nothing to plan, nothing to remember (a value that is not
            # finite goes to plan_path, which refuses it as before)
            pts = (goal,)
        elif plan:
            circles = np.concatenate([all_circles[:idx], all_circles[idx + 1:], extra_arr,
                                      np.array(ball_disc, dtype=np.float64).reshape(-1, 3)])
            key = (it.their_defense_ok, it.own_defense_ok)
            rect_arr = rect_rows.get(key)
            if rect_arr is None:  # shared by the robots allowed the same areas: read-only
                rect_arr = rect_rows[key] = np.array(rects, dtype=np.float64).reshape(-1, 4)
                rect_arr.flags.writeable = False
            if checked and all(_finite(*d) and d[2] >= 0.0 for d in ball_disc):
                obstacles = Obstacles.trusted(circles, rect_arr)
            else:
                obstacles = Obstacles(circles=circles, rects=rect_arr)
            if memory is None:
                res = plan_path(bot.xy, goal, obstacles, R, bounds=bounds)
                pts = tuple(res.points) if res.points else (goal,)
                blocked = res.blocked
            else:
                pts, blocked = memory.path(bot.id, bot.xy, goal, obstacles, bounds, now)
                searched.add(bot.id)
        else:
            pts = (goal,)
        end = pts[-1]
        max_speed = it.max_speed_mps
        if _someone_ahead(bot, pts[0], everyone):
            max_speed = min(max_speed if max_speed is not None else GUARD_SPEED_MPS,
                            GUARD_SPEED_MPS)
        field_pts = tuple(frame.point(x, y) for x, y in pts)
        fx, fy = frame.point(end[0], end[1])
        out[bot.id] = Move(
            role=it.role, x=fx, y=fy,
            orientation=None if it.orientation is None else frame.angle(it.orientation),
            path=field_pts, kick_speed_mps=it.kick_speed_mps, chip=it.chip,
            dribbler=it.dribbler, max_speed_mps=max_speed, blocked=blocked)
    if memory is not None:
        memory.forget(searched)
    return out


def _someone_ahead(bot: Bot, towards: tuple[float, float],
                   everyone: Sequence[tuple[str, Bot]]) -> bool:
    """Is another robot within ``GUARD_MM`` of ``bot`` and within 60 deg of its way?"""
    dx, dy = towards[0] - bot.x, towards[1] - bot.y
    n = math.hypot(dx, dy)
    if n < 1e-6:
        return False
    for _, o in everyone:
        if o is bot:
            continue
        ox, oy = o.x - bot.x, o.y - bot.y
        d = math.hypot(ox, oy)
        if 0.0 < d < GUARD_MM and (ox * dx + oy * dy) > GUARD_COS * d * n:
            return True
    return False
