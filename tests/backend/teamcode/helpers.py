"""Shared by the team-code tests: a team folder in a temp dir, a Game, waiting for a runner."""

from __future__ import annotations

import asyncio
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from backend.params.model import PLAYS
from backend.teamcode.discovery import Found, scan
from backend.teamcode.runner import Pending, PythonRunner
from backend.teamcode.state import FileRun
from touchline import Ball, FieldSize, Game, Referee, Robot


def game(mine: tuple[int, ...] = (1, 2), t: float = 0.0, **kw: Any) -> Game:
    ours = tuple(Robot(i, -1000.0 + 300.0 * i, 0.0, 0.0) for i in range(4))
    theirs = tuple(Robot(i, 1000.0 + 300.0 * i, 0.0, 3.14) for i in range(2))
    return Game(1, t, "blue", "negative-x", ours, theirs, Ball(0.0, 0.0), Referee(),
                FieldSize(), mine=mine, **kw)


def write(folder: Path, name: str, text: str) -> None:
    """Writes a team file as an editor would, with a new modification time (a save)."""
    p = folder / name
    p.parent.mkdir(parents=True, exist_ok=True)
    old = p.stat().st_mtime_ns if p.exists() else 0
    p.write_text(text)
    st = p.stat()
    if st.st_mtime_ns <= old:  # a coarse clock: make the save visible all the same
        os.utime(p, ns=(st.st_atime_ns, old + 1_000_000))


def found(folder: Path, name: str) -> Found:
    return scan(folder, PLAYS)[name]


async def until(cond: Callable[[], Any], timeout_s: float = 20.0, what: str = "") -> Any:
    """Waits (bounded) for ``cond()`` to be truthy, letting the loop run."""
    deadline = time.monotonic() + timeout_s
    while True:
        v = cond()
        if v:
            return v
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what or cond}")
        await asyncio.sleep(0.005)


async def started(folder: Path, name: str, kind: str = "play",
                  memory_mb: int = 1024) -> PythonRunner:
    r = PythonRunner(found(folder, name), FileRun(), folder, memory_mb, kind)
    r.ensure()
    await until(lambda: r.run.state != "starting" and r.run.state != "idle",
                what=f"{name} loaded")
    return r


async def answer(p: Pending | None, timeout_s: float = 10.0) -> Pending:
    """The tick's reply, however long it takes (the tests judge what came, not when)."""
    assert p is not None, "nothing was sent"
    await asyncio.wait([p.fut], timeout=timeout_s)
    await until(lambda: p.done, what="the reply accounted")
    return p


class Rig:
    """The strategy and control processors on a Data Bus, with the team folder ``folder``'s
    plays in real worker processes: a world and a referee written by the test, one strategy
    tick and one control step at a time (no sockets, no station loop)."""

    def __init__(self, folder: Path, play: str, **strategy: Any) -> None:
        from backend import topics
        from backend.bus import DataBus
        from backend.params.model import StationParams
        from backend.processors import ControlProcessor, StrategyProcessor
        from backend.teamcode.plays import TeamPlays
        from backend.teamcode.registry import TeamRegistry

        self.topics = topics
        self.bus = DataBus(check_types=True)
        self.registry = TeamRegistry(folder, PLAYS)
        self.registry.rescan()
        self.plays = TeamPlays(self.registry, 1024)
        self.params = StationParams.model_validate(
            {"strategy": {"play": play, "team_budget_ms": 200.0, **strategy}})
        self.strategy = StrategyProcessor(self.bus, "blue", self.params.strategy)
        self.strategy.team = self.plays
        self.control = ControlProcessor(self.bus, 0.05, 0.3)
        self.strategy.configure(self.params)
        self.control.configure(self.params)
        self.robots: dict[int, tuple[float, float, float]] = {
            1: (-1000.0, 0.0, 0.0), 2: (-1000.0, 800.0, 0.0), 3: (-1000.0, -800.0, 0.0)}
        self.ball: tuple[float, float] | None = (0.0, 0.0)
        self.last_step_start = time.monotonic()
        self.step_span = (0.0, 0.0)
        self.last: dict[int, Any] = {}

    def configure(self, **strategy: Any) -> None:
        from backend.params.model import StationParams

        values = self.params.model_dump()
        values["strategy"].update(strategy)
        self.params = StationParams.model_validate(values)
        self.strategy.configure(self.params)
        self.control.configure(self.params)

    def see(self) -> None:
        from backend.world.state import BallState, RobotState, WorldState

        robots = tuple(RobotState("blue", rid, x, y, o, t_seen=time.time())
                       for rid, (x, y, o) in sorted(self.robots.items()))
        ball = None if self.ball is None else BallState(self.ball[0], self.ball[1],
                                                        t_seen=time.time())
        self.bus.of(self.topics.WORLD).write(WorldState(time.time(), time.time_ns(), ball,
                                                        robots))

    def referee(self, command: str) -> None:
        from backend.world.referee import RefereeState

        self.bus.of(self.topics.REFEREE).write(RefereeState(
            command, "NORMAL_FIRST_HALF", len(command), None, {"goalkeeper": 0}, {},
            None, None, 0))

    async def tick(self) -> dict[int, Any]:
        """One strategy tick then one control step (a camera frame); the commands by id.
        ``step_span``: (monotonic before the previous step, after this one): the control
        step's dt (its own clock) lies within."""
        self.see()
        await self.strategy.tick()
        self.see()
        before = time.monotonic()
        self.control.step()
        self.step_span = (self.last_step_start, time.monotonic())
        self.last_step_start = before
        cs = self.bus.of(self.topics.ROBOT_COMMANDS).latest_value()
        self.last = {} if cs is None else {c.id: c for c in cs.commands}
        return self.last

    def targets(self) -> dict[int, Any]:
        t = self.bus.of(self.topics.TARGETS).latest_value() or {}
        return {rid: e for (_team, rid), e in t.items()}

    async def running(self, name: str) -> None:
        """Ticks until the play's worker answers (it starts on the first tick)."""
        for _ in range(2000):
            await self.tick()
            run = self.registry.runs.get(name)
            if run is not None and (run.state == "error" or run.ticks > 0):
                return
            await asyncio.sleep(0.005)
        raise AssertionError(f"{name} never answered")

    async def close(self) -> None:
        await self.plays.close()
