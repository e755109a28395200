"""What a 6v6 match needs from fieldsim.world: goals, ball out, last touch, dribbler, collisions,
events in the truth. Pure World driven by step(); one test through the server's truth PUB."""

from __future__ import annotations

import json
import math
import random
import socket
import time

import pytest

from fieldsim.config import SimConfig
from fieldsim.protocol import CommandHandler
from fieldsim.server import FieldSimThread
from fieldsim.world import Team, World
from sslnet.multicast import loopback_multicast_ok
from sslpb import grsim_packet_pb2 as grsim_pb
from sslpb import ssl_simulation_robot_control_pb2 as rc_pb

B0 = (Team.BLUE, 0)
Y0 = (Team.YELLOW, 0)


def world(**overrides: object) -> World:
    """Division B (half length 4.5 m, half width 3 m, goal width 1 m), one robot per team,
    both parked far from the action."""
    cfg = SimConfig(blue=1, yellow=1, **overrides)  # type: ignore[arg-type]
    w = World(cfg)
    w.teleport_robot(Team.BLUE, 0, -3.0, -2.5, 0.0)
    w.teleport_robot(Team.YELLOW, 0, -3.0, 2.5, 0.0)
    w.teleport_ball(0.0, 0.0)
    return w


def contact_d(w: World) -> float:
    return w.config.robot_radius_m + w.config.ball_radius_m


def ball_at_front(w: World, key: tuple[Team, int], x: float, y: float, theta: float) -> None:
    """Robot ``key`` at (x, y) facing ``theta`` with the ball touching its kicker."""
    w.teleport_robot(key[0], key[1], x, y, theta)
    d = contact_d(w) + 0.002
    w.teleport_ball(x + d * math.cos(theta), y + d * math.sin(theta))


def kick(w: World, key: tuple[Team, int], speed: float, angle: float = 0.0) -> None:
    w.set_command(key[0], key[1], 0.0, 0.0, 0.0, kick_speed=speed, kick_angle=angle)


def run(w: World, seconds: float) -> None:
    for _ in range(round(seconds / w.dt)):
        w.step()


def kinds(w: World) -> list[str]:
    return [e["kind"] for e in w.events]


def in_goal_box(w: World, side: float) -> bool:
    """Ball entirely inside the goal: behind the line, within the walls."""
    hl = w.geometry.half_length / 1000.0
    depth = w.geometry.goal_depth / 1000.0
    gw2 = w.geometry.goal_width / 2000.0
    r = w.config.ball_radius_m
    x = side * w.ball.x
    return hl + r - 1e-6 <= x <= hl + depth - r + 1e-6 and abs(w.ball.y) <= gw2 - r + 1e-6


# -- goals -------------------------------------------------------------------------------------


@pytest.mark.parametrize("speed", [2.0, 6.0, 10.0])
def test_kicked_ball_scores_once_and_stays_in_goal(speed: float) -> None:
    w = world()
    ball_at_front(w, B0, 3.0, 0.1, 0.0)
    kick(w, B0, speed)
    scored_at = None
    for _ in range(round(4.0 / w.dt)):
        w.step()
        if scored_at is None and w.ball_in_goal is not None:
            scored_at = w.t
        if scored_at is not None:
            assert in_goal_box(w, 1.0), (w.t, w.ball)  # never leaves, never tunnels
    assert kinds(w) == ["goal"]
    goal = w.events[0]
    assert goal["side"] == "positive"
    assert goal["last_touch"] == {"team": "blue", "id": 0}
    assert goal["x"] == pytest.approx(4500.0)
    assert goal["y"] == pytest.approx(100.0, abs=1.0)
    assert goal["t"] == pytest.approx(scored_at)
    assert w.ball_in_goal == "positive"
    assert math.hypot(w.ball.vx, w.ball.vy) == 0.0  # rolled to rest in the goal
    assert w.stats.goals == 1 and w.stats.ball_out == 0


def test_goal_on_negative_side_by_yellow() -> None:
    w = world()
    ball_at_front(w, Y0, -3.5, -0.3, math.pi)
    kick(w, Y0, 5.0)
    run(w, 3.0)
    assert kinds(w) == ["goal"]
    assert w.events[0]["side"] == "negative"
    assert w.events[0]["last_touch"] == {"team": "yellow", "id": 0}
    assert w.ball_in_goal == "negative" and in_goal_box(w, -1.0)


