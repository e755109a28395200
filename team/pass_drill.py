"""Two of our robots pass the ball to each other; the others hold their spots.

Try changing: SPOTS (where the two stand), PASS_SPEED_MPS (the rules allow 6.5), or make the
receiver turn towards the ball earlier. Save the file: the station reloads it within a second.
"""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Pass drill"
DESCRIPTION = "Two robots pass the ball back and forth; the others hold their spots"

SPOTS = ((-1500.0, 0.0), (1500.0, 0.0))  #: mm, our frame: where the two passers stand
PASS_SPEED_MPS = 3.0
CONTACT_MM = 90.0 + 21.5  #: robot radius + ball radius: the ball at the kicker


def kick_towards(game: Game, rid: int, aim: tuple[float, float], speed_mps: float) -> Target:
    """Behind the ball on the line to ``aim``, then through it with the kicker armed."""
    ball = game.ball
    robot = game.robot(rid)
    assert ball is not None and robot is not None
    dx, dy = aim[0] - ball.x, aim[1] - ball.y
    n = math.hypot(dx, dy) or 1.0
    ux, uy = dx / n, dy / n
    face = math.atan2(uy, ux)
    along = (ball.x - robot.x) * ux + (ball.y - robot.y) * uy
    across = abs(-(ball.x - robot.x) * uy + (ball.y - robot.y) * ux)
    if 0.0 < along < CONTACT_MM + 160.0 and across < 35.0:
        return Target(ball.x + ux * 80.0, ball.y + uy * 80.0, face, max_speed_mps=1.5,
                      kick_mps=speed_mps, avoid=False, role="passer")
    return Target(ball.x - ux * (CONTACT_MM + 90.0), ball.y - uy * (CONTACT_MM + 90.0), face,
                  role="passer")


def play(game: Game) -> dict[int, Target]:
    mine = sorted(game.mine)
    orders: dict[int, Target] = {}
    passers, rest = mine[:2], mine[2:]
    ball = game.ball
    for k, rid in enumerate(passers):
        x, y = SPOTS[k]
        orders[rid] = Target(x, y, 0.0 if x < 0 else math.pi, role="receiver")
    if ball is not None and len(passers) == 2 and ball.speed_mps < 0.5:
        # the passer nearer the ball fetches it and passes to the other's spot
        def dist(rid: int) -> float:
            r = game.robot(rid)
            return math.inf if r is None else math.hypot(r.x - ball.x, r.y - ball.y)
        kicker = min(passers, key=dist)
        other = SPOTS[1 - passers.index(kicker)]
        orders[kicker] = kick_towards(game, kicker, other, PASS_SPEED_MPS)
    for k, rid in enumerate(rest):  # the others stand in a row on our half
        orders[rid] = Target(-3000.0, -2000.0 + 500.0 * k, 0.0, role="waiting")
    return orders
