"""A play's answer, checked: the plain tuples a worker sends (``worker.plain_orders``, or an
Octave play's matrix) become typed orders, or an ``OrderError`` saying what is wrong (the
play then fails with kind "output"). Checked here, in the station, whatever the worker did:
the structure, finite numbers, robot ids among the play's own, no robot twice."""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import Any


class OrderError(ValueError):
    """The answer is malformed: the message says what and for which robot."""


@dataclass(frozen=True, slots=True)
class TargetOrder:
    """Drive to (x, y) (our frame, mm) with the robot's speed controller."""

    id: int
    x: float
    y: float
    orientation: float | None = None
    max_speed_mps: float | None = None
    kick_mps: float = 0.0
    chip: bool = False
    dribble: bool = False
    avoid: bool = True
    role: str = ""


@dataclass(frozen=True, slots=True)
class VelocityOrder:
    """Drive with this velocity in the robot's frame (m/s, rad/s)."""

    id: int
    forward_mps: float
    left_mps: float
    turn_radps: float
    kick_mps: float = 0.0
    chip: bool = False
    dribble: bool = False
    role: str = ""


Order = TargetOrder | VelocityOrder


def _finite(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise OrderError(f"{what} is {type(v).__name__}, not a number")
    f = float(v)
    if not math.isfinite(f):
        raise OrderError(f"{what} is {f!r}: numbers must be finite")
    return f


def _opt_finite(v: Any, what: str) -> float | None:
    return None if v is None else _finite(v, what)


def _flag(v: Any, what: str) -> bool:
    if not isinstance(v, bool):
        raise OrderError(f"{what} is {type(v).__name__}, not true/false")
    return v


def _mine_text(mine: Collection[int]) -> str:
    return ", ".join(str(i) for i in sorted(mine)) or "none"


def validate_orders(plain: Any, mine: Collection[int]) -> dict[int, Order]:
    """The orders by robot id; ``mine``: the robots this play drives now."""
    if not isinstance(plain, list):
        raise OrderError(f"the answer is {type(plain).__name__}, not a list of orders")
    out: dict[int, Order] = {}
    for item in plain:
        if not isinstance(item, tuple) or not item or not isinstance(item[0], str):
            raise OrderError(f"an order is {type(item).__name__}, not an order")
        tag = item[0]
        if len(item) < 2 or isinstance(item[1], bool) or not isinstance(item[1], int):
            raise OrderError("an order has no robot id")
        rid = item[1]
        if rid not in mine:
            raise OrderError(f"robot {rid} is not one this play drives (it drives "
                             f"{_mine_text(mine)})")
        if rid in out:
            raise OrderError(f"robot {rid} has two orders")
        w = f"robot {rid}'s order"
        if tag == "T" and len(item) == 11:
            _, _, x, y, ori, vmax, kick, chip, dribble, avoid, role = item
            vm = _opt_finite(vmax, f"{w}: max_speed_mps")
            kk = _finite(kick, f"{w}: kick_mps")
            if kk < 0.0:
                raise OrderError(f"{w}: kick_mps is {kk}: a kick speed is 0 (none) or more")
            if vm is not None and vm < 0.0:
                raise OrderError(f"{w}: max_speed_mps is {vm}: a speed limit is positive "
                                 "(None or 0: the controller's own)")
            out[rid] = TargetOrder(rid, _finite(x, f"{w}: x"), _finite(y, f"{w}: y"),
                                   _opt_finite(ori, f"{w}: orientation"),
                                   vm if vm else None, kk, _flag(chip, f"{w}: chip"),
                                   _flag(dribble, f"{w}: dribble"), _flag(avoid, f"{w}: avoid"),
                                   str(role)[:40])
        elif tag == "V" and len(item) == 9:
            _, _, fwd, left, turn, kick, chip, dribble, role = item
            kk = _finite(kick, f"{w}: kick_mps")
            if kk < 0.0:
                raise OrderError(f"{w}: kick_mps is {kk}: a kick speed is 0 (none) or more")
            out[rid] = VelocityOrder(rid, _finite(fwd, f"{w}: forward_mps"),
                                     _finite(left, f"{w}: left_mps"),
                                     _finite(turn, f"{w}: turn_radps"), kk,
                                     _flag(chip, f"{w}: chip"), _flag(dribble, f"{w}: dribble"),
                                     str(role)[:40])
        else:
            raise OrderError(f"{w} is not a Target or a Velocity")
    return out
