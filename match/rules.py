"""The numbers the match director judges by, and the field geometry it needs (pure, mm).

Every tolerance and grace period is here, in one place, and documented in docs/match.md.
Sources: the SSL rules (robot radius, STOP distance and speed, HALT braking), the official
ssl-game-controller defaults (ball placement tolerance 0.15 m, placement offsets 0.2 m from the
lines, 0.7 m from the defence areas, penalty mark 8 m (div A) / 6 m (div B) from the goal
centre, kick-off and penalty readiness checks, free-kick timeout 10 s in division B).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fieldsim.geometry import division_geometry

ROBOT_RADIUS_MM = 90.0
BALL_RADIUS_MM = 21.5

# Distances and speeds of the rules
STOP_BALL_DISTANCE_MM = 500.0  # STOP and the opponents of a free kick / kick-off / placement
DISTANCE_TOLERANCE_MM = 50.0  # what the game controller forgives on any distance rule
# a robot is "too close" when its centre is nearer than this to the ball centre
TOO_CLOSE_MM = STOP_BALL_DISTANCE_MM + ROBOT_RADIUS_MM - DISTANCE_TOLERANCE_MM
STOP_SPEED_LIMIT_MMPS = 1500.0 + 100.0  # 1.5 m/s plus 0.1 m/s tolerance
HALT_SPEED_LIMIT_MMPS = 100.0
CENTER_CIRCLE_RADIUS_MM = 500.0
PENALTY_BEHIND_BALL_MM = 1000.0  # the other robots at a penalty kick stay this far behind
COLLISION_SPEED_MPS = 1.5  # relative speed above which a collision is a foul
COLLISION_DRAWN_MPS = 0.3  # both robots are at fault if their speeds are this close
POSSESSION_DISTANCE_MM = 200.0  # robot centre to ball centre
TOUCH_DISTANCE_MM = ROBOT_RADIUS_MM + BALL_RADIUS_MM + 15.0  # fallback last-touch detection

# Ball placement
PLACEMENT_TOLERANCE_MM = 150.0
PLACEMENT_STILL_MMPS = 100.0
PLACEMENT_LINE_OFFSET_MM = 200.0
PLACEMENT_DEFENSE_AREA_OFFSET_MM = 700.0

# Ball in play after a free kick / kick-off / penalty
BALL_IN_PLAY_MM = 50.0

# No progress
NO_PROGRESS_S = 15.0
NO_PROGRESS_MM = 100.0

# Penalty mark: distance from the goal centre (ssl-game-controller default geometry)
PENALTY_MARK_DISTANCE_MM = {"A": 8000.0, "B": 6000.0}


@dataclass(frozen=True)
class Grace:
    """Seconds after a command (or set piece) starts before a rule is judged."""

    halt: float = 2.0  # rules: 2 s to brake after HALT
    stop: float = 2.0  # rules: 2 s to reach the STOP distance / speed
    set_piece_distance: float = 2.0  # opponents of a free kick / kick-off (from its start)
    placement_distance: float = 2.0  # opponents of the placing team: in the corridor so long
    defense_area: float = 1.0  # after running play starts


@dataclass(frozen=True)
class Timing:
    """How long the director holds each command (seconds)."""

    start_halt: float = 1.0
    start_stop: float = 2.0
    prepare_min: float = 2.0  # PREPARE_*: at least this long ...
    prepare_max: float = 5.0  # ... and NORMAL_START at the latest after this (kick-off)
    penalty_prepare_max: float = 10.0  # the game controller's prepare timeout
    settled_speed_mmps: float = 200.0  # "settled": every robot slower than this
    kick_timeout: float = 10.0  # NORMAL_START / DIRECT_FREE: FORCE_START if the ball has not moved
    goal_stop: float = 3.0  # the STOP after a goal (its last second judged by the STOP rules)
    goal_teleport_after: float = 1.5
    out_stop: float = 1.0
    placement_timeout: float = 15.0
    no_progress_stop: float = 2.0
    half_time: float = 3.0
    teleport_confirm: float = 3.0  # wait at most this long for a teleported ball to show up
    interlude_halt: float = 3.0  # judged for its last second (HALT grace 2 s)
    interlude_stop: float = 5.0
    interlude_before: float = 3.0  # STOP before a scripted free kick / penalty / after HALT
    timeout: float = 5.0


def clamp(v: float, lo: float, hi: float) -> float:
    return lo if v < lo else hi if v > hi else v


def dist(ax: float, ay: float, bx: float, by: float) -> float:
    return math.hypot(ax - bx, ay - by)


def dist_to_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance from P to the segment AB."""
    dx, dy = bx - ax, by - ay
    n2 = dx * dx + dy * dy
    if n2 <= 1e-12:
        return dist(px, py, ax, ay)
    t = clamp(((px - ax) * dx + (py - ay) * dy) / n2, 0.0, 1.0)
    return dist(px, py, ax + t * dx, ay + t * dy)


