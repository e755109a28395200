"""Exercise "face the ball": stay where you are and turn towards the ball."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Face the ball (reference)"
#: where each robot stood when it was first seen: it turns there (it never drifts off)
_HOME: dict[int, tuple[float, float]] = {}


def play(game: Game) -> dict[int, Target]:
    out: dict[int, Target] = {}
    ball = game.ball
    for r in game.my_robots:
        home = _HOME.setdefault(r.id, (r.x, r.y))
        heading = None if ball is None else math.atan2(ball.y - r.y, ball.x - r.x)
        out[r.id] = Target(home[0], home[1], heading, role="facing")
    return out
