"""fieldsim micro-benchmarks (not a test): physics steps/s and vision encode cost, 11 v 11.

Run from the repository root: PYTHONPATH=. .venv/bin/python bench/fieldsim_bench.py
"""

from __future__ import annotations

import math
import time

from fieldsim.config import SimConfig
from fieldsim.vision import Vision
from fieldsim.world import World


def bench_physics(seconds: float = 2.0) -> float:
    w = World(SimConfig(blue=11, yellow=11))
    t0 = time.perf_counter()
    n = 0
    while time.perf_counter() - t0 < seconds:
        for r in w.robots.values():
            w.set_command(r.team, r.id, 1.0, 0.3 * math.sin(n * 0.01), 0.5)
        for _ in range(10):
            w.step()
        n += 10
    return n / (time.perf_counter() - t0)


def bench_vision(seconds: float = 2.0) -> tuple[float, int]:
    cfg = SimConfig(blue=11, yellow=11, false_prob=0.1)
    w = World(cfg)
    v = Vision(cfg, w.geometry)
    t0 = time.perf_counter()
    n = 0
    size = 0
    while time.perf_counter() - t0 < seconds:
        for k in range(4):
            size = max(size, len(v.detect(k, w, 1.0 + n / 60).SerializeToString()))
            n += 1
    return (time.perf_counter() - t0) / n, size


def main() -> None:
    steps = bench_physics()
    per_frame, size = bench_vision()
    geom = len(Vision(SimConfig(), World().geometry).geometry_packet().SerializeToString())
    print(f"physics 11v11: {steps:,.0f} steps/s ({steps / 200:.1f}x real time at 200 Hz, "
          f"{1e6 / steps:.0f} us/step)")
    print(f"vision frame build+encode 11v11: {per_frame * 1e6:.0f} us/frame, max {size} bytes; "
          f"4 cameras at 60 Hz cost {per_frame * 240 * 100:.1f}% of one core")
    print(f"geometry packet: {geom} bytes")


if __name__ == "__main__":
    main()
