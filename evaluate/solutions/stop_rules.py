"""Exercise "keep the rules at STOP": in running play, go close to the ball; at STOP, every
robot 0.8 m from the ball (on the side it stands), slowly."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "STOP rules (reference)"
KEEP_MM = 800.0


def play(game: Game) -> dict[int, Target]:
    ball = game.ball
    out: dict[int, Target] = {}
    if ball is None:
        return out
    stopped = game.referee.situation in ("stop", "halt")
    n = max(1, len(game.my_robots))
    for k, r in enumerate(game.my_robots):
        dx, dy = r.x - ball.x, r.y - ball.y
        d = math.hypot(dx, dy)
        if d < 1.0:
            dx, dy, d = math.cos(k * 2.1), math.sin(k * 2.1), 1.0
        face = math.atan2(-dy, -dx)
        if stopped:
            if d < KEEP_MM:
                out[r.id] = Target(ball.x + dx / d * KEEP_MM, ball.y + dy / d * KEEP_MM, face,
                                   max_speed_mps=1.0, role="keep away")
            else:
                out[r.id] = Target(r.x, r.y, face, role="keep away")
        else:
            # each its own spot around the ball (planned around the others: no collision)
            a = 2.0 * math.pi * k / n
            out[r.id] = Target(ball.x + 450.0 * math.cos(a), ball.y + 450.0 * math.sin(a), face,
                               role="close")
    return out
