"""The safety envelope around the team's code: every order a team play gives passes the same
limits as Touchline's own strategy. Pure (no clock, no I/O); in our frame (our goal at -x).

What it does here, per order (the rest acts on every robot's entry, team or not: HALT, STOP's
1.5 m/s cap, kicks only when the referee allows, each robot's speed and acceleration limits,
the e-stop and arming (control and the relay), the stale stop (control, the relay)):

* a Target inside our defence area (except the referee's goalkeeper: robot 0 when no referee
  names one, the game controller's default), inside theirs (0.2 m
  further while the game is stopped), beyond the field's walls, or (STOP, the other team's
  set pieces and ball placement) within the stop distance of the ball (and of the placement
  corridor) is **moved to the nearest allowed point** and counted;
* a kick faster than the rules allow (6.5 m/s) is capped and counted;
* a Velocity order loses its component towards a forbidden area while the robot is within
  100 mm of it (counted), so it slides along instead of driving in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from domain.field import Field
from domain.rules import MAX_KICK_SPEED_MPS, STOPPED_DEFENSE_AREA_DISTANCE_MM

from ..strategy.model import ROBOT_RADIUS_MM, own_defense, their_defense
from ..strategy.roles import push_out_of_capsule, push_out_of_circle
from .orders import TargetOrder, VelocityOrder

R = ROBOT_RADIUS_MM
#: the robot's body keeps this much more than touching from an area it may not enter
MARGIN_MM = 20.0
#: a Velocity order is corrected when the robot is this close to a forbidden area
VELOCITY_GUARD_MM = 100.0
#: situations in which our robots keep the stop distance from the ball (as the built-in
#: plays do): STOP, and the other team's free kick, kickoff and ball placement
KEEP_OFF = ("stop",)
KEEP_OFF_THEIRS = ("free-kick", "placement", "kickoff-prepare", "kickoff")

Rect = tuple[float, float, float, float]  # xmin, ymin, xmax, ymax


@dataclass(frozen=True, slots=True)
class Rules:
    """What binds our robots this tick (our frame)."""

    fs: Field
    situation: str = "running"  # backend.strategy.situation's kind
    ours: bool | None = None  # our set piece (True), theirs (False)
    ball: tuple[float, float] | None = None
    designated: tuple[float, float] | None = None  # ball placement mark
    #: the referee's goalkeeper of ours; with no referee naming one, robot 0 (the game
    #: controller's default)
    keeper_id: int | None = 0
    stop_distance_mm: float = 650.0  # robot centre to ball (rules 500 plus margin)

    @property
    def keep_off_ball(self) -> bool:
        return self.ball is not None and (
            self.situation in KEEP_OFF
            or (self.ours is False and self.situation in KEEP_OFF_THEIRS))

    @property
    def stopped(self) -> bool:
        return self.situation in ("stop", "free-kick", "placement", "halt")

    def walls(self) -> Rect:
        fs = self.fs
        return (-fs.half_length - fs.boundary_width + R, -fs.half_width - fs.boundary_width + R,
                fs.half_length + fs.boundary_width - R, fs.half_width + fs.boundary_width - R)

    def areas(self, rid: int) -> list[Rect]:
        """The defence areas robot ``rid`` keeps out of, grown by its body and margin."""
        out: list[Rect] = []
        g = R + MARGIN_MM
        if rid != self.keeper_id:
            x0, y0, x1, y1 = own_defense(self.fs)
            out.append((x0 - g, y0 - g, x1 + g, y1 + g))
        t = g + (STOPPED_DEFENSE_AREA_DISTANCE_MM if self.stopped else 0.0)
        x0, y0, x1, y1 = their_defense(self.fs)
        out.append((x0 - t, y0 - t, x1 + t, y1 + t))
        return out

    def ball_zone(self) -> tuple[tuple[float, float], tuple[float, float] | None, float] | None:
        """(ball, placement mark or None, radius) the robots' centres keep out of."""
        if not self.keep_off_ball or self.ball is None:
            return None
        mark = self.designated if self.situation == "placement" and self.ours is False \
            else None
        return (self.ball, mark, self.stop_distance_mm)


def _in_rect(p: tuple[float, float], r: Rect) -> bool:
    return r[0] < p[0] < r[2] and r[1] < p[1] < r[3]


def _out_of_rect(p: tuple[float, float], r: Rect) -> list[tuple[float, float]]:
    """``p`` moved to each of the rectangle's four sides (just outside)."""
    e = 1.0
    return [(r[0] - e, p[1]), (r[2] + e, p[1]), (p[0], r[1] - e), (p[0], r[3] + e)]


def _zone_dist(p: tuple[float, float], zone: tuple[tuple[float, float],
                                                  tuple[float, float] | None, float]) -> float:
    """How far ``p`` is from the ball's zone's centre line (the ball, or ball-to-mark)."""
    a, b, _ = zone
    if b is None:
        return math.dist(p, a)
    vx, vy = b[0] - a[0], b[1] - a[1]
    ll = vx * vx + vy * vy
    t = 0.0 if ll < 1e-9 else max(0.0, min(1.0, ((p[0] - a[0]) * vx + (p[1] - a[1]) * vy) / ll))
    return math.dist(p, (a[0] + vx * t, a[1] + vy * t))


def allowed(p: tuple[float, float], rid: int, rules: Rules) -> bool:
    w = rules.walls()
    if not (w[0] <= p[0] <= w[2] and w[1] <= p[1] <= w[3]):
        return False
    if any(_in_rect(p, r) for r in rules.areas(rid)):
        return False
    zone = rules.ball_zone()
    return zone is None or _zone_dist(p, zone) >= zone[2] - 1e-6


