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

from domain.field import Field
from domain.rules import (
    BALL_RADIUS_MM,
    ROBOT_RADIUS_MM,
    STOP_BALL_DISTANCE_MM,
)

# Distances and speeds of the rules
DISTANCE_TOLERANCE_MM = 50.0  # what the game controller forgives on any distance rule
# a robot is "too close" when its centre is nearer than this to the ball centre
TOO_CLOSE_MM = STOP_BALL_DISTANCE_MM + ROBOT_RADIUS_MM - DISTANCE_TOLERANCE_MM
STOP_SPEED_LIMIT_MMPS = 1500.0 + 100.0  # 1.5 m/s plus 0.1 m/s tolerance
HALT_SPEED_LIMIT_MMPS = 100.0
CENTER_CIRCLE_RADIUS_MM = 500.0
PENALTY_BEHIND_BALL_MM = 1000.0  # the other robots at a penalty kick stay this far behind
COLLISION_DRAWN_MPS = 0.3  # both robots are at fault if their speeds are this close
POSSESSION_DISTANCE_MM = 200.0  # robot centre to ball centre
TOUCH_DISTANCE_MM = ROBOT_RADIUS_MM + BALL_RADIUS_MM + 15.0  # fallback last-touch detection

# Ball placement
PLACEMENT_STILL_MMPS = 100.0
PLACEMENT_LINE_OFFSET_MM = 200.0
PLACEMENT_DEFENSE_AREA_OFFSET_MM = 700.0

# Ball in play after a free kick / kick-off / penalty
BALL_IN_PLAY_MM = 50.0

# No progress
NO_PROGRESS_S = 15.0
NO_PROGRESS_MM = 100.0



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


def placement_position(field: Field, x: float, y: float) -> tuple[float, float]:
    """Where a ball that left the field at (x, y) is placed: 200 mm inside the field lines,
    then moved away from a defence area it is closer to than 700 mm (along x or along y,
    whichever moves it less)."""
    lx = field.half_length - PLACEMENT_LINE_OFFSET_MM
    ly = field.half_width - PLACEMENT_LINE_OFFSET_MM
    px, py = clamp(x, -lx, lx), clamp(y, -ly, ly)
    gap = PLACEMENT_DEFENSE_AREA_OFFSET_MM
    for side in (-1, 1):
        if field.dist_to_defense_area(px, py, side) >= gap:
            continue
        x0, x1, _, y1 = field.defense_rect(side)
        # candidate 1: in front of the area, towards the centre
        cx = (x0 - gap) if side > 0 else (x1 + gap)
        # candidate 2: beside the area, towards the touch line on the ball's side
        cy = math.copysign(min(y1 + gap, ly), py if py != 0.0 else 1.0)
        if abs(cy) >= y1 + gap and abs(cy - py) < abs(cx - px):
            py = cy
        else:
            px = cx
    return (px, py)
