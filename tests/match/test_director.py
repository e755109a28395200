"""The match director as a pure state machine: synthetic truth on a fake 60 Hz clock."""

from __future__ import annotations

import math

import pytest

from domain.field import division
from match.config import MatchConfig
from match.director import Director
from match.rules import (
    PLACEMENT_DEFENSE_AREA_OFFSET_MM,
    PLACEMENT_LINE_OFFSET_MM,
    TOO_CLOSE_MM,
    Timing,
    placement_position,
)
from sslpb.ssl_gc_referee_message_pb2 import Referee

from .fake import HZ, FakeWorld, Harness

TICK = 1.0 / HZ
SLACK = 3 * TICK


def commands(h: Harness) -> list[str]:
    return [e["detail"].split()[0] for e in h.d.timeline if e["kind"] == "command"]


def message(h: Harness) -> Referee:
    return Referee.FromString(h.d.encode(123))


# -- the opening kick-off ---------------------------------------------------------------------


def test_opening_halt_stop_prepare_kickoff_blue_then_normal_start_once_settled() -> None:
    h = Harness()
    h.tick()
    assert h.command() == "HALT" and h.d.referee.stage == "NORMAL_FIRST_HALF_PRE"
    t0 = h.elapsed
    t_stop = h.until_command("STOP", 3)
    assert t_stop - t0 == pytest.approx(1.0, abs=SLACK)
    t_prep = h.until_command("PREPARE_KICKOFF_BLUE", 5)
    assert t_prep - t_stop == pytest.approx(2.0, abs=SLACK)
    assert message(h).next_command == Referee.NORMAL_START
    t_start = h.until_command("NORMAL_START", 10)
    # robots stand still: NORMAL_START after the minimum preparation time
    assert t_start - t_prep == pytest.approx(2.0, abs=SLACK)
    assert h.d.referee.stage == "NORMAL_FIRST_HALF"
    h.run(0.5)
    assert not h.d.running  # the ball has not moved: the kick-off is not taken yet
    h.w.ball[0] += 60.0
    h.tick()
    assert h.d.running
    assert commands(h) == ["HALT", "STOP", "PREPARE_KICKOFF_BLUE", "NORMAL_START"]
    assert any(e["kind"] == "ball_in_play" for e in h.d.timeline)


def test_kickoff_waits_for_moving_robots_at_most_five_seconds() -> None:
    h = Harness()
    h.robot("yellow", 3, -3000.0, 1500.0, vx=500.0)  # keeps moving (the fake does not move it)
    t_prep = h.until_command("PREPARE_KICKOFF_BLUE", 5)
    t_start = h.until_command("NORMAL_START", 10)
    assert t_start - t_prep == pytest.approx(5.0, abs=SLACK)


def test_kickoff_not_taken_in_ten_seconds_is_force_started() -> None:
    h = Harness()
    t_start = h.until_command("NORMAL_START", 10)
    t_force = h.until_command("FORCE_START", 12)
    assert t_force - t_start == pytest.approx(10.0, abs=SLACK)
    assert h.d.running


def test_referee_message_carries_stage_time_and_identity() -> None:
    h = Harness(MatchConfig(half_s=60.0, interludes=False))
    h.to_running()
    h.run(2.0)
    m = message(h)
    assert m.IsInitialized()
    assert m.source_identifier.startswith("touchline-match-")
    assert m.stage == Referee.NORMAL_FIRST_HALF and m.command == Referee.NORMAL_START
    assert 57.0e6 < m.stage_time_left < 58.5e6
    assert m.blue_team_on_positive_half is False
    assert m.blue.goalkeeper == 0 and m.yellow.goalkeeper == 0


# -- goals ------------------------------------------------------------------------------------


