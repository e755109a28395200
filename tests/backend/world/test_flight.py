"""Chipped balls and several balls, on fieldsim's truth: fieldsim's World and Vision and the
backend's WorldModel in one process (no sockets). The figures of bench/chip_bench.py come from
the same runs (``python -m bench.chip_bench``)."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from backend.world.decode import decode_detection
from backend.world.flight import FlightTracker, fit_arc
from backend.world.model import WorldModel
from backend.world.state import WorldState
from bench.chip_bench import chip_run
from fieldsim.config import SimConfig
from fieldsim.vision import Vision, WorldClockFrames
from fieldsim.world import World

T0 = 1_700_000_000.0

# -- the fit itself ------------------------------------------------------------------------------


def test_the_arc_fit_recovers_a_flight_from_its_ground_points() -> None:
    """Noise-free detections of a known arc by two cameras: the fit gives it back."""
    cams = {0: (-3000.0, 1500.0, 4000.0), 1: (3000.0, 1500.0, 4000.0)}
    g = 9810.0
    x0, y0, vx, vy, vz = -500.0, 200.0, 2500.0, -400.0, 3000.0
    obs = []
    for i in range(20):
        tau = 0.01 + i / 60.0
        bx, by, bz = x0 + vx * tau, y0 + vy * tau, vz * tau - g * tau * tau / 2
        cam = i % 2
        cx, cy, h = cams[cam]
        k = h / (h - bz)
        obs.append((10.0 + tau, cam, cx + (bx - cx) * k, cy + (by - cy) * k))
    fit = fit_arc(obs, 10.0, cams, g)
    assert fit is not None
    assert fit[0] == pytest.approx((x0, y0, vx, vy, vz), abs=1e-6)
    assert fit[1] < 1e-6
    # a bounce's fit from a known start point
    fixed = fit_arc(obs, 10.0, cams, g, start=(x0, y0))
    assert fixed is not None and fixed[0] == pytest.approx((x0, y0, vx, vy, vz), abs=1e-6)


def test_camera_positions_are_checked() -> None:
    f = FlightTracker()
    f.set_cameras({0: (0.0, 0.0, 4000.0), 1: (0.0, 0.0, math.nan), 2: (1.0, 1.0, -5.0)})
    assert set(f.cameras) == {0}
    f.observe(1.0, 7, 0.0, 0.0)  # a camera with no known position: not used
    assert f.update(None, 1.0) is None


# -- chips on fieldsim's truth ------------------------------------------------------------------

CHIPS = [  # speed m/s, angle deg, heading rad, start (m); division A: the ball stops inside
    (3.0, 45.0, 0.0, (-5.0, 0.5)),
    (4.0, 60.0, math.pi * 0.8, (4.0, -2.0)),
    (4.5, 65.0, 0.0, (-5.5, 0.0)),
]


@pytest.mark.parametrize(("speed", "angle", "heading", "start"), CHIPS)
def test_a_chip_is_recognised_and_followed_in_3d(
        speed: float, angle: float, heading: float, start: tuple[float, float]) -> None:
    new = chip_run(speed, angle, heading, start)
    today = chip_run(speed, angle, heading, start, flight=False)
    assert new.kicks == 1 and new.chips == 1
    vz = speed * math.sin(math.radians(angle))
    flight_s = 2 * vz / 9.81
    # recognised in the first half of the flight
    assert new.t_recognised - new.t_kick < flight_s / 2
    # once recognised: the ground point under the ball and its height (median over the flight)
    assert sorted(new.xy_err)[len(new.xy_err) // 2] < 30.0
    assert sorted(new.z_err)[len(new.z_err) // 2] < 50.0
    # where it lands (the last estimate of the first hop) and where it finally stops
    assert new.land_pred is not None and math.dist(new.land_pred, new.land) < 100.0
    assert new.stop_pred is not None
    stop_err = math.dist(new.stop_pred, new.stop)
    assert stop_err < 300.0
    # today's estimate (the cameras' ground points, a rolling ball): much worse
    assert today.chips == 0
    assert today.stop_pred is None or math.dist(today.stop_pred, today.stop) > 3 * stop_err
    assert sorted(today.z_err)[len(today.z_err) // 2] > 100.0  # z = 0 while it flies
    assert new.other_ball_reports == 0  # the cameras' disagreement is not a second ball


def test_a_chip_the_kick_detector_misses_is_taken_from_rest() -> None:
    """Towards the nadir of the camera that sees it a chip's ground points move slowly (no
    1 m/s jump for the kick detector): the ball leaving rest starts the fit instead."""
    r = chip_run(3.5, 50.0, 0.3, (-5.0, -3.0))
    assert r.kicks == 0 and r.chips == 1
    assert r.land_pred is not None and math.dist(r.land_pred, r.land) < 100.0
    assert r.stop_pred is not None and math.dist(r.stop_pred, r.stop) < 300.0
    off = chip_run(3.5, 50.0, 0.3, (-5.0, -3.0), flight=False)
    assert off.kicks == 0 and off.stop_pred is None  # today: nothing at all


@pytest.mark.parametrize(("speed", "dribble", "seed"), [(1.0, False, 1), (2.0, True, 2)])
def test_a_ball_pushed_or_dribbled_from_rest_is_not_a_chip(
        speed: float, dribble: bool, seed: int) -> None:
    from fieldsim.world import Team

    cfg = SimConfig(blue=1, yellow=0, seed=seed, division="A")
    w = World(cfg)
    w.teleport_robot(Team.BLUE, 0, -1.0, 0.5, 0.4)
    w.teleport_ball(-1.0 + 0.4 * math.cos(0.4), 0.5 + 0.4 * math.sin(0.4))
    v = Vision(cfg, w.geometry)
    model = WorldModel()
    model.set_cameras({c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras})
    worlds = run(w, v, model, 0.3)
    for _ in range(25):  # 2.5 s driving into the ball (and spinning with it when dribbling)
        w.set_command(Team.BLUE, 0, speed, 0.0, 0.8 if dribble else 0.0,
                      dribbler_rpm=1000.0 if dribble else 0.0)
        worlds += run(w, v, model, 0.1)
    assert math.hypot(w.ball.x + 1.0, w.ball.y - 0.5) > 1.0  # the ball did move
    assert model.flight.chips == 0
    assert not any(s.ball is not None and s.ball.flying for s in worlds)


@pytest.mark.parametrize(("speed", "heading", "start", "seed", "noise"), [
    (2.5, 0.0, (-4.0, 1.0), 1, 2.0),
    (2.0, 2.0, (1.0, -3.0), 2, 2.0),
    (3.0, -2.5, (3.0, 2.0), 3, 5.0),
])
def test_a_flat_kick_is_not_a_chip(speed: float, heading: float, start: tuple[float, float],
                                   seed: int, noise: float) -> None:
    r = chip_run(speed, 0.0, heading, start, seed=seed, noise_mm=noise)
    assert r.kicks == 1 and r.chips == 0
    assert max(r.z_err) == 0.0  # never off the ground
    assert r.stop_pred is not None
    # the flight estimate changes nothing for it: the same stop prediction as without it
    off = chip_run(speed, 0.0, heading, start, seed=seed, noise_mm=noise, flight=False)
    assert off.stop_pred == r.stop_pred


def test_without_camera_positions_nothing_flies() -> None:
    cfg = SimConfig(blue=0, yellow=0, noise_mm=0.0, miss_prob=0.0)
    w = World(cfg)
    w.teleport_ball(-1.0, 0.0, 2.0, 0.0, z=0.0, vz=3.0)
    model = WorldModel()
    worlds = run(w, Vision(cfg, w.geometry), model, 1.0)
    assert not any(s.flying_balls or (s.ball is not None and s.ball.flying) for s in worlds)


# -- several balls -------------------------------------------------------------------------------


def run(w: World, v: Vision, model: WorldModel, seconds: float,
        drop: Callable[[float, float], bool] | None = None) -> list[WorldState]:
    """Step fieldsim for ``seconds``, every camera frame into the model (ball detections for
    which ``drop(x, y)`` is true left out); the world after each frame."""
    out = []
    t_end = w.t + seconds
    frames = WorldClockFrames(v, w, T0)
    while w.t < t_end:
        w.step()
        for _, tc, packet in frames.due():
            det = packet.detection
            if drop is not None:
                keep = [b for b in det.balls if not drop(b.x, b.y)]
                del det.balls[:]
                det.balls.extend(keep)
            model.update(decode_detection(det, int((T0 + tc + 0.002) * 1e9)))
            out.append(model.snapshot())
    return out


def near(s: WorldState, x: float, y: float, tol: float = 50.0) -> bool:
    return s.ball is not None and math.hypot(s.ball.x - x, s.ball.y - y) < tol


def test_a_second_ball_is_reported_and_the_played_one_kept() -> None:
    cfg = SimConfig(blue=0, yellow=0, false_prob=0.02)
    w = World(cfg)
    w.teleport_ball(-1.0, -1.0, 0.5, 0.0)  # rolling slowly
    v = Vision(cfg, w.geometry)
    model = WorldModel()
    run(w, v, model, 0.5)
    # a second ball left on the field: reported after a short confirmation, with the camera
    # that sees it; the played one is kept while it keeps being seen
    w.add_ball(1.0, 1.0)
    worlds = run(w, v, model, 2.0)
    assert all(s.ball is not None and s.ball.x < 0 for s in worlds)
    assert all(len(s.other_balls) == 1 for s in worlds[len(worlds) // 4:])
    o = worlds[-1].other_balls[0]
    assert (o.x, o.y) == pytest.approx((1000.0, 1000.0), abs=20.0)
    assert o.cameras == (1,) and o.detections > 60
    # a third one
    w.add_ball(2.0, -2.0)
    worlds = run(w, v, model, 1.0)
    assert all(s.ball is not None and s.ball.x < 0 for s in worlds)
    assert sum(len(s.other_balls) == 2 for s in worlds) > 0.7 * len(worlds)
    # false detections (2 % of frames, anywhere) never become another ball
    assert all(len(s.other_balls) <= 2 for s in worlds)


def test_when_the_played_ball_vanishes_the_other_one_is_taken() -> None:
    cfg = SimConfig(blue=0, yellow=0)
    w = World(cfg)
    w.teleport_ball(-1.0, -1.0)
    v = Vision(cfg, w.geometry)
    model = WorldModel()
    run(w, v, model, 0.5)
    w.add_ball(1.0, 1.0)
    worlds = run(w, v, model, 0.5)
    assert near(worlds[-1], -1000.0, -1000.0) and len(worlds[-1].other_balls) == 1
    # the played ball is picked up (its detections stop): the other one after a short wait
    gone = run(w, v, model, 0.5, drop=lambda x, y: x < 0)
    switched = next(i for i, s in enumerate(gone) if near(s, 1000.0, 1000.0))
    t_switch = gone[switched].t_capture - gone[0].t_capture
    assert 0.03 < t_switch < 0.2
    assert near(gone[-1], 1000.0, 1000.0) and gone[-1].other_balls == ()
    assert model.ball_recoveries == 1


def test_the_world_processor_passes_the_chip_parameters_and_camera_positions() -> None:
    from backend import topics
    from backend.bus import DataBus
    from backend.params.model import StationParams
    from backend.processors.world import WorldProcessor
    from backend.world.decode import geometry_to_dict

    bus = DataBus()
    proc = WorldProcessor(bus)
    p = StationParams()
    p.kicks.chip_restitution = 0.6
    p.kicks.decel_mps2 = 0.5
    proc.configure(p)
    fc = proc.model.flight.config
    assert (fc.enabled, fc.restitution, fc.decel_mm_s2) == (True, 0.6, 500.0)
    p.kicks.chips = False
    proc.configure(p)
    proc.reset()  # a fresh model keeps the parameters
    assert not proc.model.flight.config.enabled and proc.model.flight.config.restitution == 0.6
    # the geometry packet's camera positions reach the model
    cfg = SimConfig()
    v = Vision(cfg, World(cfg).geometry)
    bus.of(topics.GEOMETRY).write(geometry_to_dict(v.geometry_packet().geometry))
    proc._field_from_geometry()
    assert proc.model.flight.cameras == {c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras}


def _ref_launch(ft: FlightTracker, t_now: float) -> float | None:
    """FlightTracker._launch as it was written first (every detection looked at)."""
    cfg = ft.config
    obs = ft._obs
    recent = [o for o in obs if t_now - o[0] <= cfg.recognise_within_s]
    if len(recent) < cfg.min_samples:
        return None
    x0, y0 = recent[0][2], recent[0][3]
    if math.hypot(recent[-1][2] - x0, recent[-1][3] - y0) < cfg.launch_mm:
        return None
    rest = [o for o in recent if o[0] - recent[0][0] <= cfg.rest_s]
    if len(rest) < 3 or rest[-1][0] - rest[0][0] < cfg.rest_s / 2:
        return None
    if any(math.hypot(o[2] - x0, o[3] - y0) > cfg.rest_mm for o in rest):
        return None
    t0 = max(o[0] for o in recent if math.hypot(o[2] - x0, o[3] - y0) <= cfg.rest_mm)
    if t0 <= ft._last_t0 + cfg.rest_s:
        return None
    return t0


def test_launch_from_rest_finds_the_recent_detections_as_a_full_pass_did() -> None:
    """The recent detections by bisection while they are in time order, by a pass when a
    camera's came late, and the rest test in one loop that stops at the first detection away:
    the same answer either way (balls at rest, launched, cameras of one instant out of
    order)."""
    import random

    rng = random.Random(5)
    launches = 0
    for _ in range(60):
        ft = FlightTracker()
        ft.set_cameras({c: (0.0, 0.0, 4000.0) for c in range(4)})
        t = 1.7e9 + rng.uniform(0.0, 1.0)
        t_kick = t + rng.uniform(0.2, 1.5)
        speed = rng.choice([0.0, 3000.0])
        p_late = rng.choice([0.0, 0.005, 0.2])
        for _ in range(300):
            t += rng.choice([0.0, 1 / 300, 1 / 150])
            dt = max(0.0, t - t_kick)
            late = rng.random() < p_late  # a camera of this instant came after another's
            tc = t - (rng.uniform(0.0, 0.05) if late else 0.0)
            ft.observe(tc, rng.randrange(4), 100.0 + speed * dt + rng.gauss(0, 2),
                       rng.gauss(0, 2))
            t_now = t + rng.choice([0.0, 0.001])
            want = _ref_launch(ft, t_now)
            assert ft._launch(t_now) == want
            launches += want is not None
        if rng.random() < 0.3:
            ft.reset()
    assert launches > 0  # (the scenario does launch balls)


def test_launch_asked_again_without_new_detections_answers_as_a_full_pass() -> None:
    """``_launch`` keeps its last answer while nothing it reads changed (the snapshot asks at
    every pass, mostly with no ball detection new): asked again at later times (the recent
    window sliding over the same detections), earlier ones, after a flight's start and after
    a reset, it answers what the first version, every detection looked at, answers."""
    import random

    rng = random.Random(11)
    launches = nones = 0
    for _ in range(40):
        ft = FlightTracker()
        ft.set_cameras({c: (0.0, 0.0, 4000.0) for c in range(4)})
        t = 1.7e9 + rng.uniform(0.0, 1.0)
        t_kick = t + rng.uniform(0.2, 1.0)
        speed = rng.choice([0.0, 3000.0])
        p_late = rng.choice([0.0, 0.0, 0.1])
        for i in range(250):
            t += rng.choice([1 / 150, 1 / 75])
            dt = max(0.0, t - t_kick)
            late = rng.random() < p_late
            tc = t - (rng.uniform(0.0, 0.05) if late else 0.0)
            ft.observe(tc, rng.randrange(4), 100.0 + speed * dt + rng.gauss(0, 2),
                       rng.gauss(0, 2))
            # several passes before the next detection: times on, back, and past the window
            for k, t_now in enumerate((t, t + 0.001, t + 0.2, t + 0.001, t + 0.45, t + 0.6,
                                       t + 0.001)):
                if k == 1 and i % 10 == 9:
                    # a flight started between two passes (what _recognise sets)
                    ft._last_t0 = t - rng.uniform(0.0, 0.3)
                want = _ref_launch(ft, t_now)
                assert ft._launch(t_now) == want
                launches += want is not None
                nones += want is None
        if rng.random() < 0.3:
            ft.reset()
    assert launches > 0 and nones > 0  # (both answers are asked again)
