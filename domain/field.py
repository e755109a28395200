"""The field: sizes in mm under the names of the SSL rules and the SSL-Vision geometry packet,
the defaults of division A and B, and the shapes the rules refer to (defence areas, penalty
mark). A geometry packet, when there is one, says the sizes (:meth:`Field.from_geometry`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from .rules import BALL_RADIUS_MM, ROBOT_RADIUS_MM

#: The penalty mark's distance from the goal centre (the ssl-game-controller's default
#: geometry): 8 m in division A, 6 m in division B
PENALTY_MARK_DISTANCE_MM = {"A": 8000.0, "B": 6000.0}


@dataclass(frozen=True)
class Field:
    """Sizes of one field in mm (the SSL rules' names)."""

    field_length: float
    field_width: float
    goal_width: float
    goal_depth: float = 180.0
    boundary_width: float = 300.0
    penalty_area_depth: float = 1000.0
    penalty_area_width: float = 2000.0
    center_circle_radius: float = 500.0
    line_thickness: float = 10.0
    goal_height: float = 155.0
    ball_radius: float = BALL_RADIUS_MM
    max_robot_radius: float = ROBOT_RADIUS_MM
    penalty_mark_distance: float = 6000.0  # from the goal centre

    @property
    def half_length(self) -> float:
        return self.field_length / 2.0

    @property
    def half_width(self) -> float:
        return self.field_width / 2.0

    @property
    def wall_x(self) -> float:
        """x of the outer wall (field edge plus boundary)."""
        return self.half_length + self.boundary_width

    @property
    def wall_y(self) -> float:
        """y of the outer wall."""
        return self.half_width + self.boundary_width

    @classmethod
    def from_geometry(cls, g: Mapping[str, Any] | None, fallback: Field | None = None) -> Field:
        """From the decoded geometry packet (``backend.world.decode.geometry_to_dict``); a size
        missing, not a number, not finite or not positive keeps ``fallback``'s, by default
        the division whose field length is nearer the packet's (grSim's 12 x 9 m field sends
        no penalty mark: division A's 8 m, not B's 6 m)."""
        if not g:
            return fallback or DIVISION_B
        changes: dict[str, float] = {}
        for name, key in (("field_length", "field_length"), ("field_width", "field_width"),
                          ("goal_width", "goal_width"), ("goal_depth", "goal_depth"),
                          ("boundary_width", "boundary_width"),
                          ("penalty_area_depth", "penalty_area_depth"),
                          ("penalty_area_width", "penalty_area_width"),
                          ("center_circle_radius", "center_circle_radius"),
                          ("ball_radius", "ball_radius"),
                          ("max_robot_radius", "max_robot_radius"),
                          ("penalty_mark_distance", "goal_center_to_penalty_mark")):
            v = g.get(key)
            if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) \
                    and v > 0:
                changes[name] = float(v)
        base = fallback
        if base is None:
            length = changes.get("field_length", DIVISION_B.field_length)
            base = DIVISION_A if abs(length - DIVISION_A.field_length) \
                < abs(length - DIVISION_B.field_length) else DIVISION_B
        return replace(base, **changes) if changes else base

    def defense_rect(self, side: int) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1) of the defence area in front of the goal at x = side * half_length
        (+1 / -1)."""
        hl, d, hw = self.half_length, self.penalty_area_depth, self.penalty_area_width / 2.0
        if side > 0:
            return (hl - d, hl, -hw, hw)
        return (-hl, -hl + d, -hw, hw)

    def dist_to_defense_area(self, x: float, y: float, side: int) -> float:
        """0 inside the defence area of ``side``, else the distance to it."""
        x0, x1, y0, y1 = self.defense_rect(side)
        return math.hypot(max(x0 - x, 0.0, x - x1), max(y0 - y, 0.0, y - y1))

    def in_field(self, x: float, y: float) -> bool:
        return abs(x) <= self.half_length and abs(y) <= self.half_width

    def penalty_mark(self, defending_side: int) -> tuple[float, float]:
        """The penalty mark in front of the goal defended on ``defending_side`` (+1 / -1)."""
        return (defending_side * (self.half_length - self.penalty_mark_distance), 0.0)


#: Division A (SSL rules 2022+): 12 x 9 m, goal 1.8 m, defence area 1.8 m deep, 3.6 m wide
DIVISION_A = Field(12000.0, 9000.0, 1800.0, penalty_area_depth=1800.0,
                   penalty_area_width=3600.0,
                   penalty_mark_distance=PENALTY_MARK_DISTANCE_MM["A"])
#: Division B: 9 x 6 m, goal 1 m, defence area 1 m deep, 2 m wide
DIVISION_B = Field(9000.0, 6000.0, 1000.0, penalty_mark_distance=PENALTY_MARK_DISTANCE_MM["B"])


def division(name: str) -> Field:
    """The default field of division "A" or "B"."""
    if name == "A":
        return DIVISION_A
    if name == "B":
        return DIVISION_B
    raise ValueError(f"unknown division {name!r}")