def test_goal_stops_scores_for_the_attacker_teleports_and_the_conceding_team_kicks_off() -> None:
    h = Harness()
    h.to_running()
    rev = h.d.revision
    h.w.ball = [4600.0, 0.0, 0.0, 0.0]
    h.w.emit("goal", side="positive", x=4521.5, y=0.0, last_touch={"team": "blue", "id": 5})
    h.tick()
    t_goal = h.elapsed
    assert h.command() == "STOP" and h.d.revision > rev
    # blue plays on the negative half: the positive goal is yellow's, so blue scored
    assert (h.d.stats["blue"].goals, h.d.stats["yellow"].goals) == (1, 0)
    assert (message(h).blue.score, message(h).yellow.score) == (1, 0)
    n = len(h.w.teleports)
    t_tp = h.until(lambda: len(h.w.teleports) > n, 3, "teleport")
    assert t_tp - t_goal == pytest.approx(1.5, abs=SLACK)
    assert (h.w.teleports[-1].x, h.w.teleports[-1].y) == (0.0, 0.0)
    h.until_command("PREPARE_KICKOFF_YELLOW", 4)
    h.until_command("NORMAL_START", 6)


def test_after_half_time_sides_switch_and_goals_count_for_the_other_team() -> None:
    h = Harness(MatchConfig(half_s=5.0, interludes=False))
    h.to_running()
    h.until(lambda: h.d.referee.stage == "NORMAL_HALF_TIME", 10, "half time")
    assert h.command() == "HALT" and h.d.referee.blue_team_on_positive_half is True
    h.until(lambda: h.d.referee.stage == "NORMAL_SECOND_HALF_PRE", 5, "second half pre")
    h.until_command("PREPARE_KICKOFF_YELLOW", 5)  # the other team kicks off the second half
    h.until_command("NORMAL_START", 6)
    assert h.d.referee.stage == "NORMAL_SECOND_HALF"
    h.w.ball[0] += 60.0
    h.until(lambda: h.d.running, 1)
    h.w.emit("goal", side="positive", x=4521.5, y=100.0, last_touch=None)
    h.tick()
    # blue defends the positive goal now: yellow scored, blue kicks off
    assert (h.d.stats["blue"].goals, h.d.stats["yellow"].goals) == (0, 1)
    h.until_command("PREPARE_KICKOFF_BLUE", 5)


def test_stages_run_through_the_whole_match_and_it_finishes() -> None:
    h = Harness(MatchConfig(half_s=4.0, interludes=False))
    h.until(lambda: h.d.finished, 120, "end of match")
    stages = [e["detail"] for e in h.d.timeline if e["kind"] == "stage"]
    assert stages == ["NORMAL_FIRST_HALF", "NORMAL_HALF_TIME", "NORMAL_SECOND_HALF_PRE",
                      "NORMAL_SECOND_HALF", "POST_GAME"]
    assert h.command() == "HALT" and message(h).stage == Referee.POST_GAME
    res = h.d.result()
    assert res["finished"] is True
    assert res["stages"]["NORMAL_FIRST_HALF"] >= 4.0


# -- ball out and placement -------------------------------------------------------------------


def test_ball_out_placement_by_the_other_team_then_its_free_kick() -> None:
    h = Harness()
    h.to_running()
    h.w.ball = [1000.0, 3050.0, 0.0, 0.0]
    h.w.emit("ball_out", line="touch", x=1000.0, y=3000.0,
             last_touch={"team": "yellow", "id": 2})
    h.tick()
    assert h.command() == "STOP"
    t_place = h.until_command("BALL_PLACEMENT_BLUE", 2)
    assert h.d.referee.designated_position == (1000.0, 3000.0 - PLACEMENT_LINE_OFFSET_MM)
    m = message(h)
    assert (m.designated_position.x, m.designated_position.y) == (1000.0, 2800.0)
    assert m.next_command == Referee.DIRECT_FREE_BLUE
    h.run(2.0)
    h.w.ball = [1050.0, 2850.0, 300.0, 0.0]  # there, but still rolling: not yet
    h.tick()
    assert h.command() == "BALL_PLACEMENT_BLUE"
    h.w.ball = [1050.0, 2850.0, 0.0, 0.0]
    h.tick()
    assert h.command() == "DIRECT_FREE_BLUE"
    st = h.d.stats["blue"]
    assert (st.placements_ok, st.placements_failed) == (1, 0)
    assert st.placement_times_s[0] == pytest.approx(h.elapsed - t_place, abs=SLACK)
    h.w.ball[0] += 60.0
    h.tick()
    assert h.d.running


