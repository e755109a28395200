"""Exercise "ball placement": fetch the ball with the dribbler, carry it to the referee's
point, stop, let go, step back."""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Ball placement (reference)"
HOLD_MM = 90.0 + 21.5  #: robot centre to ball centre while holding it
_state: dict[str, bool] = {"released": False}


def play(game: Game) -> dict[int, Target]:
    ref, ball = game.referee, game.ball
    rid = min(game.mine) if game.mine else 0
    r = game.robot(rid)
    if r is None or ball is None or ref.situation != "placement" or ref.designated is None \
            or not ref.ours:
        return {rid: Target(r.x, r.y, None)} if r is not None else {}
    tx, ty = ref.designated
    dist_target = math.hypot(ball.x - tx, ball.y - ty)
    # carry direction: from the ball to the target (or, once there, keep the heading)
    if dist_target > 30.0:
        ux, uy = (tx - ball.x) / dist_target, (ty - ball.y) / dist_target
    else:
        ux, uy = math.cos(r.orientation), math.sin(r.orientation)
    face = math.atan2(uy, ux)
    to_ball = math.hypot(ball.x - r.x, ball.y - r.y)
    if _state["released"] or (dist_target < 40.0 and to_ball < HOLD_MM + 30.0
                              and ball.speed_mps < 0.05):
        _state["released"] = dist_target < 150.0
        # let go and step back along the heading
        return {rid: Target(ball.x - ux * (HOLD_MM + 350.0), ball.y - uy * (HOLD_MM + 350.0),
                            face, max_speed_mps=0.3, avoid=False, role="placed")}
    behind = (ball.x - ux * HOLD_MM, ball.y - uy * HOLD_MM)
    lined_up = math.hypot(r.x - behind[0], r.y - behind[1]) < 60.0 and \
        abs(math.remainder(r.orientation - face, math.tau)) < 0.25
    if to_ball > HOLD_MM + 40.0 or (not lined_up and to_ball > HOLD_MM + 10.0):
        # go behind the ball, facing the target, not touching it yet
        back = (ball.x - ux * (HOLD_MM + 150.0), ball.y - uy * (HOLD_MM + 150.0))
        far = math.hypot(r.x - back[0], r.y - back[1]) > 80.0
        aim = back if far else behind
        return {rid: Target(aim[0], aim[1], face, dribble=not far, max_speed_mps=0.6,
                            avoid=far, role="fetch")}
    # holding it: the robot goes where the ball must end, less the holding distance
    return {rid: Target(tx - ux * HOLD_MM, ty - uy * HOLD_MM, face, dribble=True,
                        max_speed_mps=0.5, avoid=False, role="carry")}
