"""The path memory: each robot's last search, reused while its inputs barely changed, and
a detour re-checked (``recheck_path``: two vectorised tests) instead of searched again while
the robot drives it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from domain.rules import ROBOT_RADIUS_MM as R

from .collision import _Inflated
from .obstacles import Bounds, Obstacles, Point, _point
from .plan import PlannedPath, plan_path

#: a robot's earlier plan stands while its start, its goal and every obstacle moved at most
#: this much (mm; vision noise is ~1 mm): a still robot in a still scene plans once, not at
#: every tick (a robot boxed in by others searched the whole graph, ~20 ms, each tick)
REUSE_MM = 5.0
#: ... for at most this long (s)
REUSE_MAX_AGE_S = 1.0
#: a detour is kept while it stays clear and its goal within ``REUSE_MM``, re-checked instead
#: of searched again, for at most this long (s): a shorter way opened meanwhile is taken then
DETOUR_MAX_AGE_S = 0.25


def recheck_path(start: ArrayLike, points: Sequence[Point], obstacles: Obstacles,
                 clearance: float, *, bounds: Bounds | None = None) -> tuple[Point, ...] | None:
    """A path planned earlier, still good from ``start`` among these obstacles: ``points``
    from the farthest waypoint that ``start`` sees directly on (the waypoints the robot has
    passed dropped), when that waypoint and every later one and segment are free; else None
    (plan again). Two vectorised tests instead of a search: the cheap way to keep a detour
    while the robot drives it."""
    s = _point(start, "start")
    if not points:
        return None
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    inf = _Inflated(obstacles, clearance, bounds)
    free = inf.points_free(np.vstack([s[None, :], pts]))
    if not free.all():
        return None
    if len(pts) > 1 and inf.segments_blocked(pts[:-1, 0], pts[:-1, 1],
                                              pts[1:, 0], pts[1:, 1]).any():
        return None
    seen = np.nonzero(~inf.blocked_from(s, pts))[0]
    if not len(seen):
        return None
    return tuple((float(x), float(y)) for x, y in pts[int(seen[-1]):])


class _Plan:
    """One robot's last search: its inputs and result."""

    __slots__ = ("blocked", "circles", "goal", "points", "rects", "simple", "start", "t")

    def __init__(self, start: tuple[float, float], goal: tuple[float, float],
                 obstacles: Obstacles, res: PlannedPath, t: float) -> None:
        self.start, self.goal, self.t = start, goal, t
        self.circles, self.rects = obstacles.circles, obstacles.rects
        self.points = res.points
        self.blocked = res.blocked
        #: a plain detour: every segment from the start on was checked (see ``recheck_path``)
        self.simple = not (res.blocked or res.goal_moved or res.start_escape or res.truncated)

    def same(self, start: tuple[float, float], goal: tuple[float, float],
             obstacles: Obstacles) -> bool:
        """Nothing moved more than ``REUSE_MM`` since this plan."""
        c, r = obstacles.circles, obstacles.rects
        return (math.dist(start, self.start) <= REUSE_MM
                and math.dist(goal, self.goal) <= REUSE_MM
                and c.shape == self.circles.shape and r.shape == self.rects.shape
                and (not c.size or float(np.abs(c - self.circles).max()) <= REUSE_MM)
                and (not r.size or float(np.abs(r - self.rects).max()) <= REUSE_MM))


class PathMemory:
    """Each robot's last search, so a tick whose inputs barely changed does not search again:
    the path is reused while nothing moved (``REUSE_MM``), or while a detour stays clear
    (``DETOUR_MAX_AGE_S``). Straight drives (one cheap test) are not remembered."""

    def __init__(self) -> None:
        self.plans: dict[int, _Plan] = {}
        self.searches = 0
        self.reused = 0

    def forget(self, keep: set[int]) -> None:
        for rid in [r for r in self.plans if r not in keep]:
            del self.plans[rid]

    def path(self, rid: int, start: tuple[float, float], goal: tuple[float, float],
             obstacles: Obstacles, bounds: tuple[float, float, float, float],
             now: float) -> tuple[tuple[tuple[float, float], ...], bool]:
        """The waypoints for ``rid`` and whether it is blocked: a reused plan or a new one."""
        old = self.plans.get(rid)
        if old is not None:
            age = now - old.t
            if 0.0 <= age <= REUSE_MAX_AGE_S and old.same(start, goal, obstacles):
                self.reused += 1
                return old.points, old.blocked
            if old.simple and 0.0 <= age <= DETOUR_MAX_AGE_S \
                    and math.dist(goal, old.goal) <= REUSE_MM:
                pts = recheck_path(start, old.points, obstacles, R, bounds=bounds)
                if pts is not None:
                    self.reused += 1
                    return pts, False
        self.searches += 1
        res = plan_path(start, goal, obstacles, R, bounds=bounds)
        self.plans[rid] = _Plan(start, goal, obstacles, res, now)
        return (tuple(res.points) if res.points else (goal,)), res.blocked
