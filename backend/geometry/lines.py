"""Lines and segments: projection, point distance, intersection.

A line or segment is given by two points ``a`` and ``b`` (shape (..., 2) each); the infinite
line runs through both, the segment is the part between them. A degenerate line (a == b) is
treated as the single point a: projection gives a, distance is the distance to a, and an
intersection with it is NaN. Unit-agnostic (field frame: mm).

Missing intersections are NaN coordinates, never exceptions, so a batch can mix hits and
misses; ``np.isnan(p[..., 0])`` is the mask of misses.
"""

from __future__ import annotations

import numpy as np

from ._types import Array, ArrayLike, as_points
from .vectors import cross, distance, dot

#: relative tolerance below which two directions count as parallel: |cross(d1, d2)| <=
#: PARALLEL_EPS * |d1| * |d2| (sine of the angle between the lines)
PARALLEL_EPS = 1e-12


def line_param(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Parameter t of the projection of p on line a->b (a + t (b - a)); 0 for a == b."""
    pp, pa, pb = as_points(p), as_points(a), as_points(b)
    d = pb - pa
    dd = dot(d, d)
    safe = np.where(dd > 0.0, dd, 1.0)
    return np.asarray(np.where(dd > 0.0, dot(pp - pa, d) / safe, 0.0), dtype=np.float64)


def _at(a: Array, b: Array, t: Array) -> Array:
    return np.asarray(a + t[..., None] * (b - a), dtype=np.float64)


def project_on_line(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Closest point to p on the infinite line through a and b."""
    pa, pb = as_points(a), as_points(b)
    return _at(pa, pb, line_param(p, pa, pb))


def project_on_segment(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Closest point to p on segment [a, b]."""
    pa, pb = as_points(a), as_points(b)
    return _at(pa, pb, np.clip(line_param(p, pa, pb), 0.0, 1.0))


def point_line_distance(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Distance from p to the infinite line through a and b (unsigned)."""
    return distance(p, project_on_line(p, a, b))


def signed_line_distance(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Distance from p to line a->b, positive on its left; distance to a when a == b."""
    pp, pa, pb = as_points(p), as_points(a), as_points(b)
    d = pb - pa
    n = np.hypot(d[..., 0], d[..., 1])
    safe = np.where(n > 0.0, n, 1.0)
    return np.asarray(np.where(n > 0.0, cross(d, pp - pa) / safe, distance(pp, pa)),
                      dtype=np.float64)


def point_segment_distance(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Distance from p to segment [a, b]."""
    return distance(p, project_on_segment(p, a, b))


def _line_line_params(a1: Array, a2: Array, b1: Array, b2: Array) -> tuple[Array, Array, Array]:
    """Parameters (t, u) of the crossing along a1->a2 and b1->b2, and the parallel mask."""
    d1 = a2 - a1
    d2 = b2 - b1
    den = cross(d1, d2)
    scale = np.hypot(d1[..., 0], d1[..., 1]) * np.hypot(d2[..., 0], d2[..., 1])
    parallel = np.abs(den) <= PARALLEL_EPS * scale  # also true for a degenerate line
    safe = np.where(parallel, 1.0, den)
    w = b1 - a1
    t = np.where(parallel, np.nan, cross(w, d2) / safe)
    u = np.where(parallel, np.nan, cross(w, d1) / safe)
    return (np.asarray(t, dtype=np.float64), np.asarray(u, dtype=np.float64),
            np.asarray(parallel, dtype=np.float64))


def line_intersection(a1: ArrayLike, a2: ArrayLike, b1: ArrayLike, b2: ArrayLike) -> Array:
    """Crossing point of the infinite lines a1-a2 and b1-b2.

    NaN where the lines are parallel (including identical lines, see ``PARALLEL_EPS``) or
    either line is degenerate.
    """
    pa1, pa2, pb1, pb2 = (as_points(x) for x in (a1, a2, b1, b2))
    t, _, _ = _line_line_params(pa1, pa2, pb1, pb2)
    return _at(pa1, pa2, t)


def segment_intersection(a1: ArrayLike, a2: ArrayLike, b1: ArrayLike, b2: ArrayLike) -> Array:
    """Crossing point of segments [a1, a2] and [b1, b2] (end points included).

    NaN where they do not cross, and where they are parallel: overlapping collinear segments
    share many points and none is returned.
    """
    pa1, pa2, pb1, pb2 = (as_points(x) for x in (a1, a2, b1, b2))
    t, u, _ = _line_line_params(pa1, pa2, pb1, pb2)
    inside = (t >= 0.0) & (t <= 1.0) & (u >= 0.0) & (u <= 1.0)  # NaN compares False
    return _at(pa1, pa2, np.where(inside, t, np.nan))
