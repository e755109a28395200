"""Ball possession: which team has the ball, estimated live (a Processor, plotted as
team.possession.ours in the Plots tab and recorded in the session log).

Try changing: NEAR_MM (how close counts as having the ball) or SMOOTHING (how fast the
estimate follows).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from touchline import Game, Processor

TITLE = "Ball possession"
NEAR_MM = 250.0
SMOOTHING = 0.05  #: per tick, how much of the newest look the estimate takes


class Possession(Processor):
    rate_hz = 20.0

    def __init__(self) -> None:
        self.ours = 0.5

    def tick(self, game: Game, inputs: Mapping[str, Any]) -> dict[str, float]:
        ball = game.ball
        if ball is None:
            return {"ours": self.ours, "near_ours_mm": -1.0, "near_theirs_mm": -1.0}

        def nearest(robots: tuple[Any, ...]) -> float:
            return min((math.hypot(r.x - ball.x, r.y - ball.y) for r in robots),
                       default=math.inf)
        d_ours, d_theirs = nearest(game.ours), nearest(game.theirs)
        look = 0.5
        if min(d_ours, d_theirs) < NEAR_MM:
            look = 1.0 if d_ours < d_theirs else 0.0
        self.ours += SMOOTHING * (look - self.ours)
        return {"ours": self.ours,
                "near_ours_mm": d_ours if math.isfinite(d_ours) else -1.0,
                "near_theirs_mm": d_theirs if math.isfinite(d_theirs) else -1.0}

    def keep(self) -> float:
        return self.ours  # a save of this file keeps the estimate

    def restore(self, kept: Any) -> None:
        self.ours = float(kept)