def test_placement_timeout_teleports_the_ball_and_counts_a_failure() -> None:
    h = Harness()
    h.to_running()
    h.w.ball = [-2000.0, -3100.0, 0.0, 0.0]
    h.w.emit("ball_out", line="touch", x=-2000.0, y=-3000.0, last_touch={"team": "blue", "id": 1})
    h.tick()
    t_place = h.until_command("BALL_PLACEMENT_YELLOW", 2)
    n = len(h.w.teleports)
    t_tp = h.until(lambda: len(h.w.teleports) > n, 20, "teleport")
    assert t_tp - t_place == pytest.approx(15.0, abs=SLACK)
    assert (h.w.teleports[-1].x, h.w.teleports[-1].y) == (-2000.0, -2800.0)
    st = h.d.stats["yellow"]
    assert (st.placements_ok, st.placements_failed) == (0, 1)
    h.until_command("DIRECT_FREE_YELLOW", 1)


def test_ball_out_with_unknown_last_touch_goes_to_the_team_defending_that_half() -> None:
    h = Harness()
    h.to_running()
    h.w.ball = [4600.0, 2000.0, 0.0, 0.0]
    h.w.emit("ball_out", line="goal", x=4500.0, y=2000.0, last_touch=None)
    h.tick()
    h.until_command("BALL_PLACEMENT_YELLOW", 2)  # yellow defends the positive goal
    assert h.d.referee.designated_position == (4300.0, 2000.0)


def test_placement_position_keeps_off_the_lines_and_the_defence_areas() -> None:
    for div in ("A", "B"):
        f = division(div)
        hl, hw = f.half_length, f.half_width
        for x, y in [(hl + 50, 0.0), (hl + 50, 300.0), (-hl - 50, -200.0), (hl - 100, hw + 40),
                     (0.0, -hw - 80), (hl - 900, 900.0), (-hl, hw)]:
            px, py = placement_position(f, x, y)
            assert abs(px) <= hl - PLACEMENT_LINE_OFFSET_MM + 1e-6
            assert abs(py) <= hw - PLACEMENT_LINE_OFFSET_MM + 1e-6
            for side in (-1, 1):
                assert f.dist_to_defense_area(px, py, side) >= \
                    PLACEMENT_DEFENSE_AREA_OFFSET_MM - 1e-6, (div, x, y, px, py)
    f = division("B")
    assert placement_position(f, 1000.0, 3100.0) == (1000.0, 2800.0)  # unchanged but the offset
    assert f.penalty_mark(1) == (-1500.0, 0.0) and f.penalty_mark(-1) == (1500.0, 0.0)
    assert division("A").penalty_mark(1) == (-2000.0, 0.0)


# -- no progress ------------------------------------------------------------------------------


def test_no_progress_for_fifteen_seconds_stops_then_force_starts() -> None:
    h = Harness(MatchConfig(half_s=300.0, interludes=False))
    t_run = h.to_running()
    h.w.ball[0] += 90.0  # moves less than 100 mm: no progress still
    t_stop = h.until_command("STOP", 20)
    assert t_stop - t_run == pytest.approx(15.0, abs=SLACK)
    t_force = h.until_command("FORCE_START", 5)
    assert t_force - t_stop == pytest.approx(2.0, abs=SLACK)
    assert h.d.result()["events"]["no_progress"] == 1


# -- violations -------------------------------------------------------------------------------


def test_halt_moving_after_the_grace_once_per_robot_per_halt() -> None:
    h = Harness(MatchConfig(timing=Timing(start_halt=6.0), interludes=False))
    h.robot("blue", 1, -2000.0, 1000.0, vx=500.0)
    h.robot("yellow", 2, 2000.0, -1000.0, vx=90.0)  # below 0.1 m/s: allowed
    h.tick()
    assert h.command() == "HALT"
    h.run(2.0 - 2 * TICK)
    assert h.violations("blue", "halt_moving") == (0, 0.0)  # grace: 2 s to brake
    h.run(3 * TICK)
    assert h.violations("blue", "halt_moving")[0] == 1
    h.run(1.0)
    count, seconds = h.violations("blue", "halt_moving")
    assert count == 1 and seconds == pytest.approx(1.0 + 2 * TICK, abs=SLACK)
    h.robot("blue", 1, -2000.0, 1000.0)
    h.run(0.5)
    h.robot("blue", 1, -2000.0, 1000.0, vy=300.0)  # moves again in the same HALT
    h.run(0.5)
    assert h.violations("blue", "halt_moving")[0] == 1
    assert h.violations("yellow", "halt_moving") == (0, 0.0)


