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
blocked it searches a visibility graph whose nodes are

- around each inflated circle, a polygon circumscribed about the circle grown by
  ``NODE_PAD_MM`` (so its edges stay outside the circle), touching it where the tangents
  from start and goal touch it, with corners at most 2 pi / ``CIRCLE_SIDES`` apart: a path
  around one circle is tangent, polygon, tangent, within 2.4 % (+ the pad) of the exact
  tangent-arc-tangent length;
- the corners of each inflated rectangle, pushed diagonally outward by ``NODE_PAD_MM``;
- start and goal;

dropping nodes inside another obstacle or outside the bounds (so overlapping obstacles are
passed around their union). Edges are tested lazily, all edges of ``EXPAND_BATCH`` expanded
nodes against every obstacle in one numpy call, inside an A* search (straight-line
heuristic) that is exact on the graph:

- the search first runs inside an ellipse around start and goal that only allows short
  detours, then wider ones (``CORRIDOR_FIRST``, ``CORRIDOR_GROWTH``), then unbounded;
- it first tests only edges that touch the end node's polygon from outside (the edges a
  taut path can use; collinear within rounding, or from inside that polygon's circumcircle,
  or at a node next to a dropped one, also count), and searches the full graph only when
  that finds nothing, so a path is found whenever the graph has one.

Gaps between obstacles narrower than about the node padding may be missed (conservative,
never unsafe). Tolerance: a segment is blocked by a circle when it comes closer than the
inflated radius minus ``EPS_MM`` to its centre, by a rectangle when it enters the inflated
rectangle shrunk by ``EPS_MM`` (touching a boundary is allowed; the slack absorbs rounding).
"""

from __future__ import annotations

import functools
import heapq
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from backend.geometry import circle_circle_intersection, segment_hits_circles
from domain.field import Field

__all__ = [
    "CIRCLE_SIDES",
    "EPS_MM",
    "MOVE_PAD_MM",
    "NODE_PAD_MM",
    "ROBOT_RADIUS_MM",
    "Blocking",
    "Bounds",
    "Obstacles",
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

Array = NDArray[np.float64]
Bounds = tuple[float, float, float, float]  #: xmin, ymin, xmax, ymax (mm)
Point = tuple[float, float]

#: SSL robots are at most 180 mm across
ROBOT_RADIUS_MM = 90.0
#: sides of the polygon placed around each circular obstacle
CIRCLE_SIDES = 12
#: graph nodes lie this far (mm) outside the inflated obstacles
NODE_PAD_MM = 1.0
#: moved goals and escape points lie this far (mm) outside the inflated obstacles (small:
#: where two boundaries meet at a shallow angle, growing both moves their crossing by
#: much more than this)
MOVE_PAD_MM = 1e-4
#: a segment may come this much (mm) inside an inflated obstacle without counting as blocked
EPS_MM = 1e-7
#: ``_Inflated.points_free`` tests up to this many points in plain floats
SMALL_T = 4


def _as_rows(a: ArrayLike | None, width: int, what: str) -> Array:
    if a is None:
        return np.zeros((0, width))
    arr = np.asarray(a, dtype=np.float64)
    if arr.size == 0:
        return np.zeros((0, width))
    arr = arr.reshape(-1, width) if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[1] != width:
        raise ValueError(f"{what} must have shape (n, {width}), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{what} must be finite")
    return arr


def _check_bounds(b: ArrayLike | None) -> Bounds | None:
    if b is None:
        return None
    if isinstance(b, tuple) and len(b) == 4 and all(type(v) is float for v in b):
        x0, y0, x1, y1 = b  # the navigation's (what the conversion below gives)
    else:
        x0, y0, x1, y1 = (float(v) for v in np.asarray(b, dtype=np.float64).reshape(4))
    if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or x0 > x1 or y0 > y1:
        raise ValueError(f"bounds must be finite (xmin, ymin, xmax, ymax), got {b}")
    return (x0, y0, x1, y1)


def _check_clearance(clearance: float) -> None:
    if not (math.isfinite(clearance) and clearance >= 0.0):
        raise ValueError(f"clearance must be a finite number >= 0, got {clearance}")


@dataclass(frozen=True, eq=False)
class Obstacles:
    """Circles ``(K, 3)`` [x, y, radius], axis-aligned rectangles ``(L, 4)``
    [xmin, ymin, xmax, ymax] and optional ``bounds`` for the robot centre, all in mm.

    Arrays are converted and checked on construction (finite, radius >= 0, min <= max)."""

    circles: Array = field(default_factory=lambda: np.zeros((0, 3)))
    rects: Array = field(default_factory=lambda: np.zeros((0, 4)))
    bounds: Bounds | None = None

    def __post_init__(self) -> None:
        c = _as_rows(self.circles, 3, "circles")
        r = _as_rows(self.rects, 4, "rects")
        if (c[:, 2] < 0.0).any():
            raise ValueError("circle radii must be >= 0")
        if ((r[:, 0] > r[:, 2]) | (r[:, 1] > r[:, 3])).any():
            raise ValueError("rects must be [xmin, ymin, xmax, ymax] with min <= max")
        object.__setattr__(self, "circles", c)
        object.__setattr__(self, "rects", r)
        object.__setattr__(self, "bounds", _check_bounds(self.bounds))

    @classmethod
    def trusted(cls, circles: Array, rects: Array) -> Obstacles:
        """Obstacles from arrays the caller has checked already: float64 circles (K, 3) and
        rects (L, 4), finite, radii >= 0, min <= max (what ``__post_init__`` checks); no
        bounds. For the navigation, which checks the tick's arrays once instead of each
        robot's share of them at every tick."""
        obs = object.__new__(cls)
        object.__setattr__(obs, "circles", circles)
        object.__setattr__(obs, "rects", rects)
        object.__setattr__(obs, "bounds", None)
        return obs

    @classmethod
    def build(cls, *, robots: ArrayLike | None = None, robot_radius: float = ROBOT_RADIUS_MM,
              circles: ArrayLike | None = None, rects: ArrayLike | None = None,
              bounds: Bounds | None = None) -> Obstacles:
        """Obstacles from robot centres ``(K, 2)`` (each a circle of ``robot_radius``), extra
        circles ``(J, 3)``, rectangles ``(L, 4)`` and bounds."""
        xy = _as_rows(robots, 2, "robots")
        rc = np.column_stack([xy, np.full(len(xy), float(robot_radius))])
        return cls(np.vstack([rc, _as_rows(circles, 3, "circles")]),
                   _as_rows(rects, 4, "rects"), bounds)

    def with_circles(self, xy: ArrayLike, radius: ArrayLike) -> Obstacles:
        """These obstacles plus circles at ``xy`` (K, 2) of ``radius`` (scalar or (K,))."""
        pts = _as_rows(xy, 2, "xy")
        r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(pts),))
        return Obstacles(np.vstack([self.circles, np.column_stack([pts, r])]), self.rects,
                         self.bounds)

    def with_rects(self, rects: ArrayLike) -> Obstacles:
        """These obstacles plus more rectangles (L, 4)."""
        return Obstacles(self.circles, np.vstack([self.rects, _as_rows(rects, 4, "rects")]),
                         self.bounds)

    def without_circles(self, indices: ArrayLike) -> Obstacles:
        """These obstacles minus the circles at ``indices`` (e.g. the planning robot)."""
        keep = np.ones(len(self.circles), dtype=bool)
        keep[np.asarray(indices, dtype=np.int64)] = False
        return Obstacles(self.circles[keep], self.rects, self.bounds)

    def with_bounds(self, bounds: Bounds | None) -> Obstacles:
        return Obstacles(self.circles, self.rects, bounds)

    def inflated(self, clearance: float) -> Obstacles:
        """Circles' radii + clearance, rectangles grown by clearance on every side."""
        c = self.circles.copy()
        c[:, 2] += clearance
        g = np.array([-clearance, -clearance, clearance, clearance])
        return Obstacles(c, self.rects + g, self.bounds)


