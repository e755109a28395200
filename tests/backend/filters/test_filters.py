"""Filter math against known truth (fixed seeds; statistical bounds are generous)."""

from __future__ import annotations

import math
import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from backend.filters import (
    FILTER_KINDS,
    AngleFilter,
    FilterSettings,
    KalmanCV,
    KalmanParams,
    MedianFilter,
    MedianParams,
    PaperFilter,
    PaperParams,
    RawFilter,
    VelocityFit,
    make_filter,
)
from domain.angles import wrap_angle

DT = 1 / 60


@given(
    good=st.lists(st.floats(-5, 5), min_size=5, max_size=5),
    outliers=st.lists(st.floats(200, 5000) | st.floats(-5000, -200), min_size=0, max_size=2),
    where=st.permutations(range(5)),
)
def test_median_of_five_ignores_up_to_two_outliers(good: list[float], outliers: list[float],
                                                   where: list[int]) -> None:
    vals = list(good)
    for k, o in enumerate(outliers):
        vals[where[k]] = o
    kept = [v for i, v in enumerate(vals) if i not in where[:len(outliers)]]
    f = MedianFilter(MedianParams(window=5))
    out = (0.0, 0.0)
    for i, v in enumerate(vals):
        out = f.update(i * DT, v, -v)
    assert min(kept) <= out[0] <= max(kept)
    assert min(kept) <= -out[1] <= max(kept)


def _outlier_series(n: int, p: float, seed: int) -> list[float]:
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        z = rng.gauss(0.0, 2.0)
        if rng.random() < p:
            z += rng.choice((-1, 1)) * rng.uniform(300, 1000)
        out.append(z)
    return out


def test_median_removes_most_outliers_with_probability_0_2() -> None:
    zs = _outlier_series(6000, 0.2, seed=7)
    med = MedianFilter()
    paper = PaperFilter()
    bad_raw = sum(abs(z) > 20 for z in zs)
    bad_med = bad_paper = 0
    for i, z in enumerate(zs):
        bad_med += abs(med.update(i * DT, z, 0.0)[0]) > 20
        bad_paper += abs(paper.update(i * DT, z, 0.0)[0]) > 20
    assert 0.17 < bad_raw / len(zs) < 0.23
    # 3+ outliers on one side in a window of 5 are rare: the median lets through < 3 %
    assert bad_med / len(zs) < 0.03
    assert bad_paper / len(zs) < 0.03


def test_weighted_average_reduces_white_noise_variance_by_w_over_2_minus_w() -> None:
    rng = random.Random(3)
    w = 0.05
    f = PaperFilter(PaperParams(window=1, w_new=w, jump_mm=1e4))
    sigma = 10.0
    errs = []
    for i in range(40000):
        x, _ = f.update(i * DT, rng.gauss(0.0, sigma), 0.0)
        if i > 500:
            errs.append(x)
    var = sum(e * e for e in errs) / len(errs)
    expected = sigma ** 2 * w / (2 - w)
    assert 0.7 * expected < var < 1.4 * expected


@pytest.mark.parametrize(("window", "extra_samples"), [(1, 0.0), (5, 2.0)])
def test_lag_on_a_ramp_is_v_dt_w_prev_over_w_new(window: int, extra_samples: float) -> None:
    v = 500.0  # mm/s: the lag stays below the 200 mm jump threshold
    w = 0.05
    f = PaperFilter(PaperParams(window=window, w_new=w))
    x = 0.0
    for i in range(2000):
        t = i * DT
        x, _ = f.update(t, v * t, 0.0)
    lag = v * (1999 * DT) - x
    # the weighted average lags v*dt*w_prev/w_new; the median of a ramp adds (N-1)/2 samples
    predicted = v * DT * (1 - w) / w + extra_samples * v * DT
    assert lag == pytest.approx(predicted, rel=0.01)


def test_at_1_m_s_the_lag_exceeds_the_jump_threshold_and_the_filter_saws() -> None:
    # steady lag would be 317 mm at 60 Hz > 200 mm: the filter re-initialises again and again
    v = 1000.0
    f = PaperFilter()
    lags = []
    for i in range(600):
        t = i * DT
        x, _ = f.update(t, v * t, 0.0)
        if i > 100:
            lags.append(v * t - x)
    assert max(lags) <= 200.0 + 3 * v * DT
    assert min(lags) < 2 * v * DT + 1e-6  # right after a re-init: only the median's delay


def test_paper_filter_reinitialises_after_a_gap() -> None:
    f = PaperFilter()
    for i in range(50):
        f.update(i * DT, 0.0, 0.0)
    assert f.update(49 * DT + 1.5, 150.0, 40.0) == (150.0, 40.0)  # gap 1.5 s > 1 s
    g = PaperFilter()
    for i in range(50):
        g.update(i * DT, 0.0, 0.0)
    x, _ = g.update(49 * DT + 0.5, 150.0, 0.0)  # gap 0.5 s, 150 mm < jump: averaged
    assert x == pytest.approx(0.0)  # median of [0, 0, 0, 0, 150] = 0


