"""The snapshot of the game a team's code gets on every tick: immutable, plain data.

All positions are in *our frame* (our goal at negative x), mm; velocities mm/s; angles rad.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field as _field
from typing import Any, Literal

#: The version of this interface. A play written for version 1 keeps working while the
#: station speaks version 1; fields may be added, none renamed or removed.
API_VERSION = 1

SituationName = Literal[
    "none",  # no referee heard: play freely
    "halt",  # every robot stands still (the station enforces it)
    "stop",  # at most 1.5 m/s, at least 0.5 m from the ball (the station enforces both)
    "running",  # normal play
    "kickoff-prepare",  # take kickoff positions
    "kickoff",  # NORMAL_START after a kickoff: the kicker kicks, the others keep positions
    "penalty-prepare",
    "penalty",
    "free-kick",  # a direct or indirect free kick, until the ball moved 50 mm
    "placement",  # ball placement to ``Referee.designated``
    "timeout",
]


@dataclass(frozen=True, slots=True)
class Robot:
    """One robot as the station's world model sees it (filtered)."""

    id: int  #: 0..15
    x: float  #: mm
    y: float  #: mm
    orientation: float  #: rad, 0 along +x, counter-clockwise
    vx: float = 0.0  #: mm/s
    vy: float = 0.0  #: mm/s
    omega: float = 0.0  #: rad/s
    #: False while the robot is not seen (occluded, off the field): its position is the last
    #: estimate
    visible: bool = True
    #: our robots only: the robot's own word on the ball at its dribbler (its sensor); None
    #: when it says nothing
    ball_contact: bool | None = None

    @property
    def xy(self) -> tuple[float, float]:
        return (self.x, self.y)

    @property
    def speed_mps(self) -> float:
        return math.hypot(self.vx, self.vy) / 1000.0


@dataclass(frozen=True, slots=True)
class Kick:
    """A kick in progress (detected by the station from the ball's motion)."""

    #: who kicked: "ours", "theirs", or None when no robot was near enough to tell
    by: Literal["ours", "theirs"] | None
    by_id: int | None  #: the kicker's id, when known
    start_x: float  #: mm, where the kick started
    start_y: float  #: mm
    start_t: float  #: s, on ``Game.t``'s clock
    vx: float  #: mm/s, initial ground velocity
    vy: float  #: mm/s
    stop_x: float  #: mm, where the ball is predicted to stop
    stop_y: float  #: mm
    stop_t: float  #: s, when (on ``Game.t``'s clock)
    chip: bool = False  #: the ball flies (a chip kick)


@dataclass(frozen=True, slots=True)
class Ball:
    x: float  #: mm
    y: float  #: mm
    vx: float = 0.0  #: mm/s
    vy: float = 0.0  #: mm/s
    z: float = 0.0  #: mm above the ground (a chipped ball; 0 on the ground)
    visible: bool = True  #: False while not seen: the position is the last estimate
    kick: Kick | None = None  #: the kick in progress, if any

    @property
    def xy(self) -> tuple[float, float]:
        return (self.x, self.y)

    @property
    def speed_mps(self) -> float:
        return math.hypot(self.vx, self.vy) / 1000.0


@dataclass(frozen=True, slots=True)
class Referee:
    """What the referee (the game controller, or the station's internal referee) says."""

    #: the referee command as the game controller names it ("HALT", "STOP", "NORMAL_START",
    #: "FORCE_START", "PREPARE_KICKOFF_BLUE", "DIRECT_FREE_YELLOW", "BALL_PLACEMENT_BLUE",
    #: ...); "" without a referee
    command: str = ""
    #: the situation as our team sees it (see ``SituationName``)
    situation: SituationName = "none"
    #: True: our kickoff / free kick / penalty / placement / timeout; False: theirs; None: not
    #: a team's
    ours: bool | None = None
    #: ball placement target (mm, our frame), during "placement"
    designated: tuple[float, float] | None = None
    stage: str = ""  #: the game stage ("NORMAL_FIRST_HALF", ...); "" unknown
    goalkeeper: int | None = None  #: our goalkeeper's id as the referee knows it
    max_robots: int | None = None  #: how many robots we may have on the field (cards)
    score_ours: int = 0  #: goals
    score_theirs: int = 0  #: goals


