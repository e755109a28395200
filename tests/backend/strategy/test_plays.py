"""Plays and referee-driven behaviour, on the pure strategy (our frame, no processes)."""

from __future__ import annotations

import itertools
import math
import random

import pytest

from backend.strategy.model import ROBOT_RADIUS_MM, Ball, Bot, Intent
from backend.strategy.plays import Strategy, StrategyInput, Tuning
from backend.strategy.situation import Situation
from domain.field import DIVISION_B

FS = DIVISION_B
R = ROBOT_RADIUS_MM
TU = Tuning()


def team(n: int, seed: int = 1, x_range: tuple[float, float] = (-4000.0, 4000.0)) -> list[Bot]:
    rnd = random.Random(seed)
    return [Bot(i, rnd.uniform(*x_range), rnd.uniform(-2800.0, 2800.0), rnd.uniform(-3, 3))
            for i in range(n)]


BALL = Ball(500.0, 300.0)


def decide(sit: Situation, ball: Ball | None = BALL, play: str = "match",
           n: int = 6, seed: int = 1, keeper: int | None = None, t: float = 0.0,
           strategy: Strategy | None = None, ours: list[Bot] | None = None):
    s = strategy or Strategy()
    inp = StrategyInput(t=t, ours=ours if ours is not None else team(n, seed),
                        theirs=team(n, seed + 100), ball=ball, fs=FS, situation=sit,
                        keeper_id=keeper, play=play, tuning=TU)
    return s.decide(inp), inp


RUNNING = Situation("running", None, "FORCE_START")


def roles(intents) -> list[str]:
    return sorted(it.role for it in intents.values())


def test_match_has_one_keeper_one_attacker_defenders_and_supporters() -> None:
    out, _ = decide(RUNNING)
    assert roles(out) == ["attacker", "defender", "defender", "goalkeeper", "supporter",
                          "supporter"]


def test_the_referee_goalkeeper_id_keeps_the_goalkeeper_role() -> None:
    out, _ = decide(RUNNING, keeper=4)
    assert out[4].role == "goalkeeper"


def test_eleven_robots_and_one_robot_get_sensible_roles() -> None:
    out, _ = decide(RUNNING, n=11)
    rs = roles(out)
    assert rs.count("goalkeeper") == 1 and rs.count("attacker") == 1 and len(rs) == 11
    one, _ = decide(RUNNING, n=1)
    assert roles(one) == ["goalkeeper"]


def test_defend_and_attack_drill_and_formation_plays() -> None:
    d, _ = decide(RUNNING, play="defend")
    assert "attacker" not in roles(d) and roles(d).count("defender") == 5
    a, _ = decide(RUNNING, play="attack-drill")
    assert roles(a).count("attacker") == 1 and "defender" not in roles(a)
    f, _ = decide(RUNNING, play="formation")
    assert set(roles(f)) == {"formation"}
    for it in f.values():
        assert it.x < 0  # formations stay on our half
    i, _ = decide(RUNNING, play="idle")
    assert i == {}


def test_roles_stay_put_under_vision_noise() -> None:
    s = Strategy()
    ours = team(6)
    rnd = random.Random(5)
    first, _ = decide(RUNNING, strategy=s, ours=ours)
    for _ in range(100):
        noisy = [Bot(b.id, b.x + rnd.gauss(0, 20), b.y + rnd.gauss(0, 20), b.orientation)
                 for b in ours]
        ball = Ball(500.0 + rnd.gauss(0, 20), 300.0 + rnd.gauss(0, 20))
        out, _ = decide(RUNNING, ball=ball, strategy=s, ours=noisy)
        assert {k: v.role for k, v in out.items()} == {k: v.role for k, v in first.items()}


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("sit", [
    Situation("stop", None, "STOP"),
    Situation("free-kick", False, "DIRECT_FREE_YELLOW"),
    Situation("kickoff-prepare", False, "PREPARE_KICKOFF_YELLOW"),
])
def test_stop_and_their_set_pieces_keep_every_target_away_from_the_ball(
        seed: int, sit: Situation) -> None:
    ball = Ball(0.0, 0.0) if sit.kind == "kickoff-prepare" else Ball(
        random.Random(seed).uniform(-3000, 3000), random.Random(seed + 1).uniform(-2000, 2000))
    out, _ = decide(sit, ball=ball, seed=seed)
    for it in out.values():
        assert math.dist((it.x, it.y), ball.xy) >= TU.stop_distance_mm - 1e-6
        assert it.kick_speed_mps == 0.0
        assert it.avoid_ball_mm >= 500.0 + 0 * R  # paths keep clear too
    if sit.kind == "stop":
        assert all(it.max_speed_mps is not None and it.max_speed_mps <= 1.5
                   for it in out.values())
        assert "blocker" in roles(out)


