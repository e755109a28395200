"""Path planning: hypothesis properties checked with plain-math references written here
(point-segment distances, separating axes, a flood fill on a grid), plus hand-built cases."""

from __future__ import annotations

import itertools
import math
from unittest.mock import patch

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from backend.geometry import in_defense_area
from backend.strategy.paths import (
    MOVE_PAD_MM,
    NODE_PAD_MM,
    Obstacles,
    PlannedPath,
    collision,
    defense_area_rects,
    enclosure,
    escape,
    field_bounds,
    first_blocking,
    nearest_free_point,
    plan_path,
    point_is_free,
    recheck_path,
    search,
    segment_is_free,
    straight_clear_of_circles,
    straight_clear_of_rest,
    straight_is_clear,
)
from domain.field import DIVISION_A, DIVISION_B

TOL = 1e-6

# -- references --------------------------------------------------------------------------


def seg_point_dist(p: tuple[float, float], a: tuple[float, float],
                   b: tuple[float, float]) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2))
    return math.dist(p, (a[0] + t * dx, a[1] + t * dy))


def seg_enters_box(a: tuple[float, float], b: tuple[float, float],
                   box: tuple[float, float, float, float]) -> bool:
    """Does segment [a, b] meet the open box? Separating axes: x, y and the segment's normal,
    each overlap strict."""
    x0, y0, x1, y1 = box
    if x0 >= x1 or y0 >= y1:
        return False
    if max(a[0], b[0]) <= x0 or min(a[0], b[0]) >= x1:
        return False
    if max(a[1], b[1]) <= y0 or min(a[1], b[1]) >= y1:
        return False
    nx, ny = -(b[1] - a[1]), b[0] - a[0]
    if nx == 0 and ny == 0:
        return x0 < a[0] < x1 and y0 < a[1] < y1
    s = nx * a[0] + ny * a[1]
    proj = [nx * x + ny * y for x in (x0, x1) for y in (y0, y1)]
    return min(proj) < s < max(proj)


class Scene:
    """Inflated obstacles as plain Python numbers."""

    def __init__(self, obs: Obstacles, clearance: float) -> None:
        self.circles = [(x, y, r + clearance) for x, y, r in obs.circles.tolist()]
        self.rects = [(x0 - clearance, y0 - clearance, x1 + clearance, y1 + clearance)
                      for x0, y0, x1, y1 in obs.rects.tolist()]
        self.bounds = obs.bounds

    def segment_ok(self, a: tuple[float, float], b: tuple[float, float],
                   tol: float = TOL) -> bool:
        if any(seg_point_dist((x, y), a, b) < r - tol for x, y, r in self.circles):
            return False
        return not any(seg_enters_box(a, b, (x0 + tol, y0 + tol, x1 - tol, y1 - tol))
                       for x0, y0, x1, y1 in self.rects)

    def point_clearance(self, p: tuple[float, float]) -> float:
        """Signed distance from p to the nearest obstacle boundary or bound: negative when
        p is inside an obstacle or out of bounds."""
        d = math.inf
        for x, y, r in self.circles:
            d = min(d, math.dist(p, (x, y)) - r)
        for x0, y0, x1, y1 in self.rects:
            dx = max(x0 - p[0], 0.0, p[0] - x1)
            dy = max(y0 - p[1], 0.0, p[1] - y1)
            out = math.hypot(dx, dy)
            inside = min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1])
            d = min(d, out if out > 0 else -inside)
        if self.bounds is not None:
            x0, y0, x1, y1 = self.bounds
            d = min(d, p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1])
        return d

    def in_bounds(self, p: tuple[float, float], tol: float = TOL) -> bool:
        if self.bounds is None:
            return True
        x0, y0, x1, y1 = self.bounds
        return x0 - tol <= p[0] <= x1 + tol and y0 - tol <= p[1] <= y1 + tol


def polyline_length(start: tuple[float, float], pts: tuple[tuple[float, float], ...]) -> float:
    out, prev = 0.0, start
    for p in pts:
        out += math.dist(prev, p)
        prev = p
    return out


