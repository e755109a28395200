import math
from dataclasses import replace
from itertools import pairwise

from backend.filters import FilterSettings
from backend.world.model import WorldModel
from backend.world.state import CameraFrame, RawBall, RawRobot, WorldState


def frame(cam: int, t: float, robots=(), balls=(), n: int = 0) -> CameraFrame:  # type: ignore[no-untyped-def]
    return CameraFrame(cam, n, t, t, int(t * 1e9), tuple(balls), tuple(robots))


def test_two_cameras_seeing_one_robot_make_one_object_at_the_mean() -> None:
    m = WorldModel()
    m.update(frame(0, 100.000, [RawRobot("blue", 3, 10.0, 20.0, 0.1, 0.9)]))
    m.update(frame(1, 100.004, [RawRobot("blue", 3, 14.0, 24.0, 0.3, 0.9)]))
    w = m.snapshot()
    blues = [r for r in w.robots if r.team == "blue"]
    assert len(blues) == 1
    r = blues[0]
    assert (r.x, r.y) == (12.0, 22.0)
    assert math.isclose(r.orientation, 0.2, abs_tol=1e-9)
    assert r.cameras == (0, 1)


def test_cameras_of_a_robot_follow_it_from_one_camera_to_the_next() -> None:
    """The cameras that saw it within camera_window_s of its latest measurement, in every
    snapshot (built afresh, or the one-camera short way once the other camera is forgotten);
    the snapshot's robot state is reused while nothing new came."""
    m = WorldModel()
    w = m.config.camera_window_s
    seen = []
    t = 100.0
    for k in range(12):  # camera 0 alone, then both at one instant, then camera 1 alone
        t = 100.0 + k * 0.0133
        cams = [0] if k < 4 else [0, 1] if k < 6 else [1]
        for c in cams:
            m.update(frame(c, t + 0.001 * c, [RawRobot("blue", 3, 10.0 * k, 0.0, 0.0, 0.9)]))
        r = m.snapshot().robots[0]
        seen.append(r.cameras)
        assert m.snapshot().robots[0] is r  # nothing new: the same state object
    assert seen[:4] == [(0,)] * 4
    assert seen[4:6] == [(0, 1)] * 2
    # camera 0 last saw it at k = 5: it counts until camera_window_s after that
    last0 = 100.0 + 5 * 0.0133
    assert seen[6:] == [(0, 1) if 100.0 + k * 0.0133 + 0.001 - last0 <= w else (1,)
                        for k in range(6, 12)]
    assert seen[-1] == (1,)


def test_same_id_in_both_teams_are_two_objects() -> None:
    m = WorldModel()
    m.update(frame(0, 1.0, [RawRobot("blue", 1, 0, 0, 0, 1), RawRobot("yellow", 1, 500, 0, 0, 1)]))
    assert {(r.team, r.id) for r in m.snapshot().robots} == {("blue", 1), ("yellow", 1)}


def test_orientation_mean_across_the_pi_wrap() -> None:
    m = WorldModel()
    m.update(frame(0, 1.0, [RawRobot("blue", 0, 0, 0, math.pi - 0.05, 1)]))
    m.update(frame(1, 1.001, [RawRobot("blue", 0, 0, 0, -math.pi + 0.05, 1)]))
    assert math.isclose(abs(m.snapshot().robots[0].orientation), math.pi, abs_tol=1e-6)


def test_velocity_from_consecutive_frames() -> None:
    m = WorldModel()
    for k in range(60):  # 1 m/s along x seen by one camera at 60 Hz
        t = 10.0 + k / 60
        m.update(frame(0, t, [RawRobot("yellow", 2, 1000.0 * (t - 10.0), 0, 0, 1)]))
    r = m.snapshot().robots[0]
    assert math.isclose(r.vx, 1000.0, rel_tol=0.02)
    assert abs(r.vy) < 1.0


def test_unseen_robot_becomes_invisible_then_dropped() -> None:
    m = WorldModel()
    m.update(frame(0, 1.0, [RawRobot("blue", 5, 0, 0, 0, 1)]))
    assert m.snapshot(now=1.1).robots[0].visible
    assert not m.snapshot(now=1.5).robots[0].visible
    assert m.snapshot(now=10.0).robots == ()


def test_ball_follows_the_detection_nearest_its_prediction() -> None:
    # Kalman with its 3 mm noise: after two detections it sits on the second (the default,
    # adaptive filter, averages them until it has learnt the noise)
    m = WorldModel(filters=FilterSettings(ball="kalman"))
    m.update(frame(0, 1.0, balls=[RawBall(0, 0, 0.9)]))
    # a false ball far away with higher confidence, and the real ball a little further on
    m.update(frame(0, 1.0 + 1 / 60, balls=[RawBall(3000, 2000, 1.0), RawBall(10, 0, 0.8)]))
    b = m.snapshot().ball
    # the world model filters: the raw value is the detection taken, the
    # filtered one is near it
    assert b is not None and (b.raw_x, b.raw_y) == (10, 0)
    assert math.hypot(b.x - 10, b.y) < 1.0


def test_ball_seen_by_two_cameras_at_once_is_averaged() -> None:
    m = WorldModel()
    m.update(frame(0, 1.0, balls=[RawBall(100, 0, 0.9)]))
    m.update(frame(1, 1.002, balls=[RawBall(110, 10, 0.9)]))
    b = m.snapshot().ball
    assert b is not None and (b.x, b.y) == (105, 5)
    assert b.cameras == (0, 1)


