"""The bodies on fieldsim's field as plain data: robots, their commands, the ball(s), teams.

Separate from the physics (``robot_physics``, ``ball_physics``) so that the cameras
(``vision``) and the protocols read the same types without importing the stepping code.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from fieldsim.geometry import FieldGeometry

MAX_ROBOT_ID = 15
ROBOT_HEIGHT_M = 0.15

class Team(enum.IntEnum):
    """Same numbers as ssl_gc_common.Team."""

    YELLOW = 1
    BLUE = 2

    @property
    def label(self) -> str:
        return "yellow" if self is Team.YELLOW else "blue"


RobotKey = tuple[Team, int]


@dataclass
class Command:
    """The latest command of one robot (local frame, before the gain C)."""

    forward: float = 0.0  # m/s
    left: float = 0.0  # m/s
    angular: float = 0.0  # rad/s ccw
    kick_speed: float = 0.0  # m/s, 3D speed; 0 = kicker not armed
    kick_angle: float = 0.0  # rad above ground, 0 = straight kick
    dribbler_rpm: float = 0.0
    received_at: float = 0.0  # World.t when it arrived


@dataclass
class Robot:
    team: Team
    id: int
    x: float  # m
    y: float  # m
    theta: float  # rad, ccw from +x
    gain: float = 1.0  # C: actual velocity setpoint = C * commanded
    vx: float = 0.0  # m/s, field frame
    vy: float = 0.0
    omega: float = 0.0  # rad/s
    command: Command | None = None
    ball_contact: bool = False
    kicks: int = 0
    last_kick_chip: bool = False  # the last kick left the ground
    dribbling: bool = False  # holds the ball with its dribbler


@dataclass
class Ball:
    x: float = 0.0  # m
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0  # m/s
    vy: float = 0.0
    vz: float = 0.0


# Formation in fractions of (half length, half width) on the negative-x half, 11 slots.
_FORMATION: tuple[tuple[float, float], ...] = (
    (-0.9, 0.0),
    (-0.65, -0.35),
    (-0.65, 0.35),
    (-0.4, -0.7),
    (-0.4, 0.7),
    (-0.25, 0.0),
    (-0.45, 0.0),
    (-0.2, -0.4),
    (-0.2, 0.4),
    (-0.8, -0.65),
    (-0.8, 0.65),
)


def formation(n: int, side: int, geometry: FieldGeometry) -> list[tuple[float, float, float]]:
    """``n`` start poses (x m, y m, theta rad) on the half with sign ``side`` (-1 or +1)."""
    hl = geometry.half_length / 1000.0
    hw = geometry.half_width / 1000.0
    poses = []
    for fx, fy in _FORMATION[:n]:
        if side < 0:
            poses.append((fx * hl, fy * hw, 0.0))
        else:
            poses.append((-fx * hl, -fy * hw, math.pi))
    return poses


@dataclass
class WorldStats:
    kicks: int = 0
    ball_wall_bounces: int = 0  # outer walls
    goal_wall_bounces: int = 0
    goals: int = 0
    ball_out: int = 0
    collisions: int = 0
    steps: int = 0