@pytest.mark.parametrize("aim_y", [0.45, -0.45, 0.3])
def test_fast_angled_shot_bounces_inside_goal_without_tunnelling(aim_y: float) -> None:
    """10 m/s towards the inner corners / side walls from close range."""
    w = world()
    x0, y0 = 4.0, -aim_y
    theta = math.atan2(aim_y - y0, 4.6 - x0)
    ball_at_front(w, B0, x0, y0, theta)
    kick(w, B0, 10.0)
    hits = w.stats.goal_wall_bounces
    run(w, 3.0)
    assert kinds(w) == ["goal"]
    assert in_goal_box(w, 1.0)
    assert w.stats.goal_wall_bounces > hits


def test_shot_beside_post_is_ball_out_on_goal_line() -> None:
    w = world()
    ball_at_front(w, B0, 3.0, 0.6, 0.0)  # goal half width 0.5 m: just outside the post
    kick(w, B0, 5.0)
    for _ in range(round(0.8 / w.dt)):
        w.step()
        if w.events:
            break
    assert kinds(w) == ["ball_out"]
    out = w.events[0]
    assert out["line"] == "goal"
    assert out["x"] == pytest.approx(4500.0)
    assert out["y"] == pytest.approx(600.0, abs=1.0)
    assert out["last_touch"] == {"team": "blue", "id": 0}
    assert w.ball_in_goal is None


def test_shot_on_post_bounces_back_no_goal() -> None:
    w = world()
    ball_at_front(w, B0, 3.5, 0.5, 0.0)  # centre on the post's inner edge: hits its front
    kick(w, B0, 4.0)
    run(w, 1.0)
    assert "goal" not in kinds(w)
    assert w.ball.vx < 0.0  # came back off the post (damped)
    assert w.stats.goal_wall_bounces >= 1


def test_chip_over_the_goal_is_ball_out_not_goal() -> None:
    w = world()
    ball_at_front(w, B0, 2.0, 0.0, 0.0)
    kick(w, B0, 8.0, math.radians(45))
    run(w, 2.0)
    assert "goal" not in kinds(w)
    assert kinds(w)[0] == "ball_out" and w.events[0]["line"] == "goal"


def test_teleport_out_of_goal_rearms() -> None:
    w = world()
    ball_at_front(w, B0, 3.0, 0.0, 0.0)
    kick(w, B0, 5.0)
    run(w, 3.0)
    assert kinds(w) == ["goal"] and w.ball_in_goal == "positive"
    # a second later: the ball is still in, no second goal
    run(w, 1.0)
    assert kinds(w) == ["goal"]
    # placed back on the field: re-armed, the next shot scores again
    ball_at_front(w, B0, 3.0, -0.2, 0.0)
    assert w.ball_in_goal is None and w.last_touch is None
    kick(w, B0, 5.0)
    run(w, 3.0)
    assert kinds(w) == ["goal", "goal"]
    assert [e["seq"] for e in w.events] == [1, 2]


def test_teleport_into_goal_is_not_a_goal() -> None:
    w = world()
    w.teleport_ball(4.6, 0.0)
    run(w, 1.0)
    assert w.events == [] and w.ball_in_goal is None
    # rolling out of the goal and back in is a goal again (it was back in the field)
    w.teleport_ball(4.6, 0.0, -1.5, 0.0)
    run(w, 0.5)
    assert abs(w.ball.x) < 4.5
    w.teleport_ball(4.0, 0.0, 2.0, 0.0)
    run(w, 2.0)
    assert kinds(w) == ["goal"] and w.events[0]["last_touch"] is None


# -- ball out ----------------------------------------------------------------------------------


