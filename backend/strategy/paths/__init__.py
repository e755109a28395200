"""Obstacle avoidance: a short collision-free polyline from a robot to its target.

Obstacles are circles (other robots, the ball) and axis-aligned rectangles (the defence
areas), optionally inside a bounding rectangle the robot centre must not leave (the field
plus its boundary margin). Planning treats the robot as a point: ``clearance`` (robot radius
plus a safety margin, mm) is added to every obstacle, a circle of radius r becoming one of
radius r + clearance and a rectangle growing by clearance on every side. The bounds are not
shrunk: they already describe where the robot centre may go.

``plan_path`` first tests the straight segment (the common case: one vectorised test, no
other work). A goal inside an obstacle (or out of bounds) is replaced by the nearest free
point; a start inside one first escapes to its nearest free point. When the segment is
blocked it searches a visibility graph around the obstacles with A*, first within a narrow
corridor, on the edges a taut path can use; when there is no way, the robot drives the
straight line as far as it is free.

Where each part lives (read ``plan.py`` first; what is imported below is the API):

- ``plan.py``: ``plan_path`` and ``PlannedPath``, the order of the steps below;
- ``obstacles.py``: ``Obstacles``, ``Bounds``, the input checks, the field's areas and
  bounds as shapes;
- ``collision.py``: obstacles grown by the clearance; the point and segment tests
  (``point_is_free``, ``segment_is_free``, ``first_blocking``) and their tolerance;
- ``straight.py``: the straight drive's test, for one robot and for a tick's robots at once;
- ``escape.py``: the nearest free point (a start or a goal inside an obstacle);
- ``graph.py``: the visibility graph's nodes and the tangent pruning of its edges;
- ``astar.py``: A* on that graph, edges tested in batches;
- ``search.py``: the corridor schedule around A*, narrow first, pruned first;
- ``enclosure.py``: no way through: the enclosed-goal test, and the free part of the
  straight line as the answer;
- ``memory.py``: ``PathMemory`` (each robot's last search, reused while it holds) and
  ``recheck_path``.

Names with a leading underscore are shared between these modules only.
"""

from __future__ import annotations

from .collision import EPS_MM, Blocking, first_blocking, point_is_free, segment_is_free
from .escape import MOVE_PAD_MM, nearest_free_point
from .graph import CIRCLE_SIDES, NODE_PAD_MM
from .memory import PathMemory, recheck_path
from .obstacles import ROBOT_RADIUS_MM, Bounds, Obstacles, defense_area_rects, field_bounds
from .plan import PlannedPath, plan_path
from .straight import straight_clear_of_circles, straight_clear_of_rest, straight_is_clear

__all__ = [
    "CIRCLE_SIDES",
    "EPS_MM",
    "MOVE_PAD_MM",
    "NODE_PAD_MM",
    "ROBOT_RADIUS_MM",
    "Blocking",
    "Bounds",
    "Obstacles",
    "PathMemory",
    "PlannedPath",
    "defense_area_rects",
    "field_bounds",
    "first_blocking",
    "nearest_free_point",
    "plan_path",
    "point_is_free",
    "recheck_path",
    "segment_is_free",
    "straight_clear_of_circles",
    "straight_clear_of_rest",
    "straight_is_clear",
]
