"""Pure vision: cameras, overlap, noise and fault statistics, determinism, geometry."""

from __future__ import annotations

import math
import statistics

import pytest

from fieldsim.config import SimConfig
from fieldsim.geometry import division_geometry, field_size_message
from fieldsim.vision import Vision
from fieldsim.world import Team, World


def setup(**overrides: object) -> tuple[World, Vision]:
    cfg = SimConfig(**overrides)  # type: ignore[arg-type]
    w = World(cfg)
    return w, Vision(cfg, w.geometry)


def test_frames_per_camera_with_own_counters() -> None:
    w, v = setup()
    numbers: dict[int, list[int]] = {k: [] for k in range(4)}
    for i in range(10):
        for k in range(4):
            p = v.detect(k, w, 1000.0 + i / 60)
            assert p.IsInitialized()
            assert p.detection.camera_id == k
            assert p.detection.t_capture == pytest.approx(1000.0 + i / 60)
            assert p.detection.t_sent >= p.detection.t_capture
            numbers[k].append(p.detection.frame_number)
    for k, nums in numbers.items():
        assert nums == list(range(nums[0], nums[0] + 10)), k
    assert len({nums[0] for nums in numbers.values()}) == 4  # counters are independent
    assert len(set(v.phases)) == 4  # cameras are not synchronised


def test_every_robot_and_ball_seen_by_some_camera() -> None:
    w, v = setup(blue=11, yellow=11, miss_prob=0.0)
    blue, yellow, balls = set(), set(), 0
    for k in range(4):
        d = v.detect(k, w, 1.0).detection
        blue |= {r.robot_id for r in d.robots_blue}
        yellow |= {r.robot_id for r in d.robots_yellow}
        balls += len(d.balls)
    assert blue == set(range(11)) and yellow == set(range(11))
    assert balls >= 1


@pytest.mark.parametrize("pos", [(0.0, 0.0), (0.2, 0.0), (0.0, -0.25), (-0.3, 1.5)])
def test_overlap_near_centre_lines(pos: tuple[float, float]) -> None:
    w, v = setup(miss_prob=0.0)
    w.teleport_ball(*pos)
    seen = [k for k in range(4) if v.detect(k, w, 1.0).detection.balls]
    assert len(seen) >= 2
    if pos == (0.0, 0.0):
        assert len(seen) == 4


def test_far_corner_seen_by_one_camera() -> None:
    w, v = setup(miss_prob=0.0)
    w.teleport_ball(4.0, 2.5)
    seen = [k for k in range(4) if v.detect(k, w, 1.0).detection.balls]
    assert len(seen) == 1


def test_noise_stddev_as_configured() -> None:
    w, v = setup(noise_mm=5.0, noise_rad=0.02, miss_prob=0.0)
    w.teleport_ball(1.0, 1.0)
    w.teleport_robot(Team.BLUE, 0, 2.0, 1.5, 0.3)
    xs, ths = [], []
    for i in range(1500):
        d = v.detect(1, w, i / 60).detection
        xs.append(d.balls[0].x)
        (rob,) = [r for r in d.robots_blue if r.robot_id == 0]
        ths.append(rob.orientation)
    assert statistics.mean(xs) == pytest.approx(1000.0, abs=1.0)
    assert 4.0 < statistics.stdev(xs) < 6.0
    assert 0.016 < statistics.stdev(ths) < 0.024


def test_zero_noise_is_exact() -> None:
    w, v = setup(noise_mm=0.0, noise_rad=0.0, miss_prob=0.0)
    w.teleport_ball(1.0, 1.0)
    d = v.detect(1, w, 1.0).detection
    assert (d.balls[0].x, d.balls[0].y) == (1000.0, 1000.0)


def test_miss_probability() -> None:
    w, v = setup(miss_prob=0.2)
    w.teleport_ball(1.0, 1.0)
    n = 2000
    missed = sum(1 for i in range(n) if not v.detect(1, w, i / 60).detection.balls)
    assert 0.16 < missed / n < 0.24


def test_false_detection_probability() -> None:
    w, v = setup(miss_prob=0.0, false_prob=0.1)
    w.teleport_ball(1.0, 1.0)
    n = 2000
    extra = sum(len(v.detect(1, w, i / 60).detection.balls) - 1 for i in range(n))
    assert 0.07 < extra / n < 0.13
    assert v.false_detections == extra


def test_false_balls_off_by_default() -> None:
    w, v = setup()
    w.teleport_ball(1.0, 1.0)
    assert all(len(v.detect(1, w, i / 60).detection.balls) <= 1 for i in range(500))


def test_deterministic_with_seed() -> None:
    def run(seed: int) -> list[bytes]:
        w, v = setup(seed=seed, false_prob=0.05, generation=1)
        out = []
        for i in range(60):
            for r in w.robots.values():
                w.set_command(r.team, r.id, 1.0, 0.2, 0.5)
            for _ in range(3):
                w.step()
            out.extend(v.detect(k, w, i / 60).SerializeToString() for k in range(4))
        return out

    assert run(5) == run(5)
    assert run(5) != run(6)