def test_touch_line_ball_out_once_then_rearmed() -> None:
    w = world()
    hw = w.geometry.half_width / 1000.0
    w.teleport_ball(1.0, hw - 0.3, 0.3, 1.5)
    back_in_at = None
    for _ in range(round(4.0 / w.dt)):
        w.step()
        if w.events and back_in_at is None and abs(w.ball.y) <= hw:
            back_in_at = w.t
    assert kinds(w) == ["ball_out"]  # one event, although it hit the wall and came back
    out = w.events[0]
    assert out["line"] == "touch"
    assert out["y"] == pytest.approx(3000.0)
    # where the centre crossed y = 3 m on its straight path: x = 1.0 + 0.3 * (0.3 / 1.5)
    assert out["x"] == pytest.approx(1060.0, abs=1.0)
    assert w.stats.ball_wall_bounces == 1
    assert back_in_at is not None  # the wall bounce brought it back inside: re-armed
    # out again over the same line: a second event
    w.teleport_ball(w.ball.x, w.ball.y, 0.0, 1.5)
    run(w, 1.0)
    assert kinds(w) == ["ball_out", "ball_out"]
    assert w.events[1]["seq"] == w.events[0]["seq"] + 1


def test_ball_rattling_in_the_corner_gives_one_event_per_exit() -> None:
    """Property over a random walk of teleports with velocity: an event happens only on a step
    where the ball is fully out, and two events are separated by a return into the field."""
    w = world()
    hl, hw = w.geometry.half_length / 1000.0, w.geometry.half_width / 1000.0
    r = w.config.ball_radius_m
    rng = random.Random(5)
    for _ in range(12):
        w.teleport_ball(rng.uniform(3.8, 4.4), rng.uniform(2.3, 2.9),
                        rng.uniform(1.5, 4.0), rng.uniform(1.5, 4.0))
        back_in = True
        for _ in range(round(3.0 / w.dt)):
            n = len(w.events)
            w.step()
            inside = abs(w.ball.x) <= hl and abs(w.ball.y) <= hw
            if len(w.events) > n:
                assert back_in
                assert abs(w.ball.x) > hl + r or abs(w.ball.y) > hw + r
                back_in = False
            if inside:
                back_in = True
    assert w.stats.ball_out >= 12
    assert w.stats.ball_wall_bounces > w.stats.ball_out  # it did rattle off the walls


def test_teleport_outside_gives_no_event() -> None:
    w = world()
    w.teleport_ball(0.0, 3.2)
    run(w, 0.5)
    assert w.events == []


# -- last touch --------------------------------------------------------------------------------


def test_last_touch_follows_contacts_and_kicks() -> None:
    w = world()
    assert w.last_touch is None
    w.teleport_robot(Team.BLUE, 0, 0.0, 0.0, math.pi)  # kicker towards -x
    w.teleport_robot(Team.YELLOW, 0, 0.8, 0.0, math.pi)
    w.teleport_ball(0.5, 0.0, -3.0, 0.0)  # rolls into the blue robot's back (~0.13 s)
    run(w, 0.1)
    assert w.last_touch is None
    run(w, 0.4)
    assert w.last_touch == B0
    assert w.ball.vx > 0.0  # bounced back towards yellow
    run(w, 3.0)
    assert w.last_touch == Y0  # reached the yellow robot
    # blue kicks a fresh ball: blue again
    ball_at_front(w, B0, 0.0, -1.0, 0.0)
    assert w.last_touch is None  # teleport resets it
    kick(w, B0, 3.0)
    w.step()
    assert w.last_touch == B0
    assert w.truth()["last_touch"] == {"team": "blue", "id": 0}


def test_ball_out_carries_last_touch() -> None:
    w = world()
    ball_at_front(w, Y0, 0.0, 2.5, math.pi / 2)
    kick(w, Y0, 2.0)
    run(w, 1.0)
    assert kinds(w) == ["ball_out"]
    assert w.events[0]["last_touch"] == {"team": "yellow", "id": 0}


# -- dribbler ----------------------------------------------------------------------------------


def dribble(w: World, seconds: float, forward: float, angular: float, rpm: float = 1000.0,
            key: tuple[Team, int] = B0, kick_speed: float = 0.0) -> None:
    """Command at every physics step, like a 200 Hz sender."""
    for _ in range(round(seconds / w.dt)):
        w.set_command(key[0], key[1], forward, 0.0, angular, kick_speed=kick_speed,
                      dribbler_rpm=rpm)
        w.step()