@pytest.mark.parametrize("ours_kick", [True, False])
def test_kickoff_positions_in_our_half_outside_the_centre_circle(ours_kick: bool) -> None:
    sit = Situation("kickoff-prepare", ours_kick, "PREPARE_KICKOFF_X")
    out, _ = decide(sit, ball=Ball(0.0, 0.0))
    kickers = [it for it in out.values() if it.role == "kicker"]
    assert len(kickers) == (1 if ours_kick else 0)
    for it in out.values():
        assert it.x <= -R + 1e-6, it  # in our half, the body included
        if it.role != "kicker":
            assert math.hypot(it.x, it.y) >= FS.center_circle_radius + R, it


def test_our_kickoff_kicker_kicks_after_normal_start() -> None:
    s = Strategy()
    ours = team(6)
    kicker_pos = Bot(3, -R - 21.5 - 60.0, 0.0, 0.0)
    ours[3] = kicker_pos
    out, _ = decide(Situation("kickoff", True, "NORMAL_START"), ball=Ball(0.0, 0.0),
                    strategy=s, ours=ours)
    k = [it for it in out.values() if it.role == "kicker"]
    assert len(k) == 1 and k[0].kick_speed_mps > 0


@pytest.mark.parametrize("ours_pen", [True, False])
def test_penalty_positions(ours_pen: bool) -> None:
    ball = Ball(FS.half_length - 2000.0, 0.0) if ours_pen else Ball(-FS.half_length + 2000.0, 0.0)
    out, _ = decide(Situation("penalty-prepare", ours_pen, "PREPARE_PENALTY_X"), ball=ball)
    for it in out.values():
        if it.role == "kicker":
            assert ours_pen and it.x < ball.x
            continue
        if it.role == "goalkeeper":
            if not ours_pen:
                assert abs(it.x - (-FS.half_length)) <= R  # on the goal line
            continue
        if ours_pen:
            assert it.x <= ball.x - 1000.0 - R
        else:
            assert it.x >= ball.x + 1000.0 + R


def test_their_ball_placement_keeps_everyone_off_the_corridor() -> None:
    dp = (-2000.0, 1500.0)
    ball = Ball(1000.0, -500.0)
    out, _ = decide(Situation("placement", False, "BALL_PLACEMENT_YELLOW", designated=dp),
                    ball=ball)
    ax, ay = ball.xy
    vx, vy = dp[0] - ax, dp[1] - ay
    for it in out.values():
        t = max(0.0, min(1.0, ((it.x - ax) * vx + (it.y - ay) * vy) / (vx * vx + vy * vy)))
        d = math.hypot(it.x - (ax + vx * t), it.y - (ay + vy * t))
        assert d >= TU.stop_distance_mm - 1e-6


