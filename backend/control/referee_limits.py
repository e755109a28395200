"""Speed limits the referee command imposes on our robots (the rules in ``domain.rules``):
HALT stops every robot at once; STOP and the other team's ball placement allow at most
1.5 m/s."""

from __future__ import annotations

import math

from backend.control.goto import LocalVelocity
from domain.rules import STOP_SPEED_MPS, speed_limit_mps


def referee_limits(
    velocity: LocalVelocity, command: str | None, our_team: str | None = None,
    stop_speed_mps: float = STOP_SPEED_MPS, max_speed_mps: float = math.inf,
) -> LocalVelocity:
    """Limit ``velocity`` for the referee ``command`` (proto enum name, e.g. "STOP"), in one
    place and once.

    HALT -> zero. STOP -> speed at most 1.5 m/s (direction kept, angular kept), or the
    operator's lower ``stop_speed_mps``. BALL_PLACEMENT_<team>: the same limit for the other
    team; the placing team may move freely. With ``our_team`` unknown (None), every ball
    placement is limited (the safe side). ``max_speed_mps``: the strategy's own cap for this
    robot, whatever the command.
    """
    return capped(velocity, min(command_cap_mps(command, our_team, stop_speed_mps),
                                max_speed_mps))


def command_cap_mps(command: str | None, our_team: str | None = None,
                    stop_speed_mps: float = STOP_SPEED_MPS) -> float:
    """The speed cap of ``referee_limits`` for ``command``, before the robot's own cap: the
    same for every robot (control takes it once per tick). 0: stop; infinity: none."""
    cap = speed_limit_mps(command, our_team)
    if 0.0 < cap < math.inf:
        cap = min(cap, stop_speed_mps)
    return cap


def capped(velocity: LocalVelocity, cap: float) -> LocalVelocity:
    """``velocity`` with its speed at most ``cap`` (direction and angular speed kept; the same
    object when within it); zero for a cap of 0 or less."""
    if cap <= 0.0:
        return LocalVelocity.zero()
    s = math.hypot(velocity.forward_mps, velocity.left_mps)
    if s <= cap:
        return velocity
    k = cap / s
    return LocalVelocity(velocity.forward_mps * k, velocity.left_mps * k, velocity.angular_radps)
