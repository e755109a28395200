"""The team's plays as the strategy runs them: a runner per play file in use (started when a
robot is given the play, stopped a while after none is), reloaded when its file or a library
changes, asked once per strategy tick, its answer checked (``orders``) and kept within the
safety envelope (``envelope``).

A strategy tick (``StrategyProcessor``) does::

    tick = plays.ask(game, groups, budget_s)     # requests out, concurrently
    ...                                           # the built-in plays decide meanwhile
    await tick.wait()                             # the budget + a small grace, never more
    out = tick.orders(rules, robots, stop_distance_mm)   # intents, velocities, stops
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

from touchline import Game

from ..strategy.model import Bot, Intent
from .discovery import Found
from .envelope import Rules, check_target, check_velocity
from .octave import OctaveRunner
from .orders import OrderError, TargetOrder, VelocityOrder, validate_orders
from .registry import TeamRegistry
from .runner import Pending, PythonRunner, Runner
from .state import ErrorInfo

log = logging.getLogger("touchline.team")

#: the tick waits this much longer than the budget for the answers (pipes, pickling, the
#: worker being scheduled on a busy machine); never more
IPC_GRACE_S = 0.02
#: a play no robot runs any more keeps its worker this long (a quick switch back is instant)
IDLE_CLOSE_S = 5.0


@dataclass
class TeamOrders:
    """What the team's plays decided this tick (our frame)."""

    intents: dict[int, Intent] = field(default_factory=dict)  # Targets, for navigation
    velocities: dict[int, VelocityOrder] = field(default_factory=dict)
    #: robots to hold still: id -> why (None: the play left it out, no failure)
    stops: dict[int, str | None] = field(default_factory=dict)
    #: the play each robot runs (for the world message)
    plays: dict[int, str] = field(default_factory=dict)


@dataclass
class _Ask:
    play: str
    mine: tuple[int, ...]
    runner: Runner | None
    pending: Pending | None
    reason: str  # why nothing was asked (no runner, failed, starting, busy)


class TeamTick:
    """One strategy tick's requests to the team's plays."""

    def __init__(self, asks: list[_Ask], deadline: float) -> None:
        self.asks = asks
        self.deadline = deadline

    async def wait(self) -> None:
        """Until every answer is in, or the deadline (the budget + grace from the ask)."""
        futs = [a.pending.fut for a in self.asks if a.pending is not None and not a.pending.done]
        if futs:
            await asyncio.wait(futs, timeout=max(0.0, self.deadline - time.monotonic()))
        # a reply's accounting runs in the future's callback: let those of the answers that
        # are in run before judging them
        await asyncio.sleep(0)
        for a in self.asks:
            if a.pending is not None and not a.pending.done and a.runner is not None:
                a.runner.late(a.pending)

    def orders(self, rules: Rules, robots: Mapping[int, Bot]) -> TeamOrders:
        """The answers, checked and kept within the envelope."""
        out = TeamOrders()
        for a in self.asks:
            for rid in a.mine:
                out.plays[rid] = a.play
            p = a.pending
            if p is None or p.output is None or a.runner is None:
                why = a.reason if p is None else p.reason
                for rid in a.mine:
                    out.stops[rid] = why or "no answer"
                continue
            runner = a.runner
            try:
                orders = validate_orders(p.output, a.mine)
            except OrderError as exc:
                runner.fail(ErrorInfo("output", str(exc), runner.name))
                err = runner.run.error
                for rid in a.mine:
                    out.stops[rid] = err.one_line() if err is not None else str(exc)
                continue
            moved = 0
            for rid in a.mine:
                o = orders.get(rid)
                if o is None:
                    out.stops[rid] = None  # the play leaves it out: it stands still
                    continue
                if isinstance(o, TargetOrder):
                    o, changed = check_target(o, rules)
                    out.intents[rid] = _intent(o, rules)
                else:
                    bot = robots.get(rid)
                    if bot is None:
                        out.stops[rid] = None
                        continue
                    o, changed = check_velocity(o, bot.x, bot.y, bot.orientation, rules)
                    out.velocities[rid] = o
                if changed:
                    moved += 1
            runner.run.moved_out += moved
        return out


def _intent(o: TargetOrder, rules: Rules) -> Intent:
    """A Target as the built-in navigation takes it: planned around robots, the areas and
    (when the referee says so) the ball, unless ``avoid`` is False."""
    avoid_ball = rules.stop_distance_mm - 20.0 if rules.keep_off_ball else 0.0
    return Intent(o.role or "team", o.x, o.y, o.orientation, kick_speed_mps=o.kick_mps,
                  chip=o.chip, dribbler=o.dribble, max_speed_mps=o.max_speed_mps,
                  plan=o.avoid or avoid_ball > 0.0, avoid_ball_mm=avoid_ball,
                  own_defense_ok=o.id == rules.keeper_id)


