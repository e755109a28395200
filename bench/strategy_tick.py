"""Strategy tick cost: world -> situation -> play -> roles -> paths, 6 v 6 and 11 v 11.

Runs ``StrategyCore.prepare`` + ``decide`` (what the StrategyProcessor does each tick,
without the engine call) on random but fixed-seed scenes, in running play, STOP and the
other team's ball placement (the expensive cases: every robot plans around the ball or a
corridor). Prints median and p99 per tick in ms.
"""

from __future__ import annotations

import math
import random
import statistics
import time

from backend.params.model import StrategyParams
from backend.strategy.core import StrategyCore
from backend.world.referee import RefereeState
from backend.world.state import BallState, RobotState, WorldState

GEOM_B = {"field_length": 9000.0, "field_width": 6000.0, "goal_width": 1000.0,
          "goal_depth": 180.0, "penalty_area_depth": 1000.0, "penalty_area_width": 2000.0}
GEOM_A = {"field_length": 12000.0, "field_width": 9000.0, "goal_width": 1800.0,
          "goal_depth": 180.0, "penalty_area_depth": 1800.0, "penalty_area_width": 3600.0}


def scene(n: int, rnd: random.Random, geom: dict[str, float]) -> WorldState:
    hl, hw = geom["field_length"] / 2 - 300, geom["field_width"] / 2 - 300
    robots = [RobotState(team, i, rnd.uniform(-hl, hl), rnd.uniform(-hw, hw),
                         rnd.uniform(-math.pi, math.pi))
              for team in ("blue", "yellow") for i in range(n)]
    ball = BallState(rnd.uniform(-hl, hl), rnd.uniform(-hw, hw), rnd.uniform(-2000, 2000),
                     rnd.uniform(-2000, 2000))
    return WorldState(0.0, 0, ball, tuple(robots))


def referee(command: str, designated: tuple[float, float] | None = None) -> RefereeState:
    team = {"goalkeeper": 0}
    return RefereeState(command, "NORMAL_FIRST_HALF", 1, None, team, team, designated, None, 0)


def run(n: int, geom: dict[str, float], ref: RefereeState | None, ticks: int = 300) -> list[float]:
    rnd = random.Random(n)
    core = StrategyCore()
    params = StrategyParams(play="match")
    worlds = [scene(n, rnd, geom) for _ in range(20)]
    times = []
    for k in range(ticks):
        t0 = time.perf_counter()
        prep = core.prepare(worlds[k % len(worlds)], geom, ref, params, "blue", True, True,
                            k * 0.05)
        core.decide(prep)
        times.append((time.perf_counter() - t0) * 1000.0)
    return times


def main() -> None:
    cases = [("running", None), ("STOP", referee("STOP")),
             ("their placement", referee("BALL_PLACEMENT_YELLOW", (0.0, 0.0)))]
    print(f"{'team':>7} {'situation':>16} {'median ms':>10} {'p99 ms':>8}")
    for n, geom in ((6, GEOM_B), (11, GEOM_A)):
        for name, ref in cases:
            ts = sorted(run(n, geom, ref))
            p99 = ts[min(len(ts) - 1, int(0.99 * len(ts)))]
            print(f"{n:>3} v {n:<3} {name:>16} {statistics.median(ts):>10.2f} {p99:>8.2f}")


if __name__ == "__main__":
    main()
