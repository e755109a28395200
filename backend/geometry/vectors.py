"""Vectors and angles in the plane.

Every function takes single points (shape (2,)) or arrays of points (shape (..., 2)) and
broadcasts them like numpy does; per-point results have the broadcast batch shape (0-d for
single points). Nothing here depends on units: lengths come out in the units that went in
(Touchline's field frame is mm), angles are radians, counter-clockwise positive.
"""

from __future__ import annotations

import math

import numpy as np

from ._types import Array, ArrayLike, as_points, as_scalars

TWO_PI = 2.0 * math.pi


def dot(a: ArrayLike, b: ArrayLike) -> Array:
    """Dot product a . b."""
    pa, pb = as_points(a), as_points(b)
    return np.asarray(pa[..., 0] * pb[..., 0] + pa[..., 1] * pb[..., 1], dtype=np.float64)


def cross(a: ArrayLike, b: ArrayLike) -> Array:
    """2-D cross product (the z of the 3-D one): a_x b_y - a_y b_x.

    Positive when b is counter-clockwise from a (less than half a turn).
    """
    pa, pb = as_points(a), as_points(b)
    return np.asarray(pa[..., 0] * pb[..., 1] - pa[..., 1] * pb[..., 0], dtype=np.float64)


def norm(v: ArrayLike) -> Array:
    """Length of v."""
    pv = as_points(v)
    return np.asarray(np.hypot(pv[..., 0], pv[..., 1]), dtype=np.float64)


def distance(a: ArrayLike, b: ArrayLike) -> Array:
    """Euclidean distance between points a and b."""
    pa, pb = as_points(a), as_points(b)
    return np.asarray(np.hypot(pb[..., 0] - pa[..., 0], pb[..., 1] - pa[..., 1]),
                      dtype=np.float64)


def normalise(v: ArrayLike, eps: float = 0.0) -> Array:
    """v scaled to unit length.

    Zero vectors (length <= ``eps``) come back as (0, 0), never NaN, so a caller multiplying
    by a speed gets zero motion; test ``norm(v) > eps`` first when that case matters.
    """
    pv = as_points(v)
    n = norm(pv)
    ok = n > eps
    # scale by the larger component first so subnormal vectors still come out unit length
    big = np.maximum(np.abs(pv[..., 0]), np.abs(pv[..., 1]))
    scaled = pv / np.where(ok, big, 1.0)[..., None]
    sn = norm(scaled)
    out = scaled / np.where(ok, sn, 1.0)[..., None]
    return np.asarray(np.where(ok[..., None], out, 0.0), dtype=np.float64)


def wrap_angle(theta: ArrayLike) -> Array:
    """Angle(s) wrapped to [-pi, pi) (pi becomes -pi); NaN and infinities become NaN.

    Touchline's one convention, the same numbers as the scalar ``domain.angles.wrap_angle``
    out of range (its arithmetic); angles already in range come back unchanged, bit for bit.
    """
    t = as_scalars(theta)
    r = np.mod(t + math.pi, TWO_PI) - math.pi
    # np.mod rounds up to 2 pi just below -pi, which would give pi: keep the interval open
    r = np.where(r == math.pi, -math.pi, r)
    r = np.where((t >= -math.pi) & (t < math.pi), t, r)
    return np.asarray(r, dtype=np.float64)


def angle_of(v: ArrayLike) -> Array:
    """Direction of v in [-pi, pi); 0 for a zero vector."""
    pv = as_points(v)
    return wrap_angle(np.arctan2(pv[..., 1], pv[..., 0]))


def signed_angle(a: ArrayLike, b: ArrayLike) -> Array:
    """Angle that turns direction a onto direction b, in [-pi, pi), counter-clockwise positive.

    0 when either vector is zero; -pi (never pi) for opposite vectors.
    """
    return wrap_angle(np.arctan2(cross(a, b), dot(a, b)))


def rotate(v: ArrayLike, angle: ArrayLike, about: ArrayLike | None = None) -> Array:
    """v rotated counter-clockwise by ``angle`` (rad), about the origin or the point ``about``.

    ``angle`` broadcasts against the batch shape of v.
    """
    pv = as_points(v)
    th = as_scalars(angle)
    if about is not None:
        c = as_points(about)
        pv = pv - c
    cs, sn = np.cos(th), np.sin(th)
    x = cs * pv[..., 0] - sn * pv[..., 1]
    y = sn * pv[..., 0] + cs * pv[..., 1]
    out = np.stack(np.broadcast_arrays(x, y), axis=-1)
    if about is not None:
        out = out + c
    return np.asarray(out, dtype=np.float64)


def from_polar(r: ArrayLike, theta: ArrayLike) -> Array:
    """Point(s) at distance r and direction theta from the origin."""
    rr, th = as_scalars(r), as_scalars(theta)
    x, y = np.broadcast_arrays(rr * np.cos(th), rr * np.sin(th))
    return np.asarray(np.stack([x, y], axis=-1), dtype=np.float64)


def perp(v: ArrayLike) -> Array:
    """v turned a quarter turn counter-clockwise: (-v_y, v_x)."""
    pv = as_points(v)
    return np.asarray(np.stack([-pv[..., 1], pv[..., 0]], axis=-1), dtype=np.float64)
