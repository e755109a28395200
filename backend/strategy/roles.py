"""The roles of our team, in our frame (our goal at -x, we attack +x). Pure functions of the
situation: each returns where a robot should go and what it should do (an ``Intent``).

- goalkeeper: on the goal line where the bisector of the angle the goal mouth makes at the
  ball crosses it; intercepts a ball moving towards the
  goal where the line fitted to its recent positions crosses the goal line (the point comes
  from ``backend.geometry.goalkeeper_target``'s rule, in plain floats as ``keeper_y``, or from
  the compute engine); clears a slow ball
  out of our defence area.
- attacker: picks the point on the goal with the widest open angle from the ball (robots cast
  angular shadows), goes behind the ball on the line through that point, and kicks.
- defenders: on the line from our goal centre to the ball, just outside our defence area,
  side by side.
- supporters: open spots in the opponents' half, away from the ball, for a pass.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

from domain.angles import wrap_angle
from domain.field import Field

from .model import BALL_RADIUS_MM, ROBOT_RADIUS_MM, Ball, Bot, Intent, own_defense

R = ROBOT_RADIUS_MM
#: centre distance robot-ball when the ball touches the kicker
CONTACT_MM = R + BALL_RADIUS_MM


def unit(dx: float, dy: float) -> tuple[float, float]:
    n = math.hypot(dx, dy)
    return (1.0, 0.0) if n < 1e-9 else (dx / n, dy / n)


def best_shot(ball: tuple[float, float], blockers: Sequence[tuple[float, float]],
              fs: Field, goal_x: float | None = None) -> tuple[tuple[float, float], float]:
    """The aim point on the opponents' goal line (x = +L/2 unless ``goal_x``) with the widest
    open angle seen from ``ball``, and that angle (rad). Each blocker (a robot between the
    ball and the goal line) hides the interval of directions its disc covers. When the goal
    is fully covered the angle is 0 and the aim is the goal centre."""
    gx = fs.half_length if goal_x is None else goal_x
    bx, by = ball
    half_goal = fs.goal_width / 2.0 - BALL_RADIUS_MM - 20.0
    if gx - bx <= 1.0:  # at or behind the goal line: no angle to speak of
        return (gx, 0.0), 0.0
    lo = math.atan2(-half_goal - by, gx - bx)
    hi = math.atan2(half_goal - by, gx - bx)
    shadows: list[tuple[float, float]] = []
    for cx, cy in blockers:
        dx, dy = cx - bx, cy - by
        d = math.hypot(dx, dy)
        if d < 1.0 or dx <= 0.0 or cx > gx + R:
            continue  # behind the ball or the goal line: no shadow on the shot
        half = math.asin(min(1.0, (R + BALL_RADIUS_MM) / d))
        a = math.atan2(dy, dx)
        shadows.append((a - half, a + half))
    shadows.sort()
    free: list[tuple[float, float]] = []
    cur = lo
    for a0, a1 in shadows:
        if a1 <= cur:
            continue
        if a0 > cur:
            free.append((cur, min(a0, hi)))
        cur = max(cur, a1)
        if cur >= hi:
            break
    if cur < hi:
        free.append((cur, hi))
    free = [(a, b) for a, b in free if b > a]
    if not free:
        return (gx, 0.0), 0.0
    a0, a1 = max(free, key=lambda iv: iv[1] - iv[0])
    mid = (a0 + a1) / 2.0
    y = by + (gx - bx) * math.tan(mid)
    return (gx, max(-half_goal, min(half_goal, y))), a1 - a0


def keeper_point(ball: Ball, fs: Field, min_speed: float) -> tuple[float, float]:
    """The goalkeeper's spot (our frame): on a line just in front of our goal line, where the
    ball's path crosses it when the ball comes towards the goal, else on the bisector of the
    angle the goal mouth makes at the ball."""
    gx = -fs.half_length + R + 30.0
    return gx, keeper_y(ball.x, ball.y, ball.vx, ball.vy, gx, fs.goal_width, R / 2.0,
                        min_speed)


def keeper_y(bx: float, by: float, vx: float, vy: float, goal_x: float, goal_width: float,
             margin: float, min_speed: float) -> float:
    """``backend.geometry.goalkeeper_target``'s y for one ball, in plain floats (the same
    operations in the same order, so the same bits; numpy on one point costs ~20 calls)."""
    # moving towards the goal line: where its path crosses it (vx != 0 then); else on the
    # bisector of the angle between the ball's lines to the two posts (at goal_x), which
    # meets the mouth dividing it as the distances to the posts (the angle bisector theorem):
    # a keeper level with a ball out wide left the far side open (regression: penalty_theirs)
    moving = (goal_x - bx) * vx > 0.0 and abs(vx) > min_speed
    if moving:
        y = by + (goal_x - bx) * vy / vx
    else:
        h = goal_width / 2.0
        dx = bx - goal_x
        d1 = math.sqrt(dx * dx + (by - h) * (by - h))
        d2 = math.sqrt(dx * dx + (by + h) * (by + h))
        y = h * (d2 - d1) / (d1 + d2) if d1 + d2 > 0.0 else by
    lim = max(goal_width / 2.0 - margin, 0.0)
    # np.clip(y, -lim, lim): a NaN stays NaN
    return lim if y > lim else (-lim if y < -lim else y)


def in_own_defense(p: tuple[float, float], fs: Field, margin: float = 0.0) -> bool:
    x0, y0, x1, y1 = own_defense(fs)
    return x0 - margin <= p[0] <= x1 + margin and y0 - margin <= p[1] <= y1 + margin


def goalkeeper(ball: Ball | None, fs: Field, point: tuple[float, float] | None,
               min_speed: float, clear_speed_mps: float, robot: Bot | None = None) -> Intent:
    """``point``: a precomputed keeper spot (e.g. from the compute engine), else computed."""
    if ball is None:
        return Intent("goalkeeper", -fs.half_length + R + 30.0, 0.0, 0.0, own_defense_ok=True)
    if in_own_defense(ball.xy, fs) and ball.speed < 400.0:
        # a slow ball in our area: only the keeper may play it; kick it out, away from goal
        away = unit(ball.x + fs.half_length, ball.y)
        it = kick_ball(ball, (ball.x + away[0] * 3000.0, ball.y + away[1] * 3000.0),
                       clear_speed_mps, role="goalkeeper", robot=robot)
        return replace(it, own_defense_ok=True)
    px, py = point if point is not None else keeper_point(ball, fs, min_speed)
    face = math.atan2(ball.y - py, ball.x - px)
    return Intent("goalkeeper", px, py, face, own_defense_ok=True)


def kick_ball(ball: Ball, aim: tuple[float, float], speed_mps: float, role: str,
              robot: Bot | None, chip: bool = False, max_speed_mps: float | None = None) -> Intent:
    """Go behind the ball on the line through ``aim``, then drive through it with the kicker
    armed. Behind-and-aligned is judged from ``robot`` (None: not yet known: approach)."""
    d = unit(aim[0] - ball.x, aim[1] - ball.y)
    face = math.atan2(d[1], d[0])
    behind = (ball.x - d[0] * (CONTACT_MM + R), ball.y - d[1] * (CONTACT_MM + R))
    if robot is not None:
        rx, ry = ball.x - robot.x, ball.y - robot.y
        along = rx * d[0] + ry * d[1]  # how far behind the ball, along the kick
        across = abs(-rx * d[1] + ry * d[0])  # off the kick line
        heading_err = abs(wrap_angle(robot.orientation - face))
        if 0.0 < along < CONTACT_MM + 160.0 and across < 35.0 and heading_err < 0.2:
            through = (ball.x + d[0] * 80.0, ball.y + d[1] * 80.0)
            return Intent(role, through[0], through[1], face, kick_speed_mps=speed_mps,
                          chip=chip, plan=False,
                          max_speed_mps=min(1.5, max_speed_mps or 1.5))
    return Intent(role, behind[0], behind[1], face, avoid_ball_mm=CONTACT_MM + 60.0,
                  max_speed_mps=max_speed_mps)


def attacker(ball: Ball, robot: Bot | None, blockers: Sequence[tuple[float, float]],
             fs: Field, kick_speed: float, pass_speed: float,
             role: str = "attacker", max_speed_mps: float | None = None) -> Intent:
    aim, angle = best_shot(ball.xy, blockers, fs)
    far = fs.half_length - ball.x > 0.6 * fs.field_length
    speed = pass_speed if far or angle < math.radians(1.0) else kick_speed
    return kick_ball(ball, aim, speed, role, robot, max_speed_mps=max_speed_mps)


#: the gap (mm) between two defenders' spots beyond what path planning keeps between robots
DEFENDER_GAP_MM = 20.0


def defender_points(n: int, ball: Ball | None, fs: Field, margin: float,
                    robot_margin_mm: float = 60.0) -> list[tuple[float, float]]:
    """``n`` spots side by side on the line from our goal centre to the ball, just outside
    our defence area (grown by ``margin`` and a robot radius). Neighbours stand
    2 R + ``robot_margin_mm`` + ``DEFENDER_GAP_MM`` apart: path planning keeps a robot's
    centre R + ``robot_margin_mm`` + R from every other robot's, so each defender's spot is
    free of its neighbours' (closer, both would escape and plan again on every tick)."""
    if n <= 0:
        return []
    g = (-fs.half_length, 0.0)
    b = ball.xy if ball is not None else (0.0, 0.0)
    u = unit(b[0] - g[0], b[1] - g[1])
    if u[0] < 0.05:  # the ball beside or behind the goal line: guard the near post side
        u = unit(0.05, u[1] if abs(u[1]) > 1e-6 else 1.0)
    x0, y0, x1, y1 = own_defense(fs)
    grow = margin + R
    # smallest t with g + u t outside the grown rectangle
    tx = (x1 + grow - g[0]) / u[0]
    ty = (y1 + grow) / abs(u[1]) if abs(u[1]) > 1e-9 else math.inf
    t = min(tx, ty) + 10.0
    cx, cy = g[0] + u[0] * t, g[1] + u[1] * t
    perp = (-u[1], u[0])
    spacing = 2.0 * R + robot_margin_mm + DEFENDER_GAP_MM
    pts = []
    for k in range(n):
        off = (k - (n - 1) / 2.0) * spacing
        px, py = cx + perp[0] * off, cy + perp[1] * off
        pts.append(_push_out_of_rect(px, py, (x0, y0, x1, y1), grow + 5.0, u))
    return pts


