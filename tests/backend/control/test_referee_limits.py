import math

import pytest

from backend.control.goto import LocalVelocity
from backend.control.referee_limits import referee_limits

FAST = LocalVelocity(2.4, -1.8, 1.0)  # 3 m/s


def speed(v: LocalVelocity) -> float:
    return math.hypot(v.forward_mps, v.left_mps)


def test_halt_is_zero_at_once() -> None:
    assert referee_limits(FAST, "HALT") == LocalVelocity.zero()


@pytest.mark.parametrize("command", ["STOP", "GOAL_BLUE"])
def test_stop_limits_speed_keeping_direction(command: str) -> None:
    v = referee_limits(FAST, command)
    assert speed(v) == pytest.approx(1.5)
    assert v.forward_mps / v.left_mps == pytest.approx(FAST.forward_mps / FAST.left_mps)
    assert v.angular_radps == FAST.angular_radps
    slow = LocalVelocity(0.3, 0.1, 0.0)
    assert referee_limits(slow, command) == slow


def test_ball_placement_limits_only_the_other_team() -> None:
    assert speed(referee_limits(FAST, "BALL_PLACEMENT_YELLOW", our_team="blue")) == \
        pytest.approx(1.5)
    assert referee_limits(FAST, "BALL_PLACEMENT_BLUE", our_team="blue") == FAST
    assert speed(referee_limits(FAST, "BALL_PLACEMENT_BLUE")) == pytest.approx(1.5)


@pytest.mark.parametrize("command", [None, "FORCE_START", "NORMAL_START", "TIMEOUT_BLUE",
                                     "DIRECT_FREE_YELLOW"])
def test_other_commands_pass(command: str | None) -> None:
    assert referee_limits(FAST, command) == FAST


def test_the_operators_stop_cap_and_the_strategys_cap_apply_once_with_the_rules() -> None:
    # the operator's lower STOP cap binds under every slow command, never in running play
    assert speed(referee_limits(FAST, "STOP", stop_speed_mps=0.8)) == pytest.approx(0.8)
    assert speed(referee_limits(FAST, "BALL_PLACEMENT_YELLOW", our_team="blue",
                                stop_speed_mps=0.8)) == pytest.approx(0.8)
    assert referee_limits(FAST, "FORCE_START", stop_speed_mps=0.8) == FAST
    # the strategy's cap binds whatever the command; the lower of the caps wins
    assert speed(referee_limits(FAST, "FORCE_START", max_speed_mps=0.75)) == pytest.approx(0.75)
    assert speed(referee_limits(FAST, "STOP", max_speed_mps=2.0)) == pytest.approx(1.5)
    assert referee_limits(FAST, "HALT", max_speed_mps=2.0) == LocalVelocity.zero()