def check_path(res: PlannedPath, start: tuple[float, float], goal: tuple[float, float],
               sc: Scene) -> None:
    """Every property a result must have, whatever the scene."""
    assert len(res.points) >= 1
    assert all(math.isfinite(c) for p in res.points for c in p)
    assert res.length == pytest.approx(polyline_length(start, res.points), rel=1e-9, abs=1e-9)
    prev = start
    for i, p in enumerate(res.points):
        if i == 0 and res.start_escape:
            # the escape point is free (to within the test tolerance) and in bounds
            assert sc.point_clearance(p) >= -TOL
        else:
            assert sc.segment_ok(prev, p), f"segment {i} {prev} -> {p} hits an obstacle"
        assert sc.in_bounds(p)
        prev = p
    end = res.points[-1]
    if not res.blocked and not res.truncated:
        if res.goal_moved:
            assert sc.point_clearance(end) >= -TOL
        else:
            assert end == goal
        assert res.length >= math.dist(start, end) - 1e-9


# -- strategies --------------------------------------------------------------------------

coord = st.floats(-2500.0, 2500.0)
pt = st.tuples(coord, coord)
circle = st.tuples(st.floats(-2000, 2000), st.floats(-2000, 2000), st.floats(20.0, 400.0))


@st.composite
def rect(draw: st.DrawFn) -> tuple[float, float, float, float]:
    x0, y0 = draw(st.floats(-2000, 2000)), draw(st.floats(-2000, 2000))
    return x0, y0, x0 + draw(st.floats(10.0, 1500.0)), y0 + draw(st.floats(10.0, 1500.0))


@st.composite
def scenes(draw: st.DrawFn) -> tuple[Obstacles, float]:
    circles = draw(st.lists(circle, max_size=9))
    rects = draw(st.lists(rect(), max_size=3))
    bounds = draw(st.sampled_from([None, (-3000.0, -3000.0, 3000.0, 3000.0),
                                   (-2600.0, -1800.0, 2600.0, 1800.0)]))
    return Obstacles(np.array(circles).reshape(-1, 3), np.array(rects).reshape(-1, 4),
                     bounds), draw(st.floats(0.0, 150.0))


# -- properties --------------------------------------------------------------------------


@given(scenes(), st.data())
@settings(max_examples=400, deadline=None)
def test_paths_avoid_obstacles(scene: tuple[Obstacles, float], data: st.DataObject) -> None:
    obs, clearance = scene
    sc = Scene(obs, clearance)
    start = data.draw(inside_points(obs, clearance), "start")
    goal = data.draw(inside_points(obs, clearance), "goal")
    res = plan_path(start, goal, obs, clearance)
    check_path(res, start, goal, sc)
    # escape and moving happen exactly when the point is not free (away from the boundary)
    if sc.point_clearance(start) < -1e-3:
        assert res.start_escape
    if sc.point_clearance(start) > 1e-3:
        assert not res.start_escape
    if sc.point_clearance(goal) < -1e-3 and not res.blocked:
        assert res.goal_moved
    if sc.point_clearance(goal) > 1e-3:
        assert not res.goal_moved
    # the straight case returns exactly the goal
    if (sc.point_clearance(start) > 1e-3 and sc.point_clearance(goal) > 1e-3
            and sc.segment_ok(start, goal, tol=-1e-3)):
        assert res.points == (goal,)
        assert not (res.blocked or res.goal_moved or res.start_escape)


def reachable_on_grid(sc: Scene, start: tuple[float, float], goal: tuple[float, float],
                      cell: float = 50.0, margin: float = 80.0) -> bool:
    """Is there a path of grid cells whose centres all keep ``margin`` from every obstacle
    and bound? Each step between 8-neighbours then keeps margin - cell / sqrt(2) > 0, so
    such a path is collision free."""
    lo, hi = -3200.0, 3200.0
    xs = np.arange(lo, hi + cell / 2, cell)
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    clear = np.full(gx.shape, np.inf)
    for x, y, r in sc.circles:
        clear = np.minimum(clear, np.hypot(gx - x, gy - y) - r)
    for x0, y0, x1, y1 in sc.rects:
        dx = np.maximum(np.maximum(x0 - gx, 0.0), gx - x1)
        dy = np.maximum(np.maximum(y0 - gy, 0.0), gy - y1)
        inside = (gx > x0) & (gx < x1) & (gy > y0) & (gy < y1)
        clear = np.minimum(clear, np.where(inside, -1.0, np.hypot(dx, dy)))
    if sc.bounds is not None:
        x0, y0, x1, y1 = sc.bounds
        clear = np.minimum(clear, np.minimum(np.minimum(gx - x0, x1 - gx),
                                             np.minimum(gy - y0, y1 - gy)))
    ok = clear >= margin

    def cell_of(p: tuple[float, float]) -> tuple[int, int]:
        return round((p[0] - lo) / cell), round((p[1] - lo) / cell)

    si, gi = cell_of(start), cell_of(goal)
    if not (ok[si] and ok[gi]):
        return False
    reach = np.zeros_like(ok)
    reach[si] = True
    while True:
        grown = reach.copy()
        for ax in (0, 1):
            for sh in (1, -1):
                grown |= np.roll(reach, sh, axis=ax)
        for sx in (1, -1):
            for sy in (1, -1):
                grown |= np.roll(np.roll(reach, sx, axis=0), sy, axis=1)
        grown &= ok
        if grown[gi]:
            return True
        if (grown == reach).all():
            return False
        reach = grown


