"""Kick detection on synthetic ball tracks: start, kicker, stop prediction, ends."""

from __future__ import annotations

import math
import random

from backend.world.kick import KickConfig, KickDetector, KickedBall, stop_of
from backend.world.state import BallState, RobotState

A = 400.0  # mm/s^2, the detector's default deceleration


def rolling(t: float, t_kick: float, v0: float, p0: tuple[float, float],
            u: tuple[float, float]) -> tuple[float, float]:
    """Ball position: still at p0 until t_kick, then rolling at v0 along u, decelerating."""
    tau = min(max(0.0, t - t_kick), v0 / A)
    s = v0 * tau - A * tau * tau / 2
    return p0[0] + u[0] * s, p0[1] + u[1] * s


def feed(det: KickDetector, track: list[tuple[float, float, float]],
         robots: tuple[RobotState, ...]) -> list[KickedBall | None]:
    out = []
    for t, x, y in track:
        out.append(det.update([(t, x, y)], BallState(x, y, t_seen=t), robots))
    return out


def noisy(ts: list[float], pos: list[tuple[float, float]], sigma: float = 2.0,
          seed: int = 3) -> list[tuple[float, float, float]]:
    rng = random.Random(seed)
    return [(t, x + rng.gauss(0, sigma), y + rng.gauss(0, sigma))
            for t, (x, y) in zip(ts, pos, strict=True)]


KICKER = RobotState("blue", 4, x=-111.5, y=0.0, orientation=0.0)
OTHER = RobotState("yellow", 2, x=-300.0, y=250.0, orientation=0.0)


def test_a_still_ball_kicked_at_4_mps_is_one_kick_by_the_right_robot() -> None:
    t_kick = 1.0041
    ts = [i / 60 for i in range(60 * 12)]
    track = noisy(ts, [rolling(t, t_kick, 4000.0, (0.0, 0.0), (1.0, 0.0)) for t in ts])
    det = KickDetector()
    kicks = feed(det, track, (OTHER, KICKER))
    assert det.kicks == 1
    first = next(i for i, k in enumerate(kicks) if k is not None)
    k = kicks[first]
    assert k is not None and k.robot == ("blue", 4)
    assert ts[first] - t_kick < 0.05  # found within three frames
    assert abs(k.start_t - t_kick) < 0.017
    assert math.hypot(k.start_x, k.start_y) < 30.0
    true_stop = 4000.0 ** 2 / (2 * A)  # 20 m: no wall in a synthetic world
    # once the initial velocity is fitted, the stop point is within 5 % of the model's
    later = [kk for kk in kicks[first:] if kk is not None][10:]
    assert later
    for kk in later[:60]:
        assert abs(kk.stop_x - true_stop) < 0.05 * true_stop, kk
        assert abs(kk.stop_y) < 0.05 * true_stop
        assert abs(kk.speed - 4000.0) < 200.0
        assert abs(kk.stop_t - (t_kick + 10.0)) < 0.5
    assert kicks[-1] is None and det.ended == "stopped"


def test_a_ball_rolling_by_a_robot_is_not_a_kick() -> None:
    ts = [i / 60 for i in range(120)]
    # rolls at 2 m/s along y, passing just in front of the robot
    track = noisy(ts, [rolling(t, 0.0, 2000.0, (0.0, -1000.0), (0.0, 1.0)) for t in ts])
    det = KickDetector()
    kicks = feed(det, track, (KICKER,))
    assert det.kicks == 0 and all(k is None for k in kicks)


def test_a_speed_jump_far_from_any_robot_is_not_a_kick() -> None:
    ts = [i / 60 for i in range(60)]
    track = noisy(ts, [rolling(t, 0.5, 4000.0, (1000.0, 1000.0), (1.0, 0.0)) for t in ts])
    det = KickDetector()
    feed(det, track, (KICKER,))
    assert det.kicks == 0


def test_the_kicker_must_face_the_ball() -> None:
    behind = RobotState("blue", 4, x=-111.5, y=0.0, orientation=math.pi)
    ts = [i / 60 for i in range(60)]
    track = noisy(ts, [rolling(t, 0.5, 4000.0, (0.0, 0.0), (1.0, 0.0)) for t in ts])
    det = KickDetector()
    feed(det, track, (behind,))
    assert det.kicks == 0


