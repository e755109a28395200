"""Navigation slows a robot that drives at another one close by (crash fouls are judged on the
relative speed; paths avoid robots where they are, not where they will be)."""

from __future__ import annotations

import pytest

from backend.strategy.model import Bot, Frame, Intent
from backend.strategy.navigate import GUARD_MM, GUARD_SPEED_MPS, navigate
from domain.field import DIVISION_B

FS = DIVISION_B


def move_of(me: Bot, other: Bot, target: tuple[float, float],
            max_speed: float | None = None) -> float | None:
    intents = {me.id: Intent("supporter", target[0], target[1], None, max_speed_mps=max_speed)}
    moves = navigate(intents, [me], [other], None, FS, Frame(1), 60.0, 120.0)
    return moves[me.id].max_speed_mps


@pytest.mark.parametrize("other_xy,capped", [
    ((500.0, 0.0), True),  # straight ahead, 500 mm
    ((400.0, 300.0), True),  # 37 deg off the way, 500 mm
    ((0.0, 500.0), False),  # beside: 90 deg
    ((-500.0, 0.0), False),  # behind
    ((GUARD_MM + 50.0, 0.0), False),  # ahead but further than the guard
])
def test_speed_is_capped_only_with_a_robot_close_ahead(other_xy: tuple[float, float],
                                                       capped: bool) -> None:
    me = Bot(1, 0.0, 0.0, 0.0)
    other = Bot(7, *other_xy, 0.0)
    got = move_of(me, other, (3000.0, 0.0))
    assert (got == GUARD_SPEED_MPS) if capped else (got is None)


def test_a_lower_limit_of_the_intent_is_kept() -> None:
    me, other = Bot(1, 0.0, 0.0, 0.0), Bot(7, 500.0, 0.0, 0.0)
    assert move_of(me, other, (3000.0, 0.0), max_speed=0.4) == 0.4
    assert move_of(me, other, (3000.0, 0.0), max_speed=2.5) == GUARD_SPEED_MPS
