"""Geometry library: hypothesis properties against scalar reference implementations written
here with the math module and loops, plus hand-picked cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from backend import geometry as g
from domain.field import DIVISION_A, DIVISION_B, Field

coord = st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False)
point = st.tuples(coord, coord)
radius = st.floats(1.0, 3e3)
angle = st.floats(-50.0, 50.0, allow_nan=False)
TOL = 1e-6


def close(a: float, b: float, tol: float = 1e-6) -> bool:
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))


# -- scalar references -------------------------------------------------------------------

def ref_wrap(t: float) -> float:
    while t >= math.pi:
        t -= 2 * math.pi
    while t < -math.pi:
        t += 2 * math.pi
    return t


def ref_seg_dist(p, a, b) -> float:  # type: ignore[no-untyped-def]
    dx, dy = b[0] - a[0], b[1] - a[1]
    L2 = dx * dx + dy * dy
    if L2 == 0:
        return math.dist(p, a)
    t = max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / L2))
    return math.dist(p, (a[0] + t * dx, a[1] + t * dy))


def ref_line_dist(p, a, b) -> float:  # type: ignore[no-untyped-def]
    dx, dy = b[0] - a[0], b[1] - a[1]
    return abs(dx * (p[1] - a[1]) - dy * (p[0] - a[0])) / math.hypot(dx, dy)


# -- vectors -----------------------------------------------------------------------------

@given(point, point)
def test_distance_dot_cross_match_math(a, b) -> None:  # type: ignore[no-untyped-def]
    assert close(float(g.distance(a, b)), math.dist(a, b))
    assert close(float(g.dot(a, b)), a[0] * b[0] + a[1] * b[1], 1e-9)
    assert close(float(g.cross(a, b)), a[0] * b[1] - a[1] * b[0], 1e-9)


@given(st.lists(point, min_size=1, max_size=30), point)
def test_batch_equals_loop(pts, q) -> None:  # type: ignore[no-untyped-def]
    arr = np.array(pts)
    d = g.distance(arr, q)
    assert d.shape == (len(pts),)
    for i, p in enumerate(pts):
        assert close(float(d[i]), math.dist(p, q))
    # broadcasting (N,1,2) against (1,M,2)
    dd = g.distance(arr[:, None, :], arr[None, :, :])
    assert dd.shape == (len(pts), len(pts))


@given(point)
def test_normalise_unit_or_zero(v) -> None:  # type: ignore[no-untyped-def]
    n = g.normalise(v)
    if math.hypot(*v) > 0:
        assert close(float(g.norm(n)), 1.0, 1e-12)
        assert float(g.cross(v, n)) == pytest.approx(0.0, abs=1e-9 * math.hypot(*v))
    else:
        assert n.tolist() == [0.0, 0.0]


def test_normalise_zero_vectors_in_a_batch() -> None:
    out = g.normalise([[0.0, 0.0], [3.0, 4.0], [-0.0, 0.0]])
    assert out.tolist() == [[0.0, 0.0], [0.6, 0.8], [0.0, 0.0]]
    assert not np.isnan(out).any()


@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_wrap_angle_range_and_equivalence(t) -> None:  # type: ignore[no-untyped-def]
    w = float(g.wrap_angle(t))
    assert -math.pi <= w < math.pi
    assert math.isclose(math.cos(w), math.cos(t), abs_tol=1e-6)
    assert math.isclose(math.sin(w), math.sin(t), abs_tol=1e-6)
    if abs(t) < 100:
        assert abs(w - ref_wrap(t)) < 1e-9 or abs(abs(w - ref_wrap(t)) - 2 * math.pi) < 1e-9


def test_wrap_angle_edges() -> None:
    assert g.wrap_angle([math.pi, -math.pi, 3 * math.pi, 0.0, -1e-300]).tolist() == [
        -math.pi, -math.pi, -math.pi, 0.0, -1e-300]
    assert math.isnan(float(g.wrap_angle(math.nan)))


@given(point, point)
def test_signed_angle_rotates_a_onto_b(a, b) -> None:  # type: ignore[no-untyped-def]
    assume(math.hypot(*a) > 1e-3 and math.hypot(*b) > 1e-3)
    th = float(g.signed_angle(a, b))
    assert -math.pi <= th < math.pi
    ref = ref_wrap(math.atan2(b[1], b[0]) - math.atan2(a[1], a[0]))
    assert abs(ref_wrap(th - ref)) < 1e-9
    rotated = g.rotate(g.normalise(a), th)
    assert np.allclose(rotated, g.normalise(b), atol=1e-9)


def test_signed_angle_hand_cases() -> None:
    assert float(g.signed_angle([1, 0], [0, 1])) == pytest.approx(math.pi / 2)
    assert float(g.signed_angle([1, 0], [0, -1])) == pytest.approx(-math.pi / 2)
    assert float(g.signed_angle([1, 0], [-1, 0])) == -math.pi
    assert float(g.signed_angle([1, 0], [-1, -0.0])) == -math.pi
    assert float(g.signed_angle([0, 0], [1, 1])) == 0.0


@given(point, angle, point)
def test_rotate_matches_scalar(v, th, c) -> None:  # type: ignore[no-untyped-def]
    x, y = v[0] - c[0], v[1] - c[1]
    ref = (c[0] + x * math.cos(th) - y * math.sin(th), c[1] + x * math.sin(th) + y * math.cos(th))
    assert np.allclose(g.rotate(v, th, about=c), ref, rtol=1e-9, atol=1e-6)
    assert close(float(g.distance(g.rotate(v, th), [0, 0])), math.hypot(*v))


def test_rotate_batch_of_angles() -> None:
    out = g.rotate([1.0, 0.0], np.array([0.0, math.pi / 2, math.pi]))
    assert np.allclose(out, [[1, 0], [0, 1], [-1, 0]])


# -- lines -------------------------------------------------------------------------------

@given(point, point, point)
def test_point_segment_and_line_distance(p, a, b) -> None:  # type: ignore[no-untyped-def]
    assert close(float(g.point_segment_distance(p, a, b)), ref_seg_dist(p, a, b), 1e-6)
    assume(math.dist(a, b) > 1e-2)
    assert float(g.point_line_distance(p, a, b)) == pytest.approx(
        ref_line_dist(p, a, b), rel=1e-6, abs=1e-5)
    proj = g.project_on_line(p, a, b)
    # the projection lies on the line and p - proj is perpendicular to it
    assert float(g.point_line_distance(proj, a, b)) == pytest.approx(0.0, abs=1e-5)
    d = np.subtract(b, a)
    assert float(g.dot(np.subtract(p, proj), d)) == pytest.approx(
        0.0, abs=1e-6 * math.hypot(*d) * max(1.0, math.dist(p, proj)))
    s = float(g.signed_line_distance(p, a, b))
    assert abs(s) == pytest.approx(ref_line_dist(p, a, b), rel=1e-6, abs=1e-5)
    assert (s >= 0) == bool(g.in_half_plane(p, a, b)) or abs(s) < 1e-6


def test_degenerate_line_is_a_point() -> None:
    assert float(g.point_line_distance([3, 4], [0, 0], [0, 0])) == 5.0
    assert g.project_on_segment([3, 4], [1, 1], [1, 1]).tolist() == [1.0, 1.0]


@given(point, point, point, point)
def test_line_intersection_lies_on_both_lines(a1, a2, b1, b2) -> None:  # type: ignore[no-untyped-def]
    da, db = np.subtract(a2, a1), np.subtract(b2, b1)
    assume(math.hypot(*da) > 1.0 and math.hypot(*db) > 1.0)
    sin = abs(float(g.cross(da, db))) / (math.hypot(*da) * math.hypot(*db))
    p = g.line_intersection(a1, a2, b1, b2)
    if sin < 1e-12:
        assert np.isnan(p).all()
        return
    assume(sin > 1e-3)
    assert not np.isnan(p).any()
    scale = 1e-6 * max(1.0, float(np.abs(p).max())) / sin
    assert float(g.point_line_distance(p, a1, a2)) < scale
    assert float(g.point_line_distance(p, b1, b2)) < scale


def test_parallel_lines_give_nan_and_segments_mask() -> None:
    p = g.line_intersection([[0, 0], [0, 0]], [[1, 0], [1, 0]], [[0, 1], [0, 1]],
                            [[1, 1], [1, 2]])
    assert np.isnan(p[0]).all()
    assert p[1].tolist() == [-1.0, 0.0]
    s = g.segment_intersection([[0, 0], [0, 0]], [[2, 2], [1, 1]], [[0, 2], [0, 2]],
                               [[2, 0], [0.5, 1.5]])
    assert s[0].tolist() == [1.0, 1.0]
    assert np.isnan(s[1]).all()  # the lines cross at (1, 1) beyond the second segment's end
    # collinear overlap: no single point
    assert np.isnan(g.segment_intersection([0, 0], [2, 0], [1, 0], [3, 0])).all()


@given(point, point, point, point)
def test_segment_intersection_matches_orientation_test(a1, a2, b1, b2) -> None:  # type: ignore[no-untyped-def]
    def orient(p, q, r) -> float:  # type: ignore[no-untyped-def]
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    o = [orient(a1, a2, b1), orient(a1, a2, b2), orient(b1, b2, a1), orient(b1, b2, a2)]
    scale = max(math.dist(a1, a2), math.dist(b1, b2)) ** 2
    assume(all(abs(x) > 1e-6 * scale + 1e-3 for x in o))  # away from touching / collinear
    proper = (o[0] > 0) != (o[1] > 0) and (o[2] > 0) != (o[3] > 0)
    p = g.segment_intersection(a1, a2, b1, b2)
    assert (not np.isnan(p).any()) == proper


# -- circles -----------------------------------------------------------------------------

@given(point, point, point, radius)
def test_line_circle_points_are_on_both(a, b, c, r) -> None:  # type: ignore[no-untyped-def]
    assume(math.dist(a, b) > 1.0)
    p1, p2 = g.line_circle_intersection(a, b, c, r)
    d = ref_line_dist(c, a, b)
    if d < r * (1 - 1e-6):
        for p in (p1, p2):
            assert float(g.distance(p, c)) == pytest.approx(r, rel=1e-6, abs=1e-5)
            assert float(g.point_line_distance(p, a, b)) < 1e-5 * max(1.0, float(np.abs(p).max()))
        assert float(g.line_param(p1, a, b)) <= float(g.line_param(p2, a, b)) + 1e-9
    elif d > r * (1 + 1e-6):
        assert np.isnan(p1).all() and np.isnan(p2).all()


@given(point, point, point, radius)
def test_segment_circle_subset_of_line_circle(a, b, c, r) -> None:  # type: ignore[no-untyped-def]
    assume(math.dist(a, b) > 1.0)
    l1, l2 = g.line_circle_intersection(a, b, c, r)
    s1, s2 = g.segment_circle_intersection(a, b, c, r)
    for lp, sp in ((l1, s1), (l2, s2)):
        if not np.isnan(sp).any():
            assert np.allclose(sp, lp)
            assert ref_seg_dist(sp, a, b) < 1e-6 * max(1.0, float(np.abs(sp).max()))


@given(point, radius, point, radius)
def test_circle_circle(c1, r1, c2, r2) -> None:  # type: ignore[no-untyped-def]
    d = math.dist(c1, c2)
    p1, p2 = g.circle_circle_intersection(c1, r1, c2, r2)
    tol = 1e-6 * max(d, r1, r2)
    if d > 1.0 and abs(r1 - r2) + tol < d < r1 + r2 - tol:
        for p in (p1, p2):
            assert float(g.distance(p, c1)) == pytest.approx(r1, rel=1e-6, abs=1e-4)
            assert float(g.distance(p, c2)) == pytest.approx(r2, rel=1e-6, abs=1e-4)
        assert float(g.cross(np.subtract(c2, c1), np.subtract(p1, c1))) >= 0  # p1 on the left
    elif d > r1 + r2 + tol or d < abs(r1 - r2) - tol:
        assert np.isnan(p1).all() and np.isnan(p2).all()


def test_circle_circle_hand_cases() -> None:
    p1, p2 = g.circle_circle_intersection([0, 0], 1, [2, 0], 1)  # touching
    assert np.allclose(p1, [1, 0]) and np.allclose(p2, [1, 0])
    p1, _ = g.circle_circle_intersection([0, 0], 1, [0, 0], 1)  # concentric
    assert np.isnan(p1).all()


@given(point, point, radius)
def test_tangent_points(p, c, r) -> None:  # type: ignore[no-untyped-def]
    t1, t2 = g.tangent_points(p, c, r)
    d = math.dist(p, c)
    if d < r * (1 - 1e-9):
        assert np.isnan(t1).all() and np.isnan(t2).all()
        return
    assume(d > r * (1 + 1e-6))
    for t in (t1, t2):
        assert float(g.distance(t, c)) == pytest.approx(r, rel=1e-6)
        # radius is perpendicular to the tangent line
        rad, tan = np.subtract(t, c), np.subtract(p, t)
        assert abs(float(g.dot(rad, tan))) <= 1e-6 * r * max(1.0, math.hypot(*tan))
    # t1 counter-clockwise from centre->p about the centre
    assert float(g.cross(np.subtract(p, c), np.subtract(t1, c))) >= -1e-6 * r * d


def ref_first_hit(a, b, centers, radii):  # type: ignore[no-untyped-def]
    """Walk the segment in tiny steps: index of the first circle strictly entered."""
    best, best_t = -1, math.inf
    for i, (c, r) in enumerate(zip(centers, radii, strict=True)):
        if ref_seg_dist(c, a, b) < r:
            # entry parameter by bisection on the first inside point
            n = 2000
            for k in range(n + 1):
                t = k / n
                q = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
                if math.dist(q, c) < r:
                    if t < best_t:
                        best, best_t = i, t
                    break
    return best, best_t


@settings(max_examples=60)
@given(point, point, st.lists(st.tuples(point, st.floats(50.0, 2000.0)), min_size=0, max_size=6))
def test_segment_hits_circles_against_loop(a, b, obstacles) -> None:  # type: ignore[no-untyped-def]
    centers = [c for c, _ in obstacles]
    radii = [r for _, r in obstacles]
    # keep away from grazing cases, where "strictly inside" is decided by rounding
    assume(all(abs(ref_seg_dist(c, a, b) - r) > 1e-3 * r for c, r in obstacles))
    res = g.segment_hits_circles(a, b, np.array(centers).reshape(-1, 2), radii)
    ref_i, ref_t = ref_first_hit(a, b, centers, radii)
    assert bool(res.hit) == (ref_i >= 0)
    if ref_i >= 0:
        length = max(math.dist(a, b), 1e-9)
        assert float(res.t) <= ref_t + 1e-9
        assert float(res.t) >= ref_t - 1.0 / 2000 - 1e-9
        # the reported circle is entered at the reported t (ties may name another circle)
        assert math.dist(res.point.tolist(), centers[int(res.first)]) <= \
            radii[int(res.first)] * (1 + 1e-6) + 1e-6 * length
    else:
        assert int(res.first) == -1 and math.isnan(float(res.t))


def test_segment_hits_circles_batch_and_cases() -> None:
    centers = np.array([[5.0, 0.0], [3.0, 0.5], [8.0, 0.0]])
    radii = np.array([1.0, 0.4, 1.0])
    a = np.array([[0.0, 0.0], [0.0, 5.0], [5.0, 0.5], [0.0, 1.0]])
    b = np.array([[10.0, 0.0], [10.0, 5.0], [5.0, 0.5], [10.0, 1.0]])
    res = g.segment_hits_circles(a, b, centers, radii)
    assert res.hit.tolist() == [True, False, True, False]  # last one grazes circle 0 and 2
    assert res.first.tolist() == [0, -1, 0, -1]
    assert res.t[0] == pytest.approx(0.4) and res.t[2] == 0.0
    assert np.allclose(res.point[0], [4, 0])
    empty = g.segment_hits_circles(a, b, np.zeros((0, 2)), np.zeros(0))
    assert empty.hit.tolist() == [False] * 4


# -- regions -----------------------------------------------------------------------------

@given(point, point, point, st.floats(10.0, 5e3), st.floats(10.0, 5e3), angle)
def test_oriented_rectangle(p, c, _unused, length, width, th) -> None:  # type: ignore[no-untyped-def]
    # reference: coordinates along the rectangle's axes by dot products
    ux, uy = math.cos(th), math.sin(th)
    dx, dy = p[0] - c[0], p[1] - c[1]
    along, across = dx * ux + dy * uy, -dx * uy + dy * ux
    assume(abs(abs(along) - length / 2) > 1e-6 and abs(abs(across) - width / 2) > 1e-6)
    ref = abs(along) <= length / 2 and abs(across) <= width / 2
    assert bool(g.in_rectangle(p, c, (length, width), th)) == ref


def test_half_plane_and_rectangle_hand_cases() -> None:
    assert g.in_half_plane([[0, 1], [0, -1], [5, 0]], [0, 0], [1, 0]).tolist() == [
        True, False, True]
    # a 2 x 2 square turned 45 degrees: its corners are on the axes at sqrt(2)
    sq = g.in_rectangle([[1.4, 0.0], [1.5, 0.0], [0.7, 0.7], [0.75, 0.75]], [0, 0], [2, 2],
                        math.pi / 4)
    assert sq.tolist() == [True, False, True, False]


@pytest.mark.parametrize("field", [DIVISION_A, DIVISION_B])
def test_defense_area(field: Field) -> None:
    hl = field.field_length / 2
    depth, hw = field.penalty_area_depth, field.penalty_area_width / 2
    pts = np.array([[hl - 1, 0], [hl - depth + 1, hw - 1], [hl - depth - 1, 0], [hl - 1, hw + 1],
                    [-hl + 1, 0], [0, 0], [hl + 1, 0]])
    assert g.in_defense_area(pts, field).tolist() == [True, True, False, False, True, False, False]
    assert g.in_defense_area(pts, field, "positive").tolist() == [
        True, True, False, False, False, False, False]
    assert g.in_defense_area(pts, field, "negative").tolist() == [
        False, False, False, False, True, False, False]
    assert g.in_defense_area([hl - depth - 50, 0], field, margin=90.0).item() is True


def test_field_geometry_from_packet_dict() -> None:
    f = Field.from_geometry({"field_length": 9000, "field_width": 6000,
                                     "goal_width": 1000, "penalty_area_depth": 1000,
                                     "penalty_area_width": 2000})
    assert f == DIVISION_B


# -- fits --------------------------------------------------------------------------------

@given(point, st.floats(-math.pi, math.pi), st.integers(2, 20), st.floats(1.0, 500.0))
def test_tls_recovers_exact_line(p0, th, n, step) -> None:  # type: ignore[no-untyped-def]
    d = (math.cos(th), math.sin(th))
    pts = [(p0[0] + k * step * d[0], p0[1] + k * step * d[1]) for k in range(n)]
    line = g.fit_line_tls(pts)
    assert np.allclose(line.direction, d, atol=1e-6)
    for q in pts:
        assert float(g.point_line_distance(q, line.point, line.point + line.direction)) < \
            1e-6 * max(1.0, abs(p0[0]), abs(p0[1]), n * step)


def test_tls_is_not_y_on_x_regression() -> None:
    # a vertical line: y-on-x least squares breaks down, total least squares does not
    line = g.fit_line_tls([[100, 0], [100, 10], [100, 20], [100, 30]])
    assert np.allclose(line.direction, [0, 1])
    assert np.isnan(g.fit_line_tls([[1, 1], [1, 1]]).direction).all()
    batch = g.fit_line_tls(np.array([[[0, 0], [1, 0], [2, 0]], [[0, 0], [0, -1], [0, -2]]]))
    assert np.allclose(batch.direction, [[1, 0], [0, -1]])



@given(point, st.tuples(coord, coord), st.integers(2, 15))
def test_motion_fit_exact(p0, v, n) -> None:  # type: ignore[no-untyped-def]
    t = [k / 60.0 for k in range(n)]
    pts = [(p0[0] + v[0] * tk, p0[1] + v[1] * tk) for tk in t]
    m = g.fit_motion_lsq(t, pts)
    assert np.allclose(m.velocity, v, rtol=1e-6, atol=1e-3)
    assert np.allclose(m.position, pts[-1], rtol=1e-6, atol=1e-3)


@given(point, st.tuples(st.floats(-8000, 8000), st.floats(-8000, 8000)))
def test_goalkeeper_target_against_scalar(ball, vel) -> None:  # type: ignore[no-untyped-def]
    goal_x, goal_w, margin, min_speed = -4500.0, 1000.0, 90.0, 100.0
    lim = goal_w / 2 - margin
    if (goal_x - ball[0]) * vel[0] > 0 and abs(vel[0]) > min_speed:
        y = ball[1] + (goal_x - ball[0]) * vel[1] / vel[0]
    else:  # on the bisector of the angle between the lines to the posts: equal angles
        a_up = math.atan2(goal_w / 2 - ball[1], goal_x - ball[0])
        a_down = math.atan2(-goal_w / 2 - ball[1], goal_x - ball[0])
        mid = a_down + (a_up - a_down) / 2 if abs(a_up - a_down) <= math.pi else None
        if mid is None:  # (behind the line: the angle wraps through pi)
            mid = a_down + (a_up - a_down + 2 * math.pi) / 2
        y = ball[1] + (goal_x - ball[0]) * math.tan(mid) if ball[0] != goal_x else ball[1]
    y = min(lim, max(-lim, y))
    out = g.goalkeeper_target(ball, vel, goal_x, goal_w, margin, min_speed)
    assert out[0] == goal_x
    assert float(out[1]) == pytest.approx(y, rel=1e-9, abs=1e-6)


def test_goalkeeper_hand_cases() -> None:
    # ball at the centre rolling to the left goal, aimed 410 mm up at the goal line
    assert g.goalkeeper_target([0, 0], [-1000, 91.111], -4500, 1000).tolist() == pytest.approx(
        [-4500, 410.0], abs=0.01)
    # rolling away, out wide: on the bisector of the angle the mouth makes at the ball, which
    # divides the mouth as the distances to the posts (4743.4 and 5147.8 mm: 20.4 mm up), not
    # level with the ball (which left the far side open)
    assert g.goalkeeper_target([0, 2000], [1000, 0], -4500, 1000, 90).tolist() == pytest.approx(
        [-4500, 500 * (math.hypot(4500, 2500) - math.hypot(4500, 1500))
         / (math.hypot(4500, 2500) + math.hypot(4500, 1500))])
    # level with the goal's centre: the middle; close in, out wide: towards the near post
    # (141 and 1105 mm to the posts); clamped to the mouth less the margin
    assert g.goalkeeper_target([-2000, 0], [0, 0], -4500, 1000).tolist() == [-4500, 0]
    assert g.goalkeeper_target([-4400, 600], [0, 0], -4500, 1000, 90).tolist() == pytest.approx(
        [-4500, 386.4958], abs=1e-3)
    assert g.goalkeeper_target([-4400, 600], [0, 0], -4500, 1000, 200).tolist() == [-4500, 300]
    assert float(g.intercept_x([0, 0], [0, 1], 5)) != float(g.intercept_x([0, 0], [0, 1], 5))