def test_our_ball_placement_sends_one_placer_that_uses_the_dribbler_when_behind() -> None:
    dp = (-1000.0, 0.0)
    ball = Ball(0.0, 0.0)
    ours = team(6)
    ours[2] = Bot(2, R + 21.5 + 20.0, 0.0, math.pi)  # behind the ball, facing the mark
    out, _ = decide(Situation("placement", True, "BALL_PLACEMENT_BLUE", designated=dp),
                    ball=ball, ours=ours)
    placers = [k for k, it in out.items() if it.role == "placer"]
    assert placers == [2]
    it = out[2]
    assert it.dribbler and it.kick_speed_mps == 0.0
    assert math.dist((it.x, it.y), dp) < 150.0  # carries the ball towards the mark


def test_timeout_parks_robots_along_our_touch_line_and_halt_freezes_targets() -> None:
    out, _ = decide(Situation("timeout", True, "TIMEOUT_BLUE"))
    for it in out.values():
        assert it.role == "parked" and it.x < 0 and it.y < -FS.half_width + 400
    ours = team(6)
    h, _ = decide(Situation("halt", None, "HALT"), ours=ours)
    for b in ours:
        assert (h[b.id].x, h[b.id].y) == (b.x, b.y) and not h[b.id].plan


def test_after_our_free_kick_the_kicker_does_not_take_the_ball_again_at_once() -> None:
    s = Strategy()
    ours = team(6, x_range=(-4000.0, -3000.0))  # everyone else far from the ball
    ball = Ball(1000.0, 0.0)
    ours[1] = Bot(1, 1000.0 - R - 60.0, 0.0, 0.0)  # right behind the ball
    fk, _ = decide(Situation("free-kick", True, "DIRECT_FREE_BLUE"), ball=ball, strategy=s,
                   ours=ours, t=0.0)
    assert fk[1].role == "kicker"
    run, _ = decide(RUNNING, ball=Ball(1500.0, 0.0), strategy=s, ours=ours, t=0.1)
    assert run[1].role != "attacker"
    later, _ = decide(RUNNING, ball=Ball(1500.0, 0.0), strategy=s, ours=ours, t=3.0)
    assert later[1].role == "attacker"


@pytest.mark.parametrize("ball", [Ball(4400.0, 2900.0), Ball(-4450.0, -2950.0),
                                  Ball(0.0, 2990.0)])
def test_keeping_clear_near_a_line_keeps_targets_in_the_field(ball: Ball) -> None:
    for seed in range(4):
        out, _ = decide(Situation("stop", None, "STOP"), ball=ball, seed=seed)
        for it in out.values():
            assert abs(it.x) <= FS.half_length and abs(it.y) <= FS.half_width, it
            assert math.dist((it.x, it.y), ball.xy) >= TU.stop_distance_mm - 1e-6, it


def test_placement_from_against_the_wall_pulls_the_ball() -> None:
    ball = Ball(FS.half_length + 150.0, -1000.0)  # out over the goal line, at the wall
    dp = (FS.half_length - 200.0, -1000.0)
    sit = Situation("placement", True, "BALL_PLACEMENT_BLUE", designated=dp)
    ours = team(6, x_range=(-4000.0, -3000.0))

    def placer_at(x: float) -> Intent:
        ours[3] = Bot(3, x, -1000.0, 0.0)  # on the mark's side, facing the ball
        out, _ = decide(sit, ball=ball, ours=ours)
        assert out[3].role == "placer"
        return out[3]

    approach = placer_at(FS.half_length - 300.0)
    assert approach.x < ball.x and approach.orientation == pytest.approx(0.0)
    assert not approach.dribbler  # not asked to get behind the ball, beyond the wall
    roll_on = placer_at(ball.x - 250.0)
    assert roll_on.dribbler and roll_on.x > ball.x - 250.0
    pull = placer_at(ball.x - 111.5)
    assert pull.dribbler and pull.x == pytest.approx(dp[0] - 111.5)  # backs up to the mark
    assert pull.orientation == pytest.approx(0.0)