class TeamPlays:
    """The runners of the team's plays (by file name), following the team folder."""

    def __init__(self, registry: TeamRegistry, memory_mb: int) -> None:
        self.registry = registry
        self.memory_mb = memory_mb
        self.runners: dict[str, Runner] = {}
        self.last_used: dict[str, float] = {}
        #: an Octave play's budget: the compute engine's timeout (strategy.engine_timeout_s)
        self.octave_timeout_s = 0.2
        #: how much longer than the budget a tick waits for the answers (wall clock). Live:
        #: IPC_GRACE_S. Headless (evaluate/) the game's clock stands still while it waits,
        #: so it waits up to the wall-clock backstop: a busy machine never makes an answer
        #: late there
        self.grace_s = IPC_GRACE_S
        self._closing: set[asyncio.Task[None]] = set()
        registry.listeners.append(self._changed)

    @property
    def team_dir(self) -> Path:
        return self.registry.dir

    def _new_runner(self, found: Found) -> Runner:
        run = self.registry.run(found.name)
        if found.language == "octave":
            return OctaveRunner(found, run, self.team_dir, self.octave_timeout_s)
        return PythonRunner(found, run, self.team_dir, self.memory_mb, "play")

    def runner(self, found: Found) -> Runner:
        r = self.runners.get(found.name)
        if r is None or r.closed:
            r = self.runners[found.name] = self._new_runner(found)
            if found.error is not None:
                r.update(found)  # fails at once with what discovery found
        return r

    def _changed(self, changed: set[str], found: Mapping[str, Found]) -> None:
        """The folder changed: files gone stop their runners; a changed play reloads; a
        changed library reloads every play of its language (it may import it)."""
        libs = {n.rsplit(".", 1)[-1] for n in changed
                if (n not in found or found[n].kind != "play") and n.endswith((".py", ".m"))}
        for name, r in list(self.runners.items()):
            f = found.get(name)
            if f is None or f.play is None:
                self._close(name)
                continue
            ext = "py" if f.language == "python" else "m"
            if name in changed or ext in libs:
                r.update(f)

    def _close(self, name: str) -> None:
        r = self.runners.pop(name, None)
        self.last_used.pop(name, None)
        if r is not None:
            task = asyncio.get_running_loop().create_task(r.close())
            self._closing.add(task)
            task.add_done_callback(self._closing.discard)

    def ask(self, game: Game, groups: Mapping[str, tuple[int, ...]], budget_s: float,
            octave_timeout_s: float | None = None, now: float | None = None) -> TeamTick:
        """Sends this tick's requests: ``groups`` maps each team play in use to the robots it
        drives (sorted ids); ``budget_s`` a Python play's CPU time, ``octave_timeout_s`` an
        Octave play's. Runners of plays not in use close after ``IDLE_CLOSE_S``."""
        now = time.monotonic() if now is None else now
        if octave_timeout_s is not None:
            self.octave_timeout_s = octave_timeout_s
            for r in self.runners.values():
                if isinstance(r, OctaveRunner):
                    r.timeout_s = octave_timeout_s
        plays = self.registry.plays()
        asks: list[_Ask] = []
        for play, mine in groups.items():
            f = plays.get(play)
            if f is None:
                asks.append(_Ask(play, mine, None, None,
                                 f"missing: no file for play {play!r} in the team folder"))
                continue
            r = self.runner(f)
            self.last_used[f.name] = now
            r.run.robots = mine  # who it drives, for the page
            r.ensure()
            if r.failed:
                err = r.run.error
                asks.append(_Ask(play, mine, r, None,
                                 err.one_line() if err is not None else "failed"))
                continue
            if r.run.state != "running":
                asks.append(_Ask(play, mine, r, None, f"{f.name} is {r.run.state}"))
                continue
            p = r.send(replace(game, mine=mine), None, budget_s, now)
            asks.append(_Ask(play, mine, r, p, "" if p is not None else
                             f"{f.name} is reloading" if r.reloading else
                             r.waiting()))
        self.release({a.runner.name for a in asks if a.runner is not None}, now)
        longest = max((a.pending.budget_s for a in asks if a.pending is not None),
                      default=budget_s)
        return TeamTick(asks, now + longest + self.grace_s)

    def release(self, used: set[str] | None = None, now: float | None = None) -> None:
        """Runners not ``used`` this tick drive no robot; those unused for
        ``IDLE_CLOSE_S`` lose their worker (a tick without any team play calls this too)."""
        now = time.monotonic() if now is None else now
        for name in list(self.runners):
            if used is None or name not in used:
                self.runners[name].run.robots = ()
                if now - self.last_used.get(name, now) > IDLE_CLOSE_S:
                    self._close(name)

    async def close(self) -> None:
        for name in list(self.runners):
            self._close(name)
        if self._closing:
            await asyncio.gather(*self._closing, return_exceptions=True)

