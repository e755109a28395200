"""What a headless run leaves for the checks: fieldsim's ground truth sampled over time and the
events of the run (goals, balls out, collisions, touches, kicks, referee commands, rule
violations), in **our frame** and SI units (m, m/s, s, rad), like the scenario files.

A check (``evaluate.checks``) is a function of a :class:`Run`; a test builds a Run by hand with
:class:`RunBuilder` (``sample`` then ``event``) to try a check on a known case.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

TeamSide = str  # "ours" | "theirs"
RobotKey = tuple[str, int]

#: columns of a robot's samples
RX, RY, RHEADING, RVX, RVY, ROMEGA = range(6)
#: columns of the ball's samples
BX, BY, BVX, BVY = range(4)


@dataclass(frozen=True)
class Event:
    """Something that happened at ``t`` s: ``kind`` is one of "goal" (``detail`` "ours": into
    our goal, "theirs": we scored), "ball_out", "collision" (``data``: the other robot and the
    relative speed), "touch" (the robot that last touched the ball changed), "kick",
    "referee" (``detail``: the command, ``team`` its team), "violation" (``detail``: the
    kind, ``data["text"]`` the judge's words), "team_error" (a team play failed)."""

    t: float
    kind: str
    team: TeamSide | None = None
    robot: int | None = None
    detail: str = ""
    data: Mapping[str, Any] = field(default_factory=dict)


@dataclass
class Run:
    """One run: ``t`` (N,) s; ``ball`` (N, 4) x, y, vx, vy; ``robots[(team, id)]`` (N, 6) x, y,
    heading, vx, vy, omega; every event in time order; the referee's placement target."""

    t: np.ndarray
    ball: np.ndarray
    robots: dict[RobotKey, np.ndarray]
    events: list[Event]
    duration_s: float
    task: Mapping[str, Any] = field(default_factory=dict)
    #: the last ball placement target the referee gave (our frame, m), if any
    designated: tuple[float, float] | None = None
    #: why the run ended early ("goal", "ball_out"), or "" at its duration
    ended_by: str = ""

    def robot(self, team: TeamSide, rid: int) -> np.ndarray:
        """The samples of a robot; a robot never on the field is a KeyError naming it."""
        try:
            return self.robots[(team, rid)]
        except KeyError:
            have = ", ".join(f"{t} {i}" for t, i in sorted(self.robots)) or "none"
            raise KeyError(f"no {team} robot {rid} in this run (robots: {have})") from None

    def of(self, kind: str) -> list[Event]:
        return [e for e in self.events if e.kind == kind]

    def index_at(self, t: float) -> int:
        """The last sample at or before ``t``."""
        i = int(np.searchsorted(self.t, t, side="right")) - 1
        return max(0, min(i, len(self.t) - 1))


class RunBuilder:
    """Collects samples and events into a :class:`Run` (the headless runner, and tests)."""

    def __init__(self, task: Mapping[str, Any] | None = None) -> None:
        self._t: list[float] = []
        self._ball: list[tuple[float, float, float, float]] = []
        self._robots: dict[RobotKey, list[tuple[float, ...]]] = {}
        self._first: dict[RobotKey, int] = {}
        self.events: list[Event] = []
        self.task = dict(task or {})
        self.designated: tuple[float, float] | None = None
        self.ended_by = ""

    def sample(self, t: float, ball: Sequence[float] | None,
               robots: Mapping[RobotKey, Sequence[float]]) -> None:
        """The truth at ``t``: ball (x, y, vx, vy), robots (x, y, heading[, vx, vy, omega])."""
        n = len(self._t)
        self._t.append(t)
        b = tuple(ball) if ball is not None else (math.nan,) * 4
        self._ball.append((b[0], b[1], b[2] if len(b) > 2 else 0.0, b[3] if len(b) > 3 else 0.0))
        for key, r in robots.items():
            rows = self._robots.get(key)
            if rows is None:
                rows = self._robots[key] = [(math.nan,) * 6] * n  # not on the field before
            row = tuple(r) + (0.0,) * (6 - len(r))
            rows.append(row)
        for rows in self._robots.values():
            if len(rows) < n + 1:
                rows.append((math.nan,) * 6)  # gone (taken off the field)

    def event(self, t: float, kind: str, team: TeamSide | None = None, robot: int | None = None,
              detail: str = "", **data: Any) -> None:
        self.events.append(Event(t, kind, team, robot, detail, data))

    def build(self, duration_s: float | None = None) -> Run:
        t = np.asarray(self._t, dtype=np.float64)
        ball = np.asarray(self._ball, dtype=np.float64).reshape(-1, 4)
        robots = {k: np.asarray(v, dtype=np.float64).reshape(-1, 6)
                  for k, v in self._robots.items()}
        dur = duration_s if duration_s is not None else (float(t[-1]) if len(t) else 0.0)
        events = sorted(self.events, key=lambda e: e.t)
        return Run(t, ball, robots, events, dur, self.task, self.designated, self.ended_by)