def test_stop_speed_and_distance_after_the_grace_each_episode_once() -> None:
    h = Harness(MatchConfig(timing=Timing(start_stop=8.0), interludes=False))
    h.until_command("STOP", 2)
    h.robot("blue", 5, -400.0, 0.0)  # 400 mm from the ball at the centre: too close
    h.robot("blue", 4, -3000.0, 0.0, vx=2000.0)  # too fast
    h.robot("yellow", 5, TOO_CLOSE_MM + 10.0, 0.0)  # just far enough
    h.robot("yellow", 4, 3000.0, 0.0, vx=1550.0)  # within the 0.1 m/s tolerance
    h.run(2.0 - 2 * TICK)
    assert h.violations("blue", "stop_distance") == (0, 0.0)
    assert h.violations("blue", "stop_speed") == (0, 0.0)
    h.run(3 * TICK)
    assert h.violations("blue", "stop_distance")[0] == 1
    assert h.violations("blue", "stop_speed")[0] == 1
    h.run(1.0)
    assert h.violations("blue", "stop_distance")[0] == 1  # one episode
    assert h.violations("blue", "stop_distance")[1] == pytest.approx(1.0 + 2 * TICK, abs=SLACK)
    h.robot("blue", 5, -1000.0, 0.0)  # leaves ...
    h.run(0.5)
    h.robot("blue", 5, -300.0, 0.0)  # ... and comes back: a second episode
    h.run(0.5)
    assert h.violations("blue", "stop_distance")[0] == 2
    assert h.violations("yellow", "stop_distance") == (0, 0.0)
    assert h.violations("yellow", "stop_speed") == (0, 0.0)


def test_set_piece_distance_only_for_the_opponents_of_the_kicking_team() -> None:
    h = Harness()
    h.until_command("PREPARE_KICKOFF_BLUE", 5)
    h.robot("yellow", 5, 450.0, 0.0)  # inside the circle, too close to the ball
    h.robot("blue", 5, -300.0, 0.0)  # the kicker may be close
    h.robot("blue", 4, -2000.0, 0.0, vx=400.0)  # keeps the preparation going to 5 s
    h.run(2.0 - 2 * TICK)
    assert h.violations("yellow", "set_piece_distance") == (0, 0.0)
    h.run(3 * TICK)
    assert h.violations("yellow", "set_piece_distance")[0] == 1
    assert h.violations("blue", "set_piece_distance") == (0, 0.0)
    # at NORMAL_START the kick-off positions are judged: yellow 5 is in the centre circle
    h.until_command("NORMAL_START", 5)
    assert h.violations("yellow", "kickoff_position")[0] == 1
    assert h.violations("blue", "kickoff_position")[0] == 0


def test_kickoff_position_one_kicker_in_the_circle_and_everyone_in_their_own_half() -> None:
    h = Harness()
    h.until_command("PREPARE_KICKOFF_BLUE", 5)
    h.robot("blue", 5, -150.0, 0.0)  # the kicker
    h.robot("blue", 4, -350.0, 200.0)  # a second blue robot in the circle
    h.robot("blue", 3, 600.0, 1500.0)  # in the opponents' half
    h.robot("yellow", 3, -700.0, 2000.0)  # in the opponents' half
    h.until_command("NORMAL_START", 6)
    bad = [(e["team"], e["robot"]) for e in h.d.timeline
           if e["kind"] == "violation" and "kickoff_position" in e["detail"]]
    assert sorted(bad) == [("blue", 3), ("blue", 4), ("yellow", 3)]