def defense_area_rects(field: Field,
                       side: Literal["positive", "negative", "either"] = "either",
                       margin: float = 0.0) -> Array:
    """The defence areas as rectangles (L, 4), grown by ``margin`` on every side: the same
    regions as ``backend.geometry.in_defense_area(..., margin=margin)``."""
    half_len = field.field_length / 2.0
    half_w = field.penalty_area_width / 2.0
    depth = field.penalty_area_depth
    rows = []
    if side in ("positive", "either"):
        rows.append([half_len - depth, -half_w, half_len, half_w])
    if side in ("negative", "either"):
        rows.append([-half_len, -half_w, -half_len + depth, half_w])
    out: Array = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    out += np.array([-margin, -margin, margin, margin])
    return out


def field_bounds(field: Field, margin: float = 0.0) -> Bounds:
    """The field rectangle grown by ``margin`` (e.g. part of the boundary run-off area)."""
    hl, hw = field.field_length / 2.0 + margin, field.field_width / 2.0 + margin
    return (-hl, -hw, hl, hw)


class _Inflated:
    """Obstacles grown by the clearance, as flat arrays for the vectorised tests."""

    __slots__ = ("bhi", "blo", "bounds", "cmat", "cr", "cr2", "cx", "cxy", "cy", "plain",
                 "rects", "rects_in", "rhalf", "rmid")

    def __init__(self, obstacles: Obstacles, clearance: float, bounds: Bounds | None) -> None:
        _check_clearance(clearance)
        c = obstacles.circles
        self.cxy: Array = c[:, :2]
        self.cx: Array = c[:, 0]
        self.cy: Array = c[:, 1]
        self.cr: Array = c[:, 2] + clearance
        self.cr2: Array = np.maximum(self.cr - EPS_MM, 0.0) ** 2  # strict-inside threshold
        self.rects: Array = obstacles.rects + np.array([-clearance, -clearance,
                                                        clearance, clearance])
        shrunk = self.rects + np.array([EPS_MM, EPS_MM, -EPS_MM, -EPS_MM])
        keep = (shrunk[:, 0] < shrunk[:, 2]) & (shrunk[:, 1] < shrunk[:, 3])
        self.rects_in: Array = shrunk[keep]  # open interiors that block
        self.rmid: Array = (self.rects_in[:, :2] + self.rects_in[:, 2:]) * 0.5
        self.rhalf: Array = (self.rects_in[:, 2:] - self.rects_in[:, :2]) * 0.5
        # columns: centres for d.c, centres for d x c, rectangle centres for d x m
        k = len(c)
        cmat = np.empty((2, 2 * k + len(self.rmid)))
        cmat[0, :k] = self.cx
        cmat[1, :k] = self.cy
        cmat[0, k:2 * k] = self.cy
        np.negative(self.cx, out=cmat[1, k:2 * k])
        cmat[0, 2 * k:] = self.rmid[:, 1]
        np.negative(self.rmid[:, 0], out=cmat[1, 2 * k:])
        self.cmat: Array = cmat
        self.bounds = _check_bounds(bounds) if bounds is not None else obstacles.bounds
        #: the circles, rectangles and bounds box as Python floats, made on first use
        self.plain: tuple[list[tuple[float, float, float]], list[list[float]],
                          tuple[float, float, float, float] | None] | None = None
        if self.bounds is not None:
            x0, y0, x1, y1 = self.bounds
            self.blo: Array = np.array([x0 - EPS_MM, y0 - EPS_MM])
            self.bhi: Array = np.array([x1 + EPS_MM, y1 + EPS_MM])

    def points_free(self, p: Array) -> NDArray[np.bool_]:
        """(T, 2) points -> (T,) outside every obstacle (boundary allowed) and in bounds."""
        if len(p) <= SMALL_T:
            return np.array([self._free(x, y) for x, y in p.tolist()], dtype=bool)
        x, y = p[:, 0:1], p[:, 1:2]
        ok = np.ones(len(p), dtype=bool)
        if len(self.cr):
            dx = x - self.cx
            dy = y - self.cy
            ok &= ~(dx * dx + dy * dy < self.cr2).any(axis=1)
        if len(self.rects_in):
            r = self.rects_in
            ok &= ~((x > r[:, 0]) & (x < r[:, 2]) & (y > r[:, 1]) & (y < r[:, 3])).any(axis=1)
        if self.bounds is not None:
            ok &= ((p >= self.blo) & (p <= self.bhi)).all(axis=1)
        return ok

    def _free(self, x: float, y: float) -> bool:
        """``points_free`` for one point in plain floats: the same operations, element by
        element (numpy's per-call cost is most of it for a few points)."""
        if self.plain is None:
            b = self.bounds
            box = None if b is None else (b[0] - EPS_MM, b[1] - EPS_MM, b[2] + EPS_MM,
                                          b[3] + EPS_MM)  # blo, bhi
            self.plain = (list(zip(self.cx.tolist(), self.cy.tolist(), self.cr2.tolist(),
                                   strict=True)), self.rects_in.tolist(), box)
        circles, rects, box = self.plain
        for cx, cy, r2 in circles:
            dx, dy = x - cx, y - cy
            if dx * dx + dy * dy < r2:
                return False
        for x0, y0, x1, y1 in rects:
            if x > x0 and x < x1 and y > y0 and y < y1:
                return False
        if box is not None:
            return box[0] <= x <= box[2] and box[1] <= y <= box[3]
        return True

    def segments_blocked(self, ax: Array, ay: Array, bx: Array, by: Array) -> NDArray[np.bool_]:
        """(P,) segments (ax, ay) -> (bx, by) that enter an obstacle, for free end points
        only (``points_free``): then a circle blocks exactly when the foot of its centre
        falls strictly inside the segment, closer than the radius, and a rectangle when the
        segment's box overlaps it and the segment's line separates two of its corners
        (separating axes). Bounds are not tested: with both ends in the rectangular bounds
        the whole segment is in."""
        dx, dy = bx - ax, by - ay
        n = len(ax)
        k, nr = len(self.cr), len(self.rects_in)
        if not k and not nr:
            return np.zeros(n, dtype=bool)
        # one product gives, per obstacle column, d.c and d x c (c: centre) for all segments
        d2 = np.empty((n, 2))
        d2[:, 0] = dx
        d2[:, 1] = dy
        pc = d2 @ self.cmat  # (P, 2K + L)
        ddc = (dx * dx + dy * dy)[:, None]
        crs = (dx * ay - dy * ax)[:, None]
        hit = np.zeros(n, dtype=bool)
        if k:
            proj = pc[:, :k] - (dx * ax + dy * ay)[:, None]
            cr = pc[:, k:2 * k] - crs
            cr *= cr
            blk = cr < self.cr2 * ddc
            blk &= proj > 0.0
            blk &= proj < ddc
            hit = np.asarray(blk.any(axis=1))
        if nr:
            c = pc[:, 2 * k:] - crs
            adx, ady = np.abs(dx)[:, None], np.abs(dy)[:, None]
            w = adx * self.rhalf[:, 1] + ady * self.rhalf[:, 0]
            over = ((np.abs((ax + bx)[:, None] * 0.5 - self.rmid[:, 0])
                     < adx * 0.5 + self.rhalf[:, 0])
                    & (np.abs((ay + by)[:, None] * 0.5 - self.rmid[:, 1])
                       < ady * 0.5 + self.rhalf[:, 1]))
            hit |= (over & (np.abs(c) < w)).any(axis=1)
        return hit

    def blocked_from(self, u: Array, targets: Array) -> NDArray[np.bool_]:
        """``segments_blocked`` for the segments u -> targets[i] (free end points only)."""
        n = len(targets)
        return self.segments_blocked(np.full(n, u[0]), np.full(n, u[1]),
                                     targets[:, 0], targets[:, 1])


