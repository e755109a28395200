"""A whole simulated game in one process, on a virtual clock: no socket, no sleep, no wall
clock, deterministic for a seed, as fast as the CPU goes.

It is the station's own pipeline with the sockets taken out. fieldsim's ``World`` (physics) and
``Vision`` (camera frames with noise, misses and each camera's phase) make the SSL-Vision
packets; each team's side is what one backend runs: the world processor (``WorldModel``), the
strategy processor (``StrategyCore``: plays, roles, paths) and the control processor (the speed
controllers, the referee's caps, the safety stops), each on its own Data Bus whose clock is
the virtual one. Their command sets go through the relay's own command table
(``larcmacs_relay.commands``: repeated at the relay's 120 Hz, stale after 0.1 s) into the
World. A scenario's referee steps, or a match's director (``match.director``, judged by
``match.judge``), give the referee; the judge counts every rule violation.

Everything happens at its own instant on the virtual clock, in time order: physics steps of
1/physics_hz, each camera's frames at its rate and phase (delivered after
``vision_latency_ms``), the strategy at ``processors.strategy_hz``, control on every world
update (and at ``control_max_wait_s`` without one), relay output cycles (commands applied
after ``command_latency_ms``), the referee. The run is recorded as an SSL log like the
station's recorder writes (vision packets, referee, our commands as TYPE_TL_COMMANDS) so the
station's Logs/replay open it.

A team play (backend/teamcode) runs in its worker process as in the station, in real time:
its worker is started and its file loaded before the game's clock starts, and each strategy
tick waits for its answer (up to the call's wall-clock backstop: a busy machine never makes
it late) while the virtual clock stands still; a play that crashes, spins or answers wrongly
stops its robots and fails as live.

Not simulated: robot feedback (ball contact from the robots; the strategy judges contact from
positions, as on a legacy grSim port), the compute engine (the built-in keeper code runs) and
the team's processors (a play's ``game.topics`` is empty).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import heapq
import itertools
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from backend import topics
from backend.bus import DataBus, Reader
from backend.control.goto import Target
from backend.messages import CommandSet, OperatorTarget
from backend.params.model import PLAYS, StationParams
from backend.params.store import ParamError, ParamStore
from backend.processors.control import ControlProcessor
from backend.processors.publisher import encode_command_set
from backend.processors.strategy import StrategyProcessor
from backend.processors.world import WorldProcessor
from backend.teamcode.plays import TeamPlays
from backend.teamcode.registry import TeamRegistry
from backend.teamcode.runner import LOAD_WALL_LIMIT_S, STACK_WAIT_S, wall_limit_s
from backend.world.decode import decode_detection, geometry_to_dict
from backend.world.referee import decode_referee
from backend.world.state import CameraFrame
from fieldsim.config import SimConfig
from fieldsim.vision import Vision
from fieldsim.world import Team as SimTeam
from fieldsim.world import World
from larcmacs_relay.codecs import Command as RelayCommand
from larcmacs_relay.commands import CommandTable
from larcmacs_relay.config import RelayConfig
from match.referee import MatchReferee
from ssllog.format import (
    TYPE_REFEREE_2013,
    TYPE_TL_COMMANDS,
    TYPE_TL_SESSION,
    TYPE_VISION_2014,
)
from ssllog.writer import LogWriter

#: the virtual clock's Unix time at t = 0 (2025-01-01 00:00 UTC): every run starts there, so
#: the same run gives the same bytes, and a replay shows times from the run's start
EPOCH_UNIX_S = 1_735_689_600
EPOCH_NS = EPOCH_UNIX_S * 1_000_000_000
#: the monotonic clock of the Data Buses at t = 0 (any positive value)
MONO0 = 1000.0
#: the relay's defaults (output rate, command timeout, chip angle)
RELAY = RelayConfig()
#: a team play's worker's memory (MB), as the station's --team-memory-mb default
TEAM_MEMORY_MB = 1024
#: the referee is recorded this often besides every change (the game controller: ~40 Hz)
REFEREE_LOG_HZ = 10.0
SIDES = ("blue", "yellow")


class RunError(RuntimeError):
    """A run that could not go on (a bad parameter, the wall-clock limit)."""


class Clock:
    """The virtual clock: ``t`` s since the start; monotonic and Unix views of it."""

    def __init__(self) -> None:
        self.t = 0.0

    def mono(self) -> float:
        return MONO0 + self.t

    def ns(self) -> int:
        return EPOCH_NS + round(self.t * 1e9)

    def us(self) -> int:
        return EPOCH_NS // 1000 + round(self.t * 1e6)


def station_params(overrides: Mapping[str, Any], our_team: str, our_side: str,
                   where: str = "params") -> StationParams:
    """The station's parameters with ``overrides`` (dotted names -> values) and our team and
    side; a bad one is a RunError naming it (validated like a PATCH of the page)."""
    nested: dict[str, Any] = {"team": {"our_team": our_team, "our_side": our_side}}
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        cur = nested
        for p in parts[:-1]:
            nxt = cur.setdefault(p, {})
            if not isinstance(nxt, dict):
                raise RunError(f"{where}: {dotted}: {p} is a value, not a group")
            cur = nxt
        cur[parts[-1]] = value
    try:
        return ParamStore(None).patch(nested)
    except ParamError as exc:
        msgs = "; ".join(f"{'.'.join(e['loc'][1:])}: {e['msg']}" for e in exc.errors)
        raise RunError(f"{where}: {msgs}") from None


class Side:
    """One team's backend: world model, strategy and control on a Data Bus of its own."""

    def __init__(self, colour: str, params: StationParams, clock: Clock,
                 record_commands: Callable[[int, int, bytes], None] | None = None) -> None:
        self.colour = colour
        self.clock = clock
        self.params = params
        bus = self.bus = DataBus(params.bus.sizes(), clock=clock.mono)
        for spec in topics.ALL:
            bus.of(spec)
        self.world = WorldProcessor(bus)
        self.strategy = StrategyProcessor(bus, colour, params.strategy,  # type: ignore[arg-type]
                                          params.processors.strategy_hz, clock=clock.mono)
        self.strategy.core.pause = None  # no station thread to let run
        self.control = ControlProcessor(bus, params.processors.control_max_wait_s,
                                        params.safety.vision_stale_s, clock=clock.mono)
        self.control.clock_ns = clock.ns
        self.control.silence = self.world.silence
        for proc in (self.world, self.strategy, self.control):
            proc.configure(params)
        self.detections = bus.of(topics.VISION_DETECTIONS)
        self.geometry = bus.of(topics.GEOMETRY)
        self.referee = bus.of(topics.REFEREE)
        self.world_topic = bus.of(topics.WORLD)
        self.operator = bus.of(topics.OPERATOR_TARGETS)
        self.commands = Reader(bus.of(topics.ROBOT_COMMANDS))
        self._world_seq = 0
        self._control_at = -math.inf
        self.record_commands = record_commands
        self.command_seq = 0
        #: the team's play host when the side runs a team play (its name): a worker process
        #: per play file (backend/teamcode), real time for the team's code itself
        self.team_plays: TeamPlays | None = None
        self.team_play = ""
        #: (t, robot (-1: the file), why), each once: the play's failures (its file's error:
        #: import, exception, output, budget, crash) and why its robots were stopped
        self.team_errors: list[tuple[float, int, str]] = []
        self._said: set[str] = set()

    def use_team_play(self, team_dir: str | None, play: str,
                      memory_mb: int = TEAM_MEMORY_MB) -> None:
        """The side's play is the team folder's ``play`` (RunError when there is none)."""
        if not team_dir:
            raise RunError(f"play {play!r} is not a built-in play ({', '.join(PLAYS)}) and "
                           "no team folder is given (--team-dir)")
        folder = Path(team_dir)
        if not folder.is_dir():
            raise RunError(f"no team folder {team_dir}")
        reg = TeamRegistry(folder, PLAYS)
        reg.rescan()
        plays = reg.plays()
        if play not in plays:
            raise RunError(f"missing: no play {play!r} in the team folder {folder.name} "
                           f"(its plays: {', '.join(sorted(plays)) or 'none'})")
        self.team_plays = TeamPlays(reg, memory_mb)
        # the game's clock stands still while a tick waits: wait for the answer up to the
        # call's wall-clock backstop (then its worker is stopped; a spin is stopped sooner,
        # at its CPU limit), never "late" on a busy machine
        budget = self.params.strategy.team_budget_ms / 1000.0
        self.team_plays.grace_s = wall_limit_s(budget) + STACK_WAIT_S + 0.1
        self.team_play = play
        self.strategy.team = self.team_plays

    async def start_team(self) -> None:
        """The team play's worker started and its file loaded before the game's clock runs
        (loading takes real time; the virtual clock would run on without it)."""
        tp = self.team_plays
        if tp is None:
            return
        r = tp.runner(tp.registry.plays()[self.team_play])
        r.ensure()
        deadline = time.monotonic() + LOAD_WALL_LIMIT_S + 5.0
        while r.run.state not in ("running", "error") and time.monotonic() < deadline:
            await asyncio.sleep(0.01)  # a real process starting: its state, bounded
        if r.run.error is not None:
            self.team_error(-1, r.run.error.one_line())

    def team_error(self, rid: int, why: str) -> None:
        if why not in self._said:
            self._said.add(why)
            self.team_errors.append((self.clock.t, rid, why))

    def after_strategy(self) -> None:
        tp = self.team_plays
        if tp is None:
            return
        for r in tp.runners.values():
            if r.run.error is not None:
                self.team_error(-1, r.run.error.one_line())
        for rid, _play, why in self.strategy.stopped:
            self.team_error(rid, why)

    async def close_team(self) -> None:
        if self.team_plays is not None:
            await self.team_plays.close()

    def vision(self, frame: CameraFrame) -> list[CommandSet]:
        """A camera frame arrives: the world model merges it, control runs on a new world."""
        self.detections.write(frame)
        self.world.step()
        if self.world_topic.seq != self._world_seq:
            self._world_seq = self.world_topic.seq
            return self.run_control()
        return []

    def run_control(self) -> list[CommandSet]:
        self._control_at = self.clock.t
        self.control.step()
        out = self.commands.read_new()
        rec = self.record_commands
        if rec is not None:
            for cs in out:
                self.command_seq += 1
                rec(self.clock.ns(), TYPE_TL_COMMANDS,
                    encode_command_set(cs, self.command_seq).SerializeToString())
        return out

    def control_due(self) -> bool:
        """No control step for ``control_max_wait_s`` (no world update: vision lost)."""
        wait = self.params.processors.control_max_wait_s
        return self.clock.t - self._control_at >= wait - 1e-9

    def operator_target(self, rid: int, x_mm: float, y_mm: float,
                        heading: float | None) -> None:
        self.operator.write(OperatorTarget(self.colour, rid,  # type: ignore[arg-type]
                                           Target(x_mm, y_mm, heading)))


