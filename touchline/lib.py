"""Touchline's own strategy pieces as a library for a team's plays (API version 1):

    from touchline import Game, Target
    from touchline.lib import attacker, defender_spots, geometry, goalkeeper, plan_path

    def play(game: Game) -> dict[int, Target]:
        keeper, *rest = sorted(game.mine)
        orders = {keeper: goalkeeper(game)}
        for rid, (x, y) in zip(rest, defender_spots(game, len(rest))):
            orders[rid] = Target(x, y, 0.0, role="defender")
        return orders

Everything works on the ``Game`` snapshot, in our frame (mm, rad), and returns plain tuples
or ``touchline.Target``; the station still checks every order (the safety envelope). These
are the functions the built-in plays use, so a team starts from what Touchline does and
changes what it wants. Importing this module loads numpy (the ``touchline`` package itself
does not): a play that does not need it stays light.

* ``geometry``: Touchline's vectorised 2-D geometry (``backend.geometry``: the paper's
  MATLAB geometry scripts: distances, projections, intersections, tangents, fits).
* ``plan_path(game, rid, x, y)``: waypoints from robot ``rid`` to (x, y) around the other
  robots, the defence areas it may not enter and (``avoid_ball_mm``) the ball.
* ``goalkeeper(game)``, ``attacker(game, rid)``, ``defender_spots(game, n)``,
  ``best_shot(game)``, ``kick_ball(game, rid, aim, speed_mps)``: the built-in roles.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from backend import geometry as geometry
from backend.strategy import roles as _roles
from backend.strategy.model import Ball as _Ball
from backend.strategy.model import Bot as _Bot
from backend.strategy.model import Intent as _Intent
from backend.strategy.model import own_defense as _own_defense
from backend.strategy.model import their_defense as _their_defense
from backend.strategy.paths import Obstacles as _Obstacles
from backend.strategy.paths import plan_path as _plan_path
from domain.field import Field as _Field

from .orders import Target

if TYPE_CHECKING:
    from .game import Game

__all__ = ["attacker", "best_shot", "defender_spots", "facing", "geometry", "goalkeeper",
           "kick_ball", "plan_path"]

#: the clearance paths keep from other robots (as the built-in strategy's default)
ROBOT_MARGIN_MM = 60.0
#: ... and from the defence areas a robot may not enter
DEFENSE_MARGIN_MM = 120.0


def _field(game: Game) -> _Field:
    f = game.field
    return _Field(f.length, f.width, f.goal_width, goal_depth=f.goal_depth,
                  boundary_width=f.boundary_width, penalty_area_depth=f.penalty_area_depth,
                  penalty_area_width=f.penalty_area_width,
                  center_circle_radius=f.center_circle_radius, ball_radius=f.ball_radius,
                  max_robot_radius=f.robot_radius)


def _ball(game: Game) -> _Ball | None:
    b = game.ball
    return None if b is None else _Ball(b.x, b.y, b.vx, b.vy)


def _bot(game: Game, rid: int) -> _Bot | None:
    r = game.robot(rid)
    return None if r is None else _Bot(r.id, r.x, r.y, r.orientation, r.vx, r.vy,
                                       r.ball_contact)


def _target(it: _Intent, role: str | None = None) -> Target:
    return Target(it.x, it.y, it.orientation, max_speed_mps=it.max_speed_mps,
                  kick_mps=it.kick_speed_mps, chip=it.chip, dribble=it.dribbler,
                  avoid=it.plan, role=role or it.role)


def plan_path(game: Game, rid: int, x: float, y: float, *,
              margin_mm: float = ROBOT_MARGIN_MM, avoid_ball_mm: float = 0.0,
              own_defense_ok: bool | None = None) -> list[tuple[float, float]]:
    """Waypoints (our frame, mm) from robot ``rid`` to (x, y): around every other robot
    (its radius + ``margin_mm``), the opponents' defence area, ours unless the robot is the
    goalkeeper (``own_defense_ok``: None asks the referee's goalkeeper id), and the ball
    when ``avoid_ball_mm`` > 0. The last point is the goal (or the nearest free point to
    it); a robot that cannot be found gets ``[(x, y)]``."""
    me = game.robot(rid)
    if me is None:
        return [(x, y)]
    fs = _field(game)
    r = fs.max_robot_radius
    circles = [(o.x, o.y, r + margin_mm) for o in (*game.ours, *game.theirs)
               if not (o.id == rid and o in game.ours)]
    if avoid_ball_mm > 0.0 and game.ball is not None:
        circles.append((game.ball.x, game.ball.y, max(1.0, avoid_ball_mm - r)))
    keeper_ok = (rid == game.referee.goalkeeper) if own_defense_ok is None else own_defense_ok
    g = DEFENSE_MARGIN_MM
    rects = [_their_defense(fs)] + ([] if keeper_ok else [_own_defense(fs)])
    rects = [(a - g, b - g, c + g, d + g) for a, b, c, d in rects]
    bounds = (-fs.half_length - 150.0, -fs.half_width - 150.0, fs.half_length + 150.0,
              fs.half_width + 150.0)
    obstacles = _Obstacles(circles=np.array(circles, dtype=np.float64).reshape(-1, 3),
                           rects=np.array(rects, dtype=np.float64).reshape(-1, 4))
    res = _plan_path((me.x, me.y), (x, y), obstacles, r, bounds=bounds)
    return [(float(px), float(py)) for px, py in res.points] or [(x, y)]


def best_shot(game: Game) -> tuple[tuple[float, float], float]:
    """The point on the opponents' goal line with the widest open angle from the ball,
    and that angle (rad); (goal centre, 0) without a ball or when the goal is covered."""
    fs = _field(game)
    if game.ball is None:
        return (fs.half_length, 0.0), 0.0
    blockers = [(o.x, o.y) for o in game.theirs]
    return _roles.best_shot((game.ball.x, game.ball.y), blockers, fs)


def goalkeeper(game: Game, min_speed_mmps: float = 300.0, rid: int | None = None) -> Target:
    """The built-in keeper: on the line in front of our goal where the ball's path crosses
    it (a ball coming faster than ``min_speed_mmps``), else where the bisector of the angle
    the goal mouth makes at the ball crosses it; a slow ball
    inside our area is kicked out. ``rid``: the keeper (default: the referee's goalkeeper)."""
    fs = _field(game)
    keeper = rid if rid is not None else game.referee.goalkeeper
    bot = _bot(game, keeper) if keeper is not None else None
    return _target(_roles.goalkeeper(_ball(game), fs, None, min_speed_mmps, 3.0, bot))


def kick_ball(game: Game, rid: int, aim: tuple[float, float], speed_mps: float,
              chip: bool = False, role: str = "kicker") -> Target:
    """Behind the ball on the line through ``aim``, then through it with the kicker armed
    (once the robot is behind the ball and facing the aim). Without a ball: stay."""
    bot = _bot(game, rid)
    ball = _ball(game)
    if ball is None or bot is None:
        here = game.robot(rid)
        return Target(here.x if here else 0.0, here.y if here else 0.0, None, role=role)
    return _target(_roles.kick_ball(ball, aim, speed_mps, role, bot, chip=chip))


def attacker(game: Game, rid: int, kick_speed_mps: float = 5.5,
             pass_speed_mps: float = 3.0) -> Target:
    """The built-in attacker: goes for the ball and shoots at the widest open angle (or
    passes forward when the shot is poor or far)."""
    bot = _bot(game, rid)
    ball = _ball(game)
    if ball is None or bot is None:
        return kick_ball(game, rid, (0.0, 0.0), 0.0, role="attacker")
    others = [(o.x, o.y) for o in game.theirs] + [(o.x, o.y) for o in game.ours
                                                    if o.id != rid]
    it = _roles.attacker(ball, bot, others, _field(game), kick_speed_mps, pass_speed_mps)
    return _target(it)


def defender_spots(game: Game, n: int, margin_mm: float = DEFENSE_MARGIN_MM
                   ) -> list[tuple[float, float]]:
    """``n`` spots side by side just outside our defence area, on the line from our goal
    centre to the ball (as the built-in defenders stand)."""
    return _roles.defender_points(n, _ball(game), _field(game), margin_mm, ROBOT_MARGIN_MM)


def facing(game: Game, x: float, y: float) -> float:
    """The heading (rad) from (x, y) towards the ball (0 without a ball)."""
    b = game.ball
    return 0.0 if b is None else math.atan2(b.y - y, b.x - x)

