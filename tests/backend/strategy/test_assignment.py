"""Target assignment: hypothesis properties against brute force over every injective
robot -> slot map, plus the hysteresis behaviour of StableAssigner."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from backend.strategy.assignment import (
    StableAssigner,
    bottleneck_assignment,
    min_cost_assignment,
)

INF = math.inf

# small integers make ties common (the tie-breaking rules get exercised), floats do not
entry = st.one_of(st.integers(0, 9).map(float), st.floats(-1e3, 1e3),
                  st.just(INF))
finite_entry = st.one_of(st.integers(0, 9).map(float), st.floats(-1e3, 1e3))


@st.composite
def matrices(draw: st.DrawFn, elements: st.SearchStrategy[float] = entry,
             max_side: int = 6) -> np.ndarray:
    n = draw(st.integers(0, max_side))
    m = draw(st.integers(0, max_side))
    rows = draw(st.lists(st.lists(elements, min_size=m, max_size=m), min_size=n, max_size=n))
    return np.array(rows, dtype=np.float64).reshape(n, m)


def all_assignments(n: int, m: int) -> list[list[int]]:
    """Every way to give min(n, m) rows distinct columns (-1: no column)."""
    out = []
    if n <= m:
        for cols in itertools.permutations(range(m), n):
            out.append(list(cols))
    else:
        for rows in itertools.permutations(range(n), m):
            a = [-1] * n
            for j, i in enumerate(rows):
                a[i] = j
            out.append(a)
    return out


def score(cost: np.ndarray, a: list[int]) -> tuple[int, float, float]:
    """(allowed pairs used, largest cost, total cost) of assignment a, forbidden pairs
    counting as unassigned."""
    used = [cost[i, j] for i, j in enumerate(a) if j >= 0 and math.isfinite(cost[i, j])]
    return len(used), max(used, default=-INF), math.fsum(used)


def check_valid(cost: np.ndarray, res: np.ndarray) -> list[int]:
    n, m = cost.shape
    assert res.shape == (n,)
    a = [int(j) for j in res]
    cols = [j for j in a if j >= 0]
    assert len(cols) == len(set(cols))
    assert all(-1 <= j < m for j in a)
    for i, j in enumerate(a):
        if j >= 0:
            assert math.isfinite(cost[i, j]), "a forbidden pair was returned"
    return a


def close(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))


@given(matrices())
@settings(max_examples=300, deadline=None)
def test_min_cost_matches_brute_force(cost: np.ndarray) -> None:
    a = check_valid(cost, min_cost_assignment(cost))
    n_used, _, total = score(cost, a)
    best_n = max(score(cost, b)[0] for b in all_assignments(*cost.shape))
    best_total = min(score(cost, b)[2] for b in all_assignments(*cost.shape)
                     if score(cost, b)[0] == best_n)
    assert n_used == best_n
    assert close(total, best_total)
    # every row that could have a column has one unless there are fewer columns
    if cost.shape[0] <= cost.shape[1] and np.isfinite(cost).all():
        assert all(j >= 0 for j in a)


@given(matrices())
@settings(max_examples=300, deadline=None)
def test_bottleneck_matches_brute_force(cost: np.ndarray) -> None:
    a = check_valid(cost, bottleneck_assignment(cost))
    n_used, worst, total = score(cost, a)
    scores = [score(cost, b) for b in all_assignments(*cost.shape)]
    best_n = max(s[0] for s in scores)
    best_worst = min(s[1] for s in scores if s[0] == best_n)
    best_total = min(s[2] for s in scores if s[0] == best_n and s[1] == best_worst)
    assert n_used == best_n
    assert worst == best_worst  # both are entries of the matrix: exact
    assert close(total, best_total)


@given(matrices(finite_entry, max_side=5), st.floats(0.0, 50.0))
@settings(max_examples=200, deadline=None)
def test_bottleneck_slack_is_min_total_within_slack(cost: np.ndarray, slack: float) -> None:
    a = check_valid(cost, bottleneck_assignment(cost, slack=slack))
    scores = [score(cost, b) for b in all_assignments(*cost.shape)]
    best_worst = min(s[1] for s in scores)
    n_used, worst, total = score(cost, a)
    assert n_used == min(cost.shape)
    assert worst <= best_worst + slack
    assert close(total, min(s[2] for s in scores if s[1] <= best_worst + slack))


def test_known_matrix() -> None:
    cost = np.array([[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]])
    assert min_cost_assignment(cost).tolist() == [1, 0, 2]  # 1 + 2 + 2 = 5
    # bottleneck: the sum-optimal assignment also has the least maximum (2)
    assert bottleneck_assignment(cost).tolist() == [1, 0, 2]
    # a case where they differ: sum prefers 0 + 10, bottleneck 6 + 6
    cost = np.array([[0.0, 6.0], [6.0, 10.0]])
    assert min_cost_assignment(cost).tolist() == [0, 1]
    assert bottleneck_assignment(cost).tolist() == [1, 0]


def test_rectangular_and_empty() -> None:
    cost = np.array([[5.0], [1.0], [3.0]])
    assert min_cost_assignment(cost).tolist() == [-1, 0, -1]
    assert min_cost_assignment(cost.T).tolist() == [1]
    assert min_cost_assignment(np.zeros((0, 3))).tolist() == []
    assert min_cost_assignment(np.zeros((3, 0))).tolist() == [-1, -1, -1]
    assert bottleneck_assignment(np.zeros((2, 0))).tolist() == [-1, -1]


def test_inf_is_forbidden() -> None:
    cost = np.array([[INF, 1.0], [INF, 2.0]])  # column 0 is forbidden for everyone
    assert min_cost_assignment(cost).tolist() == [1, -1]  # row 0 takes column 1 (cheaper)
    assert bottleneck_assignment(cost).tolist() == [1, -1]
    assert min_cost_assignment(np.full((2, 2), INF)).tolist() == [-1, -1]
    assert bottleneck_assignment(np.full((2, 2), INF)).tolist() == [-1, -1]
    # a row with only forbidden columns gets -1, the others are still optimal
    cost = np.array([[1.0, 2.0], [INF, INF], [2.0, 0.5]])
    assert min_cost_assignment(cost).tolist() == [0, -1, 1]


@pytest.mark.parametrize("bad", [math.nan, -math.inf])
def test_nan_and_minus_inf_raise(bad: float) -> None:
    cost = np.array([[1.0, bad], [0.0, 2.0]])
    with pytest.raises(ValueError, match=r"NaN|-inf"):
        min_cost_assignment(cost)
    with pytest.raises(ValueError, match=r"NaN|-inf"):
        bottleneck_assignment(cost)


def test_wrong_shape_raises() -> None:
    with pytest.raises(ValueError, match="2-D"):
        min_cost_assignment(np.zeros(3))


# -- StableAssigner ---------------------------------------------------------------------

coord = st.floats(-4000.0, 4000.0)
xy = st.tuples(coord, coord)


def names(m: int) -> list[str]:
    return [f"s{j}" for j in range(m)]


def brute_adjusted(robot_xy: np.ndarray, slot_xy: np.ndarray, prev: dict[int, int],
                   h: float) -> float:
    """Least total of distance - h per kept previous pair over every assignment of
    min(n, m) robots to the first min(n, m) slots (priority order)."""
    n, m = len(robot_xy), len(slot_xy)
    k = min(n, m)
    best = INF
    for robots in itertools.permutations(range(n), k):
        tot = 0.0
        for j, i in enumerate(robots):
            tot += math.dist(robot_xy[i], slot_xy[j]) - (h if prev.get(i) == j else 0.0)
        best = min(best, tot)
    return best


@given(st.lists(xy, min_size=0, max_size=6), st.lists(xy, min_size=0, max_size=6),
       st.lists(xy, min_size=6, max_size=6), st.floats(0.0, 1000.0))
@settings(max_examples=150, deadline=None)
def test_stable_assigner_is_optimal_with_bonus(robots: list[tuple[float, float]],
                                               slots: list[tuple[float, float]],
                                               moved: list[tuple[float, float]],
                                               h: float) -> None:
    """Second tick: the result minimises distance - h per previous pair kept, over the
    first min(N, M) slots, and fills exactly those slots."""
    n, m = len(robots), len(slots)
    ids = [10 + i for i in range(n)]
    sa = StableAssigner(hysteresis_mm=h)
    rxy = np.array(robots).reshape(n, 2)
    sxy = np.array(slots).reshape(m, 2)
    first = sa.assign(ids, rxy, names(m), sxy)
    prev = {i: int(first[rid][1:]) for i, rid in enumerate(ids) if rid in first}
    rxy2 = np.array(moved[:n]).reshape(n, 2)
    res = sa.assign(ids, rxy2, names(m), sxy)
    k = min(n, m)
    assert sorted(res.values()) == sorted(names(m)[:k])
    assert len(res) == k
    got = sum(math.dist(rxy2[i], sxy[int(res[rid][1:])])
              - (h if prev.get(i) == int(res[rid][1:]) else 0.0)
              for i, rid in enumerate(ids) if rid in res)
    assert got == pytest.approx(brute_adjusted(rxy2, sxy, prev, h), rel=1e-9, abs=1e-6)


@st.composite
def scenes(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, int]:
    n = draw(st.integers(1, 8))
    m = draw(st.integers(1, 8))
    rxy = np.array(draw(st.lists(xy, min_size=n, max_size=n)))
    sxy = np.array(draw(st.lists(xy, min_size=m, max_size=m)))
    seed = draw(st.integers(0, 2**32 - 1))
    return rxy, sxy, seed


def jitter(rng: np.random.Generator, pts: np.ndarray, r: float) -> np.ndarray:
    """Each point moved by at most r (uniform direction, uniform radius)."""
    ang = rng.uniform(0, 2 * np.pi, len(pts))
    rad = rng.uniform(0, r, len(pts))
    return pts + np.column_stack([rad * np.cos(ang), rad * np.sin(ang)])


@given(scenes())
@settings(max_examples=60, deadline=None)
def test_sum_mode_never_swaps_under_noise(scene: tuple[np.ndarray, np.ndarray, int]) -> None:
    """Robots and slots jitter by up to 50 mm around fixed places for 100 ticks: each
    distance moves by at most 100 mm < hysteresis / 2, so nothing changes."""
    rxy, sxy, seed = scene
    rng = np.random.default_rng(seed)
    ids = list(range(len(rxy)))
    sa = StableAssigner("sum", hysteresis_mm=300.0)
    first = sa.assign(ids, rxy, names(len(sxy)), sxy)
    for _ in range(100):
        res = sa.assign(ids, jitter(rng, rxy, 50.0), names(len(sxy)), jitter(rng, sxy, 50.0))
        assert res == first


@given(scenes())
@settings(max_examples=60, deadline=None)
def test_bottleneck_mode_never_swaps_under_noise(
        scene: tuple[np.ndarray, np.ndarray, int]) -> None:
    """Robot positions jitter by up to 50 mm (distances by <= 50 < hysteresis / 4)."""
    rxy, sxy, seed = scene
    rng = np.random.default_rng(seed)
    ids = list(range(len(rxy)))
    sa = StableAssigner("bottleneck", hysteresis_mm=300.0)
    first = sa.assign(ids, rxy, names(len(sxy)), sxy)
    # the first answer is the plain bottleneck assignment
    d = np.hypot(*(rxy[:, None, :] - sxy[None, :len(rxy), :]).transpose(2, 0, 1))
    cols = bottleneck_assignment(d)
    assert first == {i: f"s{j}" for i, j in enumerate(cols.tolist()) if j >= 0}
    for _ in range(100):
        assert sa.assign(ids, jitter(rng, rxy, 50.0), names(len(sxy)), sxy) == first


@given(st.floats(-2000, 3000), st.floats(-2000, 3000), st.floats(0.0, 500.0))
@settings(max_examples=200, deadline=None)
def test_swap_exactly_when_the_gain_beats_the_hysteresis(x1: float, x2: float,
                                                         h: float) -> None:
    """Two robots, two slots on a line: after the first tick the robots move; they swap
    exactly when swapping saves more than 2 h (one bonus per robot that changes)."""
    slots = np.array([[0.0, 0.0], [1000.0, 0.0]])
    sa = StableAssigner(hysteresis_mm=h)
    assert sa.assign([1, 2], slots.copy(), ["a", "b"], slots) == {1: "a", 2: "b"}
    moved = np.array([[x1, 0.0], [x2, 0.0]])
    keep = abs(x1) + abs(x2 - 1000.0)
    swap = abs(x1 - 1000.0) + abs(x2)
    assume(abs((keep - swap) - 2 * h) > 1e-6)
    res = sa.assign([1, 2], moved, ["a", "b"], slots)
    assert res == ({1: "b", 2: "a"} if keep - swap > 2 * h else {1: "a", 2: "b"})


def test_fixed_pairs_are_respected() -> None:
    slots = np.array([[-4000.0, 0.0], [0.0, 0.0], [1000.0, 0.0]])
    robots = np.array([[-3990.0, 0.0], [10.0, 0.0], [990.0, 0.0]])
    sa = StableAssigner()
    # robot 7 stands on the goalkeeper spot but robot 9 is the referee's goalkeeper
    res = sa.assign([7, 8, 9], robots, ["keeper", "mid", "fwd"], slots, fixed={9: "keeper"})
    assert res[9] == "keeper"
    assert sorted(res.values()) == ["fwd", "keeper", "mid"]
    assert res == {7: "mid", 8: "fwd", 9: "keeper"}  # least total for the other two
    # a fixed robot that is absent is ignored
    res = sa.assign([7, 8], robots[:2], ["keeper", "mid", "fwd"], slots, fixed={9: "keeper"})
    assert 9 not in res and len(res) == 2
    with pytest.raises(ValueError, match="not among"):
        sa.assign([7], robots[:1], ["keeper"], slots[:1], fixed={7: "nope"})
    with pytest.raises(ValueError, match="more than one"):
        sa.assign([7, 8], robots[:2], ["keeper", "mid"], slots[:2],
                  fixed={7: "keeper", 8: "keeper"})


@given(st.lists(xy, min_size=1, max_size=6), st.lists(xy, min_size=7, max_size=7),
       st.integers(0, 5))
@settings(max_examples=100, deadline=None)
def test_fixed_and_priority(robots: list[tuple[float, float]],
                            slots: list[tuple[float, float]], keeper: int) -> None:
    """With fewer robots than slots, the fixed robot takes its slot wherever it stands and
    the others fill exactly the next slots in priority order."""
    n = len(robots)
    ids = list(range(n))
    keeper_id = keeper % n
    res = StableAssigner().assign(ids, np.array(robots), names(7), np.array(slots),
                                  fixed={keeper_id: "s3"})
    assert res[keeper_id] == "s3"
    expected = ["s3", *[s for s in names(7) if s != "s3"][:n - 1]]
    assert sorted(res.values()) == sorted(expected)
    assert len(res) == n


def test_more_robots_than_slots() -> None:
    robots = np.array([[0.0, 0.0], [5000.0, 0.0], [100.0, 0.0], [-3000.0, 0.0]])
    slots = np.array([[50.0, 0.0], [-2900.0, 0.0]])
    res = StableAssigner().assign([1, 2, 3, 4], robots, ["a", "b"], slots)
    assert res in ({1: "a", 4: "b"}, {3: "a", 4: "b"})  # 50 mm either way to "a"
    assert list(res) == sorted(res)  # robot_ids order


def test_extra_cost_and_forbidden_pairs() -> None:
    robots = np.array([[0.0, 0.0], [1000.0, 0.0]])
    slots = np.array([[0.0, 0.0], [1000.0, 0.0]])
    extra = np.array([[5000.0, 0.0], [0.0, 0.0]])  # robot 0 should not take slot 0
    assert StableAssigner().assign([0, 1], robots, ["a", "b"], slots, extra) == {0: "b", 1: "a"}
    extra = np.array([[INF, INF], [0.0, 0.0]])  # robot 0 may take nothing
    assert StableAssigner().assign([0, 1], robots, ["a", "b"], slots, extra) == {1: "b"}
    with pytest.raises(ValueError, match="NaN"):
        StableAssigner().assign([0, 1], robots, ["a", "b"], slots, np.full((2, 2), np.nan))
    with pytest.raises(ValueError, match="extra_cost"):
        StableAssigner().assign([0, 1], robots, ["a", "b"], slots, np.zeros((2, 3)))


def test_robots_appearing_and_disappearing_move_nobody_else() -> None:
    """With a hysteresis larger than any distance, a robot leaving moves only the robot of
    the slot that falls out of the set (it takes the freed one); a robot arriving takes the
    slot that opens and nobody else moves."""
    rng = np.random.default_rng(3)
    slots = rng.uniform(-3000, 3000, (6, 2))
    robots = rng.uniform(-3000, 3000, (6, 2))
    ids = [1, 2, 3, 4, 5, 6]
    sa = StableAssigner(hysteresis_mm=1e5)
    first = sa.assign(ids, robots, names(6), slots)
    gone = next(rid for rid, s in first.items() if s == "s2")
    keep = [i for i, rid in enumerate(ids) if rid != gone]
    after = sa.assign([ids[i] for i in keep], robots[keep], names(6), slots)
    changed = {rid for rid in after if after[rid] != first[rid]}
    last = next(rid for rid, s in first.items() if s == "s5")
    assert changed == {last} and after[last] == "s2"
    back = sa.assign(ids, robots, names(6), slots)
    assert back[gone] == "s5"
    assert all(back[rid] == after[rid] for rid in after)


def test_reset_forgets_history() -> None:
    slots = np.array([[0.0, 0.0], [1000.0, 0.0]])
    sa = StableAssigner(hysteresis_mm=1e4)
    sa.assign([1, 2], slots, ["a", "b"], slots)
    swapped = slots[::-1].copy()
    assert sa.assign([1, 2], swapped, ["a", "b"], slots) == {1: "a", 2: "b"}  # sticky
    assert sa.previous == {1: "a", 2: "b"}
    sa.reset()
    assert sa.previous == {}
    assert sa.assign([1, 2], swapped, ["a", "b"], slots) == {1: "b", 2: "a"}


def test_input_checks() -> None:
    sa = StableAssigner()
    with pytest.raises(ValueError, match="distinct"):
        sa.assign([1, 1], np.zeros((2, 2)), ["a"], np.zeros((1, 2)))
    with pytest.raises(ValueError, match="distinct"):
        sa.assign([1], np.zeros((1, 2)), ["a", "a"], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="robot_xy"):
        sa.assign([1, 2], np.zeros((3, 2)), ["a"], np.zeros((1, 2)))
    with pytest.raises(ValueError, match="mode"):
        StableAssigner("fastest")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="hysteresis"):
        StableAssigner(hysteresis_mm=-1.0)
    assert sa.assign([], np.zeros((0, 2)), ["a"], np.zeros((1, 2))) == {}
    assert sa.assign([1], np.zeros((1, 2)), [], np.zeros((0, 2))) == {}