def test_dribbler_carries_ball_along_curve_and_drops_it() -> None:
    w = world()
    ball_at_front(w, B0, -2.0, -1.0, 0.0)
    r = w.robot(*B0)
    assert r is not None
    start = (w.ball.x, w.ball.y)
    dribble(w, 0.05, 0.0, 0.0)
    assert r.dribbling and w.ball_holder == B0
    max_off = 0.0
    for _ in range(round(3.0 / w.dt)):
        w.set_command(Team.BLUE, 0, 1.0, 0.0, 0.8, dribbler_rpm=1000.0)
        w.step()
        assert r.dribbling
        dx, dy = w.ball.x - r.x, w.ball.y - r.y
        assert math.hypot(dx, dy) == pytest.approx(contact_d(w), abs=1e-9)
        max_off = max(max_off, abs(math.atan2(dy, dx) - r.theta))
        assert w.last_touch == B0
    assert max_off < 1e-9  # always right in front of the kicker
    assert r.theta > 2.0  # turned ~2.4 rad: a curve, not a line
    assert math.hypot(w.ball.x - start[0], w.ball.y - start[1]) > 1.5
    # the ball moves with the robot: its velocity is the robot's plus omega x offset
    ox, oy = w.ball.x - r.x, w.ball.y - r.y
    assert w.ball.vx == pytest.approx(r.vx - r.omega * oy)
    assert w.ball.vy == pytest.approx(r.vy + r.omega * ox)
    assert w.truth()["robots"][0]["dribbling"] is True
    # dribbler off, robot backs away: the ball rolls on with the velocity it had
    v_held = (w.ball.vx, w.ball.vy)
    w.set_command(Team.BLUE, 0, -1.0, 0.0, 0.0, dribbler_rpm=0.0)
    w.step()
    assert not r.dribbling and w.ball_holder is None
    assert math.hypot(w.ball.vx, w.ball.vy) == pytest.approx(math.hypot(*v_held), abs=0.01)
    dribble(w, 1.0, -1.0, 0.0, rpm=0.0)
    assert math.hypot(w.ball.x - r.x, w.ball.y - r.y) > contact_d(w) + 0.3


def test_kick_releases_held_ball() -> None:
    w = world()
    ball_at_front(w, B0, 0.0, 0.0, 0.0)
    dribble(w, 0.5, 0.5, 0.0)
    r = w.robot(*B0)
    assert r is not None and r.dribbling
    dribble(w, 0.005, 0.5, 0.0, kick_speed=3.0)  # kick with the dribbler still on
    assert not r.dribbling and r.kicks == 1
    assert w.ball.vx == pytest.approx(3.0, abs=0.01)
    dribble(w, 0.5, 0.5, 0.0)  # dribbler stays on: the kicked ball is not caught again
    assert not r.dribbling
    assert w.ball.x - r.x > 1.0
    assert w.truth()["robots"][0]["kicks"] == 1


def test_fast_spin_releases_held_ball() -> None:
    w = world()
    ball_at_front(w, B0, 0.0, 0.0, 0.0)
    dribble(w, 0.1, 0.0, 0.0)
    r = w.robot(*B0)
    assert r is not None and r.dribbling
    released_at_omega = None
    for _ in range(round(1.0 / w.dt)):
        w.set_command(Team.BLUE, 0, 0.0, 0.0, 10.0, dribbler_rpm=1000.0)
        w.step()
        if not r.dribbling:
            released_at_omega = r.omega
            break
        assert abs(r.omega) <= w.config.dribbler_max_omega
    assert released_at_omega is not None
    assert released_at_omega > w.config.dribbler_max_omega
    # flung off tangentially at about omega * contact distance
    assert math.hypot(w.ball.vx, w.ball.vy) == pytest.approx(
        w.config.dribbler_max_omega * contact_d(w), rel=0.1)