def _placing_blue(ball: Ball, dp: tuple[float, float]
                  ) -> tuple[Situation, list[Bot], tuple[float, float]]:
    """Our ball placement to ``dp``: the situation, our team far away, the unit vector from
    the ball to the mark."""
    sit = Situation("placement", True, "BALL_PLACEMENT_BLUE", designated=dp)
    d = (dp[0] - ball.x, dp[1] - ball.y)
    n = math.hypot(*d)
    return sit, team(6, x_range=(-4000.0, -3000.0)), (d[0] / n, d[1] / n)


def test_a_pulling_placer_that_reports_no_contact_rolls_on_instead_of_backing_up() -> None:
    """The robot's own word on the ball decides when it reports it: 50 mm short of the
    ball, within the geometric hold band, a robot saying "no ball" goes on rolling onto it
    (backing up then left the ball behind, again and again); saying "ball" it pulls."""
    ball = Ball(FS.half_length - 40.0, -150.0)  # on their goal line: no room behind it
    dp = (FS.half_length - 2200.0, 0.0)
    sit, ours, u = _placing_blue(ball, dp)
    face = math.atan2(-u[1], -u[0])
    gap = 111.5 + 50.0
    pulls_to = (dp[0] + u[0] * 111.5, dp[1] + u[1] * 111.5)

    def placer(contact: bool | None) -> Intent:
        ours[3] = Bot(3, ball.x + u[0] * gap, ball.y + u[1] * gap, face, contact=contact)
        out, _ = decide(sit, ball=ball, ours=ours)
        assert out[3].role == "placer" and out[3].dribbler
        return out[3]

    no_ball = placer(False)
    assert math.dist((no_ball.x, no_ball.y), ball.xy) < 111.5  # onto the ball
    has_ball = placer(True)
    assert math.dist((has_ball.x, has_ball.y), pulls_to) < 1.0  # back to the mark with it
    silent = placer(None)  # no word: the positions say it holds the ball
    assert math.dist((silent.x, silent.y), pulls_to) < 1.0


def test_a_ball_held_for_pulling_is_pulled_to_the_mark_with_room_behind_it() -> None:
    """Once pulled off the line there is room behind the ball: the placer keeps pulling
    rather than going round the ball to push it (which cost the 30 s in a test)."""
    ball = Ball(FS.half_length - 900.0, -100.0)  # in the field, plenty of room behind
    dp = (FS.half_length - 2200.0, 0.0)
    sit, ours, u = _placing_blue(ball, dp)
    # holding it from the mark's side, facing the ball
    ours[3] = Bot(3, ball.x + u[0] * 111.5, ball.y + u[1] * 111.5, math.atan2(-u[1], -u[0]))
    out, _ = decide(sit, ball=ball, ours=ours)
    it = out[3]
    assert it.role == "placer" and it.dribbler
    assert math.dist((it.x, it.y), (dp[0] + u[0] * 111.5, dp[1] + u[1] * 111.5)) < 1.0
    # not holding it (behind the ball, facing the mark): the usual push
    ours[3] = Bot(3, ball.x - u[0] * 400.0, ball.y - u[1] * 400.0, math.atan2(u[1], u[0]))
    out, _ = decide(sit, ball=ball, ours=ours)
    assert out[3].orientation == pytest.approx(math.atan2(u[1], u[0]))


def _with_max(max_bots: int | None, ours: list[Bot], strategy: Strategy,
              sit: Situation = RUNNING, keeper: int | None = 0) -> dict[int, Intent]:
    inp = StrategyInput(t=0.0, ours=ours, theirs=team(6, 101), ball=BALL, fs=FS, situation=sit,
                        keeper_id=keeper, play="match", tuning=TU, max_bots=max_bots)
    return strategy.decide(inp)


