"""In-process, faster-than-real-time drive of fieldsim with Touchline's controllers.

fieldsim's pure core (``World``) runs at its physics rate; its ``Vision`` model produces the
4 unsynchronised 60 Hz camera frames with Gaussian noise and misses; the controllers run at
``control_hz`` on the newest detection of each robot (no filter: raw noisy positions, as a
worst case), and every command reaches the robot ``latency_s`` later.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

from backend.control.goto import Target
from backend.control.motion import RobotMotionState, make_controller
from backend.control.params import AlgorithmName, ControllerParams
from fieldsim.config import SimConfig
from fieldsim.vision import Vision
from fieldsim.world import Team, World


@dataclass
class Case:
    algorithm: AlgorithmName
    generation: int
    gains: list[float] | None
    seed: int = 1
    robots: int = 6
    distance_m: float = 3.0
    legs: int = 3  # A->B, B->A, A->B ...: the C estimate carries over between legs
    leg_s: float = 8.0
    control_hz: float = 60.0
    latency_s: float = 0.03
    params: ControllerParams = field(default_factory=ControllerParams)


@dataclass
class RobotTrace:
    rid: int
    gain: float
    t: list[float] = field(default_factory=list)  # physics time, s
    x: list[float] = field(default_factory=list)  # true field x, m
    y: list[float] = field(default_factory=list)
    tc: list[float] = field(default_factory=list)  # control tick times
    c_est: list[float] = field(default_factory=list)
    ref_x: list[float] = field(default_factory=list)  # reference along the line (Algorithm 1)
    cmd_speed: list[float] = field(default_factory=list)


@dataclass
class CaseResult:
    case: Case
    start_x: float
    traces: list[RobotTrace]
    controller_s: float = 0.0  # wall time spent in controller.step
    ticks: int = 0


def run_case(case: Case) -> CaseResult:
    import time

    cfg = SimConfig(seed=case.seed, generation=case.generation, gains=case.gains,
                    blue=case.robots, yellow=0, cameras=4)
    world = World(cfg)
    vision = Vision(cfg, world.geometry)
    x_a, x_b = -3.5, -3.5 + case.distance_m
    ys = [-2.5 + 5.0 * i / max(1, case.robots - 1) for i in range(case.robots)]
    for rid, y in enumerate(ys):
        world.teleport_robot(Team.BLUE, rid, x_a, y, 0.0)
    ctrls = [make_controller(case.algorithm, case.params) for _ in ys]
    traces = [RobotTrace(rid, world.gain_of(Team.BLUE, rid)) for rid in range(case.robots)]
    latest: dict[int, tuple[float, float, float, float]] = {}  # id -> x mm, y mm, th, t
    cam_next = [vision.phases[c] for c in range(len(vision.cameras))]
    cam_period = 1.0 / cfg.camera_hz
    ctl_period = 1.0 / case.control_hz
    ctl_next = 0.0
    last_ctl = 0.0
    pending: deque[tuple[float, int, float, float, float]] = deque()
    t_end = case.legs * case.leg_s
    spent = 0.0
    ticks = 0
    while world.t < t_end:
        t = world.t
        leg = min(case.legs - 1, int(t / case.leg_s))
        goal_x = x_b if leg % 2 == 0 else x_a
        for c, due in enumerate(cam_next):
            if t >= due:
                pkt = vision.detect(c, world, t)
                for det in pkt.detection.robots_blue:
                    latest[det.robot_id] = (det.x, det.y, det.orientation, t)
                cam_next[c] = due + cam_period
        if t >= ctl_next:
            dt = t - last_ctl if ticks else ctl_period
            last_ctl = t
            ctl_next += ctl_period
            for rid, ctrl in enumerate(ctrls):
                seen = latest.get(rid)
                if seen is None or t - seen[3] > 0.1:
                    state = RobotMotionState(0.0, 0.0, 0.0, visible=False)
                else:
                    state = RobotMotionState(seen[0], seen[1], seen[2])
                tgt = Target(goal_x * 1000.0, ys[rid] * 1000.0, 0.0)
                t0 = time.perf_counter()
                v = ctrl.step(state, tgt, dt)
                spent += time.perf_counter() - t0
                pending.append((t + case.latency_s, rid, v.forward_mps, v.left_mps,
                                v.angular_radps))
                tel = ctrl.telemetry()
                tr = traces[rid]
                tr.tc.append(t)
                tr.c_est.append(tel["c_estimate"])
                tr.ref_x.append(tel["ref_x_m"])
                tr.cmd_speed.append(tel["cmd_speed_mps"])
            ticks += 1
        while pending and pending[0][0] <= t + 1e-9:
            _, rid, fwd, left, ang = pending.popleft()
            world.set_command(Team.BLUE, rid, fwd, left, ang)
        world.step()
        if world.stats.steps % 2 == 0:
            for rid, tr in enumerate(traces):
                r = world.robot(Team.BLUE, rid)
                assert r is not None
                tr.t.append(world.t)
                tr.x.append(r.x)
                tr.y.append(r.y)
    return CaseResult(case, x_a, traces, spent, ticks * len(ctrls))


@dataclass
class LegMetrics:
    arrival_s: list[float | None]  # first time within 20 mm of the goal, from leg start
    settle_s: list[float | None]  # from then on within 20 mm until the leg ends
    overshoot_mm: list[float]
    final_error_mm: list[float]

    @property
    def arrival_spread_s(self) -> float | None:
        a = self.arrival_s
        if any(v is None for v in a):
            return None
        vals = [v for v in a if v is not None]
        return max(vals) - min(vals)


def leg_metrics(res: CaseResult, leg: int, tol_m: float = 0.02) -> LegMetrics:
    case = res.case
    x_a = res.start_x
    x_b = x_a + case.distance_m
    start_x, goal_x = (x_a, x_b) if leg % 2 == 0 else (x_b, x_a)
    sign = 1.0 if goal_x > start_x else -1.0
    t0, t1 = leg * case.leg_s, (leg + 1) * case.leg_s
    ys = [-2.5 + 5.0 * i / max(1, case.robots - 1) for i in range(case.robots)]
    out = LegMetrics([], [], [], [])
    for tr, gy in zip(res.traces, ys, strict=True):
        arrival: float | None = None
        settle: float | None = None
        over = 0.0
        last_err = math.inf
        for t, x, y in zip(tr.t, tr.x, tr.y, strict=True):
            if not t0 < t <= t1:
                continue
            err = math.hypot(goal_x - x, gy - y)
            along = (x - start_x) * sign
            over = max(over, (along - case.distance_m) * 1000.0)
            if err <= tol_m:
                if arrival is None:
                    arrival = t - t0
                if settle is None:
                    settle = t - t0
            else:
                settle = None
            last_err = err
        out.arrival_s.append(arrival)
        out.settle_s.append(settle)
        out.overshoot_mm.append(over)
        out.final_error_mm.append(last_err * 1000.0)
    return out