def test_placement_distance_for_the_opponents_near_the_ball_to_target_segment() -> None:
    h = Harness()
    h.to_running()
    h.w.ball = [0.0, 3100.0, 0.0, 0.0]
    h.w.emit("ball_out", line="touch", x=0.0, y=3000.0, last_touch={"team": "yellow", "id": 1})
    h.tick()
    h.until_command("BALL_PLACEMENT_BLUE", 2)
    h.w.ball = [-1500.0, 2000.0, 0.0, 0.0]  # the ball is being brought to (0, 2800)
    h.robot("blue", 2, -700.0, 2500.0)  # the placing team may be there
    # yellow 3 crosses the corridor: 1.5 s in, out, 1.5 s in again: no interference
    h.robot("yellow", 3, -1000.0, 2300.0)
    h.run(1.5)
    h.robot("yellow", 3, -1000.0, 1000.0)
    h.tick()
    h.robot("yellow", 3, -1000.0, 2300.0)
    h.run(1.5)
    assert h.violations("yellow", "placement_distance") == (0, 0.0)
    # yellow 2 stays near the middle of the segment: a foul after 2 s on end, not before
    h.robot("yellow", 3, -1000.0, 1000.0)
    h.robot("yellow", 2, -750.0, 2600.0)
    h.run(2.0 - TICK)  # seen inside from the first tick on: 2 s - 2 ticks inside
    assert h.violations("yellow", "placement_distance") == (0, 0.0)
    h.run(3 * TICK)  # 2 s + 1 tick
    assert h.violations("yellow", "placement_distance")[0] == 1
    assert h.violations("blue", "placement_distance") == (0, 0.0)
    # the timeline says where: robot, ball, designated position, distance to the line
    (ev,) = [e for e in h.d.timeline if e["kind"] == "violation"
             and e["detail"].startswith("placement_distance")]
    assert ev["robot"] == 2 and ev["team"] == "yellow"
    dp = h.d.referee.designated_position
    assert dp is not None
    # distance from (-750, 2600) to the segment (-1500, 2000) -> dp, by hand
    ux, uy = dp[0] + 1500.0, dp[1] - 2000.0
    t = max(0.0, min(1.0, (750.0 * ux + 600.0 * uy) / (ux * ux + uy * uy)))
    d = math.hypot(-750.0 - (-1500.0 + t * ux), 2600.0 - (2000.0 + t * uy))
    assert ev["detail"] == (f"placement_distance: robot at (-750, 2600) 0.00 m/s, ball at "
                            f"(-1500, 2000) 960 mm away, placing to ({dp[0]:.0f}, {dp[1]:.0f}),"
                            f" {d:.0f} mm from the corridor's line")


def test_defense_area_in_running_play_after_the_grace_keeper_exempt() -> None:
    h = Harness()
    h.to_running()
    h.robot("blue", 0, -4000.0, 0.0)  # the keeper in its own area: fine
    h.robot("blue", 1, -3500.0 + 80.0, 500.0)  # touches its own area
    h.robot("yellow", 1, -3500.0 - 50.0, -900.0)  # in the opponents' area
    h.robot("yellow", 2, -3500.0 + 100.0, 0.0)  # 100 mm in front of the area: not touching
    h.run(1.0 - 2 * TICK)
    assert h.violations("blue", "defense_area") == (0, 0.0)
    h.run(3 * TICK)
    assert h.violations("blue", "defense_area")[0] == 1
    assert h.violations("yellow", "defense_area")[0] == 1
    bad = {(e["team"], e["robot"]) for e in h.d.timeline
           if e["kind"] == "violation" and e["detail"].startswith("defense_area: robot at")}
    assert bad == {("blue", 1), ("yellow", 1)}


