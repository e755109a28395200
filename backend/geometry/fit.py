"""Line fits to recent positions and the goalkeeper's intercept on the goal line.

Points are arrays of shape (..., N, 2) in time order (oldest first), so a batch of tracks
fits at once. Unit-agnostic (field frame: mm, s).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ._types import Array, ArrayLike, as_points, as_scalars


class Line(NamedTuple):
    """A line as a point on it and a unit direction (NaN when it cannot be determined)."""

    point: Array
    direction: Array


def fit_line_tls(points: ArrayLike) -> Line:
    """Total-least-squares line (minimises perpendicular distances) through N >= 2 points.

    ``point`` is the centroid; ``direction`` is the principal axis, oriented from the
    first point towards the last (the direction of motion of a tracked ball). NaN when all
    points coincide or fewer than 2 are given.
    """
    pts = as_points(points)
    if pts.ndim < 2 or pts.shape[-2] < 2:
        shape = (*pts.shape[:-2], 2)
        return Line(np.full(shape, np.nan), np.full(shape, np.nan))
    centroid = pts.mean(axis=-2)
    q = pts - centroid[..., None, :]
    sxx = (q[..., 0] ** 2).sum(axis=-1)
    syy = (q[..., 1] ** 2).sum(axis=-1)
    sxy = (q[..., 0] * q[..., 1]).sum(axis=-1)
    # principal axis of the 2x2 scatter matrix in closed form
    theta = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    direction = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    span = pts[..., -1, :] - pts[..., 0, :]
    flip = (direction * span).sum(axis=-1) < 0.0
    direction = np.where(flip[..., None], -direction, direction)
    degenerate = (sxx + syy) <= 0.0
    direction = np.where(degenerate[..., None], np.nan, direction)
    return Line(np.asarray(centroid, dtype=np.float64), np.asarray(direction, dtype=np.float64))


class Motion(NamedTuple):
    """Constant-velocity fit p(t) = position + velocity * (t - t_last)."""

    position: Array  #: fitted position at the last sample's time
    velocity: Array  #: units per time unit


def fit_motion_lsq(t: ArrayLike, points: ArrayLike) -> Motion:
    """Ordinary least squares of x(t) and y(t) on time: the ball's position and velocity.

    ``t`` has shape (..., N) (e.g. capture times in s), ``points`` (..., N, 2). NaN when fewer
    than 2 distinct times are given.
    """
    tt = as_scalars(t)
    pts = as_points(points)
    if pts.ndim < 2 or pts.shape[-2] < 2:
        shape = (*pts.shape[:-2], 2)
        return Motion(np.full(shape, np.nan), np.full(shape, np.nan))
    tm = tt.mean(axis=-1)
    dt = tt - tm[..., None]
    pm = pts.mean(axis=-2)
    stt = (dt * dt).sum(axis=-1)
    ok = stt > 0.0
    safe = np.where(ok, stt, 1.0)
    vel = (dt[..., None] * (pts - pm[..., None, :])).sum(axis=-2) / safe[..., None]
    vel = np.where(ok[..., None], vel, np.nan)
    pos = pm + vel * (tt[..., -1] - tm)[..., None]
    return Motion(np.asarray(pos, dtype=np.float64), np.asarray(vel, dtype=np.float64))


def intercept_x(point: ArrayLike, direction: ArrayLike, x: ArrayLike) -> Array:
    """y where the line through ``point`` along ``direction`` crosses the vertical line at x.

    NaN where the line is parallel to it (direction x == 0).
    """
    p, d = as_points(point), as_points(direction)
    xx = as_scalars(x)
    ok = d[..., 0] != 0.0
    safe = np.where(ok, d[..., 0], 1.0)
    with np.errstate(over="ignore"):  # a nearly vertical direction gives +-inf, not a warning
        y = p[..., 1] + (xx - p[..., 0]) * d[..., 1] / safe
    return np.asarray(np.where(ok, y, np.nan), dtype=np.float64)


def goalkeeper_target(ball: ArrayLike, velocity: ArrayLike, goal_x: float, goal_width: float,
                      margin: float = 0.0, min_speed: float = 100.0) -> Array:
    """Where a goalkeeper on the goal line should stand: (goal_x, y).

    If the ball moves towards the goal line faster than ``min_speed`` (units/s along x),
    y is where its straight path crosses x = goal_x; otherwise y is where the bisector of the
    angle the goal mouth (posts at (goal_x, +-goal_width / 2)) makes at the ball crosses it,
    which divides the mouth as the ball's distances to the posts (the middle of the shots the
    ball has; level with a ball out wide left the far side open). y is clamped to the goal
    mouth shrunk by ``margin`` on each side (|y| <= goal_width / 2 - margin). The same rule as
    ``engine_scripts/goalkeeper.m``.
    """
    b, v = as_points(ball), as_points(velocity)
    towards = (goal_x - b[..., 0]) * v[..., 0]
    moving = (towards > 0.0) & (np.abs(v[..., 0]) > min_speed)
    y_hit = intercept_x(b, v, goal_x)
    # (the same operations in the same order as roles.keeper_y: the same bits)
    h = goal_width / 2.0
    dx = b[..., 0] - goal_x
    d1 = np.sqrt(dx * dx + (b[..., 1] - h) * (b[..., 1] - h))
    d2 = np.sqrt(dx * dx + (b[..., 1] + h) * (b[..., 1] + h))
    s = d1 + d2
    with np.errstate(divide="ignore", invalid="ignore"):
        y_bis = np.where(s > 0.0, h * (d2 - d1) / np.where(s > 0.0, s, 1.0), b[..., 1])
    y = np.where(moving, y_hit, y_bis)
    lim = max(goal_width / 2.0 - margin, 0.0)
    y = np.clip(y, -lim, lim)
    x = np.broadcast_to(np.float64(goal_x), y.shape)
    return np.asarray(np.stack([x, y], axis=-1), dtype=np.float64)