def _rect_entry(ax: float, ay: float, bx: float, by: float,
                x0: float, y0: float, x1: float, y1: float) -> float | None:
    """Liang-Barsky against the open rectangle (x0, x1) x (y0, y1): the fraction t in
    [0, 1] where segment a -> b enters it (0 when a is inside), or None if it never does."""
    lo, hi = 0.0, 1.0
    for u, d, a_lo, a_hi in ((ax, bx - ax, x0, x1), (ay, by - ay, y0, y1)):
        if d == 0.0:
            if not (a_lo < u < a_hi):
                return None
            continue
        ta, tb = (a_lo - u) / d, (a_hi - u) / d
        if ta > tb:
            ta, tb = tb, ta
        lo, hi = max(lo, ta), min(hi, tb)
    return lo if lo < hi else None


def _point(p: ArrayLike, what: str) -> Array:
    if isinstance(p, tuple) and len(p) == 2 and type(p[0]) is float and type(p[1]) is float:
        if not (math.isfinite(p[0]) and math.isfinite(p[1])):
            raise ValueError(f"{what} must be a finite point (x, y), got {p!r}")
        return np.array(p)  # the navigation's (x, y): what the conversion below gives
    a = np.asarray(p, dtype=np.float64).reshape(-1)
    if a.shape != (2,) or not np.isfinite(a).all():
        raise ValueError(f"{what} must be a finite point (x, y), got {p!r}")
    return a


