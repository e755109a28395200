"""A fake field for the director's unit tests: robots and ball where the test puts them, the
director's ball teleports applied, events emitted like fieldsim's (``seq``, ``t``, ``kind``),
and a fake clock that ticks the director at 60 Hz."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from match.config import MatchConfig
from match.director import Director, TeleportBall

HZ = 60.0


def kickoff_formation(blue_side: int = -1) -> dict[tuple[str, int], list[float]]:
    """Legal kick-off positions: own half, outside the centre circle, keepers on their goal
    line, nobody in a defence area."""
    spots = [(4450.0, 0.0), (2000.0, 1000.0), (2000.0, -1000.0), (3000.0, 1500.0),
             (3000.0, -1500.0), (1000.0, 0.0)]
    robots: dict[tuple[str, int], list[float]] = {}
    for team, side in (("blue", blue_side), ("yellow", -blue_side)):
        for rid, (x, y) in enumerate(spots):
            robots[(team, rid)] = [side * x, y, 0.0, 0.0]
    return robots


class FakeWorld:
    def __init__(self, *, with_events: bool = True) -> None:
        self.ball = [0.0, 0.0, 0.0, 0.0]  # x, y, vx, vy (mm, mm/s)
        self.robots = kickoff_formation()
        self.events: list[dict[str, Any]] = []
        self.seq = 0
        self.t = 0.0
        self.with_events = with_events
        self.last_touch: dict[str, Any] | None = None
        self.kicks: dict[tuple[str, int], int] | None = None
        self.teleports: list[TeleportBall] = []

    def emit(self, kind: str, **fields: Any) -> dict[str, Any]:
        self.seq += 1
        ev = {"seq": self.seq, "t": self.t, "kind": kind, **fields}
        self.events.append(ev)
        return ev

    def truth(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "t": self.t,
            "ball": {"x": self.ball[0], "y": self.ball[1], "z": 0.0,
                     "vx": self.ball[2], "vy": self.ball[3]},
            "robots": [
                {"team": team, "id": rid, "x": p[0], "y": p[1], "orientation": 0.0,
                 "vx": p[2], "vy": p[3], "omega": 0.0,
                 **({"kicks": self.kicks.get((team, rid), 0)} if self.kicks is not None else {})}
                for (team, rid), p in self.robots.items()
            ],
        }
        if self.with_events:
            out["events"] = self.events[-50:]
            out["last_touch"] = self.last_touch
        return out

    def apply(self, actions: list[TeleportBall]) -> None:
        for a in actions:
            self.ball = [a.x, a.y, 0.0, 0.0]
            self.last_touch = None
            self.teleports.append(a)


class Harness:
    """The director on a fake clock, fed the fake world's truth at 60 Hz."""

    def __init__(self, config: MatchConfig | None = None, world: FakeWorld | None = None) -> None:
        self.d = Director(config if config is not None else MatchConfig(interludes=False))
        self.w = world if world is not None else FakeWorld()
        self.now = 1000.0
        self.start = self.now
        self.on_tick: Callable[[Harness], None] | None = None

    @property
    def elapsed(self) -> float:
        return self.now - self.start

    def tick(self) -> list[TeleportBall]:
        self.now += 1.0 / HZ
        self.w.t += 1.0 / HZ
        if self.on_tick is not None:
            self.on_tick(self)
        actions = self.d.tick(self.now, self.w.truth())
        self.w.apply(actions)
        return actions

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds * HZ)):
            self.tick()

    def until(self, cond: Callable[[], bool], max_s: float, what: str = "") -> float:
        """Ticks until ``cond()``; returns the elapsed time since the harness started."""
        for _ in range(int(max_s * HZ) + 1):
            if cond():
                return self.elapsed
            self.tick()
        raise AssertionError(f"not within {max_s} s: {what or cond}; "
                             f"command {self.d.referee.command}, step {self.d.step}")

    def command(self) -> str:
        return self.d.referee.command

    def until_command(self, command: str, max_s: float) -> float:
        return self.until(lambda: self.command() == command, max_s, command)

    def to_running(self) -> float:
        """Through the opening kick-off into running play (the ball nudged when it is taken)."""
        self.until_command("NORMAL_START", 15)
        self.w.ball[0] += 60.0
        self.until(lambda: self.d.running, 1, "running")
        return self.elapsed

    def robot(self, team: str, rid: int, x: float, y: float, vx: float = 0.0,
              vy: float = 0.0) -> None:
        self.w.robots[(team, rid)] = [x, y, vx, vy]

    def violations(self, team: str, kind: str) -> tuple[int, float]:
        v = self.d.stats[team].violations[kind]
        return v.count, v.seconds


def speed(vx: float, vy: float) -> float:
    return math.hypot(vx, vy)
