import math

from backend.strategy.demo import DemoConfig, assign_greedy, demo_targets, formation


def test_formations_stay_on_our_half_and_inside_the_field() -> None:
    cfg = DemoConfig()
    for k in range(3):
        for n in (1, 6, 11):
            pts = formation(k, n, cfg)
            assert len(pts) == n
            for x, y in pts:
                assert -4500 < x < 0 and abs(y) < 3000


def test_assignment_keeps_robots_near_their_points() -> None:
    pts = [(0.0, 0.0), (1000.0, 0.0), (2000.0, 0.0)]
    robots = {7: (2050.0, 10.0), 3: (-20.0, 0.0), 5: (990.0, 5.0)}
    assert assign_greedy(robots, pts) == {3: (0.0, 0.0), 5: (1000.0, 0.0), 7: (2000.0, 0.0)}


def test_demo_gives_every_robot_a_distinct_target_and_changes_over_time() -> None:
    cfg = DemoConfig(period_s=5.0)
    robots = {i: (-3000.0 + 300 * i, 0.0) for i in range(6)}
    a = demo_targets(0.0, robots, cfg)
    b = demo_targets(5.0, robots, cfg)
    assert set(a) == set(robots) and len({(t.x, t.y) for t in a.values()}) == 6
    assert any(math.dist((a[i].x, a[i].y), (b[i].x, b[i].y)) > 100 for i in robots)