def test_collision_knocks_held_ball_loose() -> None:
    w = world()
    ball_at_front(w, B0, 0.0, 0.0, 0.0)
    dribble(w, 0.1, 0.0, 0.0)
    rb = w.robot(*B0)
    assert rb is not None and rb.dribbling
    # yellow hits blue from behind-left at speed
    w.teleport_robot(Team.YELLOW, 0, -0.5, 0.3, 0.0, vx=3.0, vy=-1.8)
    for _ in range(round(0.5 / w.dt)):
        w.set_command(Team.BLUE, 0, 0.0, 0.0, 0.0, dribbler_rpm=1000.0)
        w.step()
        if not rb.dribbling:
            break
    assert not rb.dribbling
    assert w.stats.collisions == 1


def test_dribbler_speed_passed_through_by_both_protocols() -> None:
    w = world()
    h = CommandHandler(w)
    msg = rc_pb.RobotControl()
    cmd = msg.robot_commands.add(id=0)
    cmd.move_command.local_velocity.forward = 0.0
    cmd.move_command.local_velocity.left = 0.0
    cmd.move_command.local_velocity.angular = 0.0
    cmd.dribbler_speed = 1500.0
    h.robot_control(Team.BLUE, msg.SerializeToString())
    rb = w.robot(*B0)
    assert rb is not None and rb.command is not None and rb.command.dribbler_rpm == 1500.0
    pkt = grsim_pb.grSim_Packet()
    pkt.commands.timestamp = 0.0
    pkt.commands.isteamyellow = True
    pkt.commands.robot_commands.add(id=0, kickspeedx=0.0, kickspeedz=0.0, veltangent=0.0,
                                    velnormal=0.0, velangular=0.0, spinner=True,
                                    wheelsspeed=False)
    h.grsim_packet(pkt.SerializeToString())
    ry = w.robot(*Y0)
    assert ry is not None and ry.command is not None and ry.command.dribbler_rpm > 0.0


# -- goal walls and robots ----------------------------------------------------------------------


def test_robot_stops_at_the_goal_walls_and_may_enter_the_goal() -> None:
    """The goal is open in front, as a real one: a robot driving into the mouth stops at the
    back wall (a keeper can stand on its goal line, half in the goal: the game controller's
    penalty check wants its centre within a robot radius of the line); the walls stay solid."""
    w = world()
    hl = w.geometry.half_length / 1000.0
    gw2 = w.geometry.goal_width / 2000.0
    depth = w.geometry.goal_depth / 1000.0
    thick = w.config.goal_wall_thickness_m
    R = w.config.robot_radius_m
    rb = w.robot(*B0)
    assert rb is not None
    walls = [(hl + depth, hl + depth + thick, -gw2 - thick, gw2 + thick),  # back
             (hl, hl + depth, gw2, gw2 + thick), (hl, hl + depth, -gw2 - thick, -gw2)]

    def off_walls() -> bool:
        for x0, x1, y0, y1 in walls:
            dx = max(x0 - rb.x, 0.0, rb.x - x1)
            dy = max(y0 - rb.y, 0.0, rb.y - y1)
            if math.hypot(dx, dy) < R - 1e-9:
                return False
        return True

    # straight into the mouth: in, up to the back wall
    w.teleport_robot(Team.BLUE, 0, 4.0, 0.0, 0.0)
    for _ in range(round(2.0 / w.dt)):
        w.set_command(Team.BLUE, 0, 2.0, 0.0, 0.0)
        w.step()
        assert off_walls()
    assert rb.x == pytest.approx(hl + depth - R, abs=1e-6) and rb.vx == 0.0
    # along the boundary beside the goal, into its side wall
    w.teleport_robot(Team.BLUE, 0, hl + 0.1, 1.2, -math.pi / 2)
    for _ in range(round(2.0 / w.dt)):
        w.set_command(Team.BLUE, 0, 2.0, 0.0, 0.0)
        w.step()
        assert off_walls()
    assert rb.y == pytest.approx(gw2 + thick + R, abs=1e-6)
    # teleported onto the back wall: pushed off it on the next step
    w.teleport_robot(Team.BLUE, 0, hl + depth + 0.05, 0.0, 0.0)
    w.step()
    assert off_walls()
    # a keeper on its goal line, half in the goal, stays there
    w.teleport_robot(Team.BLUE, 0, hl - 0.045, 0.0, math.pi)
    run(w, 0.5)
    assert rb.x == pytest.approx(hl - 0.045, abs=1e-6)