def nearest_allowed(p: tuple[float, float], rid: int, rules: Rules) -> tuple[float, float]:
    """``p`` if allowed, else the nearest allowed point found: each forbidden shape's way
    out (and again from there, for shapes that touch), else a search on rings around ``p``."""
    if allowed(p, rid, rules):
        return p
    w = rules.walls()
    zone = rules.ball_zone()

    def ways_out(q: tuple[float, float]) -> list[tuple[float, float]]:
        outs = [(min(max(q[0], w[0]), w[2]), min(max(q[1], w[1]), w[3]))]
        for r in rules.areas(rid):
            if _in_rect(q, r):
                outs += _out_of_rect(q, r)
        if zone is not None and _zone_dist(q, zone) < zone[2]:
            ball, mark, d = zone
            outs.append(push_out_of_capsule(q, ball, mark, d + 1.0) if mark is not None
                        else push_out_of_circle(q, ball, d + 1.0))
        return outs

    cands = ways_out(p)
    for _ in range(3):
        cands += [c2 for c in cands if not allowed(c, rid, rules) for c2 in ways_out(c)]
    ok = [c for c in cands if allowed(c, rid, rules)]
    if ok:
        return min(ok, key=lambda c: math.dist(c, p))
    for ring in range(1, 80):  # every 50 mm, 72 directions: the nearest allowed point
        r = 50.0 * ring
        ring_ok = [c for k in range(72)
                   if allowed(c := (p[0] + r * math.cos(k * math.pi / 36),
                                    p[1] + r * math.sin(k * math.pi / 36)), rid, rules)]
        if ring_ok:
            return min(ring_ok, key=lambda c: math.dist(c, p))
    return (0.0, 0.0)  # (a field with no allowed point at all: the centre)


def check_target(o: TargetOrder, rules: Rules) -> tuple[TargetOrder, list[str]]:
    """The order within the envelope, and what was changed (empty: nothing)."""
    changed: list[str] = []
    p = nearest_allowed((o.x, o.y), o.id, rules)
    if p != (o.x, o.y):
        changed.append(f"target ({o.x:.0f}, {o.y:.0f}) moved to ({p[0]:.0f}, {p[1]:.0f})")
        o = replace(o, x=p[0], y=p[1])
    if o.kick_mps > MAX_KICK_SPEED_MPS:
        changed.append(f"kick {o.kick_mps:.1f} m/s capped at {MAX_KICK_SPEED_MPS}")
        o = replace(o, kick_mps=MAX_KICK_SPEED_MPS)
    return o, changed


def _outward(p: tuple[float, float], rid: int, rules: Rules
             ) -> list[tuple[float, float]]:
    """Unit normals pointing away from each forbidden shape within the guard distance."""
    out: list[tuple[float, float]] = []
    g = VELOCITY_GUARD_MM
    for r in rules.areas(rid):
        cx = min(max(p[0], r[0]), r[2])
        cy = min(max(p[1], r[1]), r[3])
        dx, dy = p[0] - cx, p[1] - cy
        d = math.hypot(dx, dy)
        if d <= g:
            if d < 1e-6:  # inside already: out by the nearest side
                sides = [(p[0] - r[0], (-1.0, 0.0)), (r[2] - p[0], (1.0, 0.0)),
                         (p[1] - r[1], (0.0, -1.0)), (r[3] - p[1], (0.0, 1.0))]
                out.append(min(sides)[1])
            else:
                out.append((dx / d, dy / d))
    zone = rules.ball_zone()
    if zone is not None:
        ball, mark, radius = zone
        d_edge = _zone_dist(p, zone) - radius
        if d_edge <= g:
            a = ball
            if mark is not None:
                vx, vy = mark[0] - ball[0], mark[1] - ball[1]
                ll = vx * vx + vy * vy
                t = 0.0 if ll < 1e-9 else max(0.0, min(1.0, ((p[0] - ball[0]) * vx
                                                             + (p[1] - ball[1]) * vy) / ll))
                a = (ball[0] + vx * t, ball[1] + vy * t)
            dx, dy = p[0] - a[0], p[1] - a[1]
            d = math.hypot(dx, dy)
            out.append((dx / d, dy / d) if d > 1e-6 else (-1.0, 0.0))
    return out


def check_velocity(o: VelocityOrder, x: float, y: float, heading: float,
                   rules: Rules) -> tuple[VelocityOrder, list[str]]:
    """``o`` for a robot at (x, y) heading ``heading`` (our frame): no motion towards a
    forbidden area it is within the guard of; the kick capped."""
    changed: list[str] = []
    c, s = math.cos(heading), math.sin(heading)
    vx = o.forward_mps * c - o.left_mps * s
    vy = o.forward_mps * s + o.left_mps * c
    for nx, ny in _outward((x, y), o.id, rules):
        towards = vx * nx + vy * ny
        if towards < 0.0:
            vx, vy = vx - towards * nx, vy - towards * ny
    fwd, left = vx * c + vy * s, -vx * s + vy * c
    if abs(fwd - o.forward_mps) > 1e-9 or abs(left - o.left_mps) > 1e-9:
        changed.append("velocity towards a forbidden area removed")
        o = replace(o, forward_mps=fwd, left_mps=left)
    if o.kick_mps > MAX_KICK_SPEED_MPS:
        changed.append(f"kick {o.kick_mps:.1f} m/s capped at {MAX_KICK_SPEED_MPS}")
        o = replace(o, kick_mps=MAX_KICK_SPEED_MPS)
    return o, changed
