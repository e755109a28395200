"""Plain data the strategy works on, in *our frame*: our goal at negative x, whatever side we
defend in the vision frame (a half-time side switch flips the frame, not the code).

``Frame`` converts between the vision (field) frame and our frame: when our goal is at +x in
the field frame, our frame is the field frame turned by 180 degrees (x -> -x, y -> -y,
orientation + pi), which keeps left and right as a robot sees them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ROBOT_RADIUS_MM = 90.0
BALL_RADIUS_MM = 21.5


@dataclass(frozen=True, slots=True)
class Frame:
    """``sign`` = +1: our goal at negative x (our frame = field frame); -1: our goal at +x."""

    sign: int = 1

    def point(self, x: float, y: float) -> tuple[float, float]:
        """Field -> ours, and (the same operation) ours -> field."""
        return (x * self.sign, y * self.sign)

    def angle(self, a: float) -> float:
        return a if self.sign > 0 else math.atan2(-math.sin(a), -math.cos(a))


@dataclass(frozen=True, slots=True)
class FieldSize:
    """The sizes the strategy needs (mm), from the vision geometry packet."""

    length: float = 9000.0
    width: float = 6000.0
    goal_width: float = 1000.0
    goal_depth: float = 180.0
    defense_depth: float = 1000.0
    defense_width: float = 2000.0
    center_radius: float = 500.0

    @classmethod
    def from_geometry(cls, g: dict[str, float] | None) -> FieldSize:
        if not g:
            return cls()

        def val(key: str, default: float) -> float:
            v = g.get(key)
            return float(v) if isinstance(v, int | float) and v > 0 else default

        return cls(
            length=val("field_length", 9000.0), width=val("field_width", 6000.0),
            goal_width=val("goal_width", 1000.0), goal_depth=val("goal_depth", 180.0),
            defense_depth=val("penalty_area_depth", 1000.0),
            defense_width=val("penalty_area_width", 2000.0),
            center_radius=val("center_circle_radius", 500.0),
        )

    @property
    def half_length(self) -> float:
        return self.length / 2.0

    @property
    def half_width(self) -> float:
        return self.width / 2.0

    def own_defense(self) -> tuple[float, float, float, float]:
        """Our defence area (our frame) as xmin, ymin, xmax, ymax; it reaches behind the goal
        line so that paths never cut through the goal."""
        hl, hw = self.half_length, self.defense_width / 2.0
        return (-hl - 400.0, -hw, -hl + self.defense_depth, hw)

    def their_defense(self) -> tuple[float, float, float, float]:
        hl, hw = self.half_length, self.defense_width / 2.0
        return (hl - self.defense_depth, -hw, hl + 400.0, hw)


@dataclass(frozen=True, slots=True)
class Bot:
    """A robot in our frame: mm, mm/s, rad."""

    id: int
    x: float
    y: float
    orientation: float
    vx: float = 0.0
    vy: float = 0.0

    @property
    def xy(self) -> tuple[float, float]:
        return (self.x, self.y)


@dataclass(frozen=True, slots=True)
class Ball:
    x: float
    y: float
    vx: float = 0.0
    vy: float = 0.0

    @property
    def xy(self) -> tuple[float, float]:
        return (self.x, self.y)

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


@dataclass(frozen=True, slots=True)
class Intent:
    """What one robot should do this tick (our frame)."""

    role: str
    x: float
    y: float
    orientation: float | None = None
    kick_speed_mps: float = 0.0
    chip: bool = False
    dribbler: bool = False
    max_speed_mps: float | None = None
    plan: bool = True  # False: drive straight (the last few cm to the ball)
    avoid_ball_mm: float = 0.0  # keep the robot's centre this far from the ball (0: no)
    own_defense_ok: bool = False  # the keeper may enter our defence area
    their_defense_ok: bool = False  # our ball placer may enter theirs (the game is stopped)


@dataclass(frozen=True, slots=True)
class Move:
    """An intent after navigation, back in the field frame (mm, rad)."""

    role: str
    x: float
    y: float
    orientation: float | None
    path: tuple[tuple[float, float], ...]  # waypoints after the robot's position; last = target
    kick_speed_mps: float = 0.0
    chip: bool = False
    dribbler: bool = False
    max_speed_mps: float | None = None
    blocked: bool = False
