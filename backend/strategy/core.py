"""From the world model to moves: the strategy as the StrategyProcessor runs it each tick.

    core = StrategyCore()
    inp = core.prepare(world, geometry, referee, params, now)    # field -> our frame
    point = await engine.call(...)   # optional: the keeper's spot from the compute engine
    moves = core.decide(inp, keeper_point_field=point)            # plays, roles, paths

``prepare`` and ``decide`` are plain code (no I/O), so tests and the benchmark drive them
directly; the processor only adds the engine call between them.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, replace

import numpy as np

from domain.field import Field
from domain.rules import STOPPED_DEFENSE_AREA_DISTANCE_MM

from ..geometry import fit_motion_lsq
from ..params.model import StrategyParams
from ..world.referee import RefereeState
from ..world.state import Team, WorldState
from .model import ROBOT_RADIUS_MM, Ball, Bot, Frame, Intent, Move
from .navigate import navigate
from .paths import PathMemory
from .plays import Strategy, StrategyInput, Tuning
from .situation import Situation, SituationTracker

#: robot body to the opponents' defence area while the game is stopped: the rules' 0.2 m
#: plus 60 mm for the vision noise and the controller's overshoot
STOPPED_DEFENSE_MARGIN_MM = STOPPED_DEFENSE_AREA_DISTANCE_MM + 60.0


@dataclass(frozen=True, slots=True)
class Prepared:
    """One tick's input, in our frame, plus what the engine call needs in the field frame."""

    inp: StrategyInput
    frame: Frame
    ball_field: tuple[float, float] | None
    ball_velocity_field: tuple[float, float]
    goal_x_field: float  # x of the keeper's line in the field frame


