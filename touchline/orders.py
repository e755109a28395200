"""What a play answers for each robot it drives: a ``Target`` or a ``Velocity``.

A play returns ``{robot id: order}``. A robot of ``Game.mine`` the play leaves out is
stopped; an id not in ``Game.mine`` is an error of the play (its robots are stopped and the
error shown). Every order passes the station's safety envelope: HALT, STOP's 1.5 m/s and
0.5 m, the e-stop, arming, the defence areas and the field (a target inside one is moved out
and counted), each robot's speed and acceleration limits, the kick rules, and the stale stop.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Target:
    """Drive to a point (our frame) with the robot's speed controller."""

    x: float  #: mm
    y: float  #: mm
    #: rad, the heading to turn to; None keeps the current heading
    orientation: float | None = None
    #: m/s, a lower speed limit for this robot (None: the controller's own)
    max_speed_mps: float | None = None
    #: m/s, kick with this speed when the ball touches the kicker (0: no kick; the rules
    #: allow 6.5; only when the referee allows kicks)
    kick_mps: float = 0.0
    chip: bool = False  #: the kick is a chip (over robots)
    dribble: bool = False  #: spin the dribbler
    #: plan a path around the robots, the defence areas and (at STOP) the ball; False drives
    #: straight (the last centimetres to the ball)
    avoid: bool = True
    role: str = ""  #: shown on the field next to the robot


@dataclass(frozen=True, slots=True)
class Velocity:
    """Drive with a velocity in the robot's own frame (forward, left, turn), as the paper's
    speed controllers do; limited like every command (speed, acceleration, STOP)."""

    forward_mps: float  #: m/s, along the robot's heading
    left_mps: float  #: m/s, to the robot's left
    turn_radps: float  #: rad/s, counter-clockwise
    kick_mps: float = 0.0  #: m/s, as ``Target.kick_mps``
    chip: bool = False  #: the kick is a chip
    dribble: bool = False  #: spin the dribbler
    role: str = ""  #: shown on the field next to the robot


#: Stand still.
STOP = Velocity(0.0, 0.0, 0.0)

Order = Target | Velocity
