"""The adaptive filter: its noise estimate converges on data of known noise, and the
acceptance table of issue 13 section 3 holds on seeded synthetic data (a property of the
algorithm, not a timing)."""

from __future__ import annotations

import math
import random
import statistics

import pytest

from backend.filters import AdaptiveIMM, AdaptiveParams, AngleFilter, FilterSettings, make_filter
from backend.filters.adaptive import AdaptiveIMM1D
from experiments.filters import acceptance as acc

DT = 1 / 60


@pytest.mark.parametrize("noise", [0.5, 2.0, 5.0, 20.0, 60.0])
@pytest.mark.parametrize("speed", [0.0, 1500.0])
def test_noise_estimate_converges_on_known_noise(noise: float, speed: float) -> None:
    rng = random.Random(int(noise * 10 + speed))
    f = AdaptiveIMM()
    for i in range(600):
        t = i * DT
        f.update(t, 100.0 + speed * t + rng.gauss(0, noise), -50.0 + rng.gauss(0, noise))
    # 100-sample horizon: the estimate's relative std is about 1/sqrt(2 * 100 / 3)
    assert f.noise() == pytest.approx(noise, rel=0.25)


def test_noise_estimate_ignores_outliers_and_follows_a_change_of_noise() -> None:
    rng = random.Random(5)
    f = AdaptiveIMM()
    for i in range(1200):
        t = i * DT
        noise = 3.0 if i < 600 else 15.0
        x, y = 500.0 + rng.gauss(0, noise), 200.0 + rng.gauss(0, noise)
        if rng.random() < 0.2:
            x += rng.choice((-1, 1)) * rng.uniform(300.0, 1000.0)
        f.update(t, x, y)
        if i == 599:
            assert f.noise() == pytest.approx(3.0, rel=0.3)
    assert f.noise() == pytest.approx(15.0, rel=0.3)
    assert f.outlier_rate == pytest.approx(0.2, abs=0.1)


def test_orientation_noise_estimate_converges() -> None:
    rng = random.Random(9)
    f = AdaptiveIMM1D()
    for i in range(600):
        f.update(i * DT, 1.0 + 2.0 * i * DT + rng.gauss(0, 0.02), 0.0)
    assert f.noise() == pytest.approx(0.02, rel=0.25)
    assert f.velocity()[0] == pytest.approx(2.0, abs=0.05)


def test_acceptance_table_on_seeded_data() -> None:
    """Every cell within 1.1 x the best of raw / median / paper / tuned Kalman (round 3: no
    known misses left); the resting ball with 20 mm noise and outliers p = 0.2 at most 5 mm.
    The experiment's own data (seed 2022, 20 runs, a few seconds): on 4 runs the oracle,
    chosen on the very data it is scored on, fits the few runs' noise, and 4 cells read
    1.13-2.9 there while all are within 1.1 on 20 (docs/experiments/filters/README.md)."""
    rows = acc.table(seed=2022, runs=20)
    assert len(rows) == 28
    bad = {(r["scenario"], r["noise_mm"], r["p_out"]): round(r["ratio"], 3)
           for r in rows if r["ratio"] > acc.TOLERANCE}
    assert not bad, bad
    still = next(r for r in rows
                 if r["scenario"] == "still" and r["noise_mm"] == 20.0 and r["p_out"] == 0.2)
    assert still["rmse"]["adaptive"] <= 5.0
    assert still["rmse"]["kalman"] > 20.0  # what the issue started from


@pytest.mark.parametrize("noise", [2.0, 20.0])
def test_a_still_robot_reads_no_velocity(noise: float) -> None:
    v = acc.still_velocity(seed=3, runs=2, noise=noise)
    assert v["adaptive"]["rms"] <= 10.0 < v["kalman"]["rms"]
    assert v["adaptive"]["p95"] <= 10.0


