"""Chipped balls against fieldsim's truth: the world model with and without the flight estimate.

fieldsim's World and Vision and the backend's WorldModel in one process (no sockets): a robot
chips the ball; every world update is compared with fieldsim's ball at the same instant.
Figures per case: when the chip was recognised, the ground position error during the flight
(median and 95th percentile), the height error, the landing point error, and the predicted
stop point's error (the kick's ``stop_x/stop_y`` at 0.3 s after the kick) against where
fieldsim's ball stops. "today" = the flight estimate off (the station before it).

    .venv/bin/python -m bench.chip_bench
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field

from backend.world.decode import decode_detection
from backend.world.model import WorldModel
from fieldsim.config import SimConfig
from fieldsim.vision import Vision, WorldClockFrames
from fieldsim.world import Team, World

T0 = 1_700_000_000.0


@dataclass
class ChipRun:
    t_kick: float = math.nan  # Unix s
    t_land: float = math.nan  # fieldsim's first landing
    land: tuple[float, float] = (math.nan, math.nan)
    stop: tuple[float, float] = (math.nan, math.nan)
    t_recognised: float = math.nan
    xy_err: list[float] = field(default_factory=list)  # mm, in the first flight
    z_err: list[float] = field(default_factory=list)
    xyz_err_flying: list[float] = field(default_factory=list)  # 3D, once recognised
    land_recog: tuple[float, float] | None = None  # predicted at recognition
    land_pred: tuple[float, float] | None = None  # the first hop's, last estimate
    stop_pred: tuple[float, float] | None = None  # the kick's, 0.3 s after the kick
    kicks: int = 0
    chips: int = 0
    other_ball_reports: int = 0
    flying_reports_after: int = 0  # flying=True after the ball rolls (false flight)


def chip_run(speed: float, angle_deg: float, heading: float, start: tuple[float, float],
             flight: bool = True, seed: int = 1, noise_mm: float = 2.0,
             cameras: int = 4, division: str = "A") -> ChipRun:
    cfg = SimConfig(blue=1, yellow=0, seed=seed, noise_mm=noise_mm, cameras=cameras,
                    division=division)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    w.teleport_robot(Team.BLUE, 0, start[0], start[1], heading)
    d = cfg.robot_radius_m + cfg.ball_radius_m + 0.004
    w.teleport_ball(start[0] + d * math.cos(heading), start[1] + d * math.sin(heading))
    model = WorldModel()
    model.flight.config.enabled = flight
    model.set_cameras({c.camera_id: (c.cx, c.cy, c.height) for c in v.cameras})
    out = ChipRun()
    frames = WorldClockFrames(v, w, T0)
    kicked = landed = False
    t_stop: float | None = None
    while w.t < 20.0:
        if not kicked and w.t >= 0.5:
            w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, kick_speed=speed,
                          kick_angle=math.radians(angle_deg))
        vz_before = w.ball.vz
        w.step()
        if not kicked and w.stats.kicks:
            kicked, out.t_kick = True, T0 + w.t
        elif kicked and not landed and w.ball.vz > vz_before:
            landed, out.t_land = True, T0 + w.t
            out.land = (w.ball.x * 1000, w.ball.y * 1000)
        for _, tc, packet in frames.due():
            model.update(decode_detection(packet.detection, int((T0 + tc + 0.002) * 1e9)))
            world = model.snapshot()
            b = world.ball
            out.other_ball_reports += len(world.other_balls)
            if b is None or not kicked:
                continue
            fl = model.flight.flight
            if b.flying and math.isnan(out.t_recognised):
                out.t_recognised = world.t_capture
                if fl is not None:
                    out.land_recog = (fl.land_x, fl.land_y)
            if fl is not None and fl.hop == 0:
                out.land_pred = (fl.land_x, fl.land_y)
            if b.flying and t_stop is not None:
                out.flying_reports_after += 1
            # fieldsim's ball at the world's instant (it is at most a step ahead)
            lag = T0 + w.t - world.t_capture
            tz = w.ball.z - w.ball.vz * lag if w.ball.z > 0 else 0.0
            tx = (w.ball.x - w.ball.vx * lag) * 1000
            ty = (w.ball.y - w.ball.vy * lag) * 1000
            if not landed:
                out.xy_err.append(math.hypot(b.x - tx, b.y - ty))
                out.z_err.append(abs(b.z - tz * 1000))
                if b.flying:
                    out.xyz_err_flying.append(math.hypot(b.x - tx, b.y - ty,
                                                         b.z - tz * 1000))
            k_ = world.kicked_ball
            if k_ is not None and out.stop_pred is None and (
                    world.t_capture - out.t_kick >= 0.3):
                out.stop_pred = (k_.stop_x, k_.stop_y)
        if kicked and t_stop is None and w.ball.z == 0.0 and math.hypot(
                w.ball.vx, w.ball.vy) == 0.0:
            t_stop = w.t
            out.stop = (w.ball.x * 1000, w.ball.y * 1000)
        if t_stop is not None and w.t > t_stop + 0.5:
            break
    out.kicks, out.chips = model.kicks.kicks, model.flight.chips
    return out


# speed m/s, angle deg, heading rad, start (m); division A, every ball stops inside the field
CASES = [
    (3.0, 45.0, 0.0, (-5.0, 0.5)),
    (3.5, 50.0, 0.3, (-5.0, -3.0)),
    (4.0, 60.0, math.pi * 0.8, (4.0, -2.0)),
    (2.5, 30.0, -0.5, (-3.0, 3.0)),
    (4.5, 65.0, 0.0, (-5.5, 0.0)),
    (2.5, 0.0, 0.0, (-4.0, 1.0)),  # flat kicks: no flight may be recognised
    (2.0, 0.0, 2.0, (1.0, -3.0)),
]


def _p(xs: list[float], q: float) -> float:
    if not xs:
        return math.nan
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * len(s)))]


def main() -> None:
    print("speed angle | mode  | recog ms | xy med/p95 mm | z med/p95 mm | 3D recog med/p95 |"
          " land err mm (at recog/last) | stop err mm | chips")
    for speed, angle, heading, start in CASES:
        for flight in (False, True):
            r = chip_run(speed, angle, heading, start, flight=flight)
            recog = (r.t_recognised - r.t_kick) * 1000
            land = (math.dist(r.land_pred, r.land) if r.land_pred is not None else math.nan)
            land0 = (math.dist(r.land_recog, r.land) if r.land_recog is not None else math.nan)
            stop = (math.dist(r.stop_pred, r.stop) if r.stop_pred is not None else math.nan)
            print(f"{speed:4.1f} {angle:4.0f}  | {'new' if flight else 'today':5} | "
                  f"{recog:8.0f} | {statistics.median(r.xy_err):6.0f}/{_p(r.xy_err, 0.95):5.0f}"
                  f" | {statistics.median(r.z_err):5.0f}/{_p(r.z_err, 0.95):5.0f} | "
                  f"{_p(r.xyz_err_flying, 0.5):6.0f}/{_p(r.xyz_err_flying, 0.95):5.0f} | "
                  f"{land0:6.0f}/{land:6.0f} | {stop:11.0f} | {r.chips} (kicks {r.kicks}, "
                  f"others {r.other_ball_reports})")


if __name__ == "__main__":
    main()
