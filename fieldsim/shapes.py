"""Plane geometry of discs and axis-aligned rectangles (walls, goal walls) for the physics.

Pure functions in metres; swept tests so that a fast ball cannot tunnel through a thin wall.
"""

from __future__ import annotations

import math

EPS = 1e-9

# (x0, x1, y0, y1) of an axis-aligned rectangle, m
Rect = tuple[float, float, float, float]

def clamp(v: float, lo: float, hi: float) -> float:
    return lo if v < lo else hi if v > hi else v


def push_out_of_rect(
    x: float, y: float, rect: Rect, radius: float, tol: float = 0.0
) -> tuple[float, float, float, float] | None:
    """A disc at (x, y) overlapping ``rect`` by more than ``tol``: its pushed-out centre and
    the outward normal (x, y, nx, ny); None if it does not overlap."""
    x0, x1, y0, y1 = rect
    if x < x0 - radius or x > x1 + radius or y < y0 - radius or y > y1 + radius:
        return None
    cx, cy = clamp(x, x0, x1), clamp(y, y0, y1)
    dx, dy = x - cx, y - cy
    d = math.hypot(dx, dy)
    if d > EPS:
        if d >= radius - tol:
            return None
        nx, ny = dx / d, dy / d
        return cx + nx * radius, cy + ny * radius, nx, ny
    # centre inside the rectangle: out through the nearest side
    exits = (
        (x - x0, x0 - radius, y, -1.0, 0.0),
        (x1 - x, x1 + radius, y, 1.0, 0.0),
        (y - y0, x, y0 - radius, 0.0, -1.0),
        (y1 - y, x, y1 + radius, 0.0, 1.0),
    )
    _, px, py, nx, ny = min(exits)
    return px, py, nx, ny


def sweep_circle_rect(
    x0: float, y0: float, x1: float, y1: float, rect: Rect, radius: float
) -> tuple[float, float, float] | None:
    """First contact of a disc moving (x0, y0) -> (x1, y1) with ``rect`` (a rounded-rectangle
    sweep): (t in [0, 1], nx, ny) or None. The disc must start outside."""
    rx0, rx1, ry0, ry1 = rect
    dx, dy = x1 - x0, y1 - y0
    if (
        max(x0, x1) < rx0 - radius
        or min(x0, x1) > rx1 + radius
        or max(y0, y1) < ry0 - radius
        or min(y0, y1) > ry1 + radius
    ):
        return None
    best: tuple[float, float, float] | None = None
    # the rectangle grown by the radius along x, then along y (flat faces)
    for bx0, bx1, by0, by1 in (
        (rx0 - radius, rx1 + radius, ry0, ry1),
        (rx0, rx1, ry0 - radius, ry1 + radius),
    ):
        hit = sweep_point_box(x0, y0, dx, dy, bx0, bx1, by0, by1)
        if hit is not None and (best is None or hit[0] < best[0]):
            best = hit
    # the rounded corners
    a = dx * dx + dy * dy
    if a > 0.0:
        for cx, cy in ((rx0, ry0), (rx0, ry1), (rx1, ry0), (rx1, ry1)):
            fx, fy = x0 - cx, y0 - cy
            b = fx * dx + fy * dy
            c = fx * fx + fy * fy - radius * radius
            disc = b * b - a * c
            if b >= 0.0 or disc < 0.0:
                continue  # moving away from the corner or missing it
            t = (-b - math.sqrt(disc)) / a
            if 0.0 <= t <= 1.0 and (best is None or t < best[0]):
                px, py = x0 + t * dx - cx, y0 + t * dy - cy
                best = (t, px / radius, py / radius)
    return best


def sweep_point_box(
    x0: float, y0: float, dx: float, dy: float, bx0: float, bx1: float, by0: float, by1: float
) -> tuple[float, float, float] | None:
    """Slab test: first entry of the point x0 + t*dx into the box, t in [0, 1], and its face
    normal; None if it does not enter (or starts inside)."""
    t_enter, t_exit = -math.inf, math.inf
    normal = (0.0, 0.0)
    for p, d, lo, hi, axis in ((x0, dx, bx0, bx1, 0), (y0, dy, by0, by1, 1)):
        if abs(d) < 1e-15:
            if p < lo or p > hi:
                return None
            continue
        t_lo, t_hi = (lo - p) / d, (hi - p) / d
        n = -1.0 if d > 0 else 1.0
        if t_lo > t_hi:
            t_lo, t_hi = t_hi, t_lo
        if t_lo > t_enter:
            t_enter = t_lo
            normal = (n, 0.0) if axis == 0 else (0.0, n)
        t_exit = min(t_exit, t_hi)
    if t_enter > t_exit or t_enter < 0.0 or t_enter > 1.0:
        return None
    return t_enter, normal[0], normal[1]