def test_penalty_positions_keeper_on_its_line_others_a_metre_behind_the_ball() -> None:
    cfg = MatchConfig(half_s=10.0)
    cfg.interludes = True
    h = Harness(cfg)
    h.to_running()
    h.until_command("PREPARE_PENALTY_BLUE", 150)
    mark = division("B").penalty_mark(1)  # yellow defends the positive goal
    assert (h.w.teleports[-1].x, h.w.teleports[-1].y) == mark
    # everybody well behind the ball (x < -2500), the kicker at it, yellow's keeper on its line
    for rid in range(6):
        h.robot("blue", rid, -3000.0, -2000.0 + 700.0 * rid)
        h.robot("yellow", rid, -3200.0, -2000.0 + 700.0 * rid)
    h.robot("blue", 5, mark[0] - 150.0, 0.0)  # the kicker
    h.robot("yellow", 0, 4500.0, 300.0)  # keeper on the goal line
    h.robot("yellow", 3, -1000.0, 1500.0)  # in front of the ball
    h.robot("blue", 4, -1800.0, 1500.0)  # only 300 mm behind the ball
    h.until_command("NORMAL_START", 6)
    bad = sorted((e["team"], e["robot"]) for e in h.d.timeline
                 if e["kind"] == "violation" and "penalty_position" in e["detail"])
    assert bad == [("blue", 4), ("yellow", 3)]


def test_collisions_above_one_and_a_half_metres_per_second_against_the_faster_robot() -> None:
    h = Harness()
    h.to_running()
    a_fast = {"team": "blue", "id": 1, "speed_mps": 2.5}
    b_slow = {"team": "yellow", "id": 2, "speed_mps": 0.5}
    h.w.emit("collision", a=a_fast, b=b_slow, relative_speed_mps=2.0, x=0.0, y=0.0)
    h.w.emit("collision", a={"team": "blue", "id": 3, "speed_mps": 1.0},
             b={"team": "yellow", "id": 4, "speed_mps": 1.2}, relative_speed_mps=2.2,
             x=0.0, y=0.0)
    h.w.emit("collision", a=a_fast, b=b_slow, relative_speed_mps=1.4, x=0.0, y=0.0)
    h.tick()
    h.run(0.5)  # the same events stay in the truth: counted once
    assert h.violations("blue", "collision")[0] == 2  # blue 1 (faster), blue 3 (drawn)
    assert h.violations("yellow", "collision")[0] == 1  # yellow 4 (drawn)
    assert h.d.result()["events"]["collision"] == 3


# -- possession and kicks ---------------------------------------------------------------------


def test_possession_goes_to_the_team_closest_within_200_mm_in_running_play() -> None:
    h = Harness(MatchConfig(half_s=300.0, interludes=False))
    h.until_command("NORMAL_START", 10)
    h.robot("yellow", 5, 150.0, 0.0)  # close to the ball before running play: not counted
    h.run(1.0)
    assert h.d.stats["yellow"].possession_s == 0.0
    h.w.ball[0] += 60.0
    h.until(lambda: h.d.running, 1)
    h.run(2.0)
    h.robot("yellow", 5, 2000.0, 0.0)
    h.robot("blue", 5, -100.0, 100.0)
    h.run(3.0)
    h.robot("blue", 5, -1000.0, 0.0)
    h.run(1.0)  # nobody within 200 mm: loose
    res = h.d.result()
    assert h.d.stats["yellow"].possession_s == pytest.approx(2.0, abs=SLACK)
    assert h.d.stats["blue"].possession_s == pytest.approx(3.0, abs=SLACK)
    assert res["loose_ball_s"] == pytest.approx(1.0, abs=SLACK)
    assert res["teams"]["blue"]["possession_pct"] == pytest.approx(60.0, abs=1.0)


def test_kicks_are_counted_from_the_robots_counters() -> None:
    w = FakeWorld()
    w.kicks = {("blue", 1): 2}  # kicks before the first frame do not count
    h = Harness(world=w)
    h.run(0.5)
    assert h.d.result()["teams"]["blue"]["kicks"] == 0
    w.kicks[("blue", 1)] = 4
    w.kicks[("yellow", 3)] = 1
    h.run(0.5)
    res = h.d.result()["teams"]
    assert (res["blue"]["kicks"], res["yellow"]["kicks"]) == (2, 1)
    h2 = Harness()  # no counters in the truth: not measured
    h2.run(0.5)
    assert h2.d.result()["teams"]["blue"]["kicks"] is None