@given(scenes(), pt, pt)
@settings(max_examples=150, deadline=None)
def test_a_path_is_found_when_one_exists(scene: tuple[Obstacles, float],
                                         start: tuple[float, float],
                                         goal: tuple[float, float]) -> None:
    """Brute force: when a flood fill on a 50 mm grid finds a way with 80 mm to spare, the
    planner must not report blocked (it may only miss gaps narrower than its padding)."""
    obs, clearance = scene
    sc = Scene(obs, clearance)
    assume(sc.point_clearance(start) > 100.0 and sc.point_clearance(goal) > 100.0)
    res = plan_path(start, goal, obs, clearance, max_waypoints=64)
    if reachable_on_grid(sc, start, goal):
        assert not res.blocked
        assert res.points[-1] == goal


@given(st.floats(80.0, 800.0), st.floats(0.0, 150.0), st.floats(0, 2 * math.pi),
       st.floats(0, 2 * math.pi), st.floats(1.001, 6.0), st.floats(1.001, 6.0))
@settings(max_examples=300, deadline=None)
def test_single_circle_near_shortest(r: float, clearance: float, a1: float, a2: float,
                                     k1: float, k2: float) -> None:
    """Around one circle the path is within a few % of the exact shortest path (straight
    line, or tangent + arc + tangent) and never shorter than it. The bound: the polygon
    around a circle grown by the pad has corners at most 30 degrees apart, which makes its
    perimeter tan(15 deg) / (pi / 12) = 1.0236 times the arc's."""
    big = r + clearance
    s = (k1 * big * math.cos(a1), k1 * big * math.sin(a1))
    g = (k2 * big * math.cos(a2), k2 * big * math.sin(a2))
    res = plan_path(s, g, Obstacles(circles=[[0.0, 0.0, r]]), clearance)
    assert not (res.blocked or res.start_escape or res.goal_moved)
    if seg_point_dist((0.0, 0.0), s, g) >= big:
        true = math.dist(s, g)
    else:
        ds, dg = math.dist(s, (0, 0)), math.dist(g, (0, 0))
        between = math.acos(max(-1.0, min(1.0, (s[0] * g[0] + s[1] * g[1]) / (ds * dg))))
        arc = between - math.acos(big / ds) - math.acos(big / dg)
        true = math.sqrt(ds * ds - big * big) + math.sqrt(dg * dg - big * big) + big * arc
    assert res.length >= true - 1e-6
    assert res.length <= 1.025 * (1.0 + NODE_PAD_MM / big) * true + 2.0 * NODE_PAD_MM


@st.composite
def inside_points(draw: st.DrawFn, obs: Obstacles, clearance: float) -> tuple[float, float]:
    """A point anywhere, or inside one of the (inflated) obstacles."""
    sc = Scene(obs, clearance)
    kinds = ["any"] + ["circle"] * bool(sc.circles) + ["rect"] * bool(sc.rects)
    kind = draw(st.sampled_from(kinds))
    if kind == "circle":
        x, y, r = draw(st.sampled_from(sc.circles))
        a, f = draw(st.floats(0, 2 * math.pi)), draw(st.floats(0.0, 1.0))
        return x + f * r * math.cos(a), y + f * r * math.sin(a)
    if kind == "rect":
        x0, y0, x1, y1 = draw(st.sampled_from(sc.rects))
        fx, fy = draw(st.floats(0.0, 1.0)), draw(st.floats(0.0, 1.0))
        return x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)
    return draw(pt)


