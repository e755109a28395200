"""Exercise "intercept a rolling ball": drive to the first point of the ball's path the robot
can reach before the ball does, facing the ball."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Intercept (reference)"
ROBOT_SPEED = 0.9  #: m/s the robot makes good on average (the station's limit is 1.0)
DECEL = 0.4  #: m/s^2, the ball's rolling deceleration


def ball_at(x: float, y: float, vx: float, vy: float, t: float) -> tuple[float, float]:
    """Where a ball rolling from (x, y) mm at (vx, vy) mm/s is after t s."""
    v = math.hypot(vx, vy) / 1000.0
    if v < 1e-6:
        return x, y
    stop = v / DECEL
    tt = min(t, stop)
    d = (v * tt - DECEL * tt * tt / 2.0) * 1000.0
    return x + vx / (v * 1000.0) * d, y + vy / (v * 1000.0) * d


def play(game: Game) -> dict[int, Target]:
    rid = int(game.task.get("robot", 0))
    r, ball = game.robot(rid), game.ball
    if r is None or ball is None:
        return {}
    face = math.atan2(ball.y - r.y, ball.x - r.x)
    aim = (ball.x, ball.y)
    t = 0.0
    while t < 5.0:
        px, py = ball_at(ball.x, ball.y, ball.vx, ball.vy, t)
        if math.hypot(px - r.x, py - r.y) / 1000.0 / ROBOT_SPEED + 0.3 <= t:
            aim = (px, py)
            break
        t += 0.05
    else:
        aim = ball_at(ball.x, ball.y, ball.vx, ball.vy, 5.0)
    near = math.hypot(ball.x - r.x, ball.y - r.y) < 400.0
    return {rid: Target(aim[0], aim[1], face, avoid=not near, role="intercept")}