def test_pixels_inside_image() -> None:
    w, v = setup(blue=11, yellow=11)
    for k in range(4):
        d = v.detect(k, w, 1.0).detection
        for r in list(d.robots_blue) + list(d.robots_yellow):
            assert 0 <= r.pixel_x <= 1280 and 0 <= r.pixel_y <= 1024


@pytest.mark.parametrize("division", ["A", "B"])
def test_geometry_packet(division: str) -> None:
    _w, v = setup(division=division)
    p = v.geometry_packet()
    assert p.IsInitialized() and not p.HasField("detection")
    f = p.geometry.field
    g = division_geometry(division)
    if division == "B":
        assert (f.field_length, f.field_width, f.goal_width) == (9000, 6000, 1000)
        assert (f.penalty_area_depth, f.penalty_area_width) == (1000, 2000)
        assert f.goal_center_to_penalty_mark == 6000  # the ssl-game-controller's DIV_B mark
    else:
        assert (f.field_length, f.field_width, f.goal_width) == (12000, 9000, 1800)
        assert (f.penalty_area_depth, f.penalty_area_width) == (1800, 3600)
        assert f.goal_center_to_penalty_mark == 8000
    assert (f.goal_depth, f.boundary_width, f.center_circle_radius) == (180, 300, 500)
    names = {line.name for line in f.field_lines}
    assert {"TopTouchLine", "BottomTouchLine", "LeftGoalLine", "RightGoalLine", "HalfwayLine",
            "CenterLine", "LeftPenaltyStretch", "RightPenaltyStretch"} <= names
    assert len(names) == 12
    (arc,) = f.field_arcs
    assert arc.name == "CenterCircle" and arc.a2 == pytest.approx(2 * math.pi)
    top = next(line for line in f.field_lines if line.name == "TopTouchLine")
    assert top.p1.x == -g.half_length and top.p2.x == g.half_length
    assert [c.camera_id for c in p.geometry.calib] == [0, 1, 2, 3]
    assert all(c.derived_camera_world_tz > 0 for c in p.geometry.calib)
    assert field_size_message(g) == f


def test_eight_cameras_cover_the_field_and_overlap() -> None:
    """Division A with 8 cameras: every point of the field (boundary included) is seen by at
    least one camera; points on a column or row border by two or more; each camera has its
    own frame counter; the image of a camera is its rectangle."""
    w, v = setup(cameras=8, division="A", blue=11, yellow=11, miss_prob=0.0)
    cams = v.cameras
    assert [c.camera_id for c in cams] == list(range(8))
    g = w.geometry
    for i in range(41):
        for j in range(31):
            x = -g.wall_x + i * 2 * g.wall_x / 40
            y = -g.wall_y + j * 2 * g.wall_y / 30
            assert any(c.sees(x, y) for c in cams), (x, y)
    quarter = g.wall_x / 2
    for x, y in ((-quarter, 1000.0), (0.0, -1000.0), (quarter, 0.0), (0.0, 0.0)):
        assert sum(c.sees(x, y) for c in cams) >= 2, (x, y)
    assert sum(c.sees(0.0, 0.0) for c in cams) == 4
    w.teleport_ball(-quarter / 1000, 1.0)  # on the border of cameras 0 and 1 (metres)
    seen = [k for k in range(8) if v.detect(k, w, 1.0).detection.balls]
    assert seen == [0, 1]
    blue: set[int] = set()
    firsts = []
    for k in range(8):
        f1 = v.detect(k, w, 2.0).detection
        f2 = v.detect(k, w, 2.0 + 1 / 75).detection
        assert f1.camera_id == k and f2.frame_number == f1.frame_number + 1
        firsts.append(f1.frame_number)
        blue |= {r.robot_id for r in f1.robots_blue}
    assert blue == set(range(11))
    assert len(set(firsts)) == 8


def test_eight_cameras_need_a_valid_count() -> None:
    with pytest.raises(ValueError, match="1, 2, 4 or 8"):
        SimConfig(cameras=6).validate()


def test_cameras_together_share_one_phase_and_keep_their_noise() -> None:
    """``camera_phases="together"``: every camera at phase 0; each camera's random stream is
    the spread configuration's (the same detections for the same calls)."""
    w1, spread = setup(seed=5, cameras=8, division="A", blue=11, yellow=11)
    w2, together = setup(seed=5, cameras=8, division="A", blue=11, yellow=11,
                         camera_phases="together")
    assert len(set(spread.phases)) == 8
    assert together.phases == [0.0] * 8
    for k in range(8):
        assert (spread.detect(k, w1, 10.0).SerializeToString()
                == together.detect(k, w2, 10.0).SerializeToString())
    with pytest.raises(ValueError, match="camera_phases"):
        SimConfig(camera_phases="random").validate()