@given(scenes(), st.data())
@settings(max_examples=300, deadline=None)
def test_nearest_free_point(scene: tuple[Obstacles, float], data: st.DataObject) -> None:
    """The point is free, and no point 1 um clear of everything is closer by more than the
    padding: a dense ring of samples just inside that distance is all blocked."""
    obs, clearance = scene
    sc = Scene(obs, clearance)
    p = data.draw(inside_points(obs, clearance))
    q = nearest_free_point(p, obs, clearance)
    if q is None:
        return
    assert sc.point_clearance(q) >= -TOL
    d = math.dist(p, q)
    if sc.point_clearance(p) >= 0.0:
        assert q == p
        return
    inner = d - 2.0 * MOVE_PAD_MM - 1e-3
    if inner > 0.0:
        ang = np.linspace(0.0, 2 * np.pi, 2000, endpoint=False)
        for a in ang:
            x = (p[0] + inner * math.cos(a), p[1] + inner * math.sin(a))
            assert sc.point_clearance(x) < 1e-3, f"{x} is free and closer than {q}"


@given(scenes(), pt, pt)
@settings(max_examples=300, deadline=None)
def test_first_blocking_and_segment_is_free(scene: tuple[Obstacles, float],
                                            a: tuple[float, float],
                                            b: tuple[float, float]) -> None:
    obs, clearance = scene
    sc = Scene(obs, clearance)
    hit = first_blocking(a, b, obs, clearance)
    assert (hit is None) == segment_is_free(a, b, obs, clearance)
    if sc.segment_ok(a, b, tol=-1e-3):  # free with a margin
        assert hit is None
    if not sc.segment_ok(a, b, tol=1e-3):  # blocked with a margin
        assert hit is not None
    if hit is None:
        return
    # the part before the entry is free, and the entry point is on the obstacle's boundary
    # (or at a, inside it)
    entry = hit.point
    assert 0.0 <= hit.t <= 1.0
    if hit.t > 0.0:
        assert sc.segment_ok(a, entry, tol=1e-6)
    if hit.kind == "circle":
        x, y, r = sc.circles[hit.obstacle]
        dist = math.dist(entry, (x, y))
        assert dist <= r + 1e-6
        assert hit.t == 0.0 or dist == pytest.approx(r, abs=1e-6)
    else:
        x0, y0, x1, y1 = sc.rects[hit.obstacle]
        assert x0 - 1e-6 <= entry[0] <= x1 + 1e-6 and y0 - 1e-6 <= entry[1] <= y1 + 1e-6


# -- hand-built cases --------------------------------------------------------------------


def test_straight_when_free() -> None:
    obs = Obstacles(circles=[[0.0, 1000.0, 90.0]], rects=[[2000, -500, 2500, 500]])
    res = plan_path((0.0, 0.0), (1500.0, 0.0), obs, 100.0)
    assert res.points == ((1500.0, 0.0),)
    assert res.length == 1500.0
    assert not (res.blocked or res.goal_moved or res.start_escape or res.truncated)
    same = plan_path((10.0, 20.0), (10.0, 20.0), obs, 100.0)
    assert same.points == ((10.0, 20.0),) and same.length == 0.0


def test_robot_wall_is_passed_around() -> None:
    wall = [(0.0, -1000.0 + 150.0 * i) for i in range(14)]  # y from -1000 to 950
    obs = Obstacles.build(robots=wall, robot_radius=90.0)
    res = plan_path((-1500.0, 0.0), (1500.0, 0.0), obs, 100.0)
    check_path(res, (-1500.0, 0.0), (1500.0, 0.0), Scene(obs, 100.0))
    assert not res.blocked and len(res.points) >= 2
    assert res.points[-1] == (1500.0, 0.0)
    # it goes around an end of the wall: it crosses x = 0 beyond the last robot
    pts = [(-1500.0, 0.0), *res.points]
    crossings = [a[1] + (b[1] - a[1]) * (0.0 - a[0]) / (b[0] - a[0])
                 for a, b in itertools.pairwise(pts) if a[0] < 0.0 <= b[0]]
    assert len(crossings) == 1
    assert crossings[0] >= 950.0 + 190.0 - 1e-6 or crossings[0] <= -1000.0 - 190.0 + 1e-6
    assert res.length < 2 * math.hypot(1500.0, 1200.0)
    # with less clearance the detour hugs the wall closer
    thin = plan_path((-1500.0, 0.0), (1500.0, 0.0), obs, 0.0)
    assert thin.length < res.length


def test_goal_inside_is_moved_out() -> None:
    obs = Obstacles(circles=[[0.0, 0.0, 500.0]])
    res = plan_path((-2000.0, 0.0), (100.0, 0.0), obs, 100.0)
    assert res.goal_moved and not res.blocked
    end = res.points[-1]
    # nearest free point: straight out along the ray from the centre through the goal
    assert end[0] == pytest.approx(600.0 + MOVE_PAD_MM, abs=1e-9)
    assert end[1] == pytest.approx(0.0, abs=1e-9)
    check_path(res, (-2000.0, 0.0), (100.0, 0.0), Scene(obs, 100.0))


