"""The two wrap_angle functions (domain's scalar one, the geometry library's numpy one) keep
one convention: [-pi, pi), pi becomes -pi, NaN and infinities become NaN, and an angle out of
range is reduced by the same arithmetic, so both give the same number at every boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from backend import geometry as g
from domain.angles import wrap_angle

PI, TAU = math.pi, 2.0 * math.pi
BELOW_MINUS_PI = math.nextafter(-PI, -math.inf)  # (x + pi) % 2 pi rounds up to 2 pi here

BOUNDARY = [PI, -PI, 3 * PI, -3 * PI, 101 * PI, -101 * PI, TAU, -TAU, 4 * PI, -4 * PI,
            math.nextafter(PI, math.inf), BELOW_MINUS_PI, math.nextafter(-3 * PI, -math.inf),
            0.0, -0.0, 1e6, -1e6, 1e16, -1e16, 1e300, -1e300]


@pytest.mark.parametrize("a", BOUNDARY)
def test_both_wraps_give_the_same_angle_in_minus_pi_to_pi(a: float) -> None:
    s = wrap_angle(a)
    v = float(g.wrap_angle(a))
    assert s == v
    assert -PI <= s < PI
    if abs(a) < 1e6:  # beyond, adding pi alone moves a by more than the result's precision
        assert math.isclose(math.cos(s), math.cos(a), abs_tol=1e-9)
        assert math.isclose(math.sin(s), math.sin(a), abs_tol=1e-9)


def test_pi_becomes_minus_pi_in_both() -> None:
    assert wrap_angle(PI) == -PI
    assert g.wrap_angle([PI, -PI, 3 * PI]).tolist() == [-PI, -PI, -PI]


@pytest.mark.parametrize("a", [math.nan, math.inf, -math.inf])
def test_nan_and_infinities_become_nan_in_both(a: float) -> None:
    assert math.isnan(wrap_angle(a))
    with np.errstate(invalid="ignore"):
        assert math.isnan(float(g.wrap_angle(a)))


def test_an_angle_just_in_range_stays_in_range_in_both() -> None:
    # in range the numpy wrap returns the angle itself and the scalar one may round it by
    # an ulp of pi, but neither leaves [-pi, pi)
    for a in (math.nextafter(PI, 0.0), math.nextafter(-PI, 0.0), 1e-300, -1e-300):
        s, v = wrap_angle(a), float(g.wrap_angle(a))
        assert -PI <= s < PI and -PI <= v < PI
        assert abs(math.remainder(s - v, TAU)) < 1e-15