class Blocking(NamedTuple):
    """The first obstacle a segment enters (see ``first_blocking``)."""

    kind: Literal["circle", "rect"]
    obstacle: int  #: its row in ``Obstacles.circles`` or ``Obstacles.rects``
    t: float  #: fraction of the segment where it enters the inflated obstacle
    point: Point  #: the entry point


def point_is_free(p: ArrayLike, obstacles: Obstacles, clearance: float, *,
                  bounds: Bounds | None = None) -> bool:
    """True when p is outside every inflated obstacle (boundary allowed) and in bounds."""
    inf = _Inflated(obstacles, clearance, bounds)
    return bool(inf.points_free(_point(p, "p")[None, :])[0])


def segment_is_free(a: ArrayLike, b: ArrayLike, obstacles: Obstacles, clearance: float) -> bool:
    """True when segment [a, b] enters no inflated obstacle (bounds are not tested); a
    segment starting or ending inside an obstacle is not free."""
    return first_blocking(a, b, obstacles, clearance) is None


def first_blocking(a: ArrayLike, b: ArrayLike, obstacles: Obstacles,
                   clearance: float) -> Blocking | None:
    """The first inflated obstacle segment [a, b] enters (at t = 0 when a is inside one),
    or None when the segment is free; ties go to circles, then to the lower index."""
    inf = _Inflated(obstacles, clearance, None)
    pa, pb = _point(a, "a"), _point(b, "b")
    best: Blocking | None = None
    if len(inf.cr):
        h = segment_hits_circles(pa, pb, inf.cxy, np.sqrt(inf.cr2))
        if bool(h.hit):
            best = Blocking("circle", int(h.first), float(h.t),
                            (float(h.point[0]), float(h.point[1])))
    for i, (x0, y0, x1, y1) in enumerate(inf.rects.tolist()):
        t = _rect_entry(float(pa[0]), float(pa[1]), float(pb[0]), float(pb[1]),
                        x0 + EPS_MM, y0 + EPS_MM, x1 - EPS_MM, y1 - EPS_MM)
        if t is not None and (best is None or t < best.t):
            q = pa + t * (pb - pa)
            best = Blocking("rect", i, t, (float(q[0]), float(q[1])))
    return best


def _exit_bound(p: Array, inf: _Inflated) -> float:
    """A lower bound on the distance from p to any free point: p has to leave every
    obstacle it is in (and get into the bounds)."""
    lb = 0.0
    if len(inf.cr):
        d = inf.cr - np.hypot(p[0] - inf.cx, p[1] - inf.cy)
        lb = max(lb, float(d.max()))
    if len(inf.rects):
        r = inf.rects
        depth = np.minimum(np.minimum(p[0] - r[:, 0], r[:, 2] - p[0]),
                           np.minimum(p[1] - r[:, 1], r[:, 3] - p[1]))
        lb = max(lb, float(depth.max()))
    b = inf.bounds
    if b is not None:
        lb = max(lb, math.hypot(max(b[0] - p[0], 0.0, p[0] - b[2]),
                                max(b[1] - p[1], 0.0, p[1] - b[3])))
    return lb


