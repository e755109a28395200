"""The safety envelope's own rules (pure): targets out of forbidden places to the nearest
allowed point, kicks capped, a velocity's push into a forbidden area removed."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from backend.teamcode.envelope import (
    MARGIN_MM,
    VELOCITY_GUARD_MM,
    R,
    Rules,
    allowed,
    check_target,
    check_velocity,
)
from backend.teamcode.orders import TargetOrder, VelocityOrder
from domain.field import DIVISION_B

FS = DIVISION_B
HL, HW = FS.half_length, FS.half_width
PAD = FS.penalty_area_depth
PAW = FS.penalty_area_width / 2.0
RUNNING = Rules(FS, "running", None, (0.0, 0.0), keeper_id=None)


def target(x: float, y: float, rid: int = 1, **kw: object) -> TargetOrder:
    return TargetOrder(rid, x, y, **kw)  # type: ignore[arg-type]


def test_a_target_in_our_defence_area_is_moved_out_to_the_nearest_side() -> None:
    o, changed = check_target(target(-HL + PAD - 50.0, 300.0), RUNNING)
    assert changed and "moved" in changed[0]
    assert o.x == -HL + PAD + R + MARGIN_MM + 1.0 and o.y == 300.0  # out by its front side
    o, _ = check_target(target(-HL + 200.0, PAW - 10.0), RUNNING)
    assert o.y == PAW + R + MARGIN_MM + 1.0 and o.x == -HL + 200.0  # out by its long side


def test_the_goalkeeper_may_be_in_our_defence_area() -> None:
    rules = Rules(FS, "running", None, (0.0, 0.0), keeper_id=0)
    o, changed = check_target(target(-HL + 200.0, 0.0, rid=0), rules)
    assert not changed and (o.x, o.y) == (-HL + 200.0, 0.0)
    o, changed = check_target(target(-HL + 200.0, 0.0, rid=1), rules)
    assert changed  # not the keeper


def test_their_defence_area_and_its_extra_distance_while_stopped() -> None:
    o, changed = check_target(target(HL - 100.0, 0.0), RUNNING)
    assert changed and o.x == HL - PAD - R - MARGIN_MM - 1.0
    # running: right outside their area is fine; stopped: 0.2 m more
    edge = HL - PAD - R - MARGIN_MM - 10.0
    assert not check_target(target(edge, 0.0), RUNNING)[1]
    stop = Rules(FS, "stop", None, (-3000.0, 0.0))
    o, changed = check_target(target(edge, 0.0), stop)
    assert changed and o.x == HL - PAD - R - MARGIN_MM - 200.0 - 1.0


def test_the_field_walls() -> None:
    o, changed = check_target(target(HL + 1000.0, -HW - 2000.0), RUNNING)
    assert changed
    assert (o.x, o.y) == (HL + FS.boundary_width - R, -HW - FS.boundary_width + R)
    # inside the boundary (outside the lines) is allowed: robots fetch balls there
    assert not check_target(target(0.0, HW + 100.0), RUNNING)[1]


def test_the_ball_distance_at_stop_and_their_set_pieces() -> None:
    ball = (1000.0, 500.0)
    for rules in (Rules(FS, "stop", None, ball, stop_distance_mm=650.0),
                  Rules(FS, "free-kick", False, ball, stop_distance_mm=650.0),
                  Rules(FS, "kickoff-prepare", False, ball, stop_distance_mm=650.0)):
        o, changed = check_target(target(1100.0, 500.0), rules)
        assert changed and math.dist((o.x, o.y), ball) >= 650.0 - 1e-6
        assert math.dist((o.x, o.y), ball) < 660.0  # the nearest: radially out
    # our own free kick, and running play: the ball is ours to take
    for rules in (Rules(FS, "free-kick", True, ball), RUNNING):
        assert not check_target(target(1100.0, 500.0), rules)[1]


def test_their_ball_placement_keeps_the_corridor_clear() -> None:
    rules = Rules(FS, "placement", False, (0.0, 0.0), designated=(2000.0, 0.0),
                  stop_distance_mm=650.0)
    o, changed = check_target(target(1000.0, 100.0), rules)
    assert changed and abs(o.y) >= 650.0 - 1e-6  # out of the capsule, sideways


def test_a_ball_by_our_area_at_stop_still_finds_a_point() -> None:
    """Two forbidden shapes touching: the point found is allowed by both."""
    rules = Rules(FS, "stop", None, (-HL + PAD + 100.0, 0.0), stop_distance_mm=650.0)
    o, changed = check_target(target(-HL + PAD + 150.0, 0.0), rules)
    assert changed and allowed((o.x, o.y), 1, rules)


@given(st.floats(-8000, 8000), st.floats(-6000, 6000), st.floats(-4500, 4500),
       st.floats(-3000, 3000), st.sampled_from(["running", "stop", "free-kick", "placement"]),
       st.booleans())
def test_whatever_the_target_the_result_is_allowed(x: float, y: float, bx: float, by: float,
                                                   kind: str, ours: bool) -> None:
    rules = Rules(FS, kind, ours, (bx, by), designated=(bx + 500.0, by),
                  stop_distance_mm=650.0)
    o, _ = check_target(target(x, y), rules)
    assert allowed((o.x, o.y), 1, rules)
    if allowed((x, y), 1, rules):
        assert (o.x, o.y) == (x, y)


def test_kicks_are_capped_at_the_rules() -> None:
    o, changed = check_target(target(0.0, 0.0, kick_mps=20.0), RUNNING)
    assert o.kick_mps == 6.5 and changed
    v, changed = check_velocity(VelocityOrder(1, 0.0, 0.0, 0.0, kick_mps=9.0), 0.0, 0.0, 0.0,
                                RUNNING)
    assert v.kick_mps == 6.5 and changed


def test_a_velocity_into_a_forbidden_area_is_removed_near_it() -> None:
    # robot facing +x (heading 0), 50 mm in front of their grown area, driving at it
    x = HL - PAD - R - MARGIN_MM - 50.0
    v, changed = check_velocity(VelocityOrder(1, 2.0, 0.5, 1.0), x, 0.0, 0.0, RUNNING)
    assert changed and abs(v.forward_mps) < 1e-9 and v.left_mps == 0.5 and v.turn_radps == 1.0
    # driving away, or farther than the guard: untouched
    assert not check_velocity(VelocityOrder(1, -2.0, 0.5, 0.0), x, 0.0, 0.0, RUNNING)[1]
    far = x - VELOCITY_GUARD_MM - 10.0
    assert not check_velocity(VelocityOrder(1, 2.0, 0.0, 0.0), far, 0.0, 0.0, RUNNING)[1]
    # in the robot's frame: facing -y (heading -pi/2) next to our area's long side
    y = PAW + R + MARGIN_MM + 30.0
    v, changed = check_velocity(VelocityOrder(2, 1.0, 0.0, 0.0), -HL + 300.0, y,
                                -math.pi / 2, RUNNING)
    assert changed and abs(v.forward_mps) < 1e-9
    # towards the ball at STOP, close to its circle
    stop = Rules(FS, "stop", None, (0.0, 0.0), stop_distance_mm=650.0)
    v, changed = check_velocity(VelocityOrder(1, 1.0, 0.0, 0.0), -700.0, 0.0, 0.0, stop)
    assert changed and abs(v.forward_mps) < 1e-9