# -- collisions --------------------------------------------------------------------------------


def test_head_on_collision_gives_one_event_with_relative_speed() -> None:
    w = world()
    w.teleport_robot(Team.BLUE, 0, -1.0, 0.0, 0.0)
    w.teleport_robot(Team.YELLOW, 0, 1.0, 0.0, math.pi)
    w.teleport_ball(0.0, 2.0)
    for _ in range(round(2.5 / w.dt)):  # contact after ~1.1 s, then keep pushing
        w.set_command(Team.BLUE, 0, 1.0, 0.0, 0.0)
        w.set_command(Team.YELLOW, 0, 0.6, 0.0, 0.0)
        w.step()
    assert kinds(w) == ["collision"]
    ev = w.events[0]
    assert ev["relative_speed_mps"] == pytest.approx(1.6, abs=0.05)
    speeds = {ev["a"]["team"]: ev["a"]["speed_mps"], ev["b"]["team"]: ev["b"]["speed_mps"]}
    assert speeds["blue"] == pytest.approx(1.0, abs=0.02)
    assert speeds["yellow"] == pytest.approx(0.6, abs=0.02)
    assert {ev["a"]["id"], ev["b"]["id"]} == {0}
    assert w.stats.collisions == 1
    # standing in contact without pushing: still no new event; backing off and hitting again: one
    run(w, 0.5)
    for _ in range(round(1.0 / w.dt)):
        w.set_command(Team.BLUE, 0, -0.5, 0.0, 0.0)
        w.step()
    for _ in range(round(1.5 / w.dt)):
        w.set_command(Team.BLUE, 0, 1.0, 0.0, 0.0)
        w.step()
    assert kinds(w) == ["collision", "collision"]
    assert w.events[1]["relative_speed_mps"] == pytest.approx(1.0, abs=0.05)


def test_crowd_collisions_counted_once_per_contact() -> None:
    """Everybody drives to the centre (6 v 6) and keeps pushing: one event per new contact,
    not one per step in contact."""
    w = World(SimConfig(blue=6, yellow=6))
    pair_steps_in_contact = 0
    last_event_step: dict[frozenset[tuple[str, int]], int] = {}
    for step in range(round(3.0 / w.dt)):
        for r in w.robots.values():
            dx, dy = -r.x, -r.y
            n = math.hypot(dx, dy) or 1.0
            c, s = math.cos(r.theta), math.sin(r.theta)
            w.set_command(r.team, r.id, 2.0 * (c * dx + s * dy) / n,
                          2.0 * (-s * dx + c * dy) / n, 0.0)
        n_events = len(w.events)
        w.step()
        for ev in w.events[n_events:]:
            assert ev["kind"] == "collision"
            pair = frozenset({(ev["a"]["team"], ev["a"]["id"]), (ev["b"]["team"], ev["b"]["id"])})
            assert len(pair) == 2
            assert step - last_event_step.get(pair, -100) > 1  # never on consecutive steps
            last_event_step[pair] = step
            assert 0.0 <= ev["relative_speed_mps"] <= 2 * w.config.robot_max_speed
        robots = list(w.robots.values())
        pair_steps_in_contact += sum(
            1 for i, a in enumerate(robots) for b in robots[i + 1:]
            if math.hypot(a.x - b.x, a.y - b.y) < 2 * w.config.robot_radius_m + 0.001
        )
    assert w.stats.collisions >= 5
    assert w.stats.collisions == kinds(w).count("collision")
    assert w.stats.collisions * 10 < pair_steps_in_contact


# -- truth and events --------------------------------------------------------------------------


