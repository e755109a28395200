"""Partial command sets (issue 11): control steps only the robots with something new (a camera
saw the robot again, its target or the referee command changed, or the refresh interval
passed); the relay repeats the others' last command. Every stop still zeroes every robot."""

from __future__ import annotations

import math

from backend import topics
from backend.bus import DataBus
from backend.control.goto import Target
from backend.messages import CommandSet, TargetEntry
from backend.processors import ControlProcessor
from backend.world.referee import RefereeState
from backend.world.state import RobotState, WorldState
from larcmacs_relay.codecs import TEAM_BLUE, Command
from larcmacs_relay.commands import CommandTable

A, B = ("blue", 1), ("blue", 2)


def entry(x: float) -> TargetEntry:
    return TargetEntry(Target(x, 0.0, 0.0), "strategy", role="attacker")


def referee(cmd: str) -> RefereeState:
    return RefereeState(cmd, "NORMAL_FIRST_HALF", 1, None, {}, {}, None, None, 0)


def robot(key: tuple[str, int], x: float, visible: bool = True) -> RobotState:
    return RobotState(key[0], key[1], x, 100.0 * key[1], 0.0, visible=visible)  # type: ignore[arg-type]


class Rig:
    def __init__(self) -> None:
        self.bus = DataBus({}, check_types=True)
        self.c = ControlProcessor(self.bus, max_wait_s=0.05, vision_stale_s=10.0)
        self.c.strategy_stale_s = 3600.0
        self.c.refresh_s = 3600.0  # only what changed, whatever the test machine's pace
        self.world = self.bus.of(topics.WORLD)
        self.cmds = self.bus.of(topics.ROBOT_COMMANDS)
        self.bus.of(topics.TARGETS).write({A: entry(2000.0), B: entry(-2000.0)})

    def see(self, *robots: RobotState) -> None:
        self.world.write(WorldState(0.0, 0, None, tuple(robots)))

    async def tick(self) -> CommandSet | None:
        before = self.cmds.seq
        await self.c.tick()
        return self.cmds.latest_value() if self.cmds.seq > before else None


def ids(cs: CommandSet | None) -> list[tuple[str, int]]:
    assert cs is not None
    return [(c.team, c.id) for c in cs.commands]


def zero(cs: CommandSet) -> bool:
    return all((c.velocity.forward_mps, c.velocity.left_mps, c.velocity.angular_radps)
               == (0.0, 0.0, 0.0) for c in cs.commands)


async def test_a_frame_with_some_robots_commands_those_robots_only() -> None:
    r = Rig()
    a, b = robot(A, 0.0), robot(B, 0.0)
    r.see(a, b)
    assert ids(await r.tick()) == [A, B]
    r.see(robot(A, 5.0), b)  # a camera saw A again; B's state is the world model's old one
    assert ids(await r.tick()) == [A]
    assert sorted(r.c.last_commands) == [A, B]  # B keeps its command (the relay repeats it)
    assert await r.tick() is None  # nothing new at all: no command set
    r.bus.of(topics.TARGETS).write({A: entry(2000.0), B: entry(0.0)})  # B's target moved
    assert ids(await r.tick()) == [B]


async def test_a_halt_zeroes_every_robot_then_every_robot_is_commanded_again() -> None:
    r = Rig()
    a, b = robot(A, 0.0), robot(B, 0.0)
    r.see(a, b)
    await r.tick()
    r.bus.of(topics.REFEREE).write(referee("HALT"))
    halted = await r.tick()
    assert halted is not None and ids(halted) == [A, B] and zero(halted)
    halted = await r.tick()  # in every tick, though nothing changed
    assert halted is not None and ids(halted) == [A, B] and zero(halted)
    r.bus.of(topics.REFEREE).write(referee("FORCE_START"))
    assert ids(await r.tick()) == [A, B]


async def test_the_emergency_stop_stops_all_in_every_tick() -> None:
    r = Rig()
    r.see(robot(A, 0.0), robot(B, 0.0))
    await r.tick()
    r.bus.of(topics.ESTOP).write(True)
    for _ in range(2):
        cs = await r.tick()
        assert cs is not None and cs.stop_all