def test_paper_filter_reinitialises_after_a_jump_once_the_median_moves() -> None:
    f = PaperFilter()
    for i in range(50):
        f.update(i * DT, 0.0, 0.0)
    t = 50 * DT
    a = f.update(t, 1000.0, 0.0)  # one new value: the median is still 0
    b = f.update(t + DT, 1000.0, 0.0)  # two: still 0
    c = f.update(t + 2 * DT, 1000.0, 0.0)  # three of five: median 1000, > 200 mm: re-init
    assert a == (0.0, 0.0) and b == (0.0, 0.0)
    assert c == (1000.0, 0.0)


def test_kalman_tracks_a_constant_velocity_target() -> None:
    rng = random.Random(5)
    f = KalmanCV(accel_noise=2000.0, meas_noise=3.0)
    vx, vy = 1500.0, -500.0
    errs = []
    for i in range(240):
        t = i * DT
        f.update(t, 100 + vx * t + rng.gauss(0, 3), -200 + vy * t + rng.gauss(0, 3))
        if i > 60:
            e = f.estimate()
            assert e is not None
            errs.append(math.hypot(e[0] - (100 + vx * t), e[1] - (-200 + vy * t)))
    assert max(errs) < 8.0
    v = f.velocity()
    assert abs(v[0] - vx) < 60 and abs(v[1] - vy) < 60
    p = f.predict(239 * DT + 0.1)
    assert p is not None and abs(p[0] - (100 + vx * (239 * DT + 0.1))) < 15


def test_kalman_gate_rejects_outliers_and_reinitialises_after_five() -> None:
    f = KalmanCV.from_params(KalmanParams(gate_mm=150.0))
    for i in range(30):
        f.update(i * DT, 0.0, 0.0)
    for k in range(4):
        x, _ = f.update((30 + k) * DT, 1000.0, 0.0)
        assert abs(x) < 1.0
    assert f.update(34 * DT, 1000.0, 0.0) == (1000.0, 0.0)
    assert f.rejected == 5


def test_velocity_of_the_median_filters_is_the_line_fit() -> None:
    for f in (RawFilter(), MedianFilter(), PaperFilter()):
        for i in range(30):
            t = i * DT
            f.update(t, 800.0 * t, -300.0 * t)
        vx, vy = f.velocity()
        assert vx == pytest.approx(800.0, rel=1e-6) and vy == pytest.approx(-300.0, rel=1e-6)


def _line_fit(pts: list[tuple[float, float, float]], window_s: float) -> tuple[float, float]:
    """VelocityFit's velocity as it was written first (the sums over the selection in order)."""
    if len(pts) < 2:
        return (0.0, 0.0)
    t_end = pts[-1][0]
    sel = [p for p in pts if t_end - p[0] <= window_s]
    if len(sel) < 2:
        sel = [pts[-2], pts[-1]]
    n = len(sel)
    tm = sum(p[0] for p in sel) / n
    xm = sum(p[1] for p in sel) / n
    ym = sum(p[2] for p in sel) / n
    stt = sum((p[0] - tm) ** 2 for p in sel)
    if stt < 1e-9:
        return (0.0, 0.0)
    return (sum((p[0] - tm) * (p[1] - xm) for p in sel) / stt,
            sum((p[0] - tm) * (p[2] - ym) for p in sel) / stt)


@settings(max_examples=200, deadline=None)
@given(
    steps=st.lists(st.tuples(st.sampled_from(["add", "add", "add", "replace", "velocity",
                                              "clear"]),
                             st.floats(0.0, 0.08) | st.floats(-0.05, 0.0) | st.just(0.0),
                             st.floats(-3000, 3000), st.floats(-3000, 3000)),
                   max_size=80),
    window_s=st.sampled_from([0.1, 0.02, 0.05]), max_points=st.sampled_from([4, 16, 48]),
    start=st.floats(0.0, 2e9),
)
def test_velocity_fit_is_bit_equal_to_the_plain_line_fit(
        steps: list[tuple[str, float, float, float]], window_s: float, max_points: int,
        start: float) -> None:
    """The window kept from one call to the next, the sums by C: the same floats to the bit
    (the times going forward, standing still and, after a negative step, back)."""
    fit = VelocityFit(window_s, max_points)
    ref: list[tuple[float, float, float]] = []
    t = start
    for op, dt, x, y in steps:
        if op == "add":
            t += dt
            fit.add(t, x, y)
            ref = [*ref, (t, x, y)][-max_points:]
        elif op == "replace":
            fit.replace_last(x, y)
            if ref:
                ref[-1] = (ref[-1][0], x, y)
        elif op == "clear":
            fit.clear()
            ref = []
        got, want = fit.velocity(), _line_fit(ref, window_s)
        assert [math.copysign(1.0, v) for v in got] == [math.copysign(1.0, v) for v in want]
        assert got == want


