"""The straight drive: is the segment from the robot to its goal free? The common case,
tested before anything else is built: for one robot (``plan_path``'s first test), and for
all the robots of a tick at once (``straight_clear_of_circles``, then each robot's own
discs, areas and bounds in plain floats). The same test and tolerance as the collision
tests (``collision.py``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .collision import EPS_MM, _rect_entry
from .obstacles import Array, Bounds, Obstacles, Point, _check_bounds, _point


def _straight_is_clear(s: Array, g: Array, obstacles: Obstacles, clearance: float,
                       bounds: Bounds | None) -> bool:
    """Both ends in bounds and segment [s, g] entering no inflated obstacle (ends inside
    one count as entering): the common case, tested without building the graph data."""
    sx, sy, gx, gy = float(s[0]), float(s[1]), float(g[0]), float(g[1])
    if not _ends_in_bounds(sx, sy, gx, gy, bounds):
        return False
    c = obstacles.circles
    if len(c):
        dx, dy = gx - sx, gy - sy
        dd = dx * dx + dy * dy
        fx, fy = c[:, 0] - sx, c[:, 1] - sy
        if dd > EPS_MM * EPS_MM:  # shorter segments are the point s (1/dd would overflow)
            t = np.minimum(np.maximum((fx * dx + fy * dy) / dd, 0.0), 1.0)
            fx, fy = fx - t * dx, fy - t * dy
        r = np.maximum(c[:, 2] + (clearance - EPS_MM), 0.0)
        if (fx * fx + fy * fy < r * r).any():
            return False
    return _clear_of_rects(sx, sy, gx, gy, obstacles.rects.tolist(), clearance)


def _ends_in_bounds(sx: float, sy: float, gx: float, gy: float, bounds: Bounds | None) -> bool:
    if bounds is None:
        return True
    x0, y0, x1, y1 = bounds
    e = EPS_MM
    return (x0 - e <= sx <= x1 + e and x0 - e <= gx <= x1 + e
            and y0 - e <= sy <= y1 + e and y0 - e <= gy <= y1 + e)


def _clear_of_rects(sx: float, sy: float, gx: float, gy: float,
                    rects: Sequence[Sequence[float]], clearance: float) -> bool:
    grow = clearance - EPS_MM
    for x0, y0, x1, y1 in rects:
        if _rect_entry(sx, sy, gx, gy, x0 - grow, y0 - grow, x1 + grow, y1 + grow) is not None:
            return False
    return True


def straight_clear_of_circles(starts: Array, goals: Array, circles: Array, clearance: float,
                              skip: NDArray[np.int64]) -> NDArray[np.bool_]:
    """For many robots at once (one numpy pass instead of one per robot): row i's segment
    ``starts[i]`` -> ``goals[i]`` enters none of the ``circles`` (K, 3) grown by
    ``clearance``, leaving out circle ``skip[i]`` (the robot itself; -1: none). The same
    test and tolerance as ``plan_path``'s straight case, for the circles only: rectangles
    and bounds are ``straight_clear_of_rest``'s."""
    n = len(starts)
    if not len(circles) or not n:
        return np.ones(n, dtype=bool)
    sx, sy = starts[:, 0:1], starts[:, 1:2]
    dx, dy = goals[:, 0:1] - sx, goals[:, 1:2] - sy
    dd = dx * dx + dy * dy
    fx, fy = circles[:, 0] - sx, circles[:, 1] - sy  # (N, K)
    long = dd > EPS_MM * EPS_MM  # shorter segments are the point s
    t = np.minimum(np.maximum((fx * dx + fy * dy) / np.where(long, dd, 1.0), 0.0), 1.0)
    t = np.where(long, t, 0.0)
    fx, fy = fx - t * dx, fy - t * dy
    r = np.maximum(circles[:, 2] + (clearance - EPS_MM), 0.0)
    hit = fx * fx + fy * fy < r * r
    rows = np.nonzero(skip >= 0)[0]
    hit[rows, skip[rows]] = False
    return np.asarray(~hit.any(axis=1))


def straight_clear_of_rest(start: Point, goal: Point, circles: Sequence[Sequence[float]],
                           rects: Sequence[Sequence[float]], clearance: float,
                           bounds: Bounds | None) -> bool:
    """``straight_clear_of_circles``' complement for one robot, in plain floats: its own few
    circles (the ball), the rectangles and the bounds."""
    sx, sy, gx, gy = start[0], start[1], goal[0], goal[1]
    if not _ends_in_bounds(sx, sy, gx, gy, bounds):
        return False
    dx, dy = gx - sx, gy - sy
    dd = dx * dx + dy * dy
    for cx, cy, cr in circles:
        fx, fy = cx - sx, cy - sy
        if dd > EPS_MM * EPS_MM:
            t = min(max((fx * dx + fy * dy) / dd, 0.0), 1.0)
            fx, fy = fx - t * dx, fy - t * dy
        r = max(cr + (clearance - EPS_MM), 0.0)
        if fx * fx + fy * fy < r * r:
            return False
    return _clear_of_rects(sx, sy, gx, gy, rects, clearance)


def straight_is_clear(start: ArrayLike, goal: ArrayLike, obstacles: Obstacles,
                      clearance: float, bounds: Bounds | None = None) -> bool:
    """The straight drive start -> goal is free and in bounds (``obstacles.bounds`` when
    None): ``plan_path`` would answer the goal itself, without any search."""
    box = _check_bounds(bounds) if bounds is not None else obstacles.bounds
    return _straight_is_clear(_point(start, "start"), _point(goal, "goal"), obstacles,
                              clearance, box)
