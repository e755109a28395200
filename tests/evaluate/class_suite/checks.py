"""This suite's own check (a team writes its own the same way: docs/evaluate.md)."""

from __future__ import annotations

import numpy as np

from evaluate.checks import Result
from evaluate.record import RVX, RVY, Run


def stopped(run: Run, robot: int, below_mps: float = 0.2) -> Result:
    """Robot ``robot`` of ours slower than ``below_mps`` at the end of the run. Value: its
    last speed."""
    r = run.robot("ours", robot)
    speed = float(np.hypot(r[-1, RVX], r[-1, RVY]))
    ok = speed < below_mps
    return Result(ok, 1.0 if ok else 0.0,
                  f"{'stopped' if ok else 'still moving'}: {speed:.2f} m/s at the end",
                  speed, "m/s")