class _InlineExecutor(concurrent.futures.ThreadPoolExecutor):
    """Runs what is submitted at once, in the caller's thread (asyncio takes only a
    ThreadPoolExecutor as the default executor; this one never starts a thread)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any,
               **kwargs: Any) -> concurrent.futures.Future[Any]:
        fut: concurrent.futures.Future[Any] = concurrent.futures.Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            fut.set_exception(exc)
        return fut


@dataclass(order=True)
class _Due:
    t: float
    order: int  # at one instant: physics first, then cameras, deliveries, ...
    seq: int
    fn: Callable[[], Any] = field(compare=False)


class Engine:
    """The virtual-time loop shared by scenario runs and matches: physics, cameras, the
    sides, the relay, the log. Subclasses add the referee and what they observe."""

    # orders at one instant
    O_ACTION, O_CAMERA, O_DELIVER, O_REFEREE, O_STRATEGY, O_CONTROL, O_RELAY, O_SAMPLE = range(8)

    def __init__(self, sim: SimConfig, vision_latency_s: float, command_latency_s: float,
                 log_path: str | None, session: Mapping[str, Any],
                 max_wall_s: float | None = None) -> None:
        self.clock = Clock()
        sim.validate()
        self.sim = sim
        self.world = World(sim)
        self.vision_gen = Vision(sim, self.world.geometry)
        self.vision_latency_s = vision_latency_s
        self.command_latency_s = command_latency_s
        self.sides: dict[str, Side] = {}
        self.table = CommandTable(timeout_s=RELAY.command_timeout_s)
        self._heap: list[_Due] = []
        self._seq = itertools.count()
        self.max_wall_s = max_wall_s
        self.log: LogWriter | None = LogWriter(log_path) if log_path else None
        if self.log is not None:
            self.log.write(EPOCH_NS, TYPE_TL_SESSION, json.dumps(
                {"touchline": 1, "started_unix": EPOCH_UNIX_S, "reason": "evaluate",
                 **session}).encode())
        self._geometry_pkt = self.vision_gen.geometry_packet()
        self._geometry_bytes = self._geometry_pkt.SerializeToString()
        self._geometry_dict = geometry_to_dict(self._geometry_pkt.geometry)
        self.stopped = False
        self.frames = 0

    # -- scheduling ---------------------------------------------------------------------------

    def at(self, t: float, order: int, fn: Callable[[], Any]) -> None:
        heapq.heappush(self._heap, _Due(t, order, next(self._seq), fn))

    def every(self, period: float, order: int, fn: Callable[[], Any], start: float = 0.0) -> None:
        """``fn`` at start, start + period, ... (times computed from the count, no drift)."""
        n = itertools.count()

        def tick() -> Any:
            self.at(start + next(n) * period, order, tick)
            return fn()  # (a coroutine, the strategy's tick: the loop awaits it)

        next(n)
        self.at(start, order, tick)

    def record(self, rtype: int, payload: bytes, t_ns: int | None = None) -> None:
        if self.log is not None:
            self.log.write(self.clock.ns() if t_ns is None else t_ns, rtype, payload)

    def record_at(self, t_ns: int, rtype: int, payload: bytes) -> None:
        """``record`` in the station recorder's order of arguments."""
        if self.log is not None:
            self.log.write(t_ns, rtype, payload)

    # -- the parts ----------------------------------------------------------------------------

    def add_side(self, colour: str, params: StationParams, record: bool) -> Side:
        side = Side(colour, params, self.clock, self.record_at if record else None)
        side.geometry.write(self._geometry_dict)
        self.sides[colour] = side
        return side

    def start_parts(self) -> None:
        cfg = self.sim
        period = 1.0 / cfg.camera_hz
        for cam, phase in enumerate(self.vision_gen.phases):
            self.every(period, self.O_CAMERA, lambda c=cam: self._capture(c), phase)  # type: ignore[misc]
        self.every(1.0 / cfg.geometry_hz, self.O_CAMERA, self._geometry)
        for colour, side in self.sides.items():
            hz = side.params.processors.strategy_hz
            # each team's strategy at its own phase (two backends are not in step)
            offset = 0.0 if colour == "blue" else 0.5 / hz
            self.every(1.0 / hz, self.O_STRATEGY, lambda s=side: self._strategy(s), offset)  # type: ignore[misc]
            wait = side.params.processors.control_max_wait_s
            self.every(wait, self.O_CONTROL, lambda s=side: self._control_wake(s), wait)  # type: ignore[misc]
        self.every(1.0 / RELAY.output_rate_hz, self.O_RELAY, self._relay_cycle)

    def _capture(self, cam: int) -> None:
        w = self.world
        tc = self.clock.t
        pkt = self.vision_gen.detect(cam, w, EPOCH_UNIX_S + tc, None, tc - w.t)
        recv = tc + self.vision_latency_s
        pkt.detection.t_sent = EPOCH_UNIX_S + tc
        self.at(recv, self.O_DELIVER, lambda: self._deliver(pkt))

    def _deliver(self, pkt: Any) -> None:
        recv_ns = self.clock.ns()
        self.record(TYPE_VISION_2014, pkt.SerializeToString(), recv_ns)
        frame = decode_detection(pkt.detection, recv_ns)
        self.frames += 1
        for side in self.sides.values():
            self._commands(side.vision(frame))

    def _geometry(self) -> None:
        self.record(TYPE_VISION_2014, self._geometry_bytes)

    async def _strategy(self, side: Side) -> None:
        await side.strategy.tick()
        side.after_strategy()

    def _control_wake(self, side: Side) -> None:
        if side.control_due():
            self._commands(side.run_control())

    def _commands(self, sets: list[CommandSet]) -> None:
        if not sets:
            return
        when = self.clock.t + self.command_latency_s
        for cs in sets:
            self.at(when, self.O_RELAY - 1, lambda cs=cs: self._to_relay(cs))  # type: ignore[misc]

    def _to_relay(self, cs: CommandSet) -> None:
        now = self.clock.t
        if cs.stop_all:
            self.table.stop_all(now)
            return
        cmds = [RelayCommand(2 if c.team == "blue" else 1, c.id, c.velocity[0], c.velocity[1],
                             c.velocity[2], c.kick_speed_mps, c.chip, c.dribbler_rpm)
                for c in cs.commands]
        self.table.update_all(cmds, now)

    def _relay_cycle(self) -> None:
        w = self.world
        chip = math.radians(RELAY.chip_angle_deg)
        for c in self.table.due(self.clock.t):
            team = SimTeam.BLUE if c.team == 2 else SimTeam.YELLOW
            # (a non-finite command: fieldsim stops the robot and raises; the relay refuses it)
            with contextlib.suppress(ValueError):
                w.set_command(team, c.id, c.forward_mps, c.left_mps, c.angular_radps,
                              c.kick_speed_mps, chip if (c.chip and c.kick_speed_mps > 0) else 0.0,
                              c.dribbler_rpm)

    def send_referee(self, ref: MatchReferee) -> None:
        """The referee's current state to every side and into the log."""
        msg = ref.message(self.clock.us())
        self.record(TYPE_REFEREE_2013, msg.SerializeToString())
        state = decode_referee(msg)
        for side in self.sides.values():
            side.referee.write(state)

    # -- the loop -----------------------------------------------------------------------------

    def on_step(self) -> None:
        """After every physics step (events, samples)."""

    async def _loop(self, until: float) -> None:
        w = self.world
        dt = w.dt
        heap = self._heap
        wall0 = time.monotonic()
        n = 0
        while heap and not self.stopped:
            due = heapq.heappop(heap)
            if due.t > until + 1e-9:
                break
            # physics up to the event's instant (like fieldsim's real-time loop)
            while w.t + dt <= due.t + 1e-9:
                w.step()
                self.clock.t = w.t
                self.on_step()
                if self.stopped:
                    return
            self.clock.t = due.t
            res = due.fn()
            if asyncio.iscoroutine(res):
                await res
            n += 1
            if self.max_wall_s is not None and n % 2000 == 0 \
                    and time.monotonic() - wall0 > self.max_wall_s:
                raise RunError(f"the run took longer than {self.max_wall_s:g} s of wall time "
                               f"(at {self.clock.t:.1f} s of game time)")
        while w.t + dt <= until + 1e-9 and not self.stopped:
            w.step()
            self.clock.t = w.t
            self.on_step()

    def run_until(self, until: float) -> None:
        asyncio.run(self._main(until))

    async def _main(self, until: float) -> None:
        # the strategy decides in ``asyncio.to_thread`` (live: beside the station thread);
        # here nothing runs beside it, so it runs inline: no thread hand-over per tick
        asyncio.get_running_loop().set_default_executor(_InlineExecutor())
        try:
            for side in self.sides.values():
                await side.start_team()
            await self._loop(until)
        finally:
            for side in self.sides.values():
                await side.close_team()

    def close(self) -> None:
        if self.log is not None:
            self.log.finish()
            self.log = None