@dataclass(frozen=True)
class Field:
    """Field sizes (mm) of one division, from fieldsim's geometry."""

    length: float
    width: float
    goal_width: float
    defense_depth: float
    defense_width: float
    center_radius: float
    penalty_mark_distance: float

    @staticmethod
    def for_division(division: str) -> Field:
        g = division_geometry(division)
        return Field(
            length=float(g.field_length),
            width=float(g.field_width),
            goal_width=float(g.goal_width),
            defense_depth=float(g.penalty_area_depth),
            defense_width=float(g.penalty_area_width),
            center_radius=float(g.center_circle_radius),
            penalty_mark_distance=PENALTY_MARK_DISTANCE_MM[division],
        )

    @property
    def half_length(self) -> float:
        return self.length / 2.0

    @property
    def half_width(self) -> float:
        return self.width / 2.0

    def defense_rect(self, side: int) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1) of the defence area in front of the goal at x = side * half_length."""
        hl, d, hw = self.half_length, self.defense_depth, self.defense_width / 2.0
        if side > 0:
            return (hl - d, hl, -hw, hw)
        return (-hl, -hl + d, -hw, hw)

    def dist_to_defense_area(self, x: float, y: float, side: int) -> float:
        """0 inside the defence area of ``side``, else the distance to it."""
        x0, x1, y0, y1 = self.defense_rect(side)
        dx = max(x0 - x, 0.0, x - x1)
        dy = max(y0 - y, 0.0, y - y1)
        return math.hypot(dx, dy)

    def in_field(self, x: float, y: float) -> bool:
        return abs(x) <= self.half_length and abs(y) <= self.half_width

    def penalty_mark(self, defending_side: int) -> tuple[float, float]:
        """The penalty mark in front of the goal defended on ``defending_side`` (+1 / -1)."""
        return (defending_side * (self.half_length - self.penalty_mark_distance), 0.0)

    def placement_position(self, x: float, y: float) -> tuple[float, float]:
        """Where a ball that left the field at (x, y) is placed: 200 mm inside the field lines,
        then moved away from a defence area it is closer to than 700 mm (along x or along y,
        whichever moves it less)."""
        lx = self.half_length - PLACEMENT_LINE_OFFSET_MM
        ly = self.half_width - PLACEMENT_LINE_OFFSET_MM
        px, py = clamp(x, -lx, lx), clamp(y, -ly, ly)
        gap = PLACEMENT_DEFENSE_AREA_OFFSET_MM
        for side in (-1, 1):
            if self.dist_to_defense_area(px, py, side) >= gap:
                continue
            x0, x1, _, y1 = self.defense_rect(side)
            # candidate 1: in front of the area, towards the centre
            cx = (x0 - gap) if side > 0 else (x1 + gap)
            # candidate 2: beside the area, towards the touch line on the ball's side
            cy = math.copysign(min(y1 + gap, ly), py if py != 0.0 else 1.0)
            if abs(cy) >= y1 + gap and abs(cy - py) < abs(cx - px):
                py = cy
            else:
                px = cx
        return (px, py)