class StrategyCore:
    def __init__(self) -> None:
        self.tracker = SituationTracker()
        self.strategy = Strategy()
        #: built-in plays given to some robots only (strategy.robot_plays), by name
        self.strategies: dict[str, Strategy] = {}
        self.ball_history: deque[tuple[float, float, float]] = deque(maxlen=30)
        self.situation = Situation("running", None, "")
        self.frame = Frame(1)
        self.side_from_referee = False
        self.robot_margin_mm = 60.0
        self.defense_margin_mm = 120.0
        self.last_tick_ms = 0.0
        #: the robots' earlier path searches, reused while they hold (False: plan afresh
        #: every tick, as bench/strategy_replay.py --compare does)
        self.paths = PathMemory()
        self.reuse_paths = True
        #: called between two robots' navigation (see ``StrategyProcessor``); None: never
        self.pause: Callable[[], None] | None = None

    def prepare(self, world: WorldState, geometry: dict[str, float] | None,
                referee: RefereeState | None, params: StrategyParams, our_team: Team,
                our_side_negative: bool, side_from_referee: bool, now: float,
                contacts: Mapping[int, bool] | None = None) -> Prepared:
        """``contacts``: the ball contact our robots report (by id; absent: not said)."""
        fs = Field.from_geometry(geometry)
        negative = our_side_negative
        self.side_from_referee = False
        if side_from_referee and referee is not None \
                and referee.blue_team_on_positive_half is not None:
            blue_pos = referee.blue_team_on_positive_half
            negative = not blue_pos if our_team == "blue" else blue_pos
            self.side_from_referee = True
        frame = Frame(1 if negative else -1)
        self.frame = frame
        self.robot_margin_mm = params.robot_margin_mm
        self.defense_margin_mm = params.defense_margin_mm
        self.strategy.configure(params.assignment, params.assignment_hysteresis_mm)
        ours: list[Bot] = []
        theirs: list[Bot] = []
        for r in world.robots:
            if not r.visible:
                continue
            x, y = frame.point(r.x, r.y)
            vx, vy = frame.point(r.vx, r.vy)
            if r.team == our_team:
                contact = contacts.get(r.id) if contacts else None
                ours.append(Bot(r.id, x, y, frame.angle(r.orientation), vx, vy, contact))
            else:
                theirs.append(Bot(r.id, x, y, frame.angle(r.orientation), vx, vy))
        ball: Ball | None = None
        ball_field: tuple[float, float] | None = None
        vel_field = (0.0, 0.0)
        wb = world.ball
        if wb is not None and wb.visible:
            ball_field = (wb.x, wb.y)
            self.ball_history.append((wb.t_seen, wb.x, wb.y))
            vel_field = self._ball_velocity(wb.t_seen, (wb.vx, wb.vy))
            bx, by = frame.point(wb.x, wb.y)
            bvx, bvy = frame.point(*vel_field)
            ball = Ball(bx, by, bvx, bvy)
        designated = None
        if referee is not None and referee.designated_position is not None:
            designated = frame.point(*referee.designated_position)
        sit = self.tracker.update(referee.command if referee else None,
                                  referee.command_counter if referee else 0, our_team,
                                  ball.xy if ball else None, designated)
        self.situation = sit
        keeper_id = None
        if referee is not None:
            info = referee.blue if our_team == "blue" else referee.yellow
            gk = info.get("goalkeeper")
            keeper_id = int(gk) if isinstance(gk, int) else None
        tuning = Tuning(
            kick_speed_mps=params.kick_speed_mps, pass_speed_mps=params.pass_speed_mps,
            stop_distance_mm=params.stop_distance_mm,
            defense_margin_mm=params.defense_margin_mm,
            robot_margin_mm=params.robot_margin_mm,
            placement_speed_mps=params.placement_speed_mps,
            keeper_min_speed_mmps=params.keeper_min_speed_mmps,
            formation_period_s=params.formation_period_s)
        inp = StrategyInput(t=now, ours=ours, theirs=theirs, ball=ball, fs=fs, situation=sit,
                            keeper_id=keeper_id, play=params.play, tuning=tuning,
                            max_bots=referee.max_allowed_bots(our_team) if referee else None)
        goal_x = frame.point(-fs.half_length + ROBOT_RADIUS_MM + 30.0, 0.0)[0]
        return Prepared(inp, frame, ball_field, vel_field, goal_x)

    def _ball_velocity(self, t_now: float, fallback: tuple[float, float]) -> tuple[float, float]:
        """Ball velocity (mm/s, field frame) from a least-squares line through its positions
        of the last 0.15 s (the paper's line fit), else the world model's estimate."""
        recent = [s for s in self.ball_history if t_now - s[0] <= 0.15]
        if len(recent) >= 4:
            arr = np.array(recent, dtype=np.float64)
            m = fit_motion_lsq(arr[:, 0], arr[:, 1:3])
            vx, vy = float(m.velocity[0]), float(m.velocity[1])
            if np.isfinite(vx) and np.isfinite(vy):
                return (vx, vy)
        return fallback

    def decide(self, prep: Prepared,
               keeper_point_field: tuple[float, float] | None = None) -> dict[int, Move]:
        """The team's play (``strategy.play``, a built-in one) for every robot, with paths."""
        t0 = time.perf_counter()
        inp = prep.inp
        if keeper_point_field is not None:
            inp = replace(inp, keeper_point=prep.frame.point(*keeper_point_field))
        intents = self.strategy.decide(inp)
        return self._navigate(prep, intents, t0)

    def builtin_intents(self, prep: Prepared, groups: Mapping[str, Collection[int]],
                        keeper_point_field: tuple[float, float] | None = None,
                        ) -> dict[int, Intent]:
        """Each built-in play decides for its own robots (``groups``: play -> ids); the
        other robots of ours are not its to place (they are obstacles when navigating).
        The team's play (``strategy.play``) keeps ``self.strategy``; a play given to some
        robots only has a ``Strategy`` of its own (its roles and memory)."""
        inp = prep.inp
        if keeper_point_field is not None:
            inp = replace(inp, keeper_point=prep.frame.point(*keeper_point_field))
        out: dict[int, Intent] = {}
        for play, ids in groups.items():
            strategy = self.strategy if play == inp.play else \
                self.strategies.setdefault(play, Strategy())
            if strategy is not self.strategy:
                strategy.configure(self.strategy.assigner.mode,
                                   self.strategy.assigner.hysteresis_mm)
            chosen = set(ids)
            out.update(strategy.decide(replace(inp, play=play, ours=[
                b for b in inp.ours if b.id in chosen])))
        for play in [p for p in self.strategies if p not in groups]:
            del self.strategies[play]  # no robot runs it: its memory goes
        return out

    def navigate_intents(self, prep: Prepared, intents: dict[int, Intent]) -> dict[int, Move]:
        """Paths for ``intents`` (any play's, the team's code's too) around everything."""
        return self._navigate(prep, intents, time.perf_counter())

    @property
    def roles(self) -> dict[int, str]:
        """Each robot's role, whichever built-in play gave it (a copy)."""
        out = dict(self.strategy.roles)
        for s in list(self.strategies.values()):
            out.update(s.roles)
        return out

    def _navigate(self, prep: Prepared, intents: dict[int, Intent], t0: float
                  ) -> dict[int, Move]:
        inp = prep.inp
        corridor = None
        sit = inp.situation
        if sit.kind == "placement" and not sit.ours and sit.designated is not None \
                and inp.ball is not None:
            corridor = (inp.ball.xy, sit.designated, inp.tuning.stop_distance_mm - 20.0)
        their_margin = None
        if sit.kind in ("stop", "free-kick", "placement"):
            # rules: 0.2 m from the opponents' defence area during stop and free kicks
            their_margin = max(self.defense_margin_mm, STOPPED_DEFENSE_MARGIN_MM)
        moves = navigate(intents, inp.ours, inp.theirs, inp.ball, inp.fs, prep.frame,
                         self.robot_margin_mm, self.defense_margin_mm, corridor, their_margin,
                         self.paths if self.reuse_paths else None, inp.t, self.pause)
        self.last_tick_ms = (time.perf_counter() - t0) * 1000.0
        return moves
