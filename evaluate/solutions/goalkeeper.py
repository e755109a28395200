"""Exercise "goalkeeper": on a line just in front of our goal, where the ball's path crosses
it (or, for a ball not coming at the goal, between the ball and the goal's centre)."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Goalkeeper (reference)"
LINE_MM = 120.0  #: in front of the goal line


def play(game: Game) -> dict[int, Target]:
    rid = int(game.task.get("keeper", 0))
    ball, f = game.ball, game.field
    x_line = -f.half_length + LINE_MM
    half = f.goal_width / 2.0
    y = 0.0
    if ball is not None:
        y = ball.y * 0.5
        if ball.vx < -200.0:  # coming our way: where it crosses the line
            t = (x_line - ball.x) / ball.vx
            if t > 0:
                y = ball.y + ball.vy * t
    y = max(-half, min(half, y))
    face = 0.0 if ball is None else math.atan2(ball.y - y, ball.x - x_line)
    return {rid: Target(x_line, y, face, avoid=False, role="keeper")}
