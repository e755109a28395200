"""Exercise "pass between two robots": task["passer"] kicks the ball to task["receiver"], who
turns to the ball and steps onto its path."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Pass (reference)"
PASS_MPS = 3.0
CONTACT_MM = 90.0 + 21.5  #: robot radius + ball radius


def play(game: Game) -> dict[int, Target]:
    passer = int(game.task.get("passer", 0))
    receiver = int(game.task.get("receiver", 1))
    a, b, ball = game.robot(passer), game.robot(receiver), game.ball
    if a is None or b is None or ball is None:
        return {}
    out: dict[int, Target] = {}
    # the receiver: facing the ball, on its path once it rolls towards it
    face_b = math.atan2(ball.y - b.y, ball.x - b.x)
    rx, ry = b.x, b.y
    speed = math.hypot(ball.vx, ball.vy)
    if speed > 300.0:
        ux, uy = ball.vx / speed, ball.vy / speed
        along = (b.x - ball.x) * ux + (b.y - ball.y) * uy
        if along > 0:
            rx, ry = ball.x + ux * along, ball.y + uy * along
    out[receiver] = Target(rx, ry, face_b, avoid=False, role="receiver")
    # the passer: behind the ball on the line to the receiver, then through it, kicking
    if speed < 500.0:
        dx, dy = b.x - ball.x, b.y - ball.y
        n = math.hypot(dx, dy) or 1.0
        ux, uy = dx / n, dy / n
        face = math.atan2(uy, ux)
        along = (ball.x - a.x) * ux + (ball.y - a.y) * uy
        across = abs(-(ball.x - a.x) * uy + (ball.y - a.y) * ux)
        turned = abs(math.remainder(a.orientation - face, math.tau)) < 0.12
        if 0.0 < along < CONTACT_MM + 160.0 and across < 35.0 and turned:
            out[passer] = Target(ball.x + ux * 80.0, ball.y + uy * 80.0, face,
                                 max_speed_mps=0.8, kick_mps=PASS_MPS, avoid=False,
                                 role="passer")
        else:
            out[passer] = Target(ball.x - ux * (CONTACT_MM + 90.0),
                                 ball.y - uy * (CONTACT_MM + 90.0), face, role="passer")
    else:
        out[passer] = Target(a.x, a.y, None, role="passer")
    return out
