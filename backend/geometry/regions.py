"""Region tests: half-plane, oriented rectangle, defence areas (goal zones).

Point arguments have shape (..., 2) and broadcast; results are bool arrays of the batch
shape. Boundaries count as inside. The half-plane and rectangle tests are unit-agnostic;
the defence-area constants are the SSL rules' sizes in mm (field frame: origin at the centre
spot, x along the field towards the right-hand goal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ._types import ArrayLike, BoolArray, as_points, as_scalars
from .vectors import cross, rotate


def in_half_plane(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> BoolArray:
    """True where p is on the left of, or on, the directed line a->b."""
    pa = as_points(a)
    return np.asarray(cross(as_points(b) - pa, as_points(p) - pa) >= 0.0)


def in_rectangle(p: ArrayLike, center: ArrayLike, size: ArrayLike,
                 angle: ArrayLike = 0.0) -> BoolArray:
    """True where p is in the rectangle of ``size`` = (length, width) centred on ``center``.

    ``angle`` (rad) is the direction of the rectangle's length axis, counter-clockwise from
    the x axis; 0 gives an axis-aligned rectangle.
    """
    local = rotate(as_points(p) - as_points(center), -as_scalars(angle))
    half = as_points(size) / 2.0
    return np.asarray((np.abs(local[..., 0]) <= half[..., 0])
                      & (np.abs(local[..., 1]) <= half[..., 1]))


@dataclass(frozen=True)
class FieldGeometry:
    """The sizes the goal-zone tests need (mm), as in the SSL-Vision geometry packet."""

    field_length: float
    field_width: float
    goal_width: float
    penalty_area_depth: float
    penalty_area_width: float

    @classmethod
    def from_packet(cls, geom: dict[str, float]) -> FieldGeometry:
        """From the backend's decoded geometry dict (``backend.world.decode``)."""
        return cls(float(geom["field_length"]), float(geom["field_width"]),
                   float(geom["goal_width"]), float(geom["penalty_area_depth"]),
                   float(geom["penalty_area_width"]))


#: Division A field (SSL rules 2022+): 12 x 9 m, defence area 1.8 m deep, 3.6 m wide
DIVISION_A = FieldGeometry(12000.0, 9000.0, 1800.0, 1800.0, 3600.0)
#: Division B field (SSL rules 2022+): 9 x 6 m, defence area 1 m deep, 2 m wide
DIVISION_B = FieldGeometry(9000.0, 6000.0, 1000.0, 1000.0, 2000.0)


def in_defense_area(p: ArrayLike, field: FieldGeometry,
                    side: Literal["positive", "negative", "either"] = "either",
                    margin: float = 0.0) -> BoolArray:
    """True where p is inside a defence area (the rectangle penalty_area_depth deep and
    penalty_area_width wide on the field side of a goal line).

    ``side``: the area at the goal on +x ("positive"), on -x ("negative"), or either.
    ``margin`` (mm) grows the rectangle on every side (negative shrinks it), e.g. a robot
    radius to keep robots' bodies out.
    """
    pp = as_points(p)
    half_len = field.field_length / 2.0
    half_w = field.penalty_area_width / 2.0 + margin
    in_y = np.abs(pp[..., 1]) <= half_w
    x = pp[..., 0]
    pos = (x >= half_len - field.penalty_area_depth - margin) & (x <= half_len + margin) & in_y
    neg = (x <= -half_len + field.penalty_area_depth + margin) & (x >= -half_len - margin) & in_y
    if side == "positive":
        return np.asarray(pos)
    if side == "negative":
        return np.asarray(neg)
    return np.asarray(pos | neg)
