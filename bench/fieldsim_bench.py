"""fieldsim micro-benchmarks (not a test): physics steps/s and vision encode cost, 11 v 11,
and the whole simulator's CPU as a process at 8 cameras x 75 Hz, division A, 11 v 11 (issue
11: its own cost must not dominate the machine; the robots stand still, nobody commands them).

Run from the repository root: PYTHONPATH=. .venv/bin/python bench/fieldsim_bench.py
    [--process-seconds 15]
"""

from __future__ import annotations

import argparse
import math
import os
import random
import subprocess
import sys
import time
from pathlib import Path

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


def bench_process(seconds: float, cameras: int = 8, hz: float = 75.0) -> float:
    """CPU (% of one core, /proc) of ``python -m fieldsim`` at ``cameras`` x ``hz``, 11 v 11."""
    root = Path(__file__).resolve().parent.parent
    port = random.SystemRandom().randint(20000, 40000)
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldsim", "--division", "A", "--blue", "11", "--yellow", "11",
         "--cameras", str(cameras), "--camera-hz", str(hz), "--vision-port", str(port),
         "--control-port", "0", "--blue-port", "0", "--yellow-port", "0", "--grsim-port", "0",
         "--grsim-status-blue-port", "0", "--grsim-status-yellow-port", "0",
         "--log-level", "WARNING"], cwd=root)
    ticks = os.sysconf("SC_CLK_TCK")

    def cpu() -> float:
        f = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(f[11]) + int(f[12])) / ticks

    try:
        time.sleep(3.0)  # start-up (imports) is not the running cost
        c0, t0 = cpu(), time.monotonic()
        time.sleep(seconds)
        return (cpu() - c0) / (time.monotonic() - t0) * 100
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--process-seconds", type=float, default=15.0)
    a = ap.parse_args()
    steps = bench_physics()
    per_frame, size = bench_vision()
    geom = len(Vision(SimConfig(), World().geometry).geometry_packet().SerializeToString())
    print(f"physics 11v11: {steps:,.0f} steps/s ({steps / 200:.1f}x real time at 200 Hz, "
          f"{1e6 / steps:.0f} us/step)")
    print(f"vision frame build+encode 11v11: {per_frame * 1e6:.0f} us/frame, max {size} bytes; "
          f"4 cameras at 60 Hz cost {per_frame * 240 * 100:.1f}% of one core, "
          f"8 at 75 Hz {per_frame * 600 * 100:.1f}%")
    print(f"geometry packet: {geom} bytes")
    if a.process_seconds > 0:
        print(f"python -m fieldsim, 8 cameras x 75 Hz, division A, 11 v 11: "
              f"{bench_process(a.process_seconds):.1f}% of one core")


if __name__ == "__main__":
    main()
