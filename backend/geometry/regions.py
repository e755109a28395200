"""Region tests: half-plane, oriented rectangle, defence areas (goal zones).

Point arguments have shape (..., 2) and broadcast; results are bool arrays of the batch
shape. Boundaries count as inside. The half-plane and rectangle tests are unit-agnostic;
the defence-area constants are the SSL rules' sizes in mm (field frame: origin at the centre
spot, x along the field towards the right-hand goal).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from domain.field import Field

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


def in_defense_area(p: ArrayLike, field: Field,
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