@settings(max_examples=60, deadline=None)
@given(
    kind=st.sampled_from(FILTER_KINDS),
    xs=st.lists(st.floats(-3000, 3000), min_size=1, max_size=12),
    first=st.floats(-3000, 3000), second=st.floats(-3000, 3000),
)
def test_revise_equals_updating_with_the_revised_value(kind: str, xs: list[float],
                                                        first: float, second: float) -> None:
    a = make_filter(kind)  # type: ignore[arg-type]
    b = make_filter(kind)  # type: ignore[arg-type]
    for i, x in enumerate(xs):
        a.update(i * DT, x, -x)
        b.update(i * DT, x, -x)
    t = len(xs) * DT
    a.update(t, first, 0.5 * first)
    ra = a.revise(second, 0.5 * second)
    rb = b.update(t, second, 0.5 * second)
    assert ra == pytest.approx(rb, abs=1e-6)
    assert a.velocity() == pytest.approx(b.velocity(), abs=1e-6)


@pytest.mark.parametrize("kind", FILTER_KINDS)
def test_angle_filter_is_continuous_through_pi(kind: str) -> None:
    f = AngleFilter(make_filter(kind, angle=True))  # type: ignore[arg-type]
    omega = 2.0  # rad/s, through +pi -> -pi
    worst = 0.0
    for i in range(120):
        t = i * DT
        truth = wrap_angle(2.5 + omega * t)
        est = f.update(t, truth)
        if i > 5 and kind in ("raw", "kalman", "adaptive"):
            worst = max(worst, abs(wrap_angle(est - truth)))
        assert -math.pi <= est < math.pi
    assert worst < 0.05
    if kind in ("kalman", "adaptive"):
        assert f.rate() == pytest.approx(omega, rel=0.02)


def test_params_reject_nan_out_of_range_and_bad_robot_keys() -> None:
    with pytest.raises(ValidationError):
        PaperParams(w_new=math.nan)
    with pytest.raises(ValidationError):
        PaperParams(window=0)
    with pytest.raises(ValidationError):
        KalmanParams(meas_noise_mm=math.inf)
    with pytest.raises(ValidationError):
        FilterSettings(robot_overrides={"green/3": "raw"})
    with pytest.raises(ValidationError):
        FilterSettings(robot_overrides={"blue/16": "raw"})
    with pytest.raises(ValidationError):
        FilterSettings(ball="magic")  # type: ignore[arg-type]
    s = FilterSettings(robot="paper", robot_overrides={"blue/3": "kalman"})
    assert s.robot_kind("blue", 3) == "kalman" and s.robot_kind("yellow", 3) == "paper"
    assert PaperParams().w_prev == pytest.approx(0.95)


def test_every_param_has_default_bounds_unit_step_description() -> None:
    for model in (PaperParams, MedianParams, KalmanParams):
        schema = model.model_json_schema()
        for name, prop in schema["properties"].items():
            assert "default" in prop, name
            assert "minimum" in prop and "maximum" in prop, name
            assert "unit" in prop and "step" in prop, name
            assert prop.get("description"), name
    FilterSettings.model_validate_json(FilterSettings().model_dump_json())


@pytest.mark.parametrize("kind", FILTER_KINDS)
def test_the_filters_have_an_estimate_exactly_while_they_have_a_time(kind: str) -> None:
    """What lets AngleFilter skip asking them whether they forgot the object."""
    for angle in (False, True):
        f = make_filter(kind, angle=angle)  # type: ignore[arg-type]
        assert f.estimate() is None and f.t_last is None
        for i, x in enumerate([0.0, 1.0, 500.0, 2.0, -3000.0, 3.0]):
            f.update(i * DT + (5.0 if i == 3 else 0.0), x, 0.0)  # a gap, jumps
            assert f.estimate() is not None and f.t_last is not None
            f.revise(x + 1.0, 0.0)
            assert f.estimate() is not None and f.t_last is not None
        f.reset()
        assert f.estimate() is None and f.t_last is None


class _Forgetful(RawFilter):
    """A filter that forgets the object while keeping its time (not one of this package's)."""

    def __init__(self) -> None:
        super().__init__()
        self.forgot = False

    def estimate(self) -> tuple[float, float] | None:
        return None if self.forgot else super().estimate()


def test_angle_filter_does_not_unwrap_against_an_object_its_filter_forgot() -> None:
    inner = _Forgetful()
    f = AngleFilter(inner)
    for i in range(3):  # turning past +pi: unwrapped beyond it
        f.update(i * DT, wrap_angle(3.0 + 0.1 * i))
    assert inner.last_median is not None and inner.last_median[0] > math.pi
    inner.forgot = True
    f.update(3 * DT, -3.0)
    assert inner.last_median[0] == pytest.approx(-3.0)  # taken as it is
    inner.forgot = False
    f.update(4 * DT, -2.9)
    assert inner.last_median[0] == pytest.approx(-2.9)  # unwrapped against -3.0


def test_angle_filter_output_stays_below_pi_where_the_modulo_rounds_up() -> None:
    # (a + pi) % 2 pi rounds up to 2 pi just below -pi: the filter's wrap, written out, keeps
    # domain.angles' guard and answers -pi, never pi
    a = math.nextafter(-math.pi, -math.inf)
    f = AngleFilter(make_filter("raw", angle=True))
    assert f.update(0.0, a) == -math.pi
    assert f.estimate() == -math.pi
    assert f.predict(DT) == -math.pi
    assert f.revise(a) == -math.pi