def _nearest_free(p: Array, inf: _Inflated) -> Array | None:
    """Nearest point to p outside the inflated obstacles and inside the bounds (within
    ``MOVE_PAD_MM``, more where two boundaries meet at a shallow angle).

    The nearest free point lies on the boundary of the free region: where p projects on one
    obstacle's boundary (radially on a circle, perpendicularly on a rectangle side or a bound)
    or at a corner where two boundaries cross. Candidates are taken on the boundaries grown by
    ``MOVE_PAD_MM``. The projections come first: when one of them is free and no farther
    than p's way out of the obstacles it is in, it is the answer; otherwise the crossings of
    every two boundaries are added."""
    pad = MOVE_PAD_MM
    b = inf.bounds
    rp = inf.cr + pad
    xs = np.concatenate([inf.rects[:, 0] - pad, inf.rects[:, 2] + pad,
                         [b[0], b[2]] if b is not None else []])
    ys = np.concatenate([inf.rects[:, 1] - pad, inf.rects[:, 3] + pad,
                         [b[1], b[3]] if b is not None else []])
    near: list[Array] = []
    if b is not None:
        near.append(np.array([[min(max(p[0], b[0]), b[2]), min(max(p[1], b[1]), b[3])]]))
    if len(rp):
        v = p - inf.cxy
        n = np.hypot(v[:, 0], v[:, 1])
        ok = n > 1e-9
        u = np.where(ok[:, None], v / np.where(ok, n, 1.0)[:, None], np.array([1.0, 0.0]))
        near.append(inf.cxy + rp[:, None] * u)
    if len(xs):
        near.append(np.column_stack([xs, np.full(len(xs), p[1])]))
        near.append(np.column_stack([np.full(len(ys), p[0]), ys]))

    def best_of(cands: list[Array]) -> tuple[Array | None, float]:
        allc = np.vstack(cands) if cands else np.zeros((0, 2))
        allc = allc[np.isfinite(allc).all(axis=1)]
        free = allc[inf.points_free(allc)]
        if not len(free):
            return None, math.inf
        d = np.hypot(free[:, 0] - p[0], free[:, 1] - p[1])
        i = int(np.argmin(d))
        return free[i], float(d[i])

    q, dq = best_of(near)
    if q is not None and dq <= _exit_bound(p, inf) + pad + 1e-6:
        return np.asarray(q, dtype=np.float64)
    corners: list[Array] = [] if q is None else [q[None, :]]
    # q (free, first in the list, so it wins ties) is dq from p: only boundaries that come
    # within dq of p can hold a crossing that is nearer (or as near), so the others are left
    # out (``_near_p``); the crossings kept are computed as before and keep their order
    cxy, rp, xs, ys = _near_p(p, dq, inf.cxy, rp, xs, ys)
    k = len(rp)
    if k > 1:
        i, j = _pairs(k)
        q1, q2 = circle_circle_intersection(cxy[i], rp[i], cxy[j], rp[j])
        corners += [q1, q2]
    if len(xs) and len(ys):
        gx, gy = np.meshgrid(xs, ys)
        corners.append(np.column_stack([gx.ravel(), gy.ravel()]))
    if k:  # circles against the vertical and horizontal lines
        for lines, axis in ((xs, 0), (ys, 1)):
            if len(lines):
                off = lines[None, :] - cxy[:, axis:axis + 1]  # (K, X)
                h2 = rp[:, None] ** 2 - off * off
                h = np.sqrt(np.where(h2 >= 0.0, h2, np.nan))
                along = cxy[:, 1 - axis:2 - axis]
                for sgn in (1.0, -1.0):
                    pts = np.empty((*off.shape, 2))
                    pts[..., axis] = lines[None, :]
                    pts[..., 1 - axis] = along + sgn * h
                    corners.append(pts.reshape(-1, 2))
    q, _ = best_of(corners)
    return None if q is None else np.asarray(q, dtype=np.float64)


#: slack (mm) of ``_near_p``'s test, far above the rounding of a crossing's position
NEAR_SLACK_MM = 1.0


