"""What the planner avoids: circles (robots, the ball) and axis-aligned rectangles (the
defence areas), optionally inside bounds the robot centre must not leave, all in mm; the
checks every input goes through (finite, radius >= 0, min <= max), and the field's areas and
bounds as such shapes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from domain.field import Field
from domain.rules import ROBOT_RADIUS_MM as ROBOT_RADIUS_MM  # SSL robots: at most 180 mm across

Array = NDArray[np.float64]
Bounds = tuple[float, float, float, float]  #: xmin, ymin, xmax, ymax (mm)
Point = tuple[float, float]


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


def _point(p: ArrayLike, what: str) -> Array:
    if isinstance(p, tuple) and len(p) == 2 and type(p[0]) is float and type(p[1]) is float:
        if not (math.isfinite(p[0]) and math.isfinite(p[1])):
            raise ValueError(f"{what} must be a finite point (x, y), got {p!r}")
        return np.array(p)  # the navigation's (x, y): what the conversion below gives
    a = np.asarray(p, dtype=np.float64).reshape(-1)
    if a.shape != (2,) or not np.isfinite(a).all():
        raise ValueError(f"{what} must be a finite point (x, y), got {p!r}")
    return a