async def test_a_referee_command_change_commands_every_robot() -> None:
    r = Rig()
    r.see(robot(A, 0.0), robot(B, 0.0))
    await r.tick()
    r.bus.of(topics.REFEREE).write(referee("STOP"))
    assert ids(await r.tick()) == [A, B]


async def test_a_robot_not_seen_is_zeroed_in_every_tick() -> None:
    r = Rig()
    lost = robot(B, 0.0, visible=False)
    r.see(robot(A, 0.0), lost)
    await r.tick()
    r.see(robot(A, 5.0), lost)  # the same lost state object again
    cs = await r.tick()
    assert cs is not None and ids(cs) == [A, B]
    assert cs.commands[1].velocity.forward_mps == 0.0 and cs.commands[1].velocity.left_mps == 0.0
    r.see(robot(A, 10.0))  # B gone from the world altogether
    cs = await r.tick()
    assert cs is not None and ids(cs) == [A, B] and cs.commands[1].velocity.forward_mps == 0.0


async def test_each_robot_steps_with_its_own_dt() -> None:
    """B, skipped while A is stepped, gets the time since its own last step: both
    controllers' clocks (the sum of their dt) agree when both are stepped again."""
    r = Rig()
    b = robot(B, 0.0)
    r.see(robot(A, 0.0), b)
    await r.tick()
    for i in range(1, 4):
        r.see(robot(A, float(i)), b)
        assert ids(await r.tick()) == [A]
    r.see(robot(A, 4.0), robot(B, 1.0))
    assert ids(await r.tick()) == [A, B]
    tel = r.c.telemetry
    assert tel["blue/2"]["t_s"] > 0.0
    assert math.isclose(tel["blue/1"]["t_s"], tel["blue/2"]["t_s"], rel_tol=1e-9, abs_tol=1e-12)


async def test_the_refresh_interval_steps_robots_with_nothing_new() -> None:
    r = Rig()
    r.c.refresh_s = 0.0
    a, b = robot(A, 0.0), robot(B, 0.0)
    r.see(a, b)
    await r.tick()
    assert ids(await r.tick()) == [A, B]


def test_the_relay_keeps_the_robots_a_partial_set_leaves_out() -> None:
    """The relay's side: a set with A only leaves B's latest command in the table, repeated
    until it is older than the command timeout."""
    table = CommandTable(timeout_s=0.1)
    ca, cb = Command(TEAM_BLUE, 1, 1.0, 0.0, 0.0), Command(TEAM_BLUE, 2, -1.0, 0.0, 0.0)
    table.update(ca, 0.0)
    table.update(cb, 0.0)
    table.update(Command(TEAM_BLUE, 1, 0.5, 0.0, 0.0), 0.05)  # a partial set: A only
    assert [c.forward_mps for c in table.due(0.06)] == [0.5, -1.0]
    assert [c.forward_mps for c in table.due(0.12)] == [0.5, 0.0]  # B stale: zero


async def test_control_finds_its_robots_through_the_world_index_as_without_it() -> None:
    """A world from the world model carries each robot's place (``WorldState.index``):
    control looks its robots up there; the same world without it commands the same robots
    from the same states (robots missing, unseen and in another order than the keys)."""
    a, b = Rig(), Rig()
    states = [(robot(B, 10.0), robot(A, 20.0)), (robot(B, 40.0),),
              (robot(A, 50.0, visible=False), robot(B, 60.0))]
    for rs in states:
        index = {(r.team, r.id): i for i, r in enumerate(rs)}
        a.world.write(WorldState(0.0, 0, None, rs, index=index))
        b.see(*rs)
        ids_a, ids_b = ids(await a.tick()), ids(await b.tick())
        assert ids_a == ids_b
        assert {k: v[0] for k, v in a.c._basis.items()} == {k: v[0] for k, v in b.c._basis.items()}
        for k in ids_a:  # stepped from the robot's own state
            if k in a.c._basis:
                assert (a.c._basis[k][0].team, a.c._basis[k][0].id) == k
    # a wrong index would be seen: each robot stepped from the other's state
    rs = (robot(A, 70.0), robot(B, 80.0))
    a.world.write(WorldState(0.0, 0, None, rs, index={A: 1, B: 0}))
    await a.tick()
    assert a.c._basis[A][0] is rs[1]
