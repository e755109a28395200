"""The collision tests: obstacles grown by the clearance (``_Inflated``) and whether points
and segments are free of them, vectorised for the search and in plain floats for a few
points.

Tolerance: a segment is blocked by a circle when it comes closer than the inflated radius
minus ``EPS_MM`` to its centre, by a rectangle when it enters the inflated rectangle shrunk
by ``EPS_MM`` (touching a boundary is allowed; the slack absorbs rounding).
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from backend.geometry import segment_hits_circles

from .obstacles import (
    Array,
    Bounds,
    Obstacles,
    Point,
    _check_bounds,
    _check_clearance,
    _point,
)

#: a segment may come this much (mm) inside an inflated obstacle without counting as blocked
EPS_MM = 1e-7
#: ``_Inflated.points_free`` tests up to this many points in plain floats
SMALL_T = 4


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