def test_one_noise_spike_does_not_move_the_velocity() -> None:
    """A 6-sigma spike on a still object, no outliers seen before: the filter may take it
    for a kick (the position follows for a frame), but the velocity waits for the next
    measurement to confirm it, and the track comes back."""
    rng = random.Random(4)
    f = AdaptiveIMM()
    speeds = []
    for i in range(240):
        x, y = 1000.0 + rng.gauss(0, 20.0), 500.0 + rng.gauss(0, 20.0)
        if i == 150:
            x += 6 * 20.0 * math.sqrt(2.0)
        f.update(i * DT, x, y)
        if i >= 150:
            speeds.append(math.hypot(*f.velocity()))
    assert max(speeds) <= 10.0
    e = f.estimate()
    assert e is not None and math.hypot(e[0] - 1000.0, e[1] - 500.0) <= 10.0


def test_aligned_outliers_do_not_take_a_tracked_object() -> None:
    """Three false detections on one line re-acquire the track there only until the next
    true measurement: it fits the old track better, which goes on."""
    f = AdaptiveIMM()
    rng = random.Random(8)
    i = 0
    for i in range(120):  # outliers seen: the filter knows they happen
        x, y = 500.0 * i * DT + rng.gauss(0, 2.0), rng.gauss(0, 2.0)
        if i % 10 == 5:
            x += 400.0
        f.update(i * DT, x, y)
    errs = []
    for i in range(120, 180):
        x, y = 500.0 * i * DT + rng.gauss(0, 2.0), rng.gauss(0, 2.0)
        if i in (130, 131, 132):  # a line of false detections 300 mm to the side
            y += 300.0 + 20.0 * (i - 130)
        ex, ey = f.update(i * DT, x, y)
        if i >= 133:
            errs.append(math.hypot(ex - 500.0 * i * DT, ey))
    assert max(errs) <= 10.0


@pytest.mark.parametrize("noise", [2.0, 20.0])
def test_lag_at_2_m_s_is_small(noise: float) -> None:
    assert abs(acc.lag(seed=3, runs=2, noise=noise)["adaptive"]) <= 20.0


def test_kicked_ball_is_followed_within_two_frames_despite_outliers() -> None:
    rng = random.Random(11)
    run = acc.measure(acc.kicked, 2.0, 2.0, 0.2, rng)
    f = AdaptiveIMM()
    late = []
    for t, x, y, zx, zy in run:
        ex, ey = f.update(t, zx, zy)
        if t > 1.0 + 3 * DT:
            late.append(math.hypot(ex - x, ey - y))
    late.sort()
    assert late[int(0.95 * (len(late) - 1))] < 10.0


def test_is_selectable_and_builds_from_its_params() -> None:
    s = FilterSettings.model_validate({"robot": "adaptive", "ball": "adaptive"})
    assert s.robot == "adaptive" and s.ball == "adaptive"
    f = make_filter("adaptive", AdaptiveParams(init_noise_mm=50.0))
    assert isinstance(f, AdaptiveIMM) and f.noise() == pytest.approx(50.0)
    a = AngleFilter(make_filter("adaptive", angle=True))
    assert isinstance(a.inner, AdaptiveIMM1D)


def test_bad_measurements_do_not_break_it() -> None:
    f = AdaptiveIMM()
    f.update(0.0, 0.0, 0.0)
    f.update(0.0, 1e9, -1e9)  # same instant, absurd
    f.update(DT, 1.0, 1.0)
    f.update(DT / 2, 2.0, 2.0)  # older than the last one
    for i in range(2, 50):
        e = f.update(i * DT, 1.0, 1.0)
    assert all(math.isfinite(v) for v in (*e, *f.velocity()))
    assert e == pytest.approx((1.0, 1.0), abs=1.0)


