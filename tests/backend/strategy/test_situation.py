"""The referee command stream as our team's situation."""

from __future__ import annotations

import pytest

from backend.strategy.situation import SituationTracker


def run(tr: SituationTracker, cmd: str, counter: int, ball: tuple[float, float] = (0.0, 0.0),
        team: str = "blue"):
    return tr.update(cmd, counter, team, ball)


@pytest.mark.parametrize("cmd,team,key", [
    ("HALT", "blue", "halt"),
    ("STOP", "blue", "stop"),
    ("FORCE_START", "blue", "running"),
    ("PREPARE_KICKOFF_BLUE", "blue", "our-kickoff-prepare"),
    ("PREPARE_KICKOFF_BLUE", "yellow", "their-kickoff-prepare"),
    ("PREPARE_PENALTY_YELLOW", "yellow", "our-penalty-prepare"),
    ("DIRECT_FREE_YELLOW", "blue", "their-free-kick"),
    ("INDIRECT_FREE_BLUE", "blue", "our-free-kick"),
    ("BALL_PLACEMENT_BLUE", "blue", "our-placement"),
    ("BALL_PLACEMENT_BLUE", "yellow", "their-placement"),
    ("TIMEOUT_YELLOW", "blue", "their-timeout"),
    ("GOAL_BLUE", "blue", "stop"),
])
def test_each_command_maps_to_the_situation_of_our_team(cmd: str, team: str, key: str) -> None:
    s = run(SituationTracker(), cmd, 1, team=team)
    assert s.key == key
    assert s.text()  # every situation has a line for the coach


def test_no_referee_means_free_play() -> None:
    s = SituationTracker().update(None, 0, "blue", (0.0, 0.0))
    assert s.key == "running" and "No referee" in s.text()


def test_kickoff_lasts_until_the_ball_moved_then_the_game_runs() -> None:
    tr = SituationTracker()
    assert run(tr, "PREPARE_KICKOFF_YELLOW", 1).key == "their-kickoff-prepare"
    assert run(tr, "NORMAL_START", 2).key == "their-kickoff"
    assert run(tr, "NORMAL_START", 2, (30.0, 0.0)).key == "their-kickoff"  # < 50 mm
    assert run(tr, "NORMAL_START", 2, (80.0, 0.0)).key == "running"
    assert run(tr, "NORMAL_START", 2, (0.0, 0.0)).key == "running"  # stays running


def test_free_kick_runs_once_the_ball_moved() -> None:
    tr = SituationTracker()
    assert run(tr, "DIRECT_FREE_BLUE", 5, (1000.0, 0.0)).key == "our-free-kick"
    assert run(tr, "DIRECT_FREE_BLUE", 5, (1100.0, 0.0)).key == "running"
    # a new free kick (new counter) starts over
    assert run(tr, "DIRECT_FREE_BLUE", 6, (1100.0, 0.0)).key == "our-free-kick"


def test_penalty_after_normal_start_lasts_until_the_kick_then_the_game_runs() -> None:
    tr = SituationTracker()
    run(tr, "PREPARE_PENALTY_BLUE", 1, (3000.0, 0.0))
    assert run(tr, "NORMAL_START", 2, (3000.0, 0.0)).key == "our-penalty"
    assert run(tr, "NORMAL_START", 2, (3030.0, 0.0)).key == "our-penalty"
    assert run(tr, "NORMAL_START", 2, (4000.0, 0.0)).key == "running"
    assert run(tr, "STOP", 3, (4000.0, 0.0)).key == "stop"


def test_normal_start_without_a_prepare_is_running_and_unknown_commands_are_careful() -> None:
    tr = SituationTracker()
    run(tr, "STOP", 1)
    assert run(tr, "NORMAL_START", 2).key == "running"
    assert run(tr, "SOMETHING_NEW", 3).key == "stop"
