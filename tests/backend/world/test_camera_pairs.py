"""Camera disagreement: a calibration offset between two cameras, measured on the robots both
see (still ones), per pair and with the sign of b - a."""

from __future__ import annotations

import random

from backend.world.model import WorldModel
from backend.world.state import CameraFrame, RawRobot


def frame(cam: int, t: float, robots: list[RawRobot]) -> CameraFrame:
    return CameraFrame(cam, 0, t, t, int(t * 1e9), (), tuple(robots))


def test_an_offset_between_two_cameras_is_measured_per_pair() -> None:
    rng = random.Random(3)
    m = WorldModel()
    t = 1000.0
    for _ in range(240):
        t += 1 / 60
        noise = lambda: rng.gauss(0.0, 2.0)  # noqa: E731
        # camera 1 sees everything 20 mm further in x and 10 mm lower in y than camera 0;
        # camera 2 agrees with camera 1 and comes first at some instants
        m.update(frame(0, t, [RawRobot("blue", 3, 1000 + noise(), 500 + noise(), 0.0, 0.9)]))
        m.update(frame(1, t + 0.002, [
            RawRobot("blue", 3, 1020 + noise(), 490 + noise(), 0.0, 0.9),
            RawRobot("yellow", 1, -300 + noise(), 40 + noise(), 1.0, 0.9)]))
        m.update(frame(2, t + 0.003, [RawRobot("yellow", 1, -300 + noise(), 40 + noise(),
                                                1.0, 0.9)]))
    pairs = {(p["camera_a"], p["camera_b"]): p for p in m.camera_pairs.view()}
    assert set(pairs) == {(0, 1), (1, 2)}
    p01 = pairs[(0, 1)]
    assert abs(p01["dx_mm"] - 20) < 2 and abs(p01["dy_mm"] + 10) < 2 and p01["samples"] > 200
    p12 = pairs[(1, 2)]
    assert abs(p12["dx_mm"]) < 2 and abs(p12["dy_mm"]) < 2


def test_moving_robots_are_left_out() -> None:
    """Unsynchronised captures of a fast robot are not a calibration offset."""
    m = WorldModel()
    t = 1000.0
    x = 0.0
    for _ in range(120):
        t += 1 / 60
        x += 2000 / 60  # 2 m/s
        m.update(frame(0, t, [RawRobot("blue", 3, x, 0.0, 0.0, 0.9)]))
        m.update(frame(1, t + 0.004, [RawRobot("blue", 3, x + 8.0, 0.0, 0.0, 0.9)]))
    assert all(p["samples"] < 5 for p in m.camera_pairs.view())