# -- events: dedupe and tolerance -------------------------------------------------------------


def test_events_are_deduplicated_by_seq() -> None:
    h = Harness()
    h.to_running()
    ev = h.w.emit("goal", side="negative", x=-4521.5, y=0.0, last_touch=None)
    h.tick()
    h.run(1.0)  # the goal stays in the truth's recent events
    assert h.d.stats["yellow"].goals == 1
    h.until(lambda: h.d.running, 20, "running after the kick-off")
    h.w.ball[0] += 60.0
    h.run(0.2)
    # an old event delivered again (e.g. out of order) is not counted again
    h.w.events.append(dict(ev))
    h.run(0.5)
    assert h.d.stats["yellow"].goals == 1 and h.d.stats["blue"].goals == 0


def test_missing_event_fields_are_tolerated() -> None:
    h = Harness()
    h.to_running()
    h.w.events.append({"seq": 1, "kind": "goal"})  # no side, no x: ignored
    h.w.events.append({"seq": 2, "kind": "collision", "a": {"team": "blue"}})  # no speed
    h.w.events.append({"seq": 3, "kind": "unknown-kind"})
    h.w.events.append("not an event")  # type: ignore[arg-type]
    h.w.seq = 3
    h.tick()
    assert h.d.running and h.d.stats["blue"].goals == h.d.stats["yellow"].goals == 0
    h.w.ball = [-4600.0, 100.0, 0.0, 0.0]
    h.w.emit("goal", x=-4530.0)  # no side, no t, no last_touch: the side from x
    h.tick()
    assert h.d.stats["blue"].goals == 0 and h.d.stats["yellow"].goals == 1
    h.until(lambda: h.d.running, 20, "running again")
    h.w.ball = [500.0, -3100.0, 0.0, 0.0]
    h.w.last_touch = {"team": "blue", "id": 2}
    h.w.emit("ball_out")  # no line, no position: the ball's, last touch from the truth
    h.tick()
    h.until_command("BALL_PLACEMENT_YELLOW", 2)
    assert h.d.referee.designated_position == (500.0, -2800.0)


def test_malformed_truth_is_tolerated() -> None:
    d = Director(MatchConfig(interludes=False))
    d.tick(0.0, {})
    d.tick(0.1, {"ball": None, "robots": "nope", "events": "nope"})
    d.tick(0.2, {"ball": {"x": "a"}, "robots": [{"team": "red", "id": 1}, {"team": "blue"},
                                                  {"team": "blue", "id": 1, "x": 0.0}]})
    d.tick(0.3, None)
    assert d.referee.command == "HALT"


def test_without_fieldsim_events_goals_and_balls_out_are_seen_from_the_ball() -> None:
    h = Harness(world=FakeWorld(with_events=False))
    h.to_running()
    h.robot("blue", 5, 4300.0, 0.0)
    h.w.ball = [4420.0, 0.0, 0.0, 0.0]  # blue 5 touches it ...
    h.tick()
    h.w.ball = [4540.0, 0.0, 0.0, 0.0]  # ... and it crosses the positive goal line
    h.tick()
    assert h.d.stats["blue"].goals == 1
    assert h.d.result()["events_source"] == "director"
    h.robot("blue", 5, 1000.0, 0.0)
    h.until(lambda: h.d.running, 20, "running again")
    h.robot("yellow", 2, 1000.0, 2900.0)
    h.w.ball = [1000.0, 3010.0, 0.0, 0.0]  # yellow 2 touches it ...
    h.tick()
    h.w.ball = [1000.0, 3030.0, 0.0, 0.0]  # ... over the touch line
    h.tick()
    h.until_command("BALL_PLACEMENT_BLUE", 2)


def test_a_ball_left_outside_in_running_play_is_a_ball_out_after_a_second() -> None:
    h = Harness()
    t_run = h.to_running()
    h.w.ball = [2000.0, -3200.0, 0.0, 0.0]  # outside, and no event (it left during STOP)
    t_stop = h.until_command("STOP", 3)
    assert t_stop - t_run == pytest.approx(1.0, abs=SLACK)
    h.until_command("BALL_PLACEMENT_YELLOW", 2)  # nobody touched it: yellow defends x > 0


