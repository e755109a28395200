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
from ..strategy.model import Frame
from ..strategy.situation import Situation, SituationTracker
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
    """The snapshot for the team's plays, from what the strategy prepared this tick, with
    ``mine`` empty (``replace(game, mine=...)`` per play)."""
    inp = prep.inp
    vel = (inp.ball.vx, inp.ball.vy) if inp.ball is not None else None
    return snapshot(world, prep.frame, inp.situation, inp.t, inp.fs, inp.keeper_id,
                    inp.max_bots, referee, our_team, contacts, topics, replay, vel)


class GameBuilder:
    """The snapshot for the team's processors, from the latest world whenever they run
    (their rate is their own, not the strategy's): the same frame and situation rules as
    ``StrategyCore.prepare``, with a situation tracker of its own."""

    def __init__(self) -> None:
        self.tracker = SituationTracker()

    def build(self, world: WorldState, geometry: Mapping[str, object] | None,
              referee: RefereeState | None, our_team: Team, our_side_negative: bool,
              side_from_referee: bool, t: float,
              contacts: Mapping[int, bool] | None = None,
              topics: Mapping[str, Mapping[str, float]] | None = None,
              replay: bool = False) -> Game:
        negative = our_side_negative
        if side_from_referee and referee is not None \
                and referee.blue_team_on_positive_half is not None:
            blue_pos = referee.blue_team_on_positive_half
            negative = not blue_pos if our_team == "blue" else blue_pos
        frame = Frame(1 if negative else -1)
        fs = Field.from_geometry(geometry)
        wb = world.ball
        ball_xy = frame.point(wb.x, wb.y) if wb is not None and wb.visible else None
        designated = None
        if referee is not None and referee.designated_position is not None:
            designated = frame.point(*referee.designated_position)
        sit = self.tracker.update(referee.command if referee else None,
                                  referee.command_counter if referee else 0, our_team,
                                  ball_xy, designated)
        keeper = None
        if referee is not None:
            gk = referee.team(our_team).get("goalkeeper")
            keeper = int(gk) if isinstance(gk, int) and not isinstance(gk, bool) else None
        return snapshot(world, frame, sit, t, fs, keeper,
                        referee.max_allowed_bots(our_team) if referee else None, referee,
                        our_team, contacts, topics, replay)


def snapshot(world: WorldState, frame: Frame, sit: Situation, t: float, fs: Field,
             keeper_id: int | None, max_bots: int | None, referee: RefereeState | None,
             our_team: Team, contacts: Mapping[int, bool] | None = None,
             topics: Mapping[str, Mapping[str, float]] | None = None, replay: bool = False,
             ball_velocity: tuple[float, float] | None = None) -> Game:
    """A ``Game`` (``mine`` empty) in our frame: robots not lost, the ball with its kick."""
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
        bvx, bvy = ball_velocity if ball_velocity is not None else frame.point(wb.vx, wb.vy)
        kick: Kick | None = None
        k = world.kicked_ball
        if k is not None:
            by_team: Literal["ours", "theirs"] | None = None
            if k.robot is not None:
                by_team = "ours" if k.robot[0] == our_team else "theirs"
            sx, sy = frame.point(k.start_x, k.start_y)
            kvx, kvy = frame.point(k.vx, k.vy)
            ex, ey = frame.point(k.stop_x, k.stop_y)
            shift = t - world.t_capture  # the kick's capture times on the game's clock
            kick = Kick(by_team, None if k.robot is None else k.robot[1], sx, sy,
                        k.start_t + shift, kvx, kvy, ex, ey, k.stop_t + shift, k.chip)
        ball = Ball(bx, by, bvx, bvy, wb.z, wb.visible, kick)
    situation: SituationName = "none" if sit.kind == "running" and not sit.command \
        else sit.kind
    other: Team = "yellow" if our_team == "blue" else "blue"
    ref = Referee(
        command=sit.command, situation=situation, ours=sit.ours, designated=sit.designated,
        stage=referee.stage if referee is not None else "", goalkeeper=keeper_id,
        max_robots=max_bots, score_ours=_score(referee, our_team),
        score_theirs=_score(referee, other))
    return Game(API_VERSION, t, our_team, "negative-x" if frame.sign > 0 else "positive-x",
                tuple(ours), tuple(theirs), ball, ref, field_size(fs), (),
                {k: dict(v) for k, v in (topics or {}).items()}, replay)
