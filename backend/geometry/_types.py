"""Array types shared by the geometry modules."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = ["Array", "ArrayLike", "BoolArray", "as_points", "as_scalars"]


def as_points(x: ArrayLike) -> Array:
    """``x`` as float64 points of shape (..., 2); raises ValueError on another last axis."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != 2:
        raise ValueError(f"expected points of shape (..., 2), got shape {a.shape}")
    return a


def as_scalars(x: ArrayLike) -> Array:
    """``x`` as a float64 array (any shape, 0-d for a number)."""
    return np.asarray(x, dtype=np.float64)