def test_a_card_sends_the_excess_robots_to_the_halfway_line_and_play_goes_on() -> None:
    ours = team(6, 3)
    s = Strategy()
    out = _with_max(6, ours, s)
    assert "substitution" not in roles(out)
    out = _with_max(4, ours, s)  # two yellow cards
    leaving = sorted(rid for rid, it in out.items() if it.role == "substitution")
    assert len(leaving) == 2 and 0 not in leaving  # never the keeper while others can go
    for rid in leaving:
        it = out[rid]
        # within the rules' 1 m of where the halfway line meets a touch line, in the field
        corner = (0.0, math.copysign(FS.half_width, it.y))
        assert math.dist((it.x, it.y), corner) < 1000.0
        assert abs(it.y) <= FS.half_width - R
    # the four others still play the match: keeper, attacker, and so on
    rest = sorted(it.role for rid, it in out.items() if rid not in leaving)
    assert "goalkeeper" in rest and "attacker" in rest and len(rest) == 4
    # the same robots keep leaving while they move, even if others are now nearer the spot
    moved = [Bot(b.id, 0.0, 2500.0, 0.0) if b.id not in leaving else b for b in ours]
    again = _with_max(4, moved, s)
    assert sorted(r for r, it in again.items() if it.role == "substitution") == leaving


def test_robots_leaving_by_the_same_touch_line_get_spots_of_their_own() -> None:
    # every robot on the +y side: the two sent off share a touch line
    ours = [Bot(i, -1500.0 + 400.0 * i, 1200.0 + 100.0 * i, 0.0) for i in range(6)]
    out = _with_max(4, ours, Strategy())
    leaving = [out[rid] for rid in sorted(out) if out[rid].role == "substitution"]
    assert len(leaving) == 2
    a, b = leaving
    assert a.y > 0 and b.y > 0
    assert math.dist((a.x, a.y), (b.x, b.y)) >= 2.0 * R + 50.0  # not one point for two robots
    for it in leaving:  # both still within the rules' 1 m, on our side, in the field
        assert math.dist((it.x, it.y), (0.0, FS.half_width)) < 1000.0
        assert it.x < 0.0 and abs(it.y) <= FS.half_width - R


def test_a_robot_taken_out_is_not_replaced_and_an_expired_card_brings_robots_back() -> None:
    ours = team(6, 3)
    s = Strategy()
    out = _with_max(5, ours, s)
    (gone,) = [rid for rid, it in out.items() if it.role == "substitution"]
    remaining = [b for b in ours if b.id != gone]  # the robot handler took it out
    out = _with_max(5, remaining, s)
    assert "substitution" not in roles(out) and len(out) == 5
    out = _with_max(6, ours, s)  # the card expired and the robot is back
    assert "substitution" not in roles(out) and len(out) == 6


def test_substitution_obeys_stop_and_halt() -> None:
    ours = team(6, 3)
    s = Strategy()
    stop = Situation("stop", None, "STOP")
    out = _with_max(5, ours, s, stop)
    (rid,) = [r for r, it in out.items() if it.role == "substitution"]
    assert out[rid].kick_speed_mps == 0.0
    assert (out[rid].max_speed_mps or 9.9) <= 1.5
    halt = Situation("halt", None, "HALT")
    out = _with_max(5, ours, s, halt)
    b = next(b for b in ours if b.id == rid)
    assert (out[rid].x, out[rid].y) == (b.x, b.y)


def test_the_keeper_leaves_only_when_nobody_else_can() -> None:
    ours = team(2, 5)
    out = _with_max(0, ours, Strategy())
    assert roles(out) == ["substitution", "substitution"]
    out = _with_max(1, ours, Strategy())
    assert out[0].role == "goalkeeper" and out[1].role == "substitution"


