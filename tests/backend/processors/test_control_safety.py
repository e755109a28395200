"""The control processor's own safety: a stalled strategy stops every robot; kicks are never
sent while the referee has the game stopped; speed caps from the strategy hold."""

from __future__ import annotations

import math

from backend import topics
from backend.bus import DataBus
from backend.control.follow import next_waypoint
from backend.control.goto import Target
from backend.messages import CommandSet, TargetEntry
from backend.processors import ControlProcessor
from backend.world.referee import RefereeState
from backend.world.state import RobotState, WorldState


def setup(entry: TargetEntry) -> tuple[ControlProcessor, DataBus]:
    bus = DataBus({})
    c = ControlProcessor(bus, max_wait_s=0.05, vision_stale_s=10.0)
    bus.of(topics.WORLD).write(WorldState(
        0.0, 0, None, (RobotState("blue", 1, 0.0, 0.0, 0.0),)))
    bus.of(topics.TARGETS).write({("blue", 1): entry})
    return c, bus


def referee(cmd: str) -> RefereeState:
    return RefereeState(cmd, "NORMAL_FIRST_HALF", 1, None, {}, {}, None, None, 0)


async def last(c: ControlProcessor, bus: DataBus) -> CommandSet:
    await c.tick()
    cs = bus.of(topics.ROBOT_COMMANDS).latest_value()
    assert cs is not None
    return cs


async def test_a_stalled_strategy_zeroes_every_robot() -> None:
    entry = TargetEntry(Target(2000.0, 0.0, 0.0), "strategy", role="attacker")
    c, bus = setup(entry)
    c.strategy_stale_s = 10.0
    moving = await last(c, bus)
    assert moving.commands[0].velocity.forward_mps > 0 and c.halt_reason == ""
    c.strategy_stale_s = 0.0  # the targets are now "older" than allowed
    stopped = await last(c, bus)
    v = stopped.commands[0].velocity
    assert (v.forward_mps, v.left_mps, v.angular_radps) == (0.0, 0.0, 0.0)
    assert c.halt_reason.startswith("strategy stalled")


async def test_no_kick_under_stop_but_kicks_in_play_and_speed_caps_hold() -> None:
    entry = TargetEntry(Target(3000.0, 0.0, 0.0), "strategy", role="attacker",
                        kick_speed_mps=5.0, max_speed_mps=0.4)
    c, bus = setup(entry)
    c.strategy_stale_s = 10.0
    bus.of(topics.REFEREE).write(referee("FORCE_START"))
    for _ in range(30):  # let the controller ramp up to its cap (a camera sees it each time)
        seen = RobotState("blue", 1, 0.0, 0.0, 0.0)
        bus.of(topics.WORLD).write(WorldState(0.0, 0, None, (seen,)))
        cs = await last(c, bus)
    cmd = cs.commands[0]
    assert cmd.kick_speed_mps == 5.0
    assert math.hypot(cmd.velocity.forward_mps, cmd.velocity.left_mps) <= 0.4 + 1e-9
    bus.of(topics.REFEREE).write(referee("STOP"))
    assert (await last(c, bus)).commands[0].kick_speed_mps == 0.0


def _near(t: Target, x: float, y: float, o: float | None) -> bool:
    return math.isclose(t.x, x, abs_tol=1e-6) and math.isclose(t.y, y, abs_tol=1e-6) \
        and t.orientation == o


def test_next_waypoint_skips_reached_points_and_keeps_the_final_heading() -> None:
    # right-angle corners: the controller is aimed exactly at each waypoint
    e = TargetEntry(Target(700.0, 0.0, 1.0), "strategy",
                    path=((0.0, 300.0), (700.0, 300.0), (700.0, 0.0)))
    assert _near(next_waypoint(e, 0.0, 0.0), 0.0, 300.0, 1.0)
    assert _near(next_waypoint(e, 10.0, 250.0), 700.0, 300.0, 1.0)  # first one reached
    assert _near(next_waypoint(e, 400.0, 300.0), 700.0, 300.0, 1.0)  # between the two
    assert next_waypoint(e, 690.0, 290.0) == Target(700.0, 0.0, 1.0)  # never back
    assert next_waypoint(e, 0.0, 400.0) != Target(700.0, 0.0, 1.0)


