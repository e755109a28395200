"""Plain data of the world, shared by the world model, strategy, control and the API."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

from domain.teams import TEAMS as TEAMS
from domain.teams import Team as Team


@dataclass(slots=True)
class RobotState:
    team: Team
    id: int
    x: float  # mm
    y: float  # mm
    orientation: float  # rad
    vx: float = 0.0  # mm/s
    vy: float = 0.0  # mm/s
    omega: float = 0.0  # rad/s
    t_seen: float = 0.0  # t_capture (Unix s) of the newest detection merged
    visible: bool = True  # False once lost (not seen for WorldModelConfig.lost_after_s)
    cameras: tuple[int, ...] = ()  # cameras that saw it recently
    # latest merged measurement, before filtering (None when not from the world model)
    raw_x: float | None = None  # mm
    raw_y: float | None = None  # mm
    raw_orientation: float | None = None  # rad
    predicted: bool = False  # not seen for a while: x, y, orientation extrapolated
    lost: bool = False  # not seen for too long: frozen, velocity zero, visible False
    filter: str = ""  # filter kind in use: "raw", "median", "paper", "kalman", "adaptive"


@dataclass(slots=True)
class BallState:
    x: float  # mm, filtered
    y: float  # mm, filtered
    vx: float = 0.0  # mm/s
    vy: float = 0.0  # mm/s
    t_seen: float = 0.0
    visible: bool = True
    cameras: tuple[int, ...] = ()
    raw_x: float | None = None  # mm, latest associated detection (merged over cameras)
    raw_y: float | None = None
    predicted: bool = False
    lost: bool = False
    filter: str = ""
    # a chipped ball in the air (backend.world.flight): height and vertical speed, else 0
    z: float = 0.0  # mm
    vz: float = 0.0  # mm/s
    flying: bool = False  # x, y, z from the flight estimate (ground point under the ball)


@dataclass(frozen=True, slots=True)
class OtherBall:
    """A ball seen consistently besides the ball (a second ball left on the field)."""

    x: float  # mm, its latest detection
    y: float
    t_seen: float
    cameras: tuple[int, ...]
    detections: int  # consistent detections so far


class RawRobot(NamedTuple):
    """One robot detection of a camera frame (a tuple: built in one call, not a frozen
    dataclass's six ``object.__setattr__``; thousands are decoded a second). Read by name."""

    team: Team
    id: int
    x: float
    y: float
    orientation: float
    confidence: float


class RawBall(NamedTuple):
    """One ball detection of a camera frame (a tuple, as ``RawRobot``)."""

    x: float
    y: float
    confidence: float


@dataclass(frozen=True, slots=True)
class CameraFrame:
    """One camera's detection frame, decoded."""

    camera_id: int
    frame_number: int
    t_capture: float
    t_sent: float
    receive_time_ns: int
    balls: tuple[RawBall, ...]
    robots: tuple[RawRobot, ...]


@dataclass(frozen=True, slots=True)
class KickedBall:
    """A kick in progress (mm, mm/s, Unix s). ``vx``, ``vy``: the initial velocity;
    ``stop_*``: where and when the ball is predicted to stop."""

    robot: tuple[Team, int] | None
    start_x: float
    start_y: float
    start_t: float
    vx: float
    vy: float
    stop_x: float
    stop_y: float
    stop_t: float
    chip: bool = False  # the ball flies (backend.world.flight): stop after hops and roll
    vz: float = 0.0  # mm/s, a chip's initial vertical speed (vx, vy: its ground velocity)
    land_x: float | None = None  # mm, where the flight in progress lands
    land_y: float | None = None
    land_t: float | None = None

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


@dataclass(frozen=True, slots=True)
class WorldState:
    t_capture: float  # Unix s of the newest frame merged
    receive_time_ns: int  # relay receive time of the latest frame merged (this machine's clock)
    ball: BallState | None
    robots: tuple[RobotState, ...]
    cameras: tuple[CameraFrame, ...] = field(default=())
    kicked_ball: KickedBall | None = None  # the kick in progress (backend.world.kick)
    other_balls: tuple[OtherBall, ...] = ()  # balls seen consistently besides the ball
    flying_balls: bool = False  # camera positions known: a chip's height is estimated
    #: each robot's place in ``robots`` by (team, id), when the world model made this world
    #: (else None): control looks its robots up in every world without a dict of its own
    index: Mapping[tuple[Team, int], int] | None = field(default=None, repr=False,
                                                          compare=False)

    def robot(self, team: Team, rid: int) -> RobotState | None:
        if self.index is not None:
            i = self.index.get((team, rid))
            return None if i is None else self.robots[i]
        for r in self.robots:
            if r.team == team and r.id == rid:
                return r
        return None
