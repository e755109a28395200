"""Two of our robots pass the ball to each other; the others hold their spots.

The one nearer the ball fetches it and passes to the other's spot once the other stands there;
the receiver faces the ball with its dribbler on and traps it; then it passes back.

Try changing: SPOTS (where the two stand), PASS_SPEED_MPS (the rules allow 6.5; too fast and
the receiver cannot trap it), or turn the receiver's dribbler off and watch the ball bounce
off. Save the file: the station reloads it within a second.
"""

from __future__ import annotations

import math

from touchline import Game, Target

TITLE = "Pass drill"
DESCRIPTION = "Two robots pass the ball back and forth; the others hold their spots"

# where the two passers stand (mm, our frame: our goal at -x): on our half, in the open
SPOTS = ((-2000.0, -1500.0), (-2000.0, 1500.0))
PASS_SPEED_MPS = 3.0
CONTACT_MM = 90.0 + 21.5  # robot radius + ball radius: the ball at the kicker
READY_MM = 150.0  # a receiver this close to its spot is ready for the pass


def kick_towards(game: Game, rid: int, aim: tuple[float, float], speed_mps: float,
                 ready: bool) -> Target:
    """Behind the ball on the line to ``aim`` (around the ball, not through it), then, once
    the receiver is ``ready``, through it with the kicker armed. Holding the ball meanwhile:
    it keeps it on the dribbler and turns to ``aim``."""
    ball = game.ball
    robot = game.robot(rid)
    assert ball is not None and robot is not None
    dx, dy = aim[0] - ball.x, aim[1] - ball.y
    n = math.hypot(dx, dy) or 1.0
    ux, uy = dx / n, dy / n
    face = math.atan2(uy, ux)
    px, py = robot.x - ball.x, robot.y - ball.y  # the robot seen from the ball
    ahead = px * ux + py * uy  # > 0: on the aim's side of the ball (the wrong one)
    aside = -px * uy + py * ux  # off the kick line
    # the kicker kicks where the robot faces: only once it faces the aim
    aligned = abs(math.remainder(robot.orientation - face, math.tau)) < 0.03
    at_kicker = abs(math.remainder(math.atan2(-py, -px) - robot.orientation, math.tau)) < 0.6
    if math.hypot(px, py) < CONTACT_MM + 40.0 and at_kicker and not (ready and aligned):
        return Target(robot.x, robot.y, face, dribble=True, role="passer")  # keep it, turn
    if ready and aligned and -(CONTACT_MM + 160.0) < ahead < 0.0 and abs(aside) < 35.0:
        return Target(ball.x + ux * 80.0, ball.y + uy * 80.0, face, max_speed_mps=1.5,
                      kick_mps=speed_mps, avoid=False, role="passer")
    if ahead > -CONTACT_MM and abs(aside) < CONTACT_MM + 150.0:
        # on the wrong side: first beside the ball, so as not to push it on the way
        s = 1.0 if aside >= 0.0 else -1.0
        return Target(ball.x - uy * s * 300.0 - ux * 150.0, ball.y + ux * s * 300.0 - uy * 150.0,
                      face, role="passer")
    return Target(ball.x - ux * (CONTACT_MM + 90.0), ball.y - uy * (CONTACT_MM + 90.0), face,
                  role="passer")


def receive(game: Game, spot: tuple[float, float]) -> Target:
    """Waiting for the pass: on the spot facing the ball, the dribbler on to trap it; with a
    ball rolling its way, a step into the ball's line."""
    x, y = spot
    ball = game.ball
    if ball is None:
        return Target(x, y, 0.0, dribble=True, role="receiver")
    face = math.atan2(ball.y - y, ball.x - x)
    v = math.hypot(ball.vx, ball.vy)
    if v > 500.0:  # mm/s: rolling; where does it pass the spot?
        ux, uy = ball.vx / v, ball.vy / v
        along = (x - ball.x) * ux + (y - ball.y) * uy  # > 0: still coming
        px, py = ball.x + ux * along, ball.y + uy * along  # its line's point nearest the spot
        if along > 0.0 and math.hypot(px - x, py - y) < 500.0:
            x, y, face = px, py, math.atan2(-uy, -ux)
    return Target(x, y, face, dribble=True, role="receiver")


def play(game: Game) -> dict[int, Target]:
    mine = sorted(game.mine)
    orders: dict[int, Target] = {}
    passers, rest = mine[:2], mine[2:]
    ball = game.ball
    for k, rid in enumerate(passers):
        orders[rid] = receive(game, SPOTS[k])
    if ball is not None and len(passers) == 2 and ball.speed_mps < 0.5:
        # the passer nearer the ball fetches it and passes to the other's spot
        def dist(rid: int) -> float:
            r = game.robot(rid)
            return math.inf if r is None else math.hypot(r.x - ball.x, r.y - ball.y)
        kicker = min(passers, key=dist)
        k = passers.index(kicker)
        receiver = game.robot(passers[1 - k])
        spot = SPOTS[1 - k]
        ready = receiver is not None and math.hypot(receiver.x - spot[0],
                                                    receiver.y - spot[1]) < READY_MM
        orders[kicker] = kick_towards(game, kicker, spot, PASS_SPEED_MPS, ready)
    for k, rid in enumerate(rest):  # the others stand in a row on our half
        orders[rid] = Target(-3000.0, -2000.0 + 500.0 * k, 0.0, role="waiting")
    return orders