def test_a_gentle_turn_aims_past_the_waypoint_by_cos_squared_of_the_turn() -> None:
    """45 deg at (300, 300): aimed on along the robot's line by min(rest, 600) * cos^2."""
    e = TargetEntry(Target(1000.0, 0.0, 1.0), "strategy",
                    path=((300.0, 300.0), (700.0, 300.0), (1000.0, 0.0)))
    t = next_waypoint(e, 0.0, 0.0)
    ext = 600.0 * 0.5  # rest = 400 + 424 mm > 600; cos^2(45 deg) = 0.5
    assert _near(t, 300.0 + ext / math.sqrt(2), 300.0 + ext / math.sqrt(2), 1.0)
    # the second corner (45 deg) with only 424 mm left after it
    t = next_waypoint(e, 400.0, 300.0)
    assert _near(t, 700.0 + 424.26406871192853 * 0.5, 300.0, 1.0)
    # straight on through a waypoint: the whole rest, capped at 600 mm
    e = TargetEntry(Target(2000.0, 0.0, None), "strategy",
                    path=((500.0, 0.0), (900.0, 0.0), (2000.0, 0.0)))
    assert _near(next_waypoint(e, 0.0, 0.0), 1100.0, 0.0, None)
    assert next_waypoint(TargetEntry(Target(5.0, 5.0, None), "operator"), 0.0, 0.0) == \
        Target(5.0, 5.0, None)


async def test_a_world_written_from_old_frames_is_stale_vision() -> None:
    """Staleness is judged by when the relay received the newest frame merged, not only by
    when the world topic was last written: a world rewritten from nothing new stops the
    robots."""
    import time

    entry = TargetEntry(Target(2000.0, 0.0, 0.0), "strategy", role="attacker")
    c, bus = setup(entry)
    c.strategy_stale_s = 10.0
    c.vision_stale_s = 0.3
    world = bus.of(topics.WORLD)
    world.write(WorldState(0.0, time.time_ns(), None, (RobotState("blue", 1, 0.0, 0.0, 0.0),)))
    moving = await last(c, bus)
    assert moving.commands[0].velocity.forward_mps > 0 and c.halt_reason == ""
    world.write(WorldState(0.0, time.time_ns() - 2_000_000_000, None,
                           (RobotState("blue", 1, 0.0, 0.0, 0.0),)))
    stopped = await last(c, bus)
    v = stopped.commands[0].velocity
    assert (v.forward_mps, v.left_mps, v.angular_radps) == (0.0, 0.0, 0.0)
    assert c.halt_reason.startswith("no vision for 2.")


async def test_control_never_commands_the_other_team_unless_the_station_allows_it() -> None:
    """A target for the other team (an operator's click, a bug in a play) reaches no robot
    unless the station says the output can address that team (a simulator, and the
    operator's safety.other_team_in_simulator)."""
    bus = DataBus({})
    c = ControlProcessor(bus, max_wait_s=0.05, vision_stale_s=10.0)
    c.strategy_stale_s = 10.0
    robots = (RobotState("blue", 3, 0.0, 0.0, 0.0), RobotState("yellow", 3, 0.0, 0.0, 0.0))
    bus.of(topics.WORLD).write(WorldState(0.0, 0, None, robots))
    entry = TargetEntry(Target(2000.0, 0.0, 0.0), "operator", role="operator")
    bus.of(topics.TARGETS).write({("blue", 3): entry, ("yellow", 3): entry})
    cs = await last(c, bus)
    assert [(k.team, k.id) for k in cs.commands] == [("blue", 3)]
    c.may_drive_other_team = lambda: True
    cs = await last(c, bus)
    # the newly allowed robot is commanded; blue 3 has nothing new and keeps its command
    assert [(k.team, k.id) for k in cs.commands] == [("yellow", 3)]
    assert sorted(c.last_commands) == [("blue", 3), ("yellow", 3)]
