"""World model + filter cost per camera frame (22 robots and a ball), and the CPU share at
8 cameras x 75 Hz, for each filter kind (best of --reps interleaved runs). Not a test: prints
numbers. Times are this process's CPU time (``time.process_time``): on a shared machine the wall
clock also counts the other processes' turns, which made two kinds' figures differ by more than
the kinds do.

    .venv/bin/python -m bench.world_bench [--kinds kalman adaptive] [--reps 7]
"""

from __future__ import annotations

import argparse
import math
import random
import time

from backend.filters import FILTER_KINDS, FilterSettings
from backend.world.model import WorldModel
from backend.world.state import CameraFrame, RawBall, RawRobot

CAMERAS, HZ = 8, 75.0


def frames(n: int, seed: int = 1) -> list[CameraFrame]:
    """n frames from 8 unsynchronised cameras, each seeing all 22 robots and the ball (the
    worst case: every object in every frame), false balls p=0.2 (half on a robot)."""
    rng = random.Random(seed)
    out = []
    phases = [rng.uniform(0, 1 / HZ) for _ in range(CAMERAS)]
    k = 0
    while len(out) < n:
        for cam in range(CAMERAS):
            t = 1000.0 + k / HZ + phases[cam]
            robots = []
            for i in range(22):
                team = "blue" if i < 11 else "yellow"
                a = 0.3 * t + i
                robots.append(RawRobot(team, i % 11, 3000 * math.cos(a) + rng.gauss(0, 2),
                                       2000 * math.sin(a) + rng.gauss(0, 2),
                                       math.atan2(math.sin(a), math.cos(a)), 0.9))
            balls = [RawBall(1000 * math.cos(t), 500 * math.sin(t), 0.9)]
            if rng.random() < 0.2:
                r = rng.choice(robots)
                balls.append(RawBall(r.x + 5, r.y - 5, 0.95) if rng.random() < 0.5
                             else RawBall(rng.uniform(-4500, 4500), rng.uniform(-3000, 3000), 0.8))
            out.append(CameraFrame(cam, k, t, t, int(t * 1e9), tuple(balls), tuple(robots)))
        k += 1
    return out[:n]


def _run(kind: str, fs: list[CameraFrame]) -> tuple[float, float]:
    m = WorldModel(filters=FilterSettings(ball=kind, robot=kind))
    for f in fs[:600]:  # warm up
        m.update(f)
    clock = time.process_time
    t0 = clock()
    for f in fs[600:]:
        m.update(f)
    upd = (clock() - t0) / (len(fs) - 600)
    t0 = clock()
    for _ in range(500):
        m.snapshot()
    return upd, (clock() - t0) / 500


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--kinds", nargs="*", default=list(FILTER_KINDS), choices=FILTER_KINDS)
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args()
    fs = frames(6000)
    reps = a.reps
    print(f"{len(fs)} frames, 22 robots + ball in every frame, {CAMERAS} cameras x {HZ:g} Hz; "
          f"best of {reps} interleaved repetitions, CPU time")
    print(f"{'filter':8} {'update us/frame':>16} {'snapshot us':>12} "
          f"{'CPU at 8x75 Hz (1 snapshot per frame)':>40}")
    best: dict[str, tuple[float, float]] = {}
    for _ in range(reps):
        for kind in a.kinds:
            upd, snap = _run(kind, fs)
            b = best.get(kind, (math.inf, math.inf))
            best[kind] = (min(b[0], upd), min(b[1], snap))
    for kind in a.kinds:
        upd, snap = best[kind]
        per_s = CAMERAS * HZ * (upd + snap)
        print(f"{kind:8} {upd * 1e6:16.0f} {snap * 1e6:12.0f} "
              f"{100 * per_s:30.1f} % of a core")


if __name__ == "__main__":
    main()
