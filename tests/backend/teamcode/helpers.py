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