def test_a_track_begun_with_too_small_a_noise_guess_learns_q_down() -> None:
    """20 mm noise, the filter's guess before any data 10 mm: the noise estimate rescales the
    models' covariances as it grows, so the start's innovations do not read as model error and
    q falls on a straight run within the first second (round 2: median 74 mm/s^2 at 1 s, the
    oracle's 10 reached only later; now about 3.5)."""
    qs = []
    for seed in range(20):
        rng = random.Random(seed)
        f = AdaptiveIMM()
        for t, _x, _y, zx, zy in acc.measure(acc.moving(2000.0), 1.0, 20.0, 0.0, rng):
            f.update(t, zx, zy)
        qs.append(math.sqrt(f.q_m))
    assert statistics.median(qs) <= 10.0


def test_constant_deceleration_does_not_restart_the_track() -> None:
    """A ball rolling out at 3 m/s, -0.4 m/s^2, 2 mm noise: when the lag passes the gate, q is
    raised and the step redone; no restart from one measurement (round 2: 7 of 20 runs
    restarted, 1-4 times each, in the first second)."""
    for seed in range(20):
        rng = random.Random(100 + seed)
        f = AdaptiveIMM()
        for t, _x, _y, zx, zy in acc.measure(acc.bounced, 0.95, 2.0, 0.0, rng):
            f.update(t, zx, zy)
        assert f.rejected == 0, seed


def test_a_far_measurement_still_restarts_the_track() -> None:
    """The q raise is for a lag a little past the gate: a kick (5 m/s from rest, 2 mm noise)
    is still a jump, taken at once without outliers about."""
    rng = random.Random(5)
    f = AdaptiveIMM()
    run = acc.measure(acc.kicked, 1.1, 2.0, 0.0, rng)
    for t, _x, _y, zx, zy in run:
        ex, ey = f.update(t, zx, zy)
    _t, x, y, _zx, _zy = run[-1]
    assert f.rejected >= 1
    assert math.hypot(ex - x, ey - y) < 10.0
    assert math.hypot(*f.velocity()) > 3000.0


def test_a_false_maneuver_costs_a_straight_run_little() -> None:
    """A straight run at 1 m/s, 20 mm noise: the moving model's q set to its bound halfway (as
    one 4-sigma measurement does) raises the error of the next 1.5 s by less than half; the
    cruise model (small fixed q) carries the estimate while q decays (before it: 1.96 x)."""
    sums = [0.0, 0.0]
    for seed in range(20):
        run = acc.measure(acc.moving(1000.0), 3.0, 20.0, 0.0, random.Random(seed))
        for poke in (0, 1):
            f = AdaptiveIMM()
            for i, (t, x, y, zx, zy) in enumerate(run):
                if poke and i == 90:
                    f.S[4] = f.q_max
                ex, ey = f.update(t, zx, zy)
                if i >= 90:
                    sums[poke] += (ex - x) ** 2 + (ey - y) ** 2
    assert math.sqrt(sums[1] / sums[0]) < 1.5


def test_the_cruise_model_gives_way_at_a_bounce() -> None:
    """The bounced ball at 2 mm noise, then 4 frames: the cruise model does not hold the
    estimate on the old line (before the bounce the deceleration has all but ruled it out;
    the bounce itself is a jump, after which both start again from the measurements): the
    estimate is on the ball and its velocity has turned."""
    for seed in range(10):
        f = AdaptiveIMM()
        run = acc.measure(acc.bounced, 1.0 + 4 * DT, 2.0, 0.0, random.Random(200 + seed))
        for t, _x, _y, zx, zy in run:
            ex, ey = f.update(t, zx, zy)
        _t, x, y, _zx, _zy = run[-1]
        assert math.hypot(ex - x, ey - y) < 10.0, seed
        assert f.velocity()[0] < 0.0, seed