def _push_out_of_rect(px: float, py: float, rect: tuple[float, float, float, float],
                      grow: float, u: tuple[float, float]) -> tuple[float, float]:
    x0, y0, x1, y1 = rect
    for _ in range(40):
        if not (x0 - grow <= px <= x1 + grow and y0 - grow <= py <= y1 + grow):
            break
        px += u[0] * 25.0
        py += u[1] * 25.0
    return (px, py)


def supporter_points(n: int, ball: Ball | None, fs: Field) -> list[tuple[float, float]]:
    """Open spots in the opponents' half on the side away from the ball, then the other."""
    if n <= 0:
        return []
    by = ball.y if ball is not None else 0.0
    bx = ball.x if ball is not None else 0.0
    side = -1.0 if by > 0 else 1.0
    x_front = min(fs.half_length - fs.penalty_area_depth - 500.0,
                  max(bx + 1200.0, 0.25 * fs.field_length))
    x_back = max(-0.1 * fs.field_length, bx - 1500.0)
    cands = [
        (x_front, side * fs.field_width * 0.28),
        (x_back, -side * fs.field_width * 0.3),
        (x_front * 0.5, -side * fs.field_width * 0.05),
        (x_back, side * fs.field_width * 0.35),
        (x_front * 0.7, side * fs.field_width * 0.05),
    ]
    out = []
    for k in range(n):
        x, y = cands[k % len(cands)]
        if k >= len(cands):
            y += 400.0 * (k // len(cands))
        out.append((x, y))
    return out


def clamp_to_field(p: tuple[float, float], fs: Field,
                   inside: float = R + 20.0) -> tuple[float, float]:
    return (max(-fs.half_length + inside, min(fs.half_length - inside, p[0])),
            max(-fs.half_width + inside, min(fs.half_width - inside, p[1])))


def push_out_of_circle(p: tuple[float, float], c: tuple[float, float], radius: float,
                       towards: tuple[float, float] | None = None) -> tuple[float, float]:
    """``p`` moved radially out of the circle (c, radius) if inside; a point at the centre
    goes towards ``towards`` (default: our goal, -x)."""
    dx, dy = p[0] - c[0], p[1] - c[1]
    d = math.hypot(dx, dy)
    if d >= radius:
        return p
    if d < 1e-6:
        tx, ty = towards if towards is not None else (c[0] - 1.0, c[1])
        dx, dy = tx - c[0], ty - c[1]
        d = math.hypot(dx, dy) or 1.0
    return (c[0] + dx / d * radius, c[1] + dy / d * radius)


def push_out_of_capsule(p: tuple[float, float], a: tuple[float, float],
                        b: tuple[float, float], radius: float) -> tuple[float, float]:
    """``p`` moved out of the capsule of ``radius`` around the segment a-b (perpendicular to
    it, or radially at the ends)."""
    ax, ay = a
    vx, vy = b[0] - ax, b[1] - ay
    ll = vx * vx + vy * vy
    t = 0.0 if ll < 1e-9 else max(0.0, min(1.0, ((p[0] - ax) * vx + (p[1] - ay) * vy) / ll))
    q = (ax + vx * t, ay + vy * t)
    if 0.0 < t < 1.0:
        n = (-vy, vx)
        side = 1.0 if (p[0] - q[0]) * n[0] + (p[1] - q[1]) * n[1] >= 0 else -1.0
        return push_out_of_circle(p, q, radius, (q[0] + side * n[0], q[1] + side * n[1]))
    return push_out_of_circle(p, q, radius)
