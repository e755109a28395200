"""Path following: which point of a planned path the speed controller is aimed at."""

from __future__ import annotations

import math

from ..messages import TargetEntry
from .goto import Target

#: a waypoint closer than this counts as passed: the robot heads for the next one
WAYPOINT_REACHED_MM = 120.0


def next_waypoint(entry: TargetEntry, x_mm: float, y_mm: float) -> Target:
    """Where the controller steers now: the first waypoint of the planned path not yet
    reached (with the final heading), or the target itself."""
    path = entry.path
    if len(path) <= 1:
        return entry.target
    # the nearest waypoint; the next one once it is reached or already passed (the path
    # was planned a strategy tick ago, the robot has moved along it since)
    # (as min() with a key function would, without a call per waypoint at every step)
    hypot = math.hypot
    k, best = 0, hypot(path[0][0] - x_mm, path[0][1] - y_mm)
    for i in range(1, len(path)):
        d = hypot(path[i][0] - x_mm, path[i][1] - y_mm)
        if d < best:
            k, best = i, d
    if k < len(path) - 1:
        px, py = path[k]
        nx, ny = path[k + 1]
        passed = (x_mm - px) * (nx - px) + (y_mm - py) * (ny - py) > 0.0
        if passed or math.hypot(px - x_mm, py - y_mm) <= WAYPOINT_REACHED_MM:
            k += 1
    if k == len(path) - 1:
        return entry.target
    return carry_through(path, k, x_mm, y_mm, entry.target.orientation)


#: how far past an intermediate waypoint the controller is aimed at most (mm)
CARRY_MAX_MM = 600.0


def carry_through(path: tuple[tuple[float, float], ...], k: int, x_mm: float, y_mm: float,
                   orientation: float | None) -> Target:
    """The controller's target for intermediate waypoint ``k``: the waypoint itself pushed on
    along the robot's line to it, by up to the path still left after it (at most
    ``CARRY_MAX_MM``), scaled by cos^2 of the turn there. The speed controllers brake to
    stop at their target; aimed past a waypoint the robot keeps its speed through a gentle
    turn and still stops at a sharp one (90 deg or more: no carry at all)."""
    px, py = path[k]
    nx, ny = path[k + 1]
    ix, iy = px - x_mm, py - y_mm
    ox, oy = nx - px, ny - py
    li, lo = math.hypot(ix, iy), math.hypot(ox, oy)
    if li < 1e-6 or lo < 1e-6:
        return Target(px, py, orientation)
    cos_turn = (ix * ox + iy * oy) / (li * lo)
    if cos_turn <= 0.0:
        return Target(px, py, orientation)
    rest = lo + sum(math.dist(path[i], path[i + 1]) for i in range(k + 1, len(path) - 1))
    ext = min(rest, CARRY_MAX_MM) * cos_turn * cos_turn
    return Target(px + ix / li * ext, py + iy / li * ext, orientation)