def test_start_inside_escapes() -> None:
    obs = Obstacles(circles=[[0.0, 0.0, 500.0]])
    res = plan_path((0.0, -300.0), (0.0, 2000.0), obs, 100.0)
    assert res.start_escape and not res.blocked
    assert res.points[0][0] == pytest.approx(0.0, abs=1e-9)
    assert res.points[0][1] == pytest.approx(-600.0 - MOVE_PAD_MM, abs=1e-9)
    assert res.points[-1] == (0.0, 2000.0)
    check_path(res, (0.0, -300.0), (0.0, 2000.0), Scene(obs, 100.0))


def test_bounds_are_respected() -> None:
    # a wall reaching down close to the lower bound: the free way is round the top
    obs = Obstacles(rects=[[-100.0, -2900.0, 100.0, 2000.0]],
                    bounds=(-3000.0, -3000.0, 3000.0, 3000.0))
    res = plan_path((-1000.0, -2500.0), (1000.0, -2500.0), obs, 100.0)
    assert not res.blocked
    assert all(abs(x) <= 3000.0 and abs(y) <= 3000.0 for x, y in res.points)
    assert max(p[1] for p in res.points) > 2100.0
    check_path(res, (-1000.0, -2500.0), (1000.0, -2500.0), Scene(obs, 100.0))
    # the same without bounds goes below the wall, and the keyword overrides obstacles'
    free = plan_path((-1000.0, -2500.0), (1000.0, -2500.0), obs.with_bounds(None), 100.0)
    assert min(p[1] for p in free.points) < -3000.0
    again = plan_path((-1000.0, -2500.0), (1000.0, -2500.0), obs.with_bounds(None), 100.0,
                      bounds=(-3000.0, -3000.0, 3000.0, 3000.0))
    assert again.points == res.points
    # a goal out of bounds is moved in
    out = plan_path((0.0, 2500.0), (0.0, 3500.0), obs, 100.0)
    assert out.goal_moved and out.points[-1][1] <= 3000.0


def test_enclosed_goal_is_blocked_and_stops_before_the_ring() -> None:
    ring = [(1000.0 * math.cos(a), 1000.0 * math.sin(a))
            for a in np.linspace(0, 2 * np.pi, 40, endpoint=False)]
    obs = Obstacles.build(robots=ring, robot_radius=90.0)
    res = plan_path((-3000.0, 0.0), (0.0, 0.0), obs, 100.0)
    assert res.blocked and not res.goal_moved
    sc = Scene(obs, 100.0)
    check_path(res, (-3000.0, 0.0), (0.0, 0.0), sc)
    # it drives along the straight line up to the ring, not into it
    (stop,) = res.points
    assert stop[1] == pytest.approx(0.0)
    assert -1000.0 - 190.0 - 2.0 < stop[0] < -1000.0 - 150.0
    # from inside the ring to outside: also blocked
    res = plan_path((0.0, 0.0), (-3000.0, 0.0), obs, 100.0)
    assert res.blocked


def test_max_waypoints_truncates() -> None:
    # a slalom: walls alternately from the bottom and from the top
    rects = [[x, -3000.0 if i % 2 == 0 else -2000.0, x + 100.0, 2000.0 if i % 2 == 0 else 3000.0]
             for i, x in enumerate(np.arange(-2000.0, 2001.0, 800.0))]
    obs = Obstacles(rects=rects, bounds=(-3000.0, -3000.0, 3000.0, 3000.0))
    full = plan_path((-2800.0, 0.0), (2800.0, 0.0), obs, 50.0, max_waypoints=64)
    assert not full.blocked and not full.truncated and len(full.points) > 3
    short = plan_path((-2800.0, 0.0), (2800.0, 0.0), obs, 50.0, max_waypoints=3)
    assert short.truncated and short.points == full.points[:3]
    with pytest.raises(ValueError, match="max_waypoints"):
        plan_path((0.0, 0.0), (1.0, 1.0), obs, 50.0, max_waypoints=0)


def test_overlapping_obstacles_are_passed_around_their_union() -> None:
    obs = Obstacles(circles=[[0.0, -300.0, 300.0], [0.0, 300.0, 300.0]],
                    rects=[[-50.0, -900.0, 50.0, 900.0]])
    res = plan_path((-2000.0, 0.0), (2000.0, 0.0), obs, 90.0)
    assert not res.blocked
    check_path(res, (-2000.0, 0.0), (2000.0, 0.0), Scene(obs, 90.0))
    assert max(abs(p[1]) for p in res.points) > 900.0


