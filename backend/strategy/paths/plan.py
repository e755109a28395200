"""``plan_path``: the planner's one entry, and its result. It tests the straight segment
first (``straight.py``); a start inside an obstacle escapes to its nearest free point and a
goal inside one moves to its nearest free point (``escape.py``); a blocked segment goes to
the search (``search.py``); no way at all gives the free part of the straight line
(``enclosure.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .collision import _Inflated
from .enclosure import _free_prefix
from .escape import _nearest_free
from .obstacles import Array, Bounds, Obstacles, Point, _check_bounds, _check_clearance, _point
from .search import _shortest
from .straight import _straight_is_clear


@dataclass(frozen=True)
class PlannedPath:
    """Result of ``plan_path``.

    ``points``: waypoints after the start (mm); the last one is the (possibly moved) goal,
    except when ``blocked`` or ``truncated``. ``goal_moved``: the goal was inside an inflated
    obstacle (or out of bounds) and the nearest free point replaces it. ``start_escape``:
    the start was inside an inflated obstacle (or out of bounds); ``points[0]`` is then the
    nearest free point and the segment to it is not obstacle-checked. ``blocked``: no path
    exists in the graph; ``points`` then follow the straight line towards the goal only as
    far as it is free (stopping ``NODE_PAD_MM`` before the first obstacle, possibly right at
    the start), so a robot following it never drives into an obstacle.
    ``truncated``: the path needed more than ``max_waypoints`` points and only the first
    ones are returned (re-plan each tick). ``length``: polyline length from the start.
    """

    points: tuple[Point, ...]
    goal_moved: bool = False
    start_escape: bool = False
    blocked: bool = False
    length: float = 0.0
    truncated: bool = False


def _polyline_length(start: Array, pts: list[Array]) -> float:
    if not pts:
        return 0.0
    arr = np.vstack([start[None, :], *[q[None, :] for q in pts]])
    d = np.diff(arr, axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def plan_path(start: ArrayLike, goal: ArrayLike, obstacles: Obstacles, clearance: float, *,
              bounds: Bounds | None = None, max_waypoints: int = 8) -> PlannedPath:
    """A collision-free polyline from ``start`` to ``goal`` (mm) around ``obstacles`` grown by
    ``clearance``, inside ``bounds`` (``obstacles.bounds`` when None). See ``PlannedPath``
    for the result and the module docstring for the method."""
    if max_waypoints < 1:
        raise ValueError(f"max_waypoints must be >= 1, got {max_waypoints}")
    s0, g = _point(start, "start"), _point(goal, "goal")
    _check_clearance(clearance)
    box = _check_bounds(bounds) if bounds is not None else obstacles.bounds
    if _straight_is_clear(s0, g, obstacles, clearance, box):
        return PlannedPath(((float(g[0]), float(g[1])),),
                           length=math.hypot(g[0] - s0[0], g[1] - s0[1]))
    inf = _Inflated(obstacles, clearance, box)
    pts: list[Array] = []
    goal_moved = start_escape = False

    ends_free = inf.points_free(np.vstack([s0, g]))
    s = s0
    if not ends_free[0]:
        q = _nearest_free(s0, inf)
        if q is None:  # nothing is free: stay
            return PlannedPath(((float(s0[0]), float(s0[1])),), start_escape=True,
                               blocked=True, length=0.0)
        pts.append(q)
        s, start_escape = q, True
    if not ends_free[1]:
        q = _nearest_free(g, inf)
        if q is None:
            return _finish(s0, pts or [s0], max_waypoints, False, start_escape, True)
        g, goal_moved = q, True

    if (start_escape or goal_moved) and not inf.blocked_from(s, g[None, :])[0]:
        pts.append(g)
        return _finish(s0, pts, max_waypoints, goal_moved, start_escape, False)
    chain = _shortest(inf, s, g)
    if chain is None:
        stop = _free_prefix(s, g, obstacles, clearance)
        if not pts or float(np.hypot(*(stop - s))) > 0.0:
            pts.append(stop)
        return _finish(s0, pts, max_waypoints, goal_moved, start_escape, True)
    pts += chain
    return _finish(s0, pts, max_waypoints, goal_moved, start_escape, False)


def _finish(s0: Array, pts: list[Array], max_waypoints: int, goal_moved: bool,
            start_escape: bool, blocked: bool) -> PlannedPath:
    truncated = len(pts) > max_waypoints
    pts = pts[:max_waypoints]
    return PlannedPath(tuple((float(q[0]), float(q[1])) for q in pts), goal_moved=goal_moved,
                       start_escape=start_escape, blocked=blocked,
                       length=_polyline_length(s0, pts), truncated=truncated)
