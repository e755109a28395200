"""fieldsim's ground truth (``World.truth()`` as JSON) read defensively into plain values.

Everything beyond the ball and robot positions is optional: older fieldsim builds carry no
``events``, ``last_touch`` or per-robot ``kicks``/``dribbling``, and a malformed entry is
skipped rather than trusted."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

TEAMS = ("blue", "yellow")
RobotKey = tuple[str, int]


def other(team: str) -> str:
    return "yellow" if team == "blue" else "blue"


def num(value: Any) -> float | None:
    """A finite number, or None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def robot_key(value: Any) -> RobotKey | None:
    """{"team": "blue"|"yellow", "id": int} -> ("blue", 3), or None."""
    if not isinstance(value, Mapping):
        return None
    team, rid = value.get("team"), value.get("id")
    if team not in TEAMS or isinstance(rid, bool) or not isinstance(rid, int):
        return None
    return (str(team), rid)


@dataclass(frozen=True, slots=True)
class BallView:
    x: float
    y: float
    vx: float
    vy: float

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


@dataclass(frozen=True, slots=True)
class RobotView:
    team: str
    id: int
    x: float
    y: float
    vx: float
    vy: float
    kicks: int | None = None

    @property
    def key(self) -> RobotKey:
        return (self.team, self.id)

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


_MISSING: Any = object()


@dataclass(frozen=True, slots=True)
class Snapshot:
    t: float | None
    ball: BallView | None
    robots: tuple[RobotView, ...]
    events: tuple[Mapping[str, Any], ...] | None  # None: this fieldsim reports no events
    has_last_touch: bool
    last_touch: RobotKey | None


def parse_truth(truth: Mapping[str, Any]) -> Snapshot:
    ball = None
    b = truth.get("ball")
    if isinstance(b, Mapping):
        x, y = num(b.get("x")), num(b.get("y"))
        if x is not None and y is not None:
            ball = BallView(x, y, num(b.get("vx")) or 0.0, num(b.get("vy")) or 0.0)
    robots: list[RobotView] = []
    raw_robots = truth.get("robots")
    for r in raw_robots if isinstance(raw_robots, list) else []:
        key = robot_key(r)
        if key is None:
            continue
        x, y = num(r.get("x")), num(r.get("y"))
        if x is None or y is None:
            continue
        k = r.get("kicks")
        kicks = k if isinstance(k, int) and not isinstance(k, bool) else None
        robots.append(RobotView(key[0], key[1], x, y, num(r.get("vx")) or 0.0,
                                num(r.get("vy")) or 0.0, kicks))
    raw_events = truth.get("events", _MISSING)
    events: tuple[Mapping[str, Any], ...] | None
    if raw_events is _MISSING:
        events = None
    elif isinstance(raw_events, list):
        events = tuple(e for e in raw_events if isinstance(e, Mapping))
    else:
        events = ()
    has_lt = "last_touch" in truth
    return Snapshot(
        t=num(truth.get("t")),
        ball=ball,
        robots=tuple(robots),
        events=events,
        has_last_touch=has_lt,
        last_touch=robot_key(truth.get("last_touch")) if has_lt else None,
    )