def test_robots_stay_sorted_when_one_is_dropped_and_another_comes() -> None:
    """The snapshot keeps its sorted order of robots between arrivals and departures (it is
    sorted again only then), also when one goes and another comes in the same snapshot."""
    m = WorldModel()
    m.update(frame(0, 1.0, [RawRobot("blue", 1, 0, 0, 0, 1), RawRobot("blue", 2, 500, 0, 0, 1)]))
    assert [r.id for r in m.snapshot().robots] == [1, 2]
    m.update(frame(0, 4.5, [RawRobot("blue", 2, 500, 0, 0, 1)]))  # 1 not seen for 3.5 s
    assert [r.id for r in m.snapshot().robots] == [2]
    m.update(frame(0, 8.0, [RawRobot("yellow", 0, 0, 0, 0, 1)]))  # 2 goes as yellow 0 comes
    assert [(r.team, r.id) for r in m.snapshot().robots] == [("yellow", 0)]
    m.update(frame(0, 8.1, [RawRobot("blue", 9, 0, 0, 0, 1), RawRobot("blue", 3, 9, 0, 0, 1)]))
    assert [(r.team, r.id) for r in m.snapshot().robots] == [("blue", 3), ("blue", 9),
                                                             ("yellow", 0)]


def _scene(m: WorldModel, steps: int, every: int = 1) -> list[WorldState]:
    """Robots coming, seen by one or two of three cameras, one leaving the view (predicted,
    lost, dropped) and coming back; a snapshot after every ``every`` frames."""
    out = []
    for k in range(steps):
        t = 100.0 + k * 0.005
        cam = k % 3
        dets = [RawRobot("blue", i, 300.0 * i + 20.0 * t, 50.0 * cam, 0.1 * k, 0.9)
                for i in range(4) if (i + k) % 3 != 0 or i == 0]
        if k < 40 or k > 800:  # yellow 5 leaves for 3.8 s (predicted, lost, dropped) and comes back
            dets.append(RawRobot("yellow", 5, -1000.0, 10.0 * cam, 0.0, 0.9))
        if k > 300:  # a robot comes later
            dets.append(RawRobot("yellow", 1, -2000.0, 0.0, 0.0, 0.9))
        m.update(frame(cam, t, dets))
        if k % every == 0:
            out.append(m.snapshot())
    return out


def test_a_snapshot_builds_only_what_changed_and_equals_one_built_afresh() -> None:
    """While every robot was seen lately, a snapshot copies the last one's robots and builds
    those a camera saw since: the same world as the full pass over every robot (which
    ``_states = None`` forces), with the unchanged robots' states shared."""
    fast, full = WorldModel(), WorldModel()
    orig = full.snapshot

    def afresh(now: float | None = None) -> WorldState:
        full._states = None
        return orig(now)

    full.snapshot = afresh  # type: ignore[method-assign]
    for every in (1, 2):
        a, b = _scene(fast, 900, every), _scene(full, 900, every)
        assert a == b
        assert any(r.predicted for w in a for r in w.robots)
        assert any(r.lost for w in a for r in w.robots)
        assert any(len(w.robots) == 5 for w in a) and any(len(w.robots) == 6 for w in a)
        fast, full = WorldModel(), WorldModel()
        orig = full.snapshot
        full.snapshot = afresh  # type: ignore[method-assign]
    shared = 0
    worlds = _scene(WorldModel(), 200)
    for w0, w1 in pairwise(worlds):
        if len(w0.robots) == len(w1.robots):
            shared += sum(r0 is r1 for r0, r1 in zip(w0.robots, w1.robots, strict=True))
    assert shared > 0


def test_the_index_of_a_world_finds_each_robot() -> None:
    """``WorldState.index`` (the model's, read by control): every robot at its place, through
    arrivals and departures; ``robot()`` answers the same with and without it."""
    for w in _scene(WorldModel(), 900, 3):
        assert w.index is not None and len(w.index) == len(w.robots)
        for key, i in w.index.items():
            assert (w.robots[i].team, w.robots[i].id) == key
        plain = replace(w, index=None)
        for key in [("blue", 0), ("yellow", 5), ("yellow", 1), ("blue", 7)]:
            assert w.robot(*key) is plain.robot(*key)


def test_the_ball_state_is_kept_while_nothing_new_came_and_moves_when_predicted() -> None:
    m = WorldModel()
    for k in range(10):
        m.update(frame(0, 100.0 + 0.01 * k, balls=[RawBall(100.0 * k, 0.0, 0.9)]))
    b = m.snapshot().ball
    assert b is not None and not b.predicted
    m.update(frame(1, 100.095, [RawRobot("blue", 1, -3000.0, 0.0, 0.0, 0.9)]))  # no ball
    same = m.snapshot().ball
    assert same is b  # seen lately, not measured since: the same state
    m.update(frame(0, 100.1, balls=[RawBall(1000.0, 0.0, 0.9)]))
    new = m.snapshot().ball
    assert new is not b and new is not None and new.t_seen == 100.1
    # not seen for longer than predict_after_s: extrapolated to the newest capture time
    m.update(frame(1, 100.2, [RawRobot("blue", 1, -3000.0, 0.0, 0.0, 0.9)]))
    p1 = m.snapshot().ball
    m.update(frame(1, 100.21, [RawRobot("blue", 1, -3000.0, 0.0, 0.0, 0.9)]))
    p2 = m.snapshot().ball
    assert p1 is not None and p2 is not None and p1.predicted and p2.predicted
    assert p2.x > p1.x > new.x
