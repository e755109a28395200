"""Circles: intersections with lines, segments and circles; tangents; segment vs obstacles.

A circle is a centre (shape (..., 2)) and a radius (shape (...)), broadcasting. Functions
returning two points return a pair (first, second) of arrays of shape (..., 2); coordinates
are NaN where the intersection does not exist. Touching (tangent) cases return the same point
twice. Unit-agnostic (field frame: mm).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ._types import Array, ArrayLike, BoolArray, as_points, as_scalars
from .vectors import dot, perp


def _line_circle_params(a: Array, b: Array, c: Array, r: Array) -> tuple[Array, Array, Array]:
    """Roots t0 <= t1 of |a + t (b - a) - c| = r, and the discriminant (NaN roots if < 0)."""
    d = b - a
    f = a - c
    qa = dot(d, d)
    qb = dot(f, d)  # half of the usual b
    qc = dot(f, f) - r * r
    disc = qb * qb - qa * qc
    ok = (disc >= 0.0) & (qa > 0.0)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    safe = np.where(qa > 0.0, qa, 1.0)
    t0 = np.where(ok, (-qb - sq) / safe, np.nan)
    t1 = np.where(ok, (-qb + sq) / safe, np.nan)
    return (np.asarray(t0, dtype=np.float64), np.asarray(t1, dtype=np.float64),
            np.asarray(np.where(qa > 0.0, disc, -1.0), dtype=np.float64))


def _at(a: Array, b: Array, t: Array) -> Array:
    return np.asarray(a + t[..., None] * (b - a), dtype=np.float64)


def line_circle_intersection(a: ArrayLike, b: ArrayLike, center: ArrayLike,
                             radius: ArrayLike) -> tuple[Array, Array]:
    """Where the infinite line through a, b meets the circle; ordered along a->b.

    NaN when the line misses the circle or a == b.
    """
    pa, pb, pc, r = as_points(a), as_points(b), as_points(center), as_scalars(radius)
    t0, t1, _ = _line_circle_params(pa, pb, pc, r)
    return _at(pa, pb, t0), _at(pa, pb, t1)


def segment_circle_intersection(a: ArrayLike, b: ArrayLike, center: ArrayLike,
                                radius: ArrayLike) -> tuple[Array, Array]:
    """Where segment [a, b] crosses the circle's boundary; ordered along a->b.

    Each of the two line crossings is NaN when it lies outside the segment, so a segment
    that starts inside the circle and leaves it has only its second point.
    """
    pa, pb, pc, r = as_points(a), as_points(b), as_points(center), as_scalars(radius)
    t0, t1, _ = _line_circle_params(pa, pb, pc, r)
    t0 = np.where((t0 >= 0.0) & (t0 <= 1.0), t0, np.nan)
    t1 = np.where((t1 >= 0.0) & (t1 <= 1.0), t1, np.nan)
    return _at(pa, pb, t0), _at(pa, pb, t1)


def circle_circle_intersection(c1: ArrayLike, r1: ArrayLike, c2: ArrayLike,
                               r2: ArrayLike) -> tuple[Array, Array]:
    """Where two circles' boundaries cross: first the point left of c1->c2, then the right.

    NaN when they don't meet (apart, or one inside the other) or are concentric.
    """
    p1, p2 = as_points(c1), as_points(c2)
    ra, rb = as_scalars(r1), as_scalars(r2)
    d_vec = p2 - p1
    d = np.hypot(d_vec[..., 0], d_vec[..., 1])
    ok = (d > 0.0) & (d <= ra + rb) & (d >= np.abs(ra - rb))
    safe = np.where(ok, d, 1.0)
    along = (ra * ra - rb * rb + d * d) / (2.0 * safe)
    h = np.sqrt(np.maximum(ra * ra - along * along, 0.0))
    u = d_vec / safe[..., None]
    mid = p1 + along[..., None] * u
    off = h[..., None] * perp(u)
    nan = np.where(ok, 0.0, np.nan)[..., None]
    return (np.asarray(mid + off + nan, dtype=np.float64),
            np.asarray(mid - off + nan, dtype=np.float64))


def tangent_points(p: ArrayLike, center: ArrayLike, radius: ArrayLike) -> tuple[Array, Array]:
    """Points where the tangents from p touch the circle.

    The first is counter-clockwise (about the centre) from the ray centre->p, the second
    clockwise. Both equal p when p is on the circle; NaN when p is inside it.
    """
    pp, pc, r = as_points(p), as_points(center), as_scalars(radius)
    v = pp - pc
    d = np.hypot(v[..., 0], v[..., 1])
    ok = (d >= r) & (d > 0.0)
    safe = np.where(ok, d, 1.0)
    u = v / safe[..., None]
    cos_a = np.clip(r / safe, -1.0, 1.0)
    sin_a = np.sqrt(1.0 - cos_a * cos_a)
    n = perp(u)
    base = pc + (r * cos_a)[..., None] * u
    off = (r * sin_a)[..., None] * n
    nan = np.where(ok, 0.0, np.nan)[..., None]
    return (np.asarray(base + off + nan, dtype=np.float64),
            np.asarray(base - off + nan, dtype=np.float64))


class SegmentHit(NamedTuple):
    """First circle a segment runs into (see ``segment_hits_circles``)."""

    hit: BoolArray  #: bool, batch shape: the segment passes through at least one circle
    first: NDArray[np.int64]  #: int, index of the first circle met along a->b; -1 when none
    t: Array  #: float, fraction of the segment where it enters that circle; NaN if none
    point: Array  #: float (..., 2): the entry point a + t (b - a); NaN if none


def segment_hits_circles(a: ArrayLike, b: ArrayLike, centers: ArrayLike,
                         radii: ArrayLike) -> SegmentHit:
    """Does segment [a, b] pass through any of N circular obstacles, and which first?

    ``a`` and ``b`` have shape (..., 2); ``centers`` shape (N, 2) and ``radii`` shape (N,) or a
    number, the same obstacles for every segment. A segment hits a circle when some point
    of it is strictly inside (distance to the centre < radius): grazing the boundary is not
    a hit. A segment that starts inside a circle hits it at t = 0. Ties between circles
    entered at the same t go to the lower index. Cost O(batch x N) memory and time.
    """
    pa, pb = as_points(a), as_points(b)
    pc = as_points(centers).reshape(-1, 2)
    r = np.broadcast_to(as_scalars(radii), pc.shape[:-1])
    # batch (..., 1, 2) against obstacles (N, 2)
    ea, eb = pa[..., None, :], pb[..., None, :]
    d = eb - ea
    f = ea - pc
    qa = dot(d, d)
    qb = dot(f, d)
    qc = dot(f, f) - r * r
    disc = qb * qb - qa * qc
    pos = qa > 0.0
    sq = np.sqrt(np.where(disc > 0.0, disc, 0.0))
    safe = np.where(pos, qa, 1.0)
    t0 = (-qb - sq) / safe
    t1 = (-qb + sq) / safe
    hit_moving = pos & (disc > 0.0) & (t0 < 1.0) & (t1 > 0.0)
    hit_point = ~pos & (qc < 0.0)  # degenerate segment: the point is inside
    hits = hit_moving | hit_point
    entry = np.where(hits, np.where(pos, np.maximum(t0, 0.0), 0.0), np.inf)
    n = pc.shape[0]
    if n == 0:
        batch = np.broadcast_shapes(pa.shape[:-1], pb.shape[:-1])
        none_t = np.full(batch, np.nan)
        return SegmentHit(np.zeros(batch, dtype=bool), np.full(batch, -1, dtype=np.int64),
                          none_t, np.full((*batch, 2), np.nan))
    idx = np.argmin(entry, axis=-1)
    t_first = np.take_along_axis(entry, idx[..., None], axis=-1)[..., 0]
    any_hit = np.isfinite(t_first)
    t_out = np.where(any_hit, t_first, np.nan)
    pa_b, pb_b = np.broadcast_arrays(pa, pb)
    point = pa_b + np.where(any_hit, t_first, np.nan)[..., None] * (pb_b - pa_b)
    return SegmentHit(np.asarray(any_hit), np.where(any_hit, idx, -1).astype(np.int64),
                      np.asarray(t_out, dtype=np.float64), np.asarray(point, dtype=np.float64))


def in_circle(p: ArrayLike, center: ArrayLike, radius: ArrayLike) -> BoolArray:
    """True where p is inside or on the circle."""
    v = as_points(p) - as_points(center)
    return np.asarray(dot(v, v) <= as_scalars(radius) ** 2)

