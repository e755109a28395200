"""The rules that bind a team, from one place: what each referee command allows our robots
(move, speed, kick), and the distances and speeds of the SSL rules. Commands are the proto
enum names of ``Referee.Command`` ("HALT", "STOP", "BALL_PLACEMENT_BLUE", ...).

Used by the control loop (speed caps, kicks), the strategy (what to do), the internal referee
and the match director (what to judge)."""

from __future__ import annotations

import math
from typing import Literal, get_args

ROBOT_RADIUS_MM = 90.0
BALL_RADIUS_MM = 21.5

#: HALT: every robot stands still (it has this long to brake)
HALT_BRAKE_S = 2.0
#: STOP (and the other team's ball placement): at most this speed
STOP_SPEED_MPS = 1.5
#: STOP, and the opponents of a free kick, kick-off or placement: this far from the ball
STOP_BALL_DISTANCE_MM = 500.0
#: STOP, free kicks, placements: this far from the opponents' defence area
STOPPED_DEFENSE_AREA_DISTANCE_MM = 200.0
#: Ball placement: within this of the mark counts as placed (the game controller's default)
PLACEMENT_TOLERANCE_MM = 150.0
#: A collision at a relative speed above this is a foul
COLLISION_SPEED_MPS = 1.5
#: The ball may leave a kicker at most this fast
MAX_KICK_SPEED_MPS = 6.5

#: Every command the game controller sends (Referee.Command's names, in the proto's order):
#: the one list; the browser contract types commands with it and the page's type is generated
RefereeCommand = Literal[
    "HALT", "STOP", "NORMAL_START", "FORCE_START", "PREPARE_KICKOFF_YELLOW",
    "PREPARE_KICKOFF_BLUE", "PREPARE_PENALTY_YELLOW", "PREPARE_PENALTY_BLUE",
    "DIRECT_FREE_YELLOW", "DIRECT_FREE_BLUE", "INDIRECT_FREE_YELLOW", "INDIRECT_FREE_BLUE",
    "TIMEOUT_YELLOW", "TIMEOUT_BLUE", "GOAL_YELLOW", "GOAL_BLUE", "BALL_PLACEMENT_YELLOW",
    "BALL_PLACEMENT_BLUE",
]
COMMANDS: tuple[RefereeCommand, ...] = get_args(RefereeCommand)
#: The game is stopped: no kicks, the ball is not in play
STOPPED_COMMANDS: frozenset[RefereeCommand] = frozenset({
    "HALT", "STOP", "GOAL_BLUE", "GOAL_YELLOW", "BALL_PLACEMENT_BLUE", "BALL_PLACEMENT_YELLOW",
    "TIMEOUT_BLUE", "TIMEOUT_YELLOW",
})
#: Every robot at most STOP_SPEED_MPS. GOAL_* are the old (deprecated) goal commands, which the
#: game controller follows with STOP semantics.
SLOW_COMMANDS: frozenset[RefereeCommand] = frozenset({"STOP", "GOAL_BLUE", "GOAL_YELLOW"})


def command_team(command: str) -> str | None:
    """The team a command names ("blue" / "yellow"), or None."""
    for team in ("BLUE", "YELLOW"):
        if command.endswith("_" + team):
            return team.lower()
    return None


def is_stopped(command: str | None) -> bool:
    """The game is stopped (no kicks): HALT, STOP, placements, timeouts, goals."""
    return command is not None and command in STOPPED_COMMANDS


def kick_allowed(command: str | None) -> bool:
    """Our robots may kick (no referee at all: they may)."""
    return not is_stopped(command)


def speed_limit_mps(command: str | None, our_team: str | None) -> float:
    """The fastest our robots may drive under ``command``: 0 on HALT, STOP_SPEED_MPS on STOP and
    during the other team's ball placement (with ``our_team`` unknown, during every
    placement: the safe side), else infinity."""
    if command is None:
        return math.inf
    if command == "HALT":
        return 0.0
    if command in SLOW_COMMANDS:
        return STOP_SPEED_MPS
    if command.startswith("BALL_PLACEMENT_"):
        placer = command_team(command)
        if our_team is None or placer != our_team.lower():
            return STOP_SPEED_MPS
    return math.inf
