"""Speed limits the referee command imposes on our robots (the rules in ``domain.rules``):
HALT stops every robot at once; STOP and the other team's ball placement allow at most
1.5 m/s."""

from __future__ import annotations

import math

from backend.control.goto import LocalVelocity
from domain.rules import speed_limit_mps


def referee_limits(
    velocity: LocalVelocity, command: str | None, our_team: str | None = None
) -> LocalVelocity:
    """Limit ``velocity`` for the referee ``command`` (proto enum name, e.g. "STOP").

    HALT -> zero. STOP -> speed at most 1.5 m/s (direction kept, angular kept).
    BALL_PLACEMENT_<team>: limited for the other team; the placing team may move freely. With
    ``our_team`` unknown (None), every ball placement is limited (the safe side).
    """
    cap = speed_limit_mps(command, our_team)
    if cap == 0.0:
        return LocalVelocity.zero()
    s = math.hypot(velocity.forward_mps, velocity.left_mps)
    if s <= cap:
        return velocity
    k = cap / s
    return LocalVelocity(velocity.forward_mps * k, velocity.left_mps * k, velocity.angular_radps)