def test_a_bounce_off_a_wall_ends_the_kick() -> None:
    wall = 1500.0
    t_kick = 0.3
    ts = [i / 60 for i in range(90)]
    pos = []
    for t in ts:
        x, y = rolling(t, t_kick, 3000.0, (0.0, 0.0), (math.cos(0.3), math.sin(0.3)))
        if x > wall:  # reflected, restitution 0.6
            x = wall - (x - wall) * 0.6
        pos.append((x, y))
    det = KickDetector()
    kicks = feed(det, noisy(ts, pos), (RobotState("blue", 1, -111.5 * math.cos(0.3),
                                                  -111.5 * math.sin(0.3), 0.3),))
    assert det.kicks == 1
    t_bounce = next(ts[i] for i in range(1, len(ts)) if pos[i][0] < pos[i - 1][0])
    active = [t for t, k in zip(ts, kicks, strict=True) if k is not None]
    assert active and active[0] < t_kick + 0.05
    assert t_bounce - 0.05 < active[-1] < t_bounce + 0.06
    assert det.ended in ("ran back", "turned")
    assert kicks[-1] is None


def test_a_lost_ball_ends_the_kick() -> None:
    ts = [i / 60 for i in range(30)]
    track = noisy(ts, [rolling(t, 0.2, 4000.0, (0.0, 0.0), (1.0, 0.0)) for t in ts])
    det = KickDetector()
    kicks = feed(det, track, (KICKER,))
    assert kicks[-1] is not None
    _, x, y = track[-1]
    assert det.update([], BallState(x, y, visible=False, lost=True), (KICKER,)) is None
    assert det.ended == "lost"


def test_stop_prediction_formula() -> None:
    assert stop_of(0.0, 0.0, 3000.0, 4000.0, 10.0, 500.0) == (15000.0, 20000.0, 20.0)
    assert stop_of(1.0, 2.0, 0.0, 0.0, 3.0, 500.0) == (1.0, 2.0, 3.0)


def test_a_second_kick_starts_a_new_one() -> None:
    cfg = KickConfig()
    det = KickDetector(cfg)
    ts = [i / 60 for i in range(90)]
    # kicked at 2 m/s, then at t = 0.8 kicked again by a robot in its path at 5 m/s along y
    pos = []
    for t in ts:
        if t < 0.8:
            pos.append(rolling(t, 0.1, 2000.0, (0.0, 0.0), (1.0, 0.0)))
        else:
            x1, _ = rolling(0.8, 0.1, 2000.0, (0.0, 0.0), (1.0, 0.0))
            pos.append(rolling(t, 0.8, 5000.0, (x1, 0.0), (0.0, 1.0)))
    x1 = pos[ts.index(next(t for t in ts if t >= 0.8)) - 1][0]
    second = RobotState("yellow", 9, x=x1, y=-111.5, orientation=math.pi / 2)
    kicks = feed(det, noisy(ts, pos), (KICKER, second))
    assert det.kicks == 2
    assert kicks[-1] is not None and kicks[-1].robot == ("yellow", 9)
    assert abs(kicks[-1].speed - 5000.0) < 300.0


def test_the_world_processor_passes_the_kick_parameters() -> None:
    from backend.bus import DataBus
    from backend.params.model import StationParams
    from backend.processors.world import WorldProcessor

    proc = WorldProcessor(DataBus())
    p = StationParams()
    p.kicks.decel_mps2 = 0.5
    p.kicks.max_turn_deg = 45.0
    proc.configure(p)
    assert proc.model.kicks.config.decel_mps2 == 0.5
    assert proc.model.kicks.config.max_turn_deg == 45.0
    p.kicks.enabled = False
    proc.configure(p)
    assert not proc.model.kicks_enabled
    proc.reset()  # a fresh model keeps the parameters
    assert proc.model.kicks.config.decel_mps2 == 0.5 and not proc.model.kicks_enabled