# -- a whole match ----------------------------------------------------------------------------


def test_every_command_is_issued_in_a_match_with_interludes() -> None:
    cfg = MatchConfig(half_s=20.0)
    h = Harness(cfg)
    outs = {"done": False}

    def play(hh: Harness) -> None:
        d = hh.d
        # take every set piece: nudge the ball once the kicking command is on
        if d.step is not None and d.step.kind == "kick" and \
                hh.now - d.step_since > 1.0 and hh.now - d.step_since < 1.0 + TICK * 1.5:
            hh.w.ball[0] += 60.0
        # one ball out in the first half
        if d.running and not outs["done"] and d.clock_left < 12.0 and d.half == 1:
            outs["done"] = True
            hh.w.ball = [0.0, 3100.0, 0.0, 0.0]
            hh.w.emit("ball_out", line="touch", x=0.0, y=3000.0,
                      last_touch={"team": "yellow", "id": 1})

    h.on_tick = play
    h.until(lambda: h.d.finished, 600, "end of match")
    res = h.d.result()
    from backend.referee.internal import OPERATOR_COMMANDS
    assert set(res["commands"]) == set(OPERATOR_COMMANDS)
    assert all(res["commands"][c]["count"] >= 1 for c in OPERATOR_COMMANDS)
    assert all(res["interludes"].values())
    assert res["commands"]["TIMEOUT_BLUE"]["seconds"] == pytest.approx(5.0, abs=SLACK)
    assert res["finished"] and res["stage"] == "POST_GAME"
    # the halves' clocks ran for their length (interludes, HALT and timeouts do not count)
    assert h.d.clock_left <= 0.0
    m = message(h)
    assert m.blue.timeouts == 3 and m.yellow.timeouts == 3


def test_interludes_wait_for_running_play_and_time_up_runs_the_rest_before_half_time() -> None:
    h = Harness(MatchConfig(half_s=4.0))
    t_run = h.to_running()
    t_halt = h.until_command("HALT", 10)
    # the first interlude is due at 0.6 s of the clock, but waits for 3 s of running play
    assert t_halt - t_run == pytest.approx(3.0, abs=SLACK)
    h.until(lambda: h.d.referee.stage == "NORMAL_HALF_TIME", 300, "half time")
    first = [i.name for i in h.d.interludes if i.half == 1]
    assert all(i.done for i in h.d.interludes if i.half == 1), first
    assert not any(i.done for i in h.d.interludes if i.half == 2)
    started = [e["detail"] for e in h.d.timeline if e["kind"] == "interlude"]
    assert started == first  # in their order


def test_penalty_preparation_waits_up_to_ten_seconds_for_moving_robots() -> None:
    h = Harness(MatchConfig(half_s=10.0))
    h.to_running()
    t_prep = h.until_command("PREPARE_PENALTY_BLUE", 150)
    h.robot("yellow", 4, -3000.0, 0.0, vx=300.0)  # still on its way
    t_start = h.until_command("NORMAL_START", 12)
    assert t_start - t_prep == pytest.approx(10.0, abs=SLACK)


def test_a_ball_moved_off_its_spot_during_the_preparation_is_put_back_before_normal_start() -> None:
    h = Harness()
    t_prep = h.until_command("PREPARE_KICKOFF_BLUE", 5)
    h.run(0.5)
    h.w.ball = [-900.0, 400.0, 0.0, 0.0]  # pushed away from the centre
    h.w.last_touch = {"team": "blue", "id": 5}
    n = len(h.w.teleports)
    t_start = h.until_command("NORMAL_START", 6)
    assert t_start - t_prep == pytest.approx(2.0, abs=SLACK)  # put back at once: no delay
    assert len(h.w.teleports) == n + 1 and (h.w.teleports[-1].x, h.w.teleports[-1].y) == (0, 0)
    moved = [e for e in h.d.timeline if e["kind"] == "ball_moved"]
    assert [(e["team"], e["robot"]) for e in moved] == [("blue", 5)]
    assert h.d.result()["events"]["ball_moved_in_preparation"] == 1
