"""Strategy algorithms' cost (not a test): microseconds per call of plan_path and of the
target assignment, median and 99th percentile, at the sizes of a 6 v 6 (division B) and an
11 v 11 (division A) match.

plan_path: each of our robots plans to a random target on the field among every other robot
and the ball (12 or 22 circles) and both defence areas (2 rectangles), inside the field plus
200 mm. Calls are split by outcome: "free" (the straight line is clear: the common case),
"detour" (a search was needed); "tick" is all our robots planned once. Assignment: one
StableAssigner.assign per tick with noisy robot positions, and the bare solvers on random
square matrices.

Usage: PYTHONPATH=. .venv/bin/python bench/strategy_algorithms.py
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.strategy.assignment import (
    StableAssigner,
    bottleneck_assignment,
    min_cost_assignment,
)
from backend.strategy.paths import (
    ROBOT_RADIUS_MM,
    Obstacles,
    defense_area_rects,
    field_bounds,
    plan_path,
)
from domain.field import DIVISION_A, DIVISION_B, Field

BALL_RADIUS_MM = 21.5
CLEARANCE_MM = ROBOT_RADIUS_MM + 30.0


def stats(samples_s: list[float]) -> str:
    us = np.asarray(samples_s) * 1e6
    return f"{np.median(us):9.1f} {np.percentile(us, 99):9.1f} {len(us):6d}"


def random_positions(rng: np.random.Generator, field: Field, n: int) -> np.ndarray:
    hl, hw = field.field_length / 2 - 200, field.field_width / 2 - 200
    return rng.uniform([-hl, -hw], [hl, hw], size=(n, 2))


def bench_paths(per_team: int, field: Field, ticks: int,
                rng: np.random.Generator) -> None:
    rects = defense_area_rects(field)
    bounds = field_bounds(field, 200.0)
    times: dict[str, list[float]] = {"free": [], "detour": [], "tick": []}
    for _ in range(ticks):
        robots = random_positions(rng, field, 2 * per_team)
        ball = random_positions(rng, field, 1)[0]
        targets = random_positions(rng, field, per_team)
        tick = 0.0
        for i in range(per_team):  # robots 0 .. per_team - 1 are ours
            others = np.delete(robots, i, axis=0)
            obs = Obstacles.build(robots=others, circles=[[*ball, BALL_RADIUS_MM]],
                                  rects=rects, bounds=bounds)
            t0 = time.perf_counter()
            res = plan_path(robots[i], targets[i], obs, CLEARANCE_MM)
            dt = time.perf_counter() - t0
            tick += dt
            straight = (len(res.points) == 1 and not res.blocked and not res.goal_moved
                        and not res.start_escape)
            times["free" if straight else "detour"].append(dt)
        times["tick"].append(tick)
    circles = 2 * per_team  # the other robots and the ball
    for kind, samples in times.items():
        label = f"plan_path {per_team:2d} robots, {circles} circles + 2 rects: {kind}"
        print(f"{label:<58} {stats(samples)}")


def bench_assigner(n: int, mode: str, ticks: int, rng: np.random.Generator) -> None:
    field = DIVISION_A if n > 6 else DIVISION_B
    base = random_positions(rng, field, n)
    slots = random_positions(rng, field, n)
    names = [f"slot{j}" for j in range(n)]
    ids = list(range(n))
    sa = StableAssigner(mode)  # type: ignore[arg-type]
    samples = []
    for _ in range(ticks):
        xy = base + rng.normal(0.0, 20.0, size=base.shape)
        t0 = time.perf_counter()
        sa.assign(ids, xy, names, slots, fixed={0: "slot0"})
        samples.append(time.perf_counter() - t0)
    label = f"StableAssigner({mode!r}).assign, {n} robots x {n} slots"
    print(f"{label:<58} {stats(samples)}")


def bench_solver(name: str, fn: Callable[[np.ndarray], np.ndarray], n: int, reps: int,
                 rng: np.random.Generator) -> None:
    samples = []
    for _ in range(reps):
        cost = rng.uniform(0.0, 9000.0, size=(n, n))
        t0 = time.perf_counter()
        fn(cost)
        samples.append(time.perf_counter() - t0)
    print(f"{f'{name} {n}x{n} random':<58} {stats(samples)}")


def main() -> None:
    rng = np.random.default_rng(0)
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"(wall-clock times; machine load average {load})")
    print(f"{'case':<58} {'median us':>9} {'p99 us':>9} {'calls':>6}")
    bench_paths(6, DIVISION_B, 400, rng)
    bench_paths(11, DIVISION_A, 300, rng)
    for n in (6, 11):
        for mode in ("sum", "bottleneck"):
            bench_assigner(n, mode, 2000, rng)
    for n in (6, 11):
        bench_solver("min_cost_assignment", min_cost_assignment, n, 2000, rng)
        bench_solver("bottleneck_assignment", bottleneck_assignment, n, 2000, rng)


if __name__ == "__main__":
    main()
