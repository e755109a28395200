"""Speed limits the referee command imposes on our robots (SSL rules): HALT stops every robot at
once; STOP and the other team's ball placement allow at most 1.5 m/s."""

from __future__ import annotations

import math

from backend.control.goto import LocalVelocity

STOP_SPEED_MPS = 1.5

# Commands under which every robot must stay at or below STOP_SPEED_MPS. GOAL_* are the old
# (deprecated) goal commands, which the game controller follows with STOP semantics.
_SLOW_COMMANDS = frozenset({"STOP", "GOAL_BLUE", "GOAL_YELLOW"})


def referee_limits(
    velocity: LocalVelocity, command: str | None, our_team: str | None = None
) -> LocalVelocity:
    """Limit ``velocity`` for the referee ``command`` (proto enum name, e.g. "STOP").

    HALT -> zero. STOP -> speed at most 1.5 m/s (direction kept, angular kept).
    BALL_PLACEMENT_<team>: limited for the other team; the placing team may move freely. With
    ``our_team`` unknown (None), every ball placement is limited (the safe side).
    """
    if command is None:
        return velocity
    if command == "HALT":
        return LocalVelocity.zero()
    slow = command in _SLOW_COMMANDS
    if command.startswith("BALL_PLACEMENT_"):
        placer = command.removeprefix("BALL_PLACEMENT_").lower()
        slow = our_team is None or placer != our_team.lower()
    if not slow:
        return velocity
    s = math.hypot(velocity.forward_mps, velocity.left_mps)
    if s <= STOP_SPEED_MPS:
        return velocity
    k = STOP_SPEED_MPS / s
    return LocalVelocity(velocity.forward_mps * k, velocity.left_mps * k, velocity.angular_radps)