@pytest.mark.parametrize("ours_pen", [True, False])
def test_penalty_line_spots_avoid_the_other_team_standing_on_that_line(ours_pen: bool) -> None:
    """Both teams wait behind the ball at a penalty: our spots move off their robots."""
    ball = Ball(FS.half_length - 2000.0, 0.0) if ours_pen else Ball(-FS.half_length + 2000.0, 0.0)
    plain, _ = decide(Situation("penalty-prepare", ours_pen, "PREPARE_PENALTY_X"), ball=ball)
    line = [it for it in plain.values() if it.role == "waiting"]
    assert len(line) >= 3
    # their robots on exactly the spots we would take
    theirs = [Bot(10 + k, it.x, it.y, 0.0) for k, it in enumerate(line)]
    s = Strategy()
    inp = StrategyInput(t=0.0, ours=team(6, 1), theirs=theirs, ball=ball, fs=FS,
                        situation=Situation("penalty-prepare", ours_pen, "PREPARE_PENALTY_X"),
                        play="match", tuning=TU)
    out = s.decide(inp)
    moved = [it for it in out.values() if it.role == "waiting"]
    assert len(moved) == len(line)
    for it in moved:
        assert it.x == line[0].x  # still on the line behind the ball
        assert min(math.dist((it.x, it.y), b.xy) for b in theirs) >= 2 * R + 100.0
        assert abs(it.y) <= FS.half_width - R
    ys = sorted(it.y for it in moved)
    assert all(b - a >= 2 * R + 100.0 for a, b in itertools.pairwise(ys))


def _seg_dist(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    ax, ay = a
    dx, dy = b[0] - ax, b[1] - ay
    L2 = dx * dx + dy * dy
    t = 0.0 if L2 == 0.0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / L2))
    return math.dist(p, (ax + t * dx, ay + t * dy))


@pytest.mark.parametrize("kind,ball", [
    ("penalty-prepare", Ball(-1500.0, 0.0)),  # the GC's division B mark: 6 m from their goal
    ("kickoff-prepare", Ball(0.0, 0.0)),
])
def test_our_kicker_goes_round_the_ball_to_its_spot_behind_it(kind: str, ball: Ball) -> None:
    """Our robots all in front of the ball: the kicker's path to its spot behind the ball
    keeps its body off the ball (driving through it pushed the ball 1-2 m off the penalty
    mark under the ssl-game-controller, which then refused the penalty)."""
    from backend.strategy.model import Frame
    from backend.strategy.navigate import navigate
    from backend.strategy.roles import CONTACT_MM
    ours = [Bot(i, ball.x + 500.0 + 150.0 * i, (-1) ** i * 40.0 * i, math.pi)
            for i in range(6)]
    s = Strategy()
    inp = StrategyInput(t=0.0, ours=ours, theirs=[], ball=ball, fs=FS,
                        situation=Situation(kind, True, "PREPARE_X"), play="match",
                        tuning=TU)
    out = s.decide(inp)
    (kid,) = [rid for rid, it in out.items() if it.role == "kicker"]
    moves = navigate(out, ours, [], ball, FS, Frame(1), 60.0, 120.0)
    pts = [ours[kid].xy, *moves[kid].path]
    assert math.dist(pts[-1], ball.xy) >= CONTACT_MM  # its spot is behind the ball
    assert pts[-1][0] < ball.x
    closest = min(_seg_dist(ball.xy, a, b) for a, b in itertools.pairwise(pts))
    assert closest >= CONTACT_MM, closest


def test_intent_moved_is_replace_of_x_and_y() -> None:
    """``Intent.moved`` lists every field by hand: a field added to ``Intent`` and not to
    ``moved`` would be dropped silently (this test then fails)."""
    import dataclasses

    odd: dict[str, object] = {"role": "r", "x": 1.0, "y": 2.0}
    for f in dataclasses.fields(Intent):
        if f.name in odd:
            continue
        # a value different from the default, of the field's kind
        d = f.default
        odd[f.name] = (not d) if isinstance(d, bool) else 7.5 if isinstance(d, float) else 0.25
    it = Intent(**odd)  # type: ignore[arg-type]
    assert all(getattr(it, k) != f.default for f in dataclasses.fields(Intent)
               for k in [f.name] if f.default is not dataclasses.MISSING)
    assert it.moved(-3.0, 4.0) == dataclasses.replace(it, x=-3.0, y=4.0)
