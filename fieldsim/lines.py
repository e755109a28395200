"""The field lines for the ball: goals and ball out, as a linesman sees them.

A ball fully over the goal line between the posts (centre beyond the line by its radius,
``|y| < goal_width / 2``, below the goal height) is a goal; fully over a touch line, or over a
goal line outside the goal (or above it), it is out. One call per ball crossing: re-armed once
the ball centre is back inside the field lines (or the ball is placed). Where it crossed is the
point where the ball centre left the field lines (projected onto the line if that is unknown).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fieldsim.bodies import Ball
from fieldsim.shapes import clamp


@dataclass(frozen=True)
class Call:
    """A goal ("goal", with ``side``) or a ball out ("ball_out", with ``line``) at (x, y) mm."""

    kind: str
    fields: dict[str, Any]


class LineJudge:
    """Remembers where the ball left the field and whether that was called already."""

    def __init__(self, half_length: float, half_width: float, goal_half_width: float,
                 goal_height: float, ball_radius: float) -> None:
        self._hl, self._hw = half_length, half_width
        self._goal_hw, self._goal_height = goal_half_width, goal_height
        self._r = ball_radius
        self.ball_in_goal: str | None = None  # "positive" / "negative": the x side
        self._out_reported = False  # ball_out / goal raised, not yet back in the field
        self._crossed: tuple[str, float, float] | None = None  # line, x, y where it left

    def in_field(self, x: float, y: float) -> bool:
        """Ball centre inside the field lines (re-arms ball_out / goal)."""
        return abs(x) <= self._hl and abs(y) <= self._hw

    def placed(self, x: float, y: float) -> None:
        """The ball was put at (x, y): no goal pending; a ball placed outside the field raises
        nothing until it has been back inside."""
        self.ball_in_goal = None
        self._crossed = None
        self._out_reported = not self.in_field(x, y)

    def check(self, x0: float, y0: float, ball: Ball) -> Call | None:
        """The call for a ball that moved from (x0, y0) this step, if any."""
        x, y = ball.x, ball.y
        if self.in_field(x, y):
            self._out_reported = False
            self.ball_in_goal = None
            return None
        if self.in_field(x0, y0):
            self._crossed = self._exit_point(x0, y0, x, y)
        if self._out_reported:
            return None
        r = self._r
        over_goal_line = abs(x) > self._hl + r
        over_touch_line = abs(y) > self._hw + r
        if not (over_goal_line or over_touch_line):
            return None
        self._out_reported = True
        if over_goal_line and abs(y) < self._goal_hw and ball.z < self._goal_height:
            side = "positive" if x > 0 else "negative"
            self.ball_in_goal = side
            cx, cy = self._crossing("goal", x, y)
            return Call("goal", {"side": side, "x": cx * 1000.0, "y": cy * 1000.0})
        if over_goal_line and over_touch_line:
            line = self._crossed[0] if self._crossed is not None else "goal"
        else:
            line = "goal" if over_goal_line else "touch"
        cx, cy = self._crossing(line, x, y)
        return Call("ball_out", {"line": line, "x": cx * 1000.0, "y": cy * 1000.0})

    def _exit_point(self, x0: float, y0: float, x1: float, y1: float) -> tuple[str, float, float]:
        """Where the segment from inside the field lines to outside leaves them, and the line."""
        tx = ty = math.inf
        if abs(x1) > self._hl:
            tx = (math.copysign(self._hl, x1) - x0) / (x1 - x0)
        if abs(y1) > self._hw:
            ty = (math.copysign(self._hw, y1) - y0) / (y1 - y0)
        line, t = ("goal", tx) if tx <= ty else ("touch", ty)
        return line, x0 + t * (x1 - x0), y0 + t * (y1 - y0)

    def _crossing(self, line: str, x: float, y: float) -> tuple[float, float]:
        """The point on ``line`` where the ball left the field (projected if unknown)."""
        if self._crossed is not None and self._crossed[0] == line:
            return self._crossed[1], self._crossed[2]
        if line == "goal":
            return math.copysign(self._hl, x), clamp(y, -self._hw, self._hw)
        return clamp(x, -self._hl, self._hl), math.copysign(self._hw, y)
