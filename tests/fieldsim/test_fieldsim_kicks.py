"""Kick detection against fieldsim's truth: fieldsim's World and Vision and the backend's
WorldModel in one process (no sockets), a robot kicks, the detected kick is compared with
when fieldsim kicked and where its ball really stops."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest

from backend.world.decode import decode_detection
from backend.world.kick import KickedBall
from backend.world.model import WorldModel
from fieldsim.config import SimConfig
from fieldsim.vision import Vision, WorldClockFrames
from fieldsim.world import Team, World

T0 = 1_700_000_000.0  # Unix s of the simulation's t = 0


@dataclass
class Run:
    t_kick: float  # Unix s of fieldsim's kick
    stop: tuple[float, float]  # mm, where fieldsim's ball stopped
    t_stop: float  # Unix s
    kicks: list[tuple[float, KickedBall]]  # (Unix s of the world, kick) while one is active
    detector_kicks: int


def run(speed: float, heading: float, start: tuple[float, float], seed: int = 1,
        **overrides: object) -> Run:
    cfg = SimConfig(blue=1, yellow=1, seed=seed, **overrides)  # type: ignore[arg-type]
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    w.teleport_robot(Team.YELLOW, 0, 0.0, -2.5, 0.0)
    w.teleport_robot(Team.BLUE, 0, start[0], start[1], heading)
    d = cfg.robot_radius_m + cfg.ball_radius_m + 0.004
    w.teleport_ball(start[0] + d * math.cos(heading), start[1] + d * math.sin(heading))
    model = WorldModel()
    frames = WorldClockFrames(v, w, T0)
    t_kick: float | None = None
    t_stop: float | None = None
    kicks: list[tuple[float, KickedBall]] = []
    while w.t < 30.0:
        if t_kick is None and w.t >= 0.5:
            w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=speed)
        w.step()
        if t_kick is None and w.stats.kicks:
            t_kick = w.t  # the ball leaves with the kick speed from the end of this step
        for _, tc, packet in frames.due():
            model.update(decode_detection(packet.detection, int((T0 + tc + 0.002) * 1e9)))
            world = model.snapshot()
            if world.kicked_ball is not None:
                kicks.append((world.t_capture, world.kicked_ball))
        if t_kick is not None and t_stop is None and math.hypot(w.ball.vx, w.ball.vy) == 0.0:
            t_stop = w.t
        if t_stop is not None and w.t > t_stop + 0.5:
            break
    assert t_kick is not None and t_stop is not None
    return Run(T0 + t_kick, (w.ball.x * 1000, w.ball.y * 1000), T0 + t_stop, kicks,
               model.kicks.kicks)


CASES = [
    (2.0, 0.0, (-3.5, 0.0)),
    (2.5, 0.35, (-3.5, -1.5)),
    (1.5, math.pi * 0.75, (2.0, -1.0)),
    (3.0, -0.6, (-3.5, 2.0)),  # 11 m of roll: stopped by the wall, then ends
]


@pytest.mark.parametrize(("speed", "heading", "start"), CASES)
def test_a_fieldsim_kick_is_detected_and_its_stop_predicted(
        speed: float, heading: float, start: tuple[float, float]) -> None:
    r = run(speed, heading, start)
    assert r.detector_kicks == 1
    assert r.kicks
    t_first, first = r.kicks[0]
    assert first.robot == ("blue", 0)
    assert abs(first.start_t - r.t_kick) < 0.05
    assert t_first - r.t_kick < 0.06  # detected within a few frames
    # the initial velocity, fitted on the kick's first 0.1 s
    settled = next(k for t, k in r.kicks if t - r.t_kick > 0.15)
    assert abs(settled.speed - speed * 1000) < 0.05 * speed * 1000
    assert abs(math.atan2(settled.vy, settled.vx) - heading) < 0.05
    dist = speed ** 2 / (2 * 0.4) * 1000  # the roll the model predicts, mm
    if dist > 6000:
        return  # hits the wall: the prediction is beyond it
    # settled (the initial velocity fitted): within 10 % of the roll of where the ball stops
    for t, k in r.kicks:
        if t - r.t_kick < 0.1:
            continue
        err = math.hypot(k.stop_x - r.stop[0], k.stop_y - r.stop[1])
        assert err < 0.1 * dist, (t - r.t_kick, err, dist)
        assert abs(k.stop_t - r.t_stop) < 0.1 * (r.t_stop - r.t_kick)


def test_a_wall_bounce_ends_a_fieldsim_kick() -> None:
    r = run(3.0, 0.0, (2.5, 0.0))  # 1.9 m to the wall (x = 4.5 + 0.3 boundary ... )
    assert r.detector_kicks == 1
    t_last = r.kicks[-1][0]
    # the ball reaches the wall about (4.8 - 2.62) / 3 s after the kick; the kick ends then
    assert 0.5 < t_last - r.t_kick < 1.2


def test_a_ball_rolling_past_fieldsim_robots_is_not_a_kick() -> None:
    cfg = SimConfig(blue=3, yellow=3, seed=5)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    for i, team in enumerate((Team.BLUE, Team.YELLOW)):
        for rid in range(3):
            # robots facing the ball's path, their centres 160-170 mm from it (kicker reach: 190)
            w.teleport_robot(team, rid, -1.5 + rid * 1.0 + i * 0.5, 0.16 if i else -0.17,
                             -math.pi / 2 if i else math.pi / 2)
    w.teleport_ball(-3.0, 0.0, vx=2.0)
    model = WorldModel()
    frames = WorldClockFrames(v, w, T0)
    while w.t < 4.0:
        w.step()
        for _, tc, packet in frames.due():
            model.update(decode_detection(packet.detection, int((T0 + tc + 0.002) * 1e9)))
            assert model.snapshot().kicked_ball is None
    assert w.ball.x > 1.0 and abs(w.ball.y) < 0.01  # rolled past them all, untouched
    assert w.stats.kicks == 0 and model.kicks.kicks == 0


def measured_errors() -> list[str]:
    """The figures of the report (python -m tests.fieldsim.test_fieldsim_kicks)."""
    out = []
    for speed, heading, start in CASES:
        r = run(speed, heading, start)
        t_first, first = r.kicks[0]
        settled = next(k for t, k in r.kicks if t - r.t_kick > 0.15)
        dist = math.hypot(r.stop[0] - first.start_x, r.stop[1] - first.start_y)
        errs = [(t - r.t_kick, math.hypot(k.stop_x - r.stop[0], k.stop_y - r.stop[1]),
                 k.stop_t - r.t_stop) for t, k in r.kicks]
        at = {lab: min(errs, key=lambda e, x=x: abs(e[0] - x)) for lab, x in
              (("first", 0.0), ("0.1s", 0.1), ("0.5s", 0.5))}
        out.append(f"kick {speed} m/s: found {1000 * (t_first - r.t_kick):.0f} ms after, "
                   f"start_t err {1000 * (first.start_t - r.t_kick):+.1f} ms, "
                   f"speed err {first.speed - speed * 1000:+.0f} mm/s first, "
                   f"{settled.speed - speed * 1000:+.0f} mm/s settled, roll {dist:.0f} mm, "
                   + ", ".join(f"stop err @{lab} {e[1]:.0f} mm / {e[2]:+.2f} s"
                               for lab, e in at.items()))
    return out


if __name__ == "__main__":
    print("\n".join(measured_errors()))
