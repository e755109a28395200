"""Each shipped check on a hand-made run it must pass and one it must fail."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from evaluate import checks
from evaluate.record import Run, RunBuilder

DT = 0.02


def drive(start: tuple[float, float], end: tuple[float, float], seconds: float,
          total: float = 4.0, heading: float = 0.0,
          ball: Callable[[float], tuple[float, float, float, float]] | None = None,
          detour: float = 0.0) -> RunBuilder:
    """Our robot 0 moves in a straight line (``detour``: bulging sideways by that much) from
    ``start`` to ``end`` in ``seconds``, then stays; sampled every 20 ms for ``total`` s."""
    rb = RunBuilder()
    n = round(total / DT) + 1
    for i in range(n):
        t = i * DT
        k = min(1.0, t / seconds)
        x = start[0] + (end[0] - start[0]) * k
        y = start[1] + (end[1] - start[1]) * k + detour * math.sin(math.pi * k)
        b = ball(t) if ball is not None else (0.0, 0.0, 0.0, 0.0)
        rb.sample(t, b, {("ours", 0): (x, y, heading), ("theirs", 0): (3.0, 0.0, math.pi)})
    return rb


def run_of(rb: RunBuilder) -> Run:
    return rb.build()


def passes(fn: Callable[..., checks.Result], run: Run, **kw: object) -> checks.Result:
    res = checks.run_check(fn, run, kw)
    assert res.passed, res.detail
    assert 0.0 <= res.score <= 1.0
    return res


def fails(fn: Callable[..., checks.Result], run: Run, **kw: object) -> checks.Result:
    res = checks.run_check(fn, run, kw)
    assert not res.passed, res.detail
    assert 0.0 <= res.score < 1.0
    return res


def test_reach() -> None:
    run = run_of(drive((-2.0, 0.0), (1.0, 0.5), 2.0))
    res = passes(checks.reach, run, robot=0, target=(1.0, 0.5), tolerance_m=0.1)
    assert res.value == pytest.approx(2.0 * (1 - 0.1 / math.hypot(3.0, 0.5)), abs=0.03)
    fails(checks.reach, run, robot=0, target=(1.0, 0.5), within_s=1.0)
    fails(checks.reach, run, robot=0, target=(2.0, 0.5))
    passes(checks.reach, run, robot=0, target=(1.0, 0.5), hold_s=1.5)
    fails(checks.reach, run, robot=0, target=(1.0, 0.5), heading_deg=90.0)
    with pytest.raises(KeyError, match="no ours robot 3"):
        checks.reach(run, robot=3, target=(0.0, 0.0))
    assert not checks.run_check(checks.reach, run, {"robot": 3, "target": (0.0, 0.0)}).passed


def test_time_to_reach_scores_between_good_and_bad() -> None:
    run = run_of(drive((0.0, 0.0), (2.0, 0.0), 2.0))
    res = passes(checks.time_to_reach, run, robot=0, target=(2.0, 0.0), good_s=1.0, bad_s=3.0)
    assert 0.4 < res.score < 0.6
    fails(checks.time_to_reach, run, robot=0, target=(2.0, 0.0), good_s=0.5, bad_s=1.0)


def test_path_length() -> None:
    straight = run_of(drive((0.0, 0.0), (2.0, 0.0), 2.0))
    res = passes(checks.path_length, straight, robot=0, max_ratio=1.1)
    assert res.value == pytest.approx(2.0, abs=1e-6)
    bent = run_of(drive((0.0, 0.0), (2.0, 0.0), 2.0, detour=1.0))
    fails(checks.path_length, bent, robot=0, max_ratio=1.1)
    fails(checks.path_length, straight, robot=0, max_m=1.5)


def test_face_ball() -> None:
    facing = run_of(drive((0.0, 0.0), (0.0, 0.0), 1.0, heading=0.0,
                          ball=lambda t: (1.0, 0.0, 0.0, 0.0)))
    passes(checks.face_ball, facing, robot=0, tolerance_deg=5.0)
    away = run_of(drive((0.0, 0.0), (0.0, 0.0), 1.0, heading=math.pi / 2,
                        ball=lambda t: (1.0, 0.0, 0.0, 0.0)))
    res = fails(checks.face_ball, away, robot=0, tolerance_deg=5.0)
    assert res.value == pytest.approx(90.0)


def test_ball_placed() -> None:
    def rolling(stop: float) -> Callable[[float], tuple[float, float, float, float]]:
        # the ball rolls along x at 1 m/s and stops at x = stop
        return lambda t: (min(t, stop), 0.0, 1.0 if t < stop else 0.0, 0.0)
    rb = drive((0.0, 0.0), (0.0, 0.0), 1.0, ball=rolling(1.9))
    rb.designated = (2.0, 0.0)
    run = run_of(rb)
    res = passes(checks.ball_placed, run)
    assert res.value == pytest.approx(1.9, abs=DT)
    fails(checks.ball_placed, run, tolerance_m=0.05)
    fails(checks.ball_placed, run, before_s=1.0)
    short = drive((0.0, 0.0), (0.0, 0.0), 1.0, ball=rolling(1.0))
    short.designated = (2.0, 0.0)
    fails(checks.ball_placed, run_of(short))


def test_goals() -> None:
    rb = drive((0.0, 0.0), (0.0, 0.0), 1.0)
    rb.event(1.5, "goal", "ours", 0, "theirs")
    scored = run_of(rb)
    passes(checks.ball_in_goal, scored)
    passes(checks.ball_in_goal, scored, before_s=2.0)
    fails(checks.ball_in_goal, scored, before_s=1.0)
    fails(checks.ball_in_goal, scored, goal="ours")
    passes(checks.keeper_saved, scored)
    rb.event(2.5, "goal", "theirs", 0, "ours")
    conceded = run_of(rb)
    fails(checks.keeper_saved, conceded)
    passes(checks.keeper_saved, conceded, after_s=3.0)


def test_touches_and_passes() -> None:
    rb = drive((0.0, 0.0), (0.0, 0.0), 1.0, ball=lambda t: (min(2.0, max(0.0, t - 1.0)) * 1.0,
                                                            0.0, 0.0, 0.0))
    rb.event(1.0, "kick", "ours", 0)
    rb.event(1.0, "touch", "ours", 0)
    rb.event(3.0, "touch", "ours", 1)
    run = run_of(rb)
    passes(checks.touched_ball, run, robot=1)
    fails(checks.touched_ball, run, robot=1, before_s=2.0)
    fails(checks.touched_ball, run, team="theirs")
    res = passes(checks.pass_completed, run, passer=0, receiver=1)
    assert res.value == 1.0
    fails(checks.pass_completed, run, passer=0, receiver=1, min_distance_m=3.0)
    fails(checks.pass_completed, run, passer=1, receiver=0)
    # intercepted on the way: nobody else may touch it between kick and reception
    rb.events.insert(2, rb.events[0].__class__(2.0, "touch", "theirs", 4))
    fails(checks.pass_completed, run_of(rb), passer=0, receiver=1)


def test_no_collision_and_no_violation() -> None:
    clean = run_of(drive((0.0, 0.0), (1.0, 0.0), 1.0))
    passes(checks.no_collision, clean)
    passes(checks.no_violation, clean)
    rb = drive((0.0, 0.0), (1.0, 0.0), 1.0)
    rb.event(0.5, "collision", "ours", 0, other_team="theirs", other=2,
             relative_speed_mps=0.8)
    rb.event(0.7, "violation", "ours", 0, "stop_speed", text="stop_speed: robot at ...")
    dirty = run_of(rb)
    fails(checks.no_collision, dirty)
    passes(checks.no_collision, dirty, min_speed_mps=1.5)
    fails(checks.no_violation, dirty)
    passes(checks.no_violation, dirty, kinds=("defense_area",))
    passes(checks.no_violation, dirty, team="theirs")


def test_a_broken_check_fails_its_own_result_only() -> None:
    run = run_of(drive((0.0, 0.0), (1.0, 0.0), 1.0))

    def raises(run: Run) -> checks.Result:
        raise ZeroDivisionError("oops")

    def wrong(run: Run) -> object:
        return True

    assert "ZeroDivisionError: oops" in checks.run_check(raises, run, {}).detail
    assert "returned bool" in checks.run_check(wrong, run, {}).detail  # type: ignore[arg-type]


def test_every_builtin_check_is_tested_here() -> None:
    import inspect
    import sys
    src = inspect.getsource(sys.modules[__name__])
    untested = [n for n in checks.BUILTIN if f"checks.{n}," not in src]
    assert not untested
