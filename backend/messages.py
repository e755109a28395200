"""The messages the processors pass on the Data Bus (besides the world and referee states of
``backend.world``): operator targets, the strategy's targets, the command sets."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from .contract import TargetSource
from .control.goto import LocalVelocity, Target
from .world.state import Team


class Command(NamedTuple):
    """One robot's command (a tuple: built in one call, not a frozen dataclass's six
    ``object.__setattr__``; one per robot a camera saw, hundreds a second). Read by name."""

    team: Team
    id: int
    velocity: LocalVelocity
    kick_speed_mps: float = 0.0
    chip: bool = False
    dribbler_rpm: float = 0.0


class CommandSet(NamedTuple):
    """One control tick's commands (a tuple, as ``Command``)."""

    created_time_ns: int
    source_receive_time_ns: int
    commands: tuple[Command, ...]
    stop_all: bool = False


@dataclass(frozen=True, slots=True)
class TargetEntry:
    """Where one robot goes and what it does, as strategy (or an operator) decided."""

    target: Target
    source: TargetSource
    role: str = ""
    path: tuple[tuple[float, float], ...] = ()  # waypoints (mm) after the robot; last = target
    kick_speed_mps: float = 0.0
    chip: bool = False
    dribbler_rpm: float = 0.0
    max_speed_mps: float | None = None
    #: a velocity order in the robot's frame (a team play's ``Velocity``) instead of driving
    #: to ``target`` (then the robot's position): limited like every command
    velocity: LocalVelocity | None = None
    #: stand still now: zero commanded, no deceleration ramp (a team play that failed)
    stop: bool = False


@dataclass(frozen=True, slots=True)
class OperatorTarget:
    team: Team
    id: int
    target: Target | None  # None: release the robot back to the strategy