@functools.lru_cache(maxsize=64)
def _pairs(k: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """``np.triu_indices(k, 1)``, made once per k (read-only: shared between calls)."""
    i, j = np.triu_indices(k, 1)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


def _near_p(p: Array, dist: float, cxy: Array, rp: Array, xs: Array, ys: Array,
            ) -> tuple[Array, Array, Array, Array]:
    """The circles (centres ``cxy``, radii ``rp``), vertical lines ``xs`` and horizontal
    lines ``ys`` that come within ``dist`` (+ ``NEAR_SLACK_MM``) of ``p``, in their order:
    a point on a circle is at least | |c p| - r | from p, one on a line |x - p_x| (or
    |y - p_y|). ``dist`` = inf keeps all of them."""
    lim = dist + NEAR_SLACK_MM
    if not math.isfinite(lim):
        return cxy, rp, xs, ys
    e = np.hypot(cxy[:, 0] - p[0], cxy[:, 1] - p[1])
    keep = np.abs(e - rp) <= lim
    return (cxy[keep], rp[keep], xs[np.abs(xs - p[0]) <= lim],
            ys[np.abs(ys - p[1]) <= lim])


def nearest_free_point(p: ArrayLike, obstacles: Obstacles, clearance: float, *,
                       bounds: Bounds | None = None) -> Point | None:
    """p itself when free, else the nearest point (to within about ``MOVE_PAD_MM``) outside
    every inflated obstacle and inside the bounds; None when nothing is free."""
    inf = _Inflated(obstacles, clearance, bounds)
    pp = _point(p, "p")
    q = pp if inf.points_free(pp[None, :])[0] else _nearest_free(pp, inf)
    return None if q is None else (float(q[0]), float(q[1]))


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


class _Graph(NamedTuple):
    """Candidate waypoints (free ones only) with what the tangent pruning needs."""

    xy: Array  #: (V, 2) node positions
    to_prev: Array  #: (V, 2) unit vector along the polygon edge to the previous corner
    to_next: Array  #: (V, 2) unit vector along the polygon edge to the next corner
    owner: Array  #: (V, 3) centre and squared radius of a circle holding that polygon
    always: NDArray[np.bool_]  #: (V,) never pruned (near another obstacle)

    @classmethod
    def concat(cls, parts: list[_Graph]) -> _Graph:
        return cls(*(np.concatenate([pt[i] for pt in parts]) for i in range(5)))


def _circle_nodes(inf: _Inflated, s: Array, g: Array, sel: NDArray[np.int64]) -> _Graph:
    """Around each selected inflated circle a polygon circumscribed about the circle grown
    by the pad, touching it where the tangents from start and goal touch it (on the radius
    through an end point closer than that) and with corners at most 2 pi / ``CIRCLE_SIDES``
    apart in between: every edge between neighbouring nodes lies on a tangent of that
    circle, so it stays outside, and start -> touch point is a tangent too. The free nodes,
    with the directions of the polygon's edges at each (for the tangent pruning); all edges
    of a circle that comes near another obstacle are kept."""
    n, k = CIRCLE_SIDES, len(sel)
    two_pi = 2.0 * math.pi
    cxy, cx, cy = inf.cxy[sel], inf.cx[sel], inf.cy[sel]
    rt = inf.cr[sel] + NODE_PAD_MM  # (k,) the circle the polygon touches
    v = np.stack([s, g])[:, None, :] - cxy  # (2, k, 2)
    d = np.hypot(v[..., 0], v[..., 1])
    theta = np.arctan2(v[..., 1], v[..., 0])
    half = np.arccos(np.minimum(rt / np.maximum(d, 1e-12), 1.0))  # 0 from inside rt
    a = np.sort(np.concatenate([theta - half, theta + half]).T % two_pi, axis=1)  # (k, 4)
    arc = a[:, [1, 2, 3, 0]] - a  # arc j: from touch point j to touch point j + 1
    arc[:, 3] += two_pi  # the wrap-around (2 pi when all four coincide)
    a, arc = a.ravel(), arc.ravel()
    cnt = np.where(arc > 1e-9, np.ceil(arc / (two_pi / n) - 1e-9), 0.0).astype(np.int64)
    half_step = arc / (2.0 * np.maximum(cnt, 1))
    owner = np.repeat(np.arange(k), 4)
    # corners, arc after arc: arc j's corner i at angle a_j + (2 i + 1) half_step_j, where
    # the tangents at a_j + 2 i half_step_j and a_j + (2 i + 2) half_step_j cross
    j = np.repeat(np.arange(4 * k), cnt)
    i = np.arange(len(j)) - (np.cumsum(cnt) - cnt)[j]
    hs = half_step[j]
    ang = np.concatenate([a[j] + (2 * i + 1) * hs, a])  # corners, then touch points
    hs = np.concatenate([hs, np.zeros(4 * k)])  # a touch point sits on a straight edge
    who = np.concatenate([owner[j], owner])
    rad = rt[who] / np.cos(hs)
    cs, sn = np.cos(ang), np.sin(ang)
    xy = cxy[who] + rad[:, None] * np.column_stack([cs, sn])
    # circles whose polygon may reach another obstacle or a bound: only their nodes can be
    # inside one (the others are free by construction), and theirs may sit in a notch
    # between obstacles, so their edges are never pruned
    rv = rt / math.cos(math.pi / n)  # no node is farther from its centre
    gap = np.hypot(cx[:, None] - inf.cx, cy[:, None] - inf.cy)  # (k, K)
    gap[np.arange(k), sel] = np.inf
    crowded: NDArray[np.bool_] = np.asarray((gap < rv[:, None] + inf.cr).any(axis=1))
    if len(inf.rects):
        r = inf.rects
        ox = np.maximum(np.maximum(r[:, 0] - cx[:, None], 0.0), cx[:, None] - r[:, 2])
        oy = np.maximum(np.maximum(r[:, 1] - cy[:, None], 0.0), cy[:, None] - r[:, 3])
        crowded |= (np.hypot(ox, oy) < rv[:, None]).any(axis=1)
    b = inf.bounds
    if b is not None:
        crowded |= (cx - rv < b[0]) | (cx + rv > b[2]) | (cy - rv < b[1]) | (cy + rv > b[3])
    near = crowded[who]
    keep = np.ones(len(xy), dtype=bool)
    keep[near] = inf.points_free(xy[near])
    keep[len(j):] &= arc > 1e-9  # a zero-length arc: its touch point is the next one's
    # edge directions at a node: along the tangents at ang - hs (back) and ang + hs (on)
    ch, sh = np.cos(hs), np.sin(hs)
    cc, ss, cs_, sc = cs * ch, sn * sh, cs * sh, sn * ch
    dirs = np.column_stack([sc - cs_, -(cc + ss), -(sc + cs_), cc - ss])[keep]
    own = np.column_stack([cxy, rv * rv])[who]
    return _Graph(xy[keep], dirs[:, :2], dirs[:, 2:], own[keep], near[keep])


def _rect_nodes(inf: _Inflated, sel: NDArray[np.int64]) -> _Graph:
    """The corners of each selected inflated rectangle pushed diagonally out by the pad
    (the free ones); few, so never pruned."""
    r, e = inf.rects[sel], NODE_PAD_MM
    quad = np.stack([r[:, [0, 2, 2, 0]] + np.array([-e, e, e, -e]),
                     r[:, [1, 1, 3, 3]] + np.array([-e, -e, e, e])], axis=-1).reshape(-1, 2)
    quad = quad[inf.points_free(quad)]
    z = np.zeros_like(quad)
    return _Graph(quad, z, z, np.zeros((len(quad), 3)), np.ones(len(quad), dtype=bool))


def _graph_nodes(inf: _Inflated, s: Array, g: Array, circles: NDArray[np.int64],
                 rects: NDArray[np.int64]) -> _Graph:
    """Waypoints around the given obstacles (see the module docstring), the free ones."""
    parts = []
    if len(circles):
        parts.append(_circle_nodes(inf, s, g, circles))
    if len(rects):
        parts.append(_rect_nodes(inf, rects))
    if not parts:
        z = np.zeros((0, 2))
        return _Graph(z, z, z, np.zeros((0, 3)), np.zeros(0, dtype=bool))
    return _Graph.concat(parts)


#: nodes expanded together in one vectorised step of the search
EXPAND_BATCH = 8


def _tangent_ok(ux: Array, uy: Array, vx: Array, vy: Array, graph: _Graph,
                vi: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Edges u -> v worth testing when pruning: v's polygon lies on one side of the line uv
    near v (the line touches the polygon at v, as the edges of a taut path around it do),
    or u is within the polygon's circumcircle, or v's obstacle is near another one."""
    dx, dy = vx - ux, vy - uy
    p, q = graph.to_prev[vi], graph.to_next[vi]
    s1 = dx * p[:, 1] - dy * p[:, 0]
    s2 = dx * q[:, 1] - dy * q[:, 0]
    # same side, or collinear within rounding: sin products above -1e-9
    scale = dx * dx + dy * dy
    o = graph.owner[vi]
    inside = (ux - o[:, 0]) ** 2 + (uy - o[:, 1]) ** 2 < o[:, 2]
    return np.asarray((s1 * s2 >= -1e-9 * scale) | inside | graph.always[vi])


class _OverBudget(Exception):
    """``_astar`` expanded more nodes than its budget allows."""


def _astar(inf: _Inflated, s: Array, g: Array, graph: _Graph, limit: float,
           prune: bool, budget: int | None = None) -> list[Array] | None:
    """Shortest path s -> g (excluding s) of length <= ``limit`` through the graph's nodes,
    in the lazily built visibility graph; None when there is none that short.

    Only nodes with |s v| + |v g| <= limit can be on such a path (the ellipse with foci s
    and g), so the others are dropped before anything is tested. The search is best-first on
    f = g + |v goal| (a consistent heuristic), but pops up to ``EXPAND_BATCH`` nodes at a
    time and tests all their edges in one numpy call (numpy's per-call cost dominates at
    these sizes); a node whose cost improves after its expansion is expanded again, and the
    search stops when the smallest f left is no better than the goal's cost, so the result
    is the exact shortest path in the graph. An edge is tested only when it improves its end
    node and could still lead to a path under the bound; with ``prune`` also only when it
    passes ``_tangent_ok``. With a ``budget`` it raises ``_OverBudget`` after that many
    expansions."""
    cx, cy = graph.xy[:, 0], graph.xy[:, 1]
    near = np.hypot(cx - s[0], cy - s[1]) + np.hypot(cx - g[0], cy - g[1]) <= limit
    ends = _Graph(np.vstack([s, g]), np.zeros((2, 2)), np.zeros((2, 2)),
                  np.array([[0.0, 0.0, np.inf]] * 2), np.ones(2, dtype=bool))  # never pruned
    sub = _Graph.concat([ends, _Graph(*(a[near] for a in graph))])
    x, y = sub.xy[:, 0].copy(), sub.xy[:, 1].copy()
    v = len(x)
    h = np.hypot(x - g[0], y - g[1])
    best = np.full(v, np.inf)
    best[0] = 0.0
    expanded_at = [math.inf] * v  # cost of each node when it was last expanded
    hl = h.tolist()
    parent = np.full(v, -1, dtype=np.int64)
    heap: list[tuple[float, int]] = [(float(h[0]), 0)]
    while heap:
        batch: list[int] = []
        goal_cost = float(best[1])
        while heap and len(batch) < EXPAND_BATCH:
            f, u = heapq.heappop(heap)
            if f >= goal_cost:  # nothing left can beat the path to the goal
                heap.clear()
                break
            bu = float(best[u])
            if bu < expanded_at[u] and f <= bu + hl[u]:  # else a stale entry
                batch.append(u)
                expanded_at[u] = bu
        if not batch:
            break
        if budget is not None:
            budget -= len(batch)
            if budget < 0:
                raise _OverBudget
        ub = np.asarray(batch, dtype=np.int64)
        ux, uy = x[ub][:, None], y[ub][:, None]
        new = best[ub][:, None] + np.hypot(x - ux, y - uy)  # (B, V)
        f_new = new + h
        bi, vi = np.nonzero((new < best) & (f_new < min(goal_cost, limit + 1e-9)))
        if prune and len(bi):
            ok = _tangent_ok(x[ub[bi]], y[ub[bi]], x[vi], y[vi], sub, vi)
            bi, vi = bi[ok], vi[ok]
        if not len(bi):
            continue
        ok = ~inf.segments_blocked(x[ub[bi]], y[ub[bi]], x[vi], y[vi])
        bi, vi = bi[ok], vi[ok]
        if not len(bi):
            continue
        nv = new[bi, vi]
        order = np.lexsort((nv, vi))  # per end node, its cheapest new edge first
        vs = vi[order]
        first = np.ones(len(vs), dtype=bool)
        first[1:] = vs[1:] != vs[:-1]
        sel = order[first]
        vsel, csel = vi[sel], nv[sel]
        best[vsel] = csel
        parent[vsel] = ub[bi[sel]]
        for w, fw in zip(vsel.tolist(), (csel + h[vsel]).tolist(), strict=True):
            heapq.heappush(heap, (fw, w))
    if not np.isfinite(best[1]):
        return None
    chain: list[Array] = []
    w = 1
    while w != 0:
        chain.append(sub.xy[w])
        w = int(parent[w])
    chain.reverse()
    return chain


#: corridor schedule of ``_shortest``: first extra length over the straight distance, in
#: units of the largest inflated circle's circumference, and the growth factor
CORRIDOR_FIRST = 1.0
CORRIDOR_GROWTH = 2.5
#: node expansions of the search back from the goal before the unbounded search (see
#: ``_enclosed``)
POCKET_BUDGET = 2 * EXPAND_BATCH


def _enclosed(inf: _Inflated, s: Array, g: Array, graph: _Graph) -> bool:
    """The goal sits in a small pocket the start cannot reach (e.g. a goal moved to the nearest
    free point between two robots and a defence area): the search back from the goal runs
    out of nodes within ``POCKET_BUDGET`` expansions without meeting the start. The graph's
    edges are the same both ways, so then there is no path at all, and the unbounded search
    from the start, which would visit every node on the field twice (pruned, then not), is
    not needed."""
    try:
        return _astar(inf, g, s, graph, math.inf, False, POCKET_BUDGET) is None
    except _OverBudget:
        return False


def _shortest(inf: _Inflated, s: Array, g: Array, prune: bool = True) -> list[Array] | None:
    """``_astar`` within a growing corridor: most detours are short (around one or two
    robots), and a narrow ellipse keeps the search small: only the obstacles that can have
    nodes in it get any. Each stage is exact for its bound and the last has none. With
    ``prune`` the tangent-pruned graph is searched first and the full graph only when that
    finds nothing, so a path is found whenever the full graph has one."""
    direct = float(np.hypot(g[0] - s[0], g[1] - s[1]))
    # every node of an obstacle lies within `reach` of its centre c, so it is in the
    # ellipse of a bound L only if |s c| + |c g| - 2 reach <= L
    rv = (inf.cr + NODE_PAD_MM) / math.cos(math.pi / CIRCLE_SIDES)
    mid = (inf.rects[:, :2] + inf.rects[:, 2:]) * 0.5
    half = np.hypot(inf.rects[:, 2] - inf.rects[:, 0], inf.rects[:, 3] - inf.rects[:, 1]) * 0.5
    centre = np.vstack([inf.cxy, mid])
    reach = np.concatenate([rv, half + NODE_PAD_MM * math.sqrt(2.0)])
    via = (np.hypot(centre[:, 0] - s[0], centre[:, 1] - s[1])
           + np.hypot(centre[:, 0] - g[0], centre[:, 1] - g[1]))
    lo, hi = via - 2.0 * reach, via + 2.0 * reach
    far = float(hi.max()) if len(hi) else 0.0  # past it the bound no longer prunes
    k = len(inf.cr)
    extra = CORRIDOR_FIRST * 2.0 * math.pi * max(float(rv.max()) if k else 0.0, 100.0)
    graph, used = None, None
    while True:
        limit = direct + extra if direct + extra < far else math.inf
        take = lo <= limit
        if used is None or (take != used).any():
            used = take
            graph = _graph_nodes(inf, s, g, np.nonzero(take[:k])[0], np.nonzero(take[k:])[0])
        assert graph is not None
        if math.isinf(limit) and _enclosed(inf, s, g, graph):
            return None
        chain = _astar(inf, s, g, graph, limit, prune)
        if chain is not None or math.isinf(limit):
            break
        extra *= CORRIDOR_GROWTH
    if chain is None and prune:
        chain = _astar(inf, s, g, graph, math.inf, False)
    return chain


def _free_prefix(a: Array, b: Array, obstacles: Obstacles, clearance: float) -> Array:
    """The farthest point of [a, b] reachable from a before the first obstacle, backed off
    by ``NODE_PAD_MM`` (a itself when the first obstacle is right there)."""
    hit = first_blocking(a, b, obstacles, clearance)
    if hit is None:
        return b
    length = float(np.hypot(*(b - a)))
    t = max(hit.t - NODE_PAD_MM / length, 0.0) if length > 0.0 else 0.0
    return np.asarray(a + t * (b - a), dtype=np.float64)


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


def _finish(s0: Array, pts: list[Array], max_waypoints: int, goal_moved: bool,
            start_escape: bool, blocked: bool) -> PlannedPath:
    truncated = len(pts) > max_waypoints
    pts = pts[:max_waypoints]
    return PlannedPath(tuple((float(q[0]), float(q[1])) for q in pts), goal_moved=goal_moved,
                       start_escape=start_escape, blocked=blocked,
                       length=_polyline_length(s0, pts), truncated=truncated)
