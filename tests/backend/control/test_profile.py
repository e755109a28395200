import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backend.control.profile import Trapezoid, trapezoid


def samples(p: Trapezoid, n: int = 2000) -> list[tuple[float, float, float]]:
    T = p.duration
    ts = [T * 1.2 * i / n for i in range(n + 1)]
    return [(t, p.sample(t).pos, p.sample(t).vel) for t in ts]


def test_long_distance_is_a_trapezoid_with_the_textbook_times() -> None:
    p = Trapezoid(3.0, 1.0, 3.0)
    assert not p.is_triangle
    assert p.t_w == pytest.approx(1 / 3)
    # 1/6 m accelerating, 1/6 m braking, 8/3 m at 1 m/s
    assert p.t_v == pytest.approx(1 / 3 + 8 / 3)
    assert p.duration == pytest.approx(3 + 1 / 3)
    assert p.sample(1.0).vel == pytest.approx(1.0)
    assert p.sample(p.duration).pos == 3.0
    assert p.sample(100.0).pos == 3.0 and p.sample(100.0).vel == 0.0


def test_short_distance_is_a_triangle_that_never_reaches_v() -> None:
    p = Trapezoid(0.1, 1.0, 3.0)
    assert p.is_triangle
    vp = math.sqrt(3.0 * 0.1)
    assert p.peak_speed == pytest.approx(vp)
    assert p.t_w == pytest.approx(p.t_v)
    assert p.duration == pytest.approx(2 * vp / 3.0)
    assert max(v for _, _, v in samples(p)) <= vp + 1e-12
    assert p.sample(p.duration).pos == pytest.approx(0.1, abs=1e-12)


def test_zero_distance_stays_put() -> None:
    p = Trapezoid(0.0, 1.0, 3.0)
    assert p.duration == 0.0
    assert p.sample(0.5).pos == 0.0 and p.sample(0.5).vel == 0.0


def test_bad_limits_are_rejected() -> None:
    with pytest.raises(ValueError):
        trapezoid(0.1, 1.0, 0.0, 3.0)


@settings(max_examples=300, deadline=None)
@given(d=st.floats(0.0, 12.0), v=st.floats(0.05, 5.0), w=st.floats(0.1, 10.0),
       v0=st.floats(0.0, 6.0))
def test_limits_hold_and_b_is_reached_exactly(d: float, v: float, w: float, v0: float) -> None:
    p = Trapezoid(d, v, w, v0)
    pts = samples(p, 600)
    eps = 1e-9 * max(1.0, d, v, w)
    prev_t, prev_x, prev_v = pts[0]
    assert prev_x == 0.0
    for t, x, vel in pts[1:]:
        assert -eps <= vel <= v + eps  # |x'| <= v
        assert x >= prev_x - eps  # never goes back
        assert x <= d + eps  # never past B
        h = t - prev_t
        if h > 0:
            assert abs(vel - prev_v) <= w * h + 1e-7 * max(1.0, w)  # |x''| <= w
            # position is the integral of the speed (trapezoid rule: exact for a linear speed,
            # off by at most w h^2 / 4 across a corner of the profile)
            assert x - prev_x == pytest.approx((vel + prev_v) / 2 * h,
                                               abs=w * h * h / 4 + 1e-7 * max(1.0, v))
        prev_t, prev_x, prev_v = t, x, vel
    end = p.sample(p.duration)
    assert end.pos == pytest.approx(d, abs=1e-12 * max(1.0, d))
    assert end.vel == pytest.approx(0.0, abs=1e-9)
    assert p.sample(p.duration + 1.0).pos == pytest.approx(d, abs=1e-12 * max(1.0, d))