def test_truth_carries_match_state_and_is_json() -> None:
    w = world()
    t0 = w.truth()
    assert t0["events"] == [] and t0["last_touch"] is None and t0["ball_in_goal"] is None
    assert t0["stats"] == {"kicks": 0, "goals": 0, "ball_out": 0, "collisions": 0}
    ball_at_front(w, B0, 3.0, 0.0, 0.0)
    kick(w, B0, 5.0)
    run(w, 2.0)
    truth = json.loads(json.dumps(w.truth()))
    # existing keys and units unchanged
    assert {"t", "ball", "robots"} <= set(truth)
    assert set(truth["ball"]) == {"x", "y", "z", "vx", "vy"}
    assert truth["ball"]["x"] == pytest.approx(w.ball.x * 1000.0)
    robot = next(r for r in truth["robots"] if r["team"] == "blue")
    assert {"team", "id", "x", "y", "orientation", "vx", "vy", "omega", "C"} <= set(robot)
    assert robot["x"] == pytest.approx(3000.0) and robot["kicks"] == 1
    assert robot["dribbling"] is False
    # new keys
    assert truth["ball_in_goal"] == "positive"
    assert truth["last_touch"] == {"team": "blue", "id": 0}
    assert truth["stats"] == {"kicks": 1, "goals": 1, "ball_out": 0, "collisions": 0}
    (goal,) = truth["events"]
    assert goal["kind"] == "goal" and goal["seq"] == 1 and 0.0 < goal["t"] <= truth["t"]
    assert set(goal) == {"seq", "t", "kind", "side", "x", "y", "last_touch"}


def test_events_bounded_and_seq_increasing() -> None:
    w = world()
    hw = w.geometry.half_width / 1000.0
    n = 300
    for _ in range(n):  # each: a ball rolling over the touch line
        w.teleport_ball(0.0, hw - 0.05, 0.0, 1.0)
        run(w, 0.2)
    kept, in_truth = w.config.events_kept, w.config.truth_events
    assert w.stats.ball_out == n
    assert len(w.events) == kept
    seqs = [e["seq"] for e in w.events]
    assert seqs == list(range(n - kept + 1, n + 1))
    truth_events = w.truth()["events"]
    assert len(truth_events) == in_truth
    assert [e["seq"] for e in truth_events] == seqs[-in_truth:]
    times = [e["t"] for e in w.events]
    assert times == sorted(times)


def test_small_event_bounds_from_config() -> None:
    w = world(events_kept=10, truth_events=3)
    for _ in range(25):
        w.teleport_ball(0.0, 2.95, 0.0, 1.0)
        run(w, 0.2)
    assert len(w.events) == 10 and w.events[-1]["seq"] == 25
    assert [e["seq"] for e in w.truth()["events"]] == [23, 24, 25]
    with pytest.raises(ValueError):
        SimConfig(events_kept=5, truth_events=6).validate()


# -- through the server ------------------------------------------------------------------------


@pytest.mark.skipif(not loopback_multicast_ok(), reason="no multicast on loopback")
def test_goal_event_in_published_truth() -> None:
    import zmq

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    tcp_port = s.getsockname()[1]
    s.close()
    endpoint = f"tcp://127.0.0.1:{tcp_port}"
    cfg = SimConfig(
        vision_port=random.SystemRandom().randint(20000, 40000), control_port=0, blue_port=0,
        yellow_port=0, grsim_port=0, truth_pub=endpoint, blue=1, yellow=0,
    )
    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, b"truth")
    try:
        with FieldSimThread(cfg) as handle:
            sub.connect(endpoint)
            assert sub.poll(5000), "no truth published"
            sub.recv_multipart()  # connected and receiving

            def shoot(sim: object) -> None:
                w = sim.world  # type: ignore[attr-defined]
                ball_at_front(w, B0, 3.5, 0.2, 0.0)
                kick(w, B0, 5.0)

            handle.call(shoot)
            goal = None
            deadline = time.monotonic() + 5.0
            while goal is None and time.monotonic() < deadline:
                if not sub.poll(100):
                    continue
                topic, body = sub.recv_multipart()
                assert topic == b"truth"
                truth = json.loads(body)
                goals = [e for e in truth["events"] if e["kind"] == "goal"]
                if goals:
                    goal = goals[0]
                    assert truth["ball_in_goal"] == "positive"
                    assert truth["stats"]["goals"] == 1
                    assert "t_unix" in truth
            assert goal is not None, "no goal event in the published truth"
            assert goal["side"] == "positive"
            assert goal["last_touch"] == {"team": "blue", "id": 0}
            assert goal["y"] == pytest.approx(200.0, abs=2.0)
    finally:
        sub.close()
        ctx.term()
