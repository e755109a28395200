"""The report's intervals on known answers and on a synthetic series."""

from __future__ import annotations

import random

import pytest

from evaluate import stats
from evaluate.series import summarise_matches, summarise_suite


def test_wilson_known_values() -> None:
    # textbook: 8 of 10 -> 0.490 to 0.943; 0 of 10 -> 0 to 0.278
    p, lo, hi = stats.wilson(8, 10)
    assert (p, round(lo, 3), round(hi, 3)) == (0.8, 0.490, 0.943)
    assert tuple(round(v, 3) for v in stats.wilson(0, 10)) == (0.0, 0.0, 0.278)
    assert stats.wilson(0, 0)[1:] == (0.0, 1.0)
    with pytest.raises(ValueError):
        stats.wilson(11, 10)


def test_newcombe_known_value() -> None:
    # Newcombe (1998), method 10: 56/70 against 48/80 -> 0.200, 95 % 0.0524 to 0.3339
    d, lo, hi = stats.newcombe(56, 70, 48, 80)
    assert (round(d, 4), round(lo, 4), round(hi, 4)) == (0.2, 0.0524, 0.3339)


def test_wilson_covers_the_true_rate_about_95_percent_of_the_time() -> None:
    rng = random.Random(28)
    for p, n in ((0.3, 40), (0.55, 40), (0.9, 20)):
        hits = 0
        trials = 3000
        for _ in range(trials):
            k = sum(rng.random() < p for _ in range(n))
            _, lo, hi = stats.wilson(k, n)
            hits += lo <= p <= hi
        assert 0.925 <= hits / trials <= 0.975, (p, n, hits / trials)


def _match(i: int, a_goals: int, b_goals: int) -> dict[str, object]:
    # A plays blue in even matches, yellow in odd ones (sides swapped half the time)
    a_blue = i % 2 == 0
    return {"kind": "match", "name": f"m{i}", "error": None,
            "blue": "A" if a_blue else "B", "yellow": "B" if a_blue else "A",
            "score": {"blue": a_goals if a_blue else b_goals,
                      "yellow": b_goals if a_blue else a_goals}}


def test_a_win_rate_of_055_over_40_matches_is_not_better() -> None:
    series = [_match(i, 1, 0) for i in range(22)] + [_match(i, 0, 1) for i in range(22, 40)]
    s = summarise_matches(series, "A", "B")
    assert (s["win"], s["loss"], s["draw"], s["played"]) == (22, 18, 0, 40)
    assert s["win_rate"]["rate"] == 0.55
    # by hand: centre (0.55 + z^2/80) / (1 + z^2/40) = 0.5456, half-width 0.1473
    assert (s["decided_share"]["low"], s["decided_share"]["high"]) == (0.3983, 0.6929)
    d = s["difference"]  # 2 p - 1 and its interval from the share's
    assert d["difference"] == pytest.approx(0.1)
    assert (d["low"], d["high"]) == (pytest.approx(-0.2034, abs=1e-4),
                                     pytest.approx(0.3859, abs=1e-4))
    assert not d["significant"] and d["verdict"].startswith("not significant")
    assert s["goal_difference"]["mean"] == pytest.approx(0.1)


def test_a_clear_win_is_significant_and_draws_are_not_decided() -> None:
    series = ([_match(i, 2, 0) for i in range(30)] + [_match(i, 0, 1) for i in range(30, 36)]
              + [_match(i, 1, 1) for i in range(36, 40)])
    s = summarise_matches(series, "A", "B")
    assert (s["win"], s["loss"], s["draw"]) == (30, 6, 4)
    assert s["decided_share"]["n"] == 36
    assert s["difference"]["significant"] and s["difference"]["low"] > 0


def test_suite_summary_and_difference() -> None:
    runs = [{"scenario": "a", "title": "A", "name": f"a#{i}", "passed": i < 7,
             "score": 1.0 if i < 7 else 0.0} for i in range(10)]
    s = summarise_suite(runs)
    sc = s["scenarios"][0]
    assert (sc["passed"], sc["runs"], sc["pass_rate"]["low"], sc["pass_rate"]["high"]) == \
        (7, 10, 0.3968, 0.8922)
    assert sc["failed_runs"] == ["a#7", "a#8", "a#9"]
    diff = stats.difference(7, 10, 3, 10)
    assert not diff["significant"]
    assert stats.difference(19, 20, 3, 20)["significant"]