def test_the_world_message_kick_matches_the_contract() -> None:
    from pydantic import TypeAdapter

    from backend import contract
    from backend.views import kick_view

    k = KickedBall(("blue", 4), 10.0, -20.0, 100.0, 3000.0, 4000.0, 1e4, 2e4, 112.5)
    v = kick_view(k, 101.0)
    assert v is not None
    TypeAdapter(contract.BallKick).validate_python(v, strict=True)
    assert v["robot"] == {"team": "blue", "id": 4}
    assert v["speed_mps"] == 5.0 and v["stop_in_s"] == 11.5
    assert kick_view(None, 0.0) is None
    anon = kick_view(KickedBall(None, 0, 0, 0, 0, 0, 0, 0, 0), 0.0)
    assert anon is not None and anon["robot"] is None


def test_a_still_ball_with_noisy_vision_in_front_of_a_robot_is_not_kicked() -> None:
    ts = [i / 120 for i in range(120 * 30)]  # 30 s at 120 measurements a second
    for sigma in (2.0, 5.0, 10.0):
        det = KickDetector()
        feed(det, noisy(ts, [(0.0, 0.0)] * len(ts), sigma=sigma, seed=int(sigma)), (KICKER,))
        assert det.kicks == 0, sigma


def _ref_slope(pts: list[tuple[float, float, float]]) -> tuple[float, float] | None:
    """The line fit as it was written first (sums over generators)."""
    n = len(pts)
    if n < 2:
        return None
    tm = sum(p[0] for p in pts) / n
    stt = sum((p[0] - tm) ** 2 for p in pts)
    if stt < 1e-10:
        return None
    xm = sum(p[1] for p in pts) / n
    ym = sum(p[2] for p in pts) / n
    return (sum((p[0] - tm) * (p[1] - xm) for p in pts) / stt,
            sum((p[0] - tm) * (p[2] - ym) for p in pts) / stt)


def _ref_line(pts: list[tuple[float, float, float]]) -> object:
    v = _ref_slope(pts)
    if v is None:
        return None
    n = len(pts)
    tm = sum(p[0] for p in pts) / n
    xm = sum(p[1] for p in pts) / n
    ym = sum(p[2] for p in pts) / n
    ss = sum((p[1] - xm - v[0] * (p[0] - tm)) ** 2 + (p[2] - ym - v[1] * (p[0] - tm)) ** 2
             for p in pts)
    rms = math.sqrt(ss / max(1, 2 * (n - 2))) if n > 2 else 0.0
    t = pts[-1][0]
    return (t, xm + v[0] * (t - tm), ym + v[1] * (t - tm)), v, rms


def _ref_rolling(pts: list[tuple[float, float, float]], decel: float,
                 u: tuple[float, float] | None) -> object:
    """fit_rolling's line fit as the generators summed it, on the points fit_rolling corrects
    (the correction is the detector's own: only the sums are the reference here)."""
    from backend.world import kick

    c = kick._rolling_points(pts, decel, u)
    if c is None:
        return None
    t0, corr = c
    w = _ref_slope(corr)
    if w is None:
        return None
    k = len(corr)
    tm = sum(c[0] for c in corr) / k
    return (t0, sum(c[1] for c in corr) / k - w[0] * tm,
            sum(c[2] for c in corr) / k - w[1] * tm), w


def test_the_line_fits_are_bit_equal_to_the_plain_sums() -> None:
    """The fits sum in plain loops: the same floats, to the bit, as the generators did."""
    from backend.world import kick

    rng = random.Random(11)
    for _ in range(2000):
        n = rng.randint(0, 12)
        t0 = rng.uniform(0.0, 2e9)
        pts = [(t0 + rng.uniform(0.0, 0.2), rng.uniform(-6000, 6000), rng.uniform(-4500, 4500))
               for _ in range(n)]
        if rng.random() < 0.5:
            pts.sort()
        if rng.random() < 0.1 and pts:  # a still ball: every point at one time
            pts = [(pts[0][0], x, y) for _, x, y in pts]
        assert kick._slope(pts) == _ref_slope(pts)
        assert kick._line(pts) == _ref_line(pts)
        u = None if rng.random() < 0.5 else (0.6, -0.8)
        assert kick.fit_rolling(pts, 400.0, u) == _ref_rolling(pts, 400.0, u)
