"""The strategy processor: plays, roles and paths into targets; the compute engine."""

from __future__ import annotations

import asyncio
import os
import pickle
import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any, BinaryIO

import numpy as np

from .. import topics
from ..bus import DataBus, Reader
from ..control.goto import LocalVelocity, Target
from ..engine import EngineError, PoolEngine
from ..messages import TargetEntry
from ..params.model import PLAYS, StationParams, StrategyParams
from ..processor import Every, Processor
from ..strategy.core import Prepared, StrategyCore
from ..strategy.model import Move
from ..teamcode.envelope import Rules
from ..teamcode.game import build_game
from ..teamcode.plays import TeamPlays, TeamTick
from ..world.referee import RefereeState
from ..world.state import Team, WorldState
from .common import badlog

#: our goalkeeper while no referee names one (the game controller's default)
KEEPER_DEFAULT = 0
#: an engine answer older than this is not used (the built-in code is, as a fallback)
ENGINE_MAX_AGE_S = 0.25
DRIBBLER_RPM = 3000.0
#: a robot's word on ball contact counts for this long after its answer (the simulation
#: protocol answers every command; grSim's status comes at its own rate)
CONTACT_MAX_AGE_S = 0.2
#: ``TOUCHLINE_STRATEGY_RECORD=FILE`` (bench/strategy_replay.py): each tick's strategy input
#: is pickled to FILE, so the strategy's cost at full scale can be replayed and profiled
#: offline on the inputs of a real game (``{team}`` in FILE: our team, for two backends)
RECORD_ENV = "TOUCHLINE_STRATEGY_RECORD"


def _let_station_run() -> None:
    time.sleep(0)