@dataclass(frozen=True, slots=True)
class FieldSize:
    """The field, from the geometry packet (mm)."""

    length: float = 9000.0  #: mm, goal line to goal line (division B by default)
    width: float = 6000.0  #: mm, touch line to touch line
    goal_width: float = 1000.0  #: mm, inside the posts
    goal_depth: float = 180.0  #: mm
    boundary_width: float = 300.0  #: mm, between the field lines and the walls
    penalty_area_depth: float = 1000.0  #: mm, the defence area's depth from the goal line
    penalty_area_width: float = 2000.0  #: mm, the defence area's width
    center_circle_radius: float = 500.0  #: mm
    robot_radius: float = 90.0  #: mm, the largest robot radius allowed
    ball_radius: float = 21.5  #: mm

    @property
    def half_length(self) -> float:
        return self.length / 2.0

    @property
    def half_width(self) -> float:
        return self.width / 2.0

    @property
    def our_goal(self) -> tuple[float, float]:
        """Centre of our goal line (always at negative x)."""
        return (-self.length / 2.0, 0.0)

    @property
    def their_goal(self) -> tuple[float, float]:
        return (self.length / 2.0, 0.0)

    def in_our_defense_area(self, x: float, y: float) -> bool:
        return x < -self.half_length + self.penalty_area_depth \
            and abs(y) < self.penalty_area_width / 2.0

    def in_their_defense_area(self, x: float, y: float) -> bool:
        return x > self.half_length - self.penalty_area_depth \
            and abs(y) < self.penalty_area_width / 2.0


@dataclass(frozen=True, slots=True)
class Game:
    """One tick's snapshot: everything a play or a processor may look at."""

    version: int  #: ``API_VERSION`` of the station that built it
    #: s: the station's clock (starts near 0; in a replay, the log's time from its start)
    t: float
    our_team: Literal["blue", "yellow"]  #: the team the station drives
    #: where our goal is in the *vision* frame; the snapshot itself is always in our frame
    our_side: Literal["negative-x", "positive-x"]
    ours: tuple[Robot, ...]  #: our robots on the field, by id
    theirs: tuple[Robot, ...]  #: the other team's robots, by id
    ball: Ball | None  #: None while no ball is known
    referee: Referee  #: what the referee says, as our team sees it
    field: FieldSize  #: the field's sizes (the geometry packet's)
    #: the ids of our robots this play drives (the operator may give other robots other plays,
    #: or drive them by hand); a processor gets every robot of ours here
    mine: tuple[int, ...] = ()
    #: the latest output of each of the team's processors, by processor name (file name)
    topics: Mapping[str, Mapping[str, float]] = _field(default_factory=dict)
    #: True in a replay (what-if on a recorded log): nothing the play orders is sent
    replay: bool = False
    #: an exercise's parameters when the play runs in one (``python -m evaluate``, the
    #: Evaluate tab: the scenario's ``[task]`` table as its file gives it, e.g.
    #: ``{"robot": 0, "target_mm": [1000.0, 500.0]}``); empty in a game
    task: Mapping[str, Any] = _field(default_factory=dict)

    def robot(self, rid: int) -> Robot | None:
        """Our robot ``rid``, None when it is not on the field."""
        for r in self.ours:
            if r.id == rid:
                return r
        return None

    def opponent(self, rid: int) -> Robot | None:
        for r in self.theirs:
            if r.id == rid:
                return r
        return None

    @property
    def my_robots(self) -> tuple[Robot, ...]:
        """Our robots this play drives, by id (only those on the field)."""
        mine = set(self.mine)
        return tuple(r for r in self.ours if r.id in mine)
