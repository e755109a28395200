"""Controller cost per tick: 11 robots, each algorithm (numbers, not a test).

    .venv/bin/python bench/control_bench.py

Each robot drives back and forth on x' = C u (C from 0.6 to 1.4) at 60 Hz; the time of
``step`` + ``telemetry`` for all 11 robots together is measured per tick.
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.control.goto import Target
from backend.control.motion import RobotMotionState, make_controller
from backend.control.params import ALGORITHMS

ROBOTS = 11
TICKS = 6000  # 100 s at 60 Hz
DT = 1 / 60


def bench(algorithm: str) -> list[float]:
    ctrls = [make_controller(algorithm) for _ in range(ROBOTS)]  # type: ignore[arg-type]
    pos = [[0.0, 300.0 * i, 0.0] for i in range(ROBOTS)]
    gains = [0.6 + 0.8 * i / (ROBOTS - 1) for i in range(ROBOTS)]
    per_tick: list[float] = []
    for k in range(TICKS):
        leg = (k // 360) % 2  # new target every 6 s
        cmds = []
        t0 = time.perf_counter_ns()
        for i, ctrl in enumerate(ctrls):
            x, y, th = pos[i]
            tgt = Target(3000.0 if leg == 0 else 0.0, 300.0 * i, 0.5)
            cmds.append(ctrl.step(RobotMotionState(x, y, th), tgt, DT))
            ctrl.telemetry()
        per_tick.append((time.perf_counter_ns() - t0) / 1e3)
        for i, v in enumerate(cmds):
            x, y, th = pos[i]
            c, s = math.cos(th), math.sin(th)
            g = gains[i] * DT * 1000.0
            pos[i] = [x + g * (v.forward_mps * c - v.left_mps * s),
                      y + g * (v.forward_mps * s + v.left_mps * c),
                      th + gains[i] * v.angular_radps * DT]
    return per_tick


def main() -> None:
    print(f"{ROBOTS} robots, {TICKS} ticks at 60 Hz, step + telemetry for all robots per tick")
    print(f"{'algorithm':<14}{'median us':>10}{'p99 us':>10}{'max us':>10}{'us/robot':>10}"
          f"{'% core @60Hz':>14}")
    for alg in ALGORITHMS:
        bench(alg)  # warm up
        t = sorted(bench(alg))
        med = statistics.median(t)
        p99 = t[int(0.99 * len(t))]
        print(f"{alg:<14}{med:>10.1f}{p99:>10.1f}{t[-1]:>10.1f}{med / ROBOTS:>10.2f}"
              f"{med * 60 / 1e4:>14.3f}")


if __name__ == "__main__":
    main()
