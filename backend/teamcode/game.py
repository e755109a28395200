"""The ``touchline.Game`` snapshot a team play gets, built once per strategy tick from what the
built-in strategy prepared (``StrategyCore.prepare``: our frame, the referee's situation)
and the world; each play gets it with its own ``mine`` (``dataclasses.replace``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

from domain.field import Field
from touchline import API_VERSION, Ball, FieldSize, Game, Kick, Referee, Robot
from touchline.game import SituationName

from ..strategy.core import Prepared
from ..world.referee import RefereeState
from ..world.state import Team, WorldState


def field_size(fs: Field) -> FieldSize:
    return FieldSize(length=fs.field_length, width=fs.field_width, goal_width=fs.goal_width,
                     goal_depth=fs.goal_depth, boundary_width=fs.boundary_width,
                     penalty_area_depth=fs.penalty_area_depth,
                     penalty_area_width=fs.penalty_area_width,
                     center_circle_radius=fs.center_circle_radius,
                     robot_radius=fs.max_robot_radius, ball_radius=fs.ball_radius)


def _score(referee: RefereeState | None, team: Team) -> int:
    if referee is None:
        return 0
    v = referee.team(team).get("score")
    return int(v) if isinstance(v, int) and not isinstance(v, bool) else 0


def build_game(prep: Prepared, world: WorldState, referee: RefereeState | None,
               our_team: Team, contacts: Mapping[int, bool] | None = None,
               topics: Mapping[str, Mapping[str, float]] | None = None,
               replay: bool = False) -> Game:
    """The snapshot with ``mine`` empty (``replace(game, mine=...)`` per play)."""
    frame = prep.frame
    inp = prep.inp
    ours: list[Robot] = []
    theirs: list[Robot] = []
    for r in world.robots:
        if r.lost:
            continue
        x, y = frame.point(r.x, r.y)
        vx, vy = frame.point(r.vx, r.vy)
        ori = frame.angle(r.orientation)
        if r.team == our_team:
            contact = contacts.get(r.id) if contacts else None
            ours.append(Robot(r.id, x, y, ori, vx, vy, r.omega, r.visible, contact))
        else:
            theirs.append(Robot(r.id, x, y, ori, vx, vy, r.omega, r.visible))
    ours.sort(key=lambda r: r.id)
    theirs.sort(key=lambda r: r.id)
    ball: Ball | None = None
    wb = world.ball
    if wb is not None and not wb.lost:
        bx, by = frame.point(wb.x, wb.y)
        # the strategy's own velocity (a line fitted to the last positions) when it has one
        if inp.ball is not None:
            bvx, bvy = inp.ball.vx, inp.ball.vy
        else:
            bvx, bvy = frame.point(wb.vx, wb.vy)
        kick: Kick | None = None
        k = world.kicked_ball
        if k is not None:
            by_team: Literal["ours", "theirs"] | None = None
            if k.robot is not None:
                by_team = "ours" if k.robot[0] == our_team else "theirs"
            sx, sy = frame.point(k.start_x, k.start_y)
            kvx, kvy = frame.point(k.vx, k.vy)
            ex, ey = frame.point(k.stop_x, k.stop_y)
            # the kick's capture times on the game's clock
            shift = inp.t - world.t_capture
            kick = Kick(by_team, None if k.robot is None else k.robot[1], sx, sy,
                        k.start_t + shift, kvx, kvy, ex, ey, k.stop_t + shift, k.chip)
        ball = Ball(bx, by, bvx, bvy, wb.z, wb.visible, kick)
    sit = inp.situation
    situation: SituationName = "none" if sit.kind == "running" and not sit.command \
        else sit.kind
    other: Team = "yellow" if our_team == "blue" else "blue"
    ref = Referee(
        command=sit.command, situation=situation, ours=sit.ours, designated=sit.designated,
        stage=referee.stage if referee is not None else "", goalkeeper=inp.keeper_id,
        max_robots=inp.max_bots, score_ours=_score(referee, our_team),
        score_theirs=_score(referee, other))
    return Game(API_VERSION, inp.t, our_team, "negative-x" if frame.sign > 0 else "positive-x",
                tuple(ours), tuple(theirs), ball, ref, field_size(inp.fs), (),
                dict(topics or {}), replay)