def test_defense_area_rects_match_in_defense_area() -> None:
    rng = np.random.default_rng(5)
    for field in (DIVISION_A, DIVISION_B):
        p = rng.uniform([-7000, -5000], [7000, 5000], size=(4000, 2))
        for margin in (0.0, 250.0):
            r = defense_area_rects(field, margin=margin)
            inside = ((p[:, None, 0] >= r[:, 0]) & (p[:, None, 0] <= r[:, 2])
                      & (p[:, None, 1] >= r[:, 1]) & (p[:, None, 1] <= r[:, 3])).any(axis=1)
            assert (inside == in_defense_area(p, field, margin=margin)).all()
        assert len(defense_area_rects(field, "positive")) == 1
        assert defense_area_rects(field, "negative")[0, 0] == -field.field_length / 2
    assert field_bounds(DIVISION_B, 300.0) == (-4800.0, -3300.0, 4800.0, 3300.0)


def test_obstacles_helpers_and_checks() -> None:
    obs = Obstacles.build(robots=[[0.0, 0.0], [500.0, 0.0]], circles=[[9.0, 9.0, 21.0]],
                          rects=[[0.0, 0.0, 1.0, 1.0]], bounds=(-1.0, -1.0, 1.0, 1.0))
    assert obs.circles.tolist() == [[0.0, 0.0, 90.0], [500.0, 0.0, 90.0], [9.0, 9.0, 21.0]]
    assert obs.without_circles([0]).circles.shape == (2, 3)
    assert obs.with_circles([[1.0, 2.0]], 3.0).circles[-1].tolist() == [1.0, 2.0, 3.0]
    assert obs.with_rects([[0, 0, 2, 2]]).rects.shape == (2, 4)
    grown = obs.inflated(10.0)
    assert grown.circles[0, 2] == 100.0 and grown.rects[0].tolist() == [-10, -10, 11, 11]
    assert Obstacles().circles.shape == (0, 3) and Obstacles().rects.shape == (0, 4)
    assert point_is_free((200.0, 0.0), obs, 10.0, bounds=(-1e4, -1e4, 1e4, 1e4))
    assert not point_is_free((200.0, 0.0), obs, 10.0)  # out of the tiny bounds
    with pytest.raises(ValueError, match="radii"):
        Obstacles(circles=[[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match="min <= max"):
        Obstacles(rects=[[1.0, 0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="finite"):
        Obstacles(circles=[[math.nan, 0.0, 1.0]])
    with pytest.raises(ValueError, match="bounds"):
        Obstacles(bounds=(1.0, 0.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="clearance"):
        plan_path((0.0, 0.0), (1.0, 0.0), obs, -1.0)
    with pytest.raises(ValueError, match="start"):
        plan_path((math.inf, 0.0), (1.0, 0.0), obs, 1.0)


@pytest.mark.parametrize("gap", [0.0, 7.871649045916051e-158, 1e-300, 1e-9])
def test_start_inside_obstacle_with_goal_a_hair_away_escapes(gap: float) -> None:
    """Found by hypothesis in CI: a goal a denormal distance from a start inside a disc made
    the straight-line test divide by ~0 and wrongly report a clear line."""
    obs = Obstacles(np.array([[0.0, 0.0, 20.0]]), np.zeros((0, 4)), None)
    res = plan_path((0.0, 0.0), (0.0, gap), obs, 0.0)
    assert res.start_escape
    check_path(res, (0.0, 0.0), (0.0, gap), Scene(obs, 0.0))


# -- the cheap ways around a search (backend/strategy/navigate.py's PathMemory uses them) --


def test_goal_in_a_pocket_is_blocked_without_searching_the_field(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A defender wedged between two others in front of our defence area (a real game's
    case): its goal moves to the nearest free point, a pocket between the two robots and the
    area that the start cannot reach. The search back from the goal runs dry at once, so
    the unbounded search from the start (every node on the field) is not run."""
    robots = [[-5877.0, -86.0, 150.0], [-3981.0, -229.0, 150.0], [-3977.0, 250.0, 150.0]]
    obs = Obstacles(circles=robots, rects=[[-6520.0, -1920.0, -4080.0, 1920.0]])
    bounds = (-6150.0, -4650.0, 6150.0, 4650.0)
    start, goal = (-3959.6, 12.1), (-3980.0, -13.7)
    calls: list[float] = []
    real = search._astar

    def spy(inf, s, g, graph, limit, prune, budget=None):  # type: ignore[no-untyped-def]
        if budget is None:
            calls.append(limit)
        return real(inf, s, g, graph, limit, prune, budget)

    monkeypatch.setattr(search, "_astar", spy)
    res = plan_path(start, goal, obs, 90.0, bounds=bounds)
    assert res.blocked and res.goal_moved and res.start_escape
    assert calls and all(math.isfinite(limit) for limit in calls)
    monkeypatch.setattr(enclosure, "POCKET_BUDGET", -1)  # the back search off: same answer
    calls.clear()
    assert plan_path(start, goal, obs, 90.0, bounds=bounds) == res
    assert any(math.isinf(limit) for limit in calls)


@given(scenes(), pt, pt)
@settings(max_examples=150, deadline=None)
def test_the_pocket_shortcut_changes_no_answer(scene: tuple[Obstacles, float],
                                               start: tuple[float, float],
                                               goal: tuple[float, float]) -> None:
    obs, clearance = scene
    fast = plan_path(start, goal, obs, clearance)
    with patch.object(enclosure, "POCKET_BUDGET", -1):
        slow = plan_path(start, goal, obs, clearance)
    assert fast == slow


def test_recheck_path_keeps_a_clear_detour_from_the_robot_on() -> None:
    obs = Obstacles(circles=[[0.0, 0.0, 200.0]])
    res = plan_path((-1500.0, 0.0), (1500.0, 0.0), obs, 90.0)
    assert len(res.points) > 1
    again = recheck_path((-1500.0, 0.0), res.points, obs, 90.0)
    assert again == res.points
    # further along: the waypoints it has passed (or no longer needs) are dropped
    mid = res.points[len(res.points) // 2]
    later = recheck_path(mid, res.points, obs, 90.0)
    assert later is not None and later[-1] == (1500.0, 0.0)
    assert len(later) < len(res.points) and set(later) <= set(res.points)
    check_path(PlannedPath(later), mid, (1500.0, 0.0), Scene(obs, 90.0))


def test_recheck_path_refuses_a_path_an_obstacle_now_crosses() -> None:
    obs = Obstacles(circles=[[0.0, 0.0, 200.0]])
    res = plan_path((-1500.0, 0.0), (1500.0, 0.0), obs, 90.0)
    for blocker in res.points[:-1]:  # a robot on a waypoint, or on a segment
        moved = obs.with_circles([blocker], 90.0)
        assert recheck_path((-1500.0, 0.0), res.points, moved, 90.0) is None
    a, b = res.points[0], res.points[1]
    on_segment = obs.with_circles([((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)], 50.0)
    assert recheck_path((-1500.0, 0.0), res.points, on_segment, 90.0) is None
    # the robot itself inside an obstacle now: plan again
    assert recheck_path((0.0, 100.0), res.points, obs, 90.0) is None
    assert recheck_path((-1500.0, 0.0), (), obs, 90.0) is None


def test_straight_is_clear_is_plan_paths_first_answer() -> None:
    obs = Obstacles(circles=[[0.0, 0.0, 200.0]], bounds=(-3000.0, -3000.0, 3000.0, 3000.0))
    assert straight_is_clear((-1500.0, 1000.0), (1500.0, 1000.0), obs, 90.0)
    assert not straight_is_clear((-1500.0, 0.0), (1500.0, 0.0), obs, 90.0)
    assert not straight_is_clear((-1500.0, 1000.0), (3500.0, 1000.0), obs, 90.0)


@given(scenes(), st.lists(st.tuples(pt, pt), min_size=1, max_size=6), st.data())
@settings(max_examples=200, deadline=None)
def test_straight_tests_for_many_robots_agree_with_plan_paths(
        scene: tuple[Obstacles, float], segs: list[tuple[tuple[float, float], ...]],
        data: st.DataObject) -> None:
    """navigate's one-pass straight test (circles for all robots, then each robot's own
    discs, areas and bounds) answers as plan_path's straight case, with a circle left out
    per robot (the robot itself) and some circles given as the robot's own."""
    obs, clearance = scene
    k = len(obs.circles)
    skip = np.array([data.draw(st.integers(-1, k - 1), "skip") for _ in segs], dtype=np.int64)
    split = data.draw(st.integers(0, k), "own circles from")
    starts = np.array([s for s, _ in segs], dtype=np.float64).reshape(-1, 2)
    goals = np.array([g for _, g in segs], dtype=np.float64).reshape(-1, 2)
    common = obs.circles[:split]
    skip = np.where(skip < split, skip, -1)
    ok = straight_clear_of_circles(starts, goals, common, clearance, skip)
    for i, (s, g) in enumerate(segs):
        keep = np.ones(k, dtype=bool)
        if skip[i] >= 0:
            keep[skip[i]] = False
        ref = straight_is_clear(s, g, Obstacles(obs.circles[keep], obs.rects, obs.bounds),
                                clearance)
        got = bool(ok[i]) and straight_clear_of_rest(
            s, g, obs.circles[split:].tolist(), obs.rects.tolist(), clearance, obs.bounds)
        assert got == ref


def _keep_all(p: object, dist: float, cxy: np.ndarray, rp: np.ndarray, xs: np.ndarray,
              ys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return cxy, rp, xs, ys


@given(scenes(), st.data())
@settings(max_examples=300, deadline=None)
def test_leaving_out_far_boundaries_changes_no_nearest_free_point(
        scene: tuple[Obstacles, float], data: st.DataObject) -> None:
    """``_near_p`` only drops crossings farther than the best projection: the same answer,
    bit for bit, as with every boundary's crossings."""
    obs, clearance = scene
    p = data.draw(inside_points(obs, clearance))
    fast = nearest_free_point(p, obs, clearance)
    with patch.object(escape, "_near_p", _keep_all):
        slow = nearest_free_point(p, obs, clearance)
    assert fast == slow


def test_near_p_keeps_what_comes_within_the_distance_in_order() -> None:
    cxy = np.array([[0.0, 0.0], [1000.0, 0.0], [0.0, 300.0], [5000.0, 5000.0]])
    rp = np.array([100.0, 100.0, 100.0, 100.0])
    xs = np.array([-50.0, 400.0, 30.0])
    ys = np.array([900.0, -20.0])
    c, r, x, y = escape._near_p(np.array([0.0, 0.0]), 150.0, cxy, rp, xs, ys)
    # circle 0: p at its centre, boundary 100 away; circle 2: boundary 200 away; the others
    # farther; lines 50 and 30 away in x, 20 in y
    assert c.tolist() == [[0.0, 0.0]] and r.tolist() == [100.0]
    assert x.tolist() == [-50.0, 30.0] and y.tolist() == [-20.0]
    c, r, x, y = escape._near_p(np.array([0.0, 0.0]), 250.0, cxy, rp, xs, ys)
    assert c.tolist() == [[0.0, 0.0], [0.0, 300.0]]
    every = escape._near_p(np.array([0.0, 0.0]), math.inf, cxy, rp, xs, ys)
    assert all(a is b for a, b in zip(every, (cxy, rp, xs, ys), strict=True))


def test_pairs_are_triu_indices_and_read_only() -> None:
    for k in (2, 5, 23):
        i, j = escape._pairs(k)
        ri, rj = np.triu_indices(k, 1)
        assert i.tolist() == ri.tolist() and j.tolist() == rj.tolist()
        with pytest.raises(ValueError):
            i[0] = 1


@given(scenes(), st.lists(pt, min_size=1, max_size=collision.SMALL_T), st.floats(0.0, 150.0))
@settings(max_examples=300, deadline=None)
def test_points_free_in_plain_floats_is_the_numpy_test(scene: tuple[Obstacles, float],
                                                       pts: list[tuple[float, float]],
                                                       clearance: float) -> None:
    obs, _ = scene
    inf = collision._Inflated(obs, clearance, None)
    few = np.array(pts, dtype=np.float64)
    # past SMALL_T points the numpy test runs: the same points, padded with copies
    many = np.vstack([few] * (collision.SMALL_T + 1))
    assert inf.points_free(few).tolist() == inf.points_free(many)[:len(pts)].tolist()
    assert inf.points_free(few).dtype == np.bool_


def test_trusted_obstacles_are_the_checked_ones() -> None:
    c = np.array([[0.0, 0.0, 150.0], [500.0, 10.0, 150.0]])
    r = np.array([[-100.0, -50.0, 100.0, 50.0]])
    a, b = Obstacles(c, r), Obstacles.trusted(c, r)
    assert (a.circles == b.circles).all() and (a.rects == b.rects).all()
    assert a.bounds is None and b.bounds is None
    assert plan_path((-1000.0, 0.0), (1000.0, 0.0), a, 90.0) \
        == plan_path((-1000.0, 0.0), (1000.0, 0.0), b, 90.0)