def test_aligned_outliers_and_one_more_do_not_move_a_resting_ball() -> None:
    """A resting ball, 20 mm noise, false detections seen before: three false detections on
    one line (a phantom the size of a robot's speed) then one more elsewhere. The line is not
    shown until a measurement confirms it, and an outlier confirms nothing (before: the
    fourth took the phantom, 500-700 mm off for four frames; seed 3 of the acceptance table,
    still / 20 mm / p 0.2, read 2.3 x the best there)."""
    for seed in range(10):
        rng = random.Random(seed)
        f = AdaptiveIMM()
        errs = []
        for i in range(180):
            x, y = 1000.0 + rng.gauss(0, 20.0), 500.0 + rng.gauss(0, 20.0)
            if i < 120 and i % 5 == 2:
                a = rng.uniform(0.0, 2 * math.pi)
                x, y = x + 500.0 * math.cos(a), y + 500.0 * math.sin(a)
            if i in (120, 121, 122):
                x, y = 1400.0 + 1000.0 * (i - 120) * DT + rng.gauss(0, 20.0), 800.0
            if i == 123:
                x, y = 600.0, 100.0
            ex, ey = f.update(i * DT, x, y)
            if i >= 120:
                errs.append(math.hypot(ex - 1000.0, ey - 500.0))
        assert max(errs) <= 20.0, seed


def test_a_resting_object_never_reports_a_velocity_from_one_noise_sample() -> None:
    """A resting ball at 2 mm noise: about one measurement in 10^4 lies just outside the gate
    (4.5 sigma); it moved the estimate a few mm and reported 0.5-0.6 m/s for that frame, which
    the game controller reads as a ball "not steady". 60 seeded 30 s runs at 60 Hz had 8 such
    frames; none may be over 0.2 m/s (the GC's threshold), and the ball is still followed when
    it really starts to move."""
    over = 0
    for seed in range(60):
        rng = random.Random(seed)
        f = AdaptiveIMM()
        for i in range(1800):
            t = i / 60.0
            f.update(t, 1000.0 + rng.gauss(0.0, 2.0), 500.0 + rng.gauss(0.0, 2.0))
            if t > 0.5 and math.hypot(*f.velocity()) > 200.0:
                over += 1
    assert over == 0
    # then it rolls off at 1 m/s: followed within a few frames
    rng = random.Random(1)
    f = AdaptiveIMM()
    for i in range(120):
        t = i / 60.0
        x = 1000.0 + (1000.0 * (t - 1.0) if t > 1.0 else 0.0)
        f.update(t, x + rng.gauss(0.0, 2.0), 500.0 + rng.gauss(0.0, 2.0))
    assert abs(f.velocity()[0] - 1000.0) < 100.0


def test_the_orientation_filter_takes_a_sample_just_outside_its_gate_from_rest() -> None:
    """The 1-D variant shares the step: one heading 5.5 sigma off after 15 s at rest raised
    an IndexError (the held velocity read the 2-D state) and the world model lost the frame."""
    for seed in range(20):
        rng = random.Random(seed)
        f = AdaptiveIMM1D()
        for i in range(1800):
            x = 0.5 + rng.gauss(0.0, 0.01) + (0.055 if i == 900 else 0.0)
            f.update(i / 60.0, x, 0.0)
        assert abs(f.estimate_fast()[0] - 0.5) < 0.01


def test_the_orientation_filter_takes_three_aligned_far_headings() -> None:
    """Three rejected headings on one line re-acquire the track; the 1-D state has no cruise
    model, and the check whether the line starts where the object was read it (IndexError:
    the world model lost the frame)."""
    rng = random.Random(1)
    f = AdaptiveIMM1D()
    for i in range(60):
        f.update(i / 60.0, 0.5 + rng.gauss(0.0, 0.01), 0.0)
    for k in range(3):  # 1.5 rad away: farther than the top rate allows in a frame
        f.update((60 + k) / 60.0, 2.0 + 0.1 * k, 0.0)
    assert f.estimate_fast()[0] == 2.2
    f.update(63 / 60.0, 2.3, 0.0)
    assert abs(f.estimate_fast()[0] - 2.3) < 0.01
    assert abs(f.velocity()[0] - 6.0) < 0.5
