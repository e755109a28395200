"""The escape: the nearest free point to a point inside an obstacle (or out of bounds). A
start inside one escapes there first; a goal inside one is replaced by it.

The nearest free point lies on the boundary of the free region: where the point projects
on one obstacle's boundary or where two boundaries cross. The projections are tried first;
the crossings only when none of them is near enough, and then only of the boundaries that
come that near.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from backend.geometry import circle_circle_intersection

from .collision import _Inflated
from .obstacles import Array, Bounds, Obstacles, Point, _point

#: moved goals and escape points lie this far (mm) outside the inflated obstacles (small:
#: where two boundaries meet at a shallow angle, growing both moves their crossing by
#: much more than this)
MOVE_PAD_MM = 1e-4


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