class StrategyProcessor(Processor):
    """Decides targets: operator targets first, the selected play for the rest of our team
    (roles, referee-driven behaviour, planned paths). The keeper's spot may come from the
    compute engine; a failed or late engine call falls back to the built-in code."""

    name = "strategy"

    def __init__(self, bus: DataBus, our_team: Team, params: StrategyParams | None = None,
                 hz: float = 20.0, clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__(Every(hz))
        self.world = bus.of(topics.WORLD)
        self.geometry = bus.of(topics.GEOMETRY)
        self.referee = bus.of(topics.REFEREE)
        self.operator = Reader(bus.of(topics.OPERATOR_TARGETS))
        self.targets = bus.of(topics.TARGETS)
        #: what each robot reports back ({(team, id): RobotFeedbackView}): ball contact, ...
        self.feedback = bus.of(topics.ROBOT_FEEDBACK)
        self.our_team: Team = our_team
        self.our_side_negative = True
        self.side_from_referee = True
        self.params = params or StrategyParams()
        self.core = StrategyCore()
        # decide runs in a worker thread beside the station thread, and both need the GIL:
        # between two robots' paths the worker gives it up (sleep(0) releases it and lets
        # the OS run the station thread), so a station pass waits for one robot's planning
        # at most instead of the whole tick's share of it (bench/strategy_gil.py: the
        # station's p99 delay 2.2-2.6 -> 0.9-1.0 ms beside a busy strategy)
        self.core.pause = _let_station_run
        self.referee_source: Callable[[], RefereeState | None] = self.referee.latest_value
        self.operator_targets: dict[tuple[Team, int], Target] = {}
        self.engine: PoolEngine | None = None
        self.engine_fallbacks = 0
        self.engine_last_error = ""
        self._engine_task: asyncio.Task[tuple[float, float]] | None = None
        self._engine_point: tuple[float, tuple[float, float]] | None = None
        #: monotonic seconds (a virtual clock headless: evaluate/)
        self.clock = clock
        self._t0 = clock()
        self._record: BinaryIO | None = None
        #: called once, with the first targets for a robot (the station's start timeline)
        self.on_first_targets: Callable[[], None] | None = None
        #: the team's own plays (backend/teamcode; the station sets it), and what they need
        self.team: TeamPlays | None = None
        self.replaying: Callable[[], bool] = lambda: False
        self.team_topics: Callable[[], Mapping[str, Mapping[str, float]]] = dict
        #: for the world message: the play each robot of ours runs, and robots held still
        #: because their team play failed (id, play, reason)
        self.robot_plays: dict[int, str] = {}
        #: an exercise's parameters for the team's plays (Game.task; evaluate/ sets it)
        self.task: Mapping[str, Any] = {}
        self.stopped: list[tuple[int, str, str]] = []

    def ball_contact(self, team: Team, rid: int) -> bool:
        """The robot reports the ball at its dribbler (False when it reports nothing)."""
        views = self.feedback.latest_value() or {}
        fb = views.get((team, rid))
        return bool(fb is not None and fb.ball_contact)

    def contacts(self, team: Team) -> dict[int, bool]:
        """Ball contact of each of ``team``'s robots that reports it now (answered within
        ``CONTACT_MAX_AGE_S``); the others are judged from the positions."""
        out: dict[int, bool] = {}
        for (t, rid), fb in (self.feedback.latest_value() or {}).items():
            if t == team:
                c = fb.contact(CONTACT_MAX_AGE_S)
                if c is not None:
                    out[rid] = c
        return out

    def configure(self, params: StationParams) -> None:
        t = params.team
        self.our_team = t.our_team
        self.our_side_negative = t.our_side == "negative-x"
        self.side_from_referee = t.side_from_referee
        self.params = params.strategy
        self.set_rate(params.processors.strategy_hz)
        rec = os.environ.get(RECORD_ENV)
        if rec and self._record is None:
            self._record = open(rec.replace("{team}", self.our_team), "wb")  # noqa: SIM115

    async def tick(self) -> None:
        for op in self.operator.read_new():
            if op.target is None:
                self.operator_targets.pop((op.team, op.id), None)
            else:
                self.operator_targets[(op.team, op.id)] = op.target
        out: dict[tuple[Team, int], TargetEntry] = {
            k: TargetEntry(t, "operator", role="operator")
            for k, t in self.operator_targets.items()
        }
        world = self.world.latest_value()
        p = self.params
        robot_plays = p.robot_plays
        if world is not None and (p.play != "idle" or robot_plays):
            now = self.clock() - self._t0
            contacts = self.contacts(self.our_team)
            referee = self.referee_source()
            prep = self.core.prepare(world, self.geometry.latest_value(), referee, p,
                                     self.our_team, self.our_side_negative,
                                     self.side_from_referee, now, contacts)
            keeper = await self._engine_keeper(prep)
            if self._record is not None:
                pickle.dump((prep, keeper), self._record)
                self._record.flush()
            team = self.our_team
            if not robot_plays and p.play in PLAYS:
                # the built-in play for the whole team: roles and paths in a worker thread,
                # so a slow decision never holds up a control tick on the station loop
                # (control goes on with the previous targets meanwhile)
                self.robot_plays = {b.id: p.play for b in prep.inp.ours
                                    if (team, b.id) not in out} if p.play != "idle" else {}
                self.stopped = []
                if self.team is not None and self.team.runners:
                    self.team.release()  # no team play in use: their workers go in a while
                moves = await asyncio.to_thread(self.core.decide, prep, keeper)
            else:
                moves = await self._mixed_tick(prep, world, referee, contacts, keeper, out)
            for rid, mv in moves.items():
                key = (team, rid)
                if key in out:
                    continue
                out[key] = TargetEntry(
                    Target(mv.x, mv.y, mv.orientation),
                    "team" if self._team_robot(rid) else "strategy", role=mv.role,
                    path=mv.path, kick_speed_mps=mv.kick_speed_mps, chip=mv.chip,
                    dribbler_rpm=DRIBBLER_RPM if mv.dribbler else 0.0,
                    max_speed_mps=mv.max_speed_mps)
        else:
            self.robot_plays, self.stopped = {}, []
            if self.team is not None and self.team.runners:
                self.team.release()
        self.targets.write(out)
        if out and self.on_first_targets is not None:
            hook, self.on_first_targets = self.on_first_targets, None
            hook()

    def _team_robot(self, rid: int) -> bool:
        play = self.robot_plays.get(rid)
        return play is not None and play not in PLAYS

    async def _mixed_tick(self, prep: Prepared, world: WorldState,
                          referee: RefereeState | None, contacts: dict[int, bool],
                          keeper: tuple[float, float] | None,
                          out: dict[tuple[Team, int], TargetEntry]) -> dict[int, Move]:
        """Robots grouped by the play they run (``strategy.play``, ``strategy.robot_plays``):
        the team's plays are asked in their workers while the built-in plays decide in a
        worker thread, for their own robots; the team's answers are checked and kept within
        the safety envelope; then every intent is navigated. Robots whose team play failed
        (or did not answer in time) get a stop entry written into ``out``."""
        p = self.params
        team = self.our_team
        groups: dict[str, list[int]] = {}
        for b in prep.inp.ours:
            if (team, b.id) in out:
                continue  # an operator drives it
            groups.setdefault(p.robot_plays.get(str(b.id), p.play), []).append(b.id)
        builtin: dict[str, list[int]] = {play: ids for play, ids in groups.items()
                                         if play in PLAYS}
        theirs = {play: tuple(sorted(ids)) for play, ids in groups.items()
                  if play not in PLAYS}
        self.robot_plays = {rid: play for play, ids in groups.items() for rid in ids
                            if play != "idle"}
        tick: TeamTick | None = None
        if theirs:
            if self.team is None:
                raise RuntimeError("team plays chosen but no team code host")
            game = build_game(prep, world, referee, team, contacts, self.team_topics(),
                              self.replaying())
            if self.task:
                game = replace(game, task=self.task)
            tick = self.team.ask(game, theirs, p.team_budget_ms / 1000.0, p.engine_timeout_s)
        intents = await asyncio.to_thread(self.core.builtin_intents, prep, builtin, keeper)
        stopped: list[tuple[int, str, str]] = []
        if tick is not None:
            await tick.wait()
            sit = prep.inp.situation
            rules = Rules(prep.inp.fs, sit.kind, sit.ours,
                          prep.inp.ball.xy if prep.inp.ball is not None else None,
                          sit.designated, KEEPER_DEFAULT if prep.inp.keeper_id is None
                          else prep.inp.keeper_id, p.stop_distance_mm)
            bots = {b.id: b for b in prep.inp.ours}
            orders = tick.orders(rules, bots)
            intents.update(orders.intents)
            frame = prep.frame
            for rid, why in orders.stops.items():
                b = bots[rid]
                fx, fy = frame.point(b.x, b.y)
                out[(team, rid)] = TargetEntry(Target(fx, fy, None), "team", role="stopped",
                                               stop=True)
                if why is not None:
                    stopped.append((rid, orders.plays.get(rid, ""), why))
            for rid, v in orders.velocities.items():
                b = bots[rid]
                fx, fy = frame.point(b.x, b.y)
                out[(team, rid)] = TargetEntry(
                    Target(fx, fy, None), "team", role=v.role or "team",
                    kick_speed_mps=v.kick_mps, chip=v.chip,
                    dribbler_rpm=DRIBBLER_RPM if v.dribble else 0.0,
                    velocity=LocalVelocity(v.forward_mps, v.left_mps, v.turn_radps))
        self.stopped = stopped
        return await asyncio.to_thread(self.core.navigate_intents, prep, intents)

    async def _engine_keeper(self, prep: Prepared) -> tuple[float, float] | None:
        """The keeper's spot (field frame) from the compute engine, or None (built-in code).

        The tick never waits for the engine: one call is in flight at a time, and the tick
        uses the newest answer if it is at most ``ENGINE_MAX_AGE_S`` old (the answer to the
        previous tick's ball, normally). A failed, late or malformed answer is a fallback."""
        eng = self.engine
        if eng is None or prep.ball_field is None or self.params.play in ("formation", "idle"):
            return None
        task = self._engine_task
        if task is not None and task.done():
            self._engine_task = None
            try:
                point = task.result()
                self._engine_point = (self.clock(), point)
            except Exception as exc:
                self.engine_fallbacks += 1
                msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                self.engine_last_error = msg
                badlog.warning("engine-keeper", "engine keeper call failed, built-in code "
                                "used: %s", msg)
                self._engine_point = None
                return None
        if self._engine_task is None:
            self._engine_task = asyncio.get_running_loop().create_task(
                self._call_keeper(eng, prep))
        got = self._engine_point
        if got is None or self.clock() - got[0] > ENGINE_MAX_AGE_S:
            if got is not None:
                self.engine_fallbacks += 1  # the engine is late: use the built-in code
            return None
        return got[1]

    async def _call_keeper(self, eng: PoolEngine, prep: Prepared) -> tuple[float, float]:
        p = self.params
        res = await eng.call(p.goalkeeper_function,
                             np.array([prep.ball_field], dtype=np.float64),
                             np.array([prep.ball_velocity_field], dtype=np.float64),
                             prep.goal_x_field, prep.inp.fs.goal_width,
                             45.0, p.keeper_min_speed_mmps, timeout_s=p.engine_timeout_s)
        try:
            arr = np.asarray(res, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise EngineError(f"{p.goalkeeper_function} returned {res!r}, expected [x y]") \
                from exc
        if arr.size < 2 or not np.all(np.isfinite(arr[:2])):
            raise EngineError(f"{p.goalkeeper_function} returned {res!r}, expected [x y]")
        return (float(arr[0]), float(arr[1]))

    async def engine_settled(self) -> None:
        """Waits until the engine call in flight (if any) has finished (tests, shutdown)."""
        task = self._engine_task
        if task is not None:
            await asyncio.wait([task])

    def drop_engine(self) -> None:
        """Forget the engine (being replaced): its answers no longer count."""
        self.engine = None
        self._engine_point = None
        if self._engine_task is not None:
            self._engine_task.cancel()
            self._engine_task = None
