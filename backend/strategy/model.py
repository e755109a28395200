"""Plain data the strategy works on, in *our frame*: our goal at negative x, whatever side we
defend in the vision frame (a half-time side switch flips the frame, not the code).

``Frame`` converts between the vision (field) frame and our frame: when our goal is at +x in
the field frame, our frame is the field frame turned by 180 degrees (x -> -x, y -> -y,
orientation + pi), which keeps left and right as a robot sees them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from domain.field import Field
from domain.rules import BALL_RADIUS_MM as BALL_RADIUS_MM
from domain.rules import ROBOT_RADIUS_MM as ROBOT_RADIUS_MM


@dataclass(frozen=True, slots=True)
class Frame:
    """``sign`` = +1: our goal at negative x (our frame = field frame); -1: our goal at +x."""

    sign: int = 1

    def point(self, x: float, y: float) -> tuple[float, float]:
        """Field -> ours, and (the same operation) ours -> field."""
        return (x * self.sign, y * self.sign)

    def angle(self, a: float) -> float:
        return a if self.sign > 0 else math.atan2(-math.sin(a), -math.cos(a))


def own_defense(fs: Field) -> tuple[float, float, float, float]:
    """Our defence area (our frame) as xmin, ymin, xmax, ymax; it reaches behind the goal
    line so that paths never cut through the goal."""
    hl, hw = fs.half_length, fs.penalty_area_width / 2.0
    return (-hl - 400.0, -hw, -hl + fs.penalty_area_depth, hw)


def their_defense(fs: Field) -> tuple[float, float, float, float]:
    hl, hw = fs.half_length, fs.penalty_area_width / 2.0
    return (hl - fs.penalty_area_depth, -hw, hl + 400.0, hw)


@dataclass(frozen=True, slots=True)
class Bot:
    """A robot in our frame: mm, mm/s, rad."""

    id: int
    x: float
    y: float
    orientation: float
    vx: float = 0.0
    vy: float = 0.0
    #: the robot's own word on the ball at its dribbler (its feedback: simulation protocol's
    #: dribbler_ball_contact, grSim's infrared); None when it says nothing (then geometry)
    contact: bool | None = None

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

    def moved(self, x: float, y: float) -> Intent:
        """This intent with its target at (x, y): ``dataclasses.replace(self, x=x, y=y)``
        without the cost of ``replace`` (it runs for every robot at every tick)."""
        return Intent(self.role, x, y, self.orientation, self.kick_speed_mps, self.chip,
                      self.dribbler, self.max_speed_mps, self.plan, self.avoid_ball_mm,
                      self.own_defense_ok, self.their_defense_ok)


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
