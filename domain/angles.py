"""Angles in radians.

Touchline's one wrapping convention (this scalar ``wrap_angle`` and the geometry library's numpy
``backend.geometry.wrap_angle`` keep it alike, ``tests/domain/test_angles.py``): an angle comes
back in [-pi, pi); pi (and every odd multiple) becomes -pi; NaN and the infinities become NaN.
An angle out of range is reduced as ``(a + pi) % 2 pi - pi`` in both, so both give the same
number for it; past about 1e6 rad adding pi alone costs more than the result's precision.
No caller depends on which end is kept (heading errors, bearings, the filters' unwrapping treat
-pi and pi alike), as orientations computed with atan2 come with either.
"""

from __future__ import annotations

import math

_PI, _TAU = math.pi, 2.0 * math.pi


def wrap_angle(a: float) -> float:
    """``a`` in [-pi, pi) (pi becomes -pi; NaN stays NaN).

    In range the result may differ from ``a`` by an ulp of pi (the sum rounds); the filters
    and fieldsim have always computed it so, and their outputs stay bit for bit.
    """
    r = (a + _PI) % _TAU - _PI
    # just below -pi the modulo rounds up to 2 pi, which would give pi: keep the interval open
    return -_PI if r == _PI else r
