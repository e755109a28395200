"""Navigation reuses a robot's path search while it still holds (paths/memory.py's PathMemory): the
same path while nothing moved, a clear detour re-checked instead of searched, a new search
once something changed or the plan got old."""

from __future__ import annotations

from backend.strategy.model import Bot, Frame, Intent
from backend.strategy.navigate import navigate
from backend.strategy.paths.memory import (
    DETOUR_MAX_AGE_S,
    REUSE_MAX_AGE_S,
    REUSE_MM,
    PathMemory,
)
from domain.field import DIVISION_B

FS = DIVISION_B
ME = Bot(1, -2000.0, 0.0, 0.0)
GOAL = Intent("supporter", 2000.0, 0.0, None)
OTHER = Bot(7, 0.0, 0.0, 0.0)


def drive(memory: PathMemory | None, me: Bot = ME, other: Bot = OTHER,
          goal: Intent = GOAL, now: float = 0.0) -> tuple[tuple[float, float], ...]:
    moves = navigate({me.id: goal}, [me], [other], None, FS, Frame(1), 60.0, 120.0,
                     memory=memory, now=now)
    return moves[me.id].path


def test_a_still_scene_is_searched_once() -> None:
    mem = PathMemory()
    first = drive(mem)
    assert len(first) > 1 and first == drive(None)
    for k in range(1, 10):
        assert drive(mem, now=0.05 * k) == first
    assert (mem.searches, mem.reused) == (1, 9)


def test_vision_noise_keeps_the_plan_a_real_move_does_not() -> None:
    mem = PathMemory()
    first = drive(mem)
    d = REUSE_MM * 0.5
    jitter = drive(mem, me=Bot(1, ME.x + d, ME.y - d, 0.0), other=Bot(7, d, d, 0.0), now=0.05)
    assert jitter == first and mem.searches == 1
    # the other robot steps aside onto the old path: searched again, a different way
    moved = drive(mem, other=Bot(7, first[0][0], first[0][1], 0.0), now=0.1)
    assert mem.searches == 2 and moved != first


def wall(dx: float = 0.0, dy: float = 0.0) -> list[Bot]:
    """Three robots in a line across the way (their discs overlap: one long obstacle)."""
    return [Bot(7 + k, dx, dy + 300.0 * k, 0.0) for k in (-1, 0, 1)]


def test_a_clear_detour_is_kept_while_the_robot_drives_it_then_searched_again() -> None:
    mem = PathMemory()

    def go(me: Bot, dx: float, now: float, dy: float = 0.0) -> tuple[tuple[float, float], ...]:
        moves = navigate({1: GOAL}, [me], wall(dx, dy), None, FS, Frame(1), 60.0, 120.0,
                         memory=mem, now=now)
        return moves[1].path

    first = go(ME, 0.0, 0.0)
    assert len(first) > 2
    # the robot has reached the first waypoint and the wall stepped back a little, away from
    # the way on (not the same inputs any more): the rest of the detour is still clear,
    # kept, the waypoint the robot has reached dropped
    wx, wy = first[0]
    on = go(Bot(1, wx, wy, 0.0), -40.0, 0.1)
    assert mem.searches == 1 and on == first[1:]
    # still clear: kept until it is too old (the way may be shorter now)
    assert go(Bot(1, wx, wy, 0.0), -40.0, DETOUR_MAX_AGE_S - 0.01) == first[1:]
    assert mem.searches == 1
    go(Bot(1, wx, wy, 0.0), -40.0, DETOUR_MAX_AGE_S + 0.01)
    assert mem.searches == 2
    # the wall moves onto the detour: searched again at once
    mem.plans.clear()
    first = go(ME, 0.0, 0.0)
    side = 30.0 if first[0][1] > 0 else -30.0
    assert go(ME, 0.0, 0.05, side) != first
    assert mem.searches == 4


def test_an_old_plan_is_searched_again_even_in_a_still_scene() -> None:
    mem = PathMemory()
    drive(mem)
    drive(mem, now=REUSE_MAX_AGE_S + 0.01)
    assert mem.searches == 2


def test_a_moved_goal_is_searched_again() -> None:
    mem = PathMemory()
    drive(mem)
    drive(mem, goal=Intent("supporter", 2000.0, 3 * REUSE_MM, None), now=0.05)
    assert mem.searches == 2


def test_straight_drives_are_not_remembered() -> None:
    mem = PathMemory()
    drive(mem)
    assert 1 in mem.plans
    assert drive(mem, other=Bot(7, 0.0, 2000.0, 0.0), now=0.05) == ((GOAL.x, GOAL.y),)
    assert not mem.plans
    assert mem.searches == 1


def test_the_pause_comes_between_two_robots() -> None:
    """The processor's pause (the GIL handed to the station thread) runs between robots."""
    calls: list[int] = []
    ours = [Bot(k, -2000.0, 500.0 * k, 0.0) for k in range(4)]
    intents = {b.id: Intent("supporter", 2000.0, b.y, None) for b in ours}
    moves = navigate(intents, ours, [], None, FS, Frame(1), 60.0, 120.0, memory=PathMemory(),
                     pause=lambda: calls.append(len(calls)))
    assert len(moves) == 4 and len(calls) == 3


def test_a_robot_at_no_finite_position_is_refused_as_before() -> None:
    """The tick's obstacles are checked once; one that is not finite still makes a search
    refuse (Obstacles' own check), with or without the memory."""
    import math

    import pytest

    bad = Bot(8, math.nan, 0.0, 0.0)
    for mem in (PathMemory(), None):
        with pytest.raises(ValueError, match="finite"):
            navigate({ME.id: GOAL}, [ME], [OTHER, bad], None, FS, Frame(1), 60.0, 120.0,
                     memory=mem)
