"""The classroom formations of the ``formation`` play: our robots cycle between formation
points on their own half (the play assigns robots to the points). Pure code: positions are a
function of the formation index, the number of robots and the field."""

from __future__ import annotations

import math
from dataclasses import dataclass

from domain.field import DIVISION_B


@dataclass
class FormationConfig:
    period_s: float = 5.0  # time on each formation
    field_length_mm: float = DIVISION_B.field_length
    field_width_mm: float = DIVISION_B.field_width
    own_half_sign: int = -1  # -1: our goal is at negative x


def _circle(n: int, cx: float, cy: float, r: float) -> list[tuple[float, float]]:
    return [(cx + r * math.cos(2 * math.pi * i / n + math.pi / 2),
             cy + r * math.sin(2 * math.pi * i / n + math.pi / 2)) for i in range(n)]


def _lines(n: int, x0: float, x1: float, w: float) -> list[tuple[float, float]]:
    front = (n + 1) // 2
    back = n - front
    pts = [(x0, -w / 2 + w * (i + 0.5) / front) for i in range(front)]
    pts += [(x1, -w / 2 + w * (i + 0.5) / back) for i in range(back)] if back else []
    return pts


def formation(index: int, n: int, cfg: FormationConfig) -> list[tuple[float, float]]:
    """Formation ``index`` (0..2) for ``n`` robots, in mm, on our half."""
    s = cfg.own_half_sign
    half = cfg.field_length_mm / 2
    usable_w = cfg.field_width_mm * 0.7
    if n == 0:
        return []
    kind = index % 3
    if kind == 0:
        return _circle(n, s * half * 0.45, 0.0, min(1100.0, cfg.field_width_mm * 0.2))
    if kind == 1:
        return _lines(n, s * half * 0.25, s * half * 0.6, usable_w)
    # a diagonal chevron
    pts = []
    dy = min(650.0, usable_w / max(1, n - 1))
    dx = min(450.0, half * 0.35 / max(1.0, (n - 1) / 2))
    for i in range(n):
        k = i - (n - 1) / 2
        pts.append((s * (half * 0.3 + abs(k) * dx), k * dy))
    return pts
