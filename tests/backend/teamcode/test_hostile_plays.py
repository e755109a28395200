"""A hostile team play against each limit of the safety envelope, through the real strategy
and control processors (the play in its own worker process): whatever the play orders, the
commands keep the rules. The relay-side limits (arming, its stale stop) act on every command
set whatever made it; tests/integration/test_team_code.py checks them through the relay."""

from __future__ import annotations

import math
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from backend import topics
from backend.teamcode.envelope import MARGIN_MM, R
from domain.field import DIVISION_B

from .helpers import Rig, write

HL = DIVISION_B.half_length
PAD = DIVISION_B.penalty_area_depth

#: drive every robot of its own as far and fast as it can, kicking at full power
RUSH = ("from touchline import Target, Velocity\n"
        "def play(game):\n"
        "    return {{rid: Target({x}, {y}, None, max_speed_mps=99.0, kick_mps=50.0,\n"
        "                        avoid={avoid}) for rid in game.mine}}\n")
SPEED = ("from touchline import Velocity\n"
         "def play(game):\n"
         "    return {{rid: Velocity({fwd}, 0.0, 30.0, kick_mps=50.0) for rid in game.mine}}\n")


def speed(c: Any) -> float:
    return math.hypot(c.velocity.forward_mps, c.velocity.left_mps)


@pytest.fixture
async def rig(tmp_path: Path) -> AsyncIterator[Rig]:
    write(tmp_path, "rush.py", RUSH.format(x=4000.0, y=2500.0, avoid=True))
    write(tmp_path, "fast.py", SPEED.format(fwd=10.0))
    write(tmp_path, "lib/placeholder.py", "X = 1\n")
    r = Rig(tmp_path, "rush")
    try:
        yield r
    finally:
        await r.close()


async def test_halt_stops_every_robot(rig: Rig) -> None:
    await rig.running("rush.py")
    for _ in range(5):
        cmds = await rig.tick()
    assert cmds and max(speed(c) for c in cmds.values()) > 0.0  # it moves them
    rig.referee("HALT")
    cmds = await rig.tick()
    assert cmds and all(speed(c) == 0.0 and c.velocity.angular_radps == 0.0
                        and c.kick_speed_mps == 0.0 for c in cmds.values())
    rig.configure(play="fast")
    await rig.running("fast.py")
    cmds = await rig.tick()
    assert all(speed(c) == 0.0 and c.velocity.angular_radps == 0.0 for c in cmds.values())


async def test_stop_caps_at_1_5_mps_and_no_kick(rig: Rig) -> None:
    rig.referee("STOP")
    rig.configure(play="fast")
    await rig.running("fast.py")
    top = 0.0
    for _ in range(3000):  # the acceleration limit ramps it up to the cap (by control's clock)
        cmds = await rig.tick()
        assert cmds and all(speed(c) <= 1.5 + 1e-9 for c in cmds.values())
        assert all(c.kick_speed_mps == 0.0 for c in cmds.values())
        top = max(top, *(speed(c) for c in cmds.values()))
        if top > 1.49:
            break
    assert top > 1.49  # asked 10 m/s: held at the cap
    rig.configure(play="rush")
    await rig.running("rush.py")
    for _ in range(100):
        cmds = await rig.tick()
        assert all(speed(c) <= 1.5 + 1e-9 and c.kick_speed_mps == 0.0 for c in cmds.values())


async def test_the_ball_distance_at_stop(rig: Rig, tmp_path: Path) -> None:
    write(tmp_path, "to_ball.py", "from touchline import Target\n"
                                  "def play(game):\n"
                                  "    b = game.ball\n"
                                  "    return {rid: Target(b.x + 10.0 * rid, b.y, avoid=False)\n"
                                  "            for rid in game.mine}\n")
    rig.registry.rescan()
    rig.ball = (500.0, 300.0)
    rig.referee("STOP")
    rig.configure(play="to_ball")
    await rig.running("to_ball.py")
    await rig.tick()
    stop_mm = rig.params.strategy.stop_distance_mm
    for rid, e in rig.targets().items():
        assert math.dist((e.target.x, e.target.y), rig.ball) >= stop_mm - 1e-6, rid
        # the path keeps clear of the ball too (planned although the play said avoid=False)
        for px, py in e.path:
            assert math.dist((px, py), rig.ball) >= stop_mm - 20.0 - 1e-6
    assert rig.registry.runs["to_ball.py"].moved_out >= 3
    # running play: the play may go to the ball
    rig.referee("FORCE_START")
    await rig.tick()
    e = rig.targets()[1]
    assert math.dist((e.target.x, e.target.y), rig.ball) == pytest.approx(10.0)


async def test_the_emergency_stop(rig: Rig) -> None:
    await rig.running("rush.py")
    await rig.tick()
    rig.bus.of(topics.ESTOP).write(True)
    await rig.tick()
    cs = rig.bus.of(topics.ROBOT_COMMANDS).latest_value()
    assert cs is not None and cs.stop_all and cs.commands == ()
    assert rig.control.halt_reason == "emergency stop"


async def test_defence_areas(rig: Rig, tmp_path: Path) -> None:
    write(tmp_path, "camp.py", "from touchline import Target\n"
                               "def play(game):\n"
                               "    L = game.field.half_length\n"
                               "    return {0: Target(-L + 300.0, 0.0),\n"
                               "            1: Target(-L + 300.0, 100.0),\n"
                               "            2: Target(L - 300.0, 0.0),\n"
                               "            3: Target(L - 300.0, 0.0, avoid=False)}\n")
    rig.registry.rescan()
    rig.robots[0] = (-3000.0, 0.0, 0.0)
    rig.referee("FORCE_START")  # robot 0 is the referee's goalkeeper
    rig.configure(play="camp")
    await rig.running("camp.py")
    await rig.tick()
    t = rig.targets()
    assert (t[0].target.x, t[0].target.y) == (-HL + 300.0, 0.0)  # the keeper may
    assert t[1].target.x >= -HL + PAD + R + MARGIN_MM  # the others may not
    for rid in (2, 3):
        assert t[rid].target.x <= HL - PAD - R - MARGIN_MM, rid
    assert rig.registry.runs["camp.py"].moved_out >= 3


async def test_the_field(rig: Rig, tmp_path: Path) -> None:
    write(tmp_path, "away.py", RUSH.format(x=20000.0, y=-20000.0, avoid=False))
    rig.registry.rescan()
    rig.configure(play="away")
    await rig.running("away.py")
    await rig.tick()
    for e in rig.targets().values():
        assert abs(e.target.x) <= HL + DIVISION_B.boundary_width - R
        assert abs(e.target.y) <= DIVISION_B.half_width + DIVISION_B.boundary_width - R


async def test_speed_and_acceleration_limits(rig: Rig) -> None:
    lim = rig.params.control.params_for("blue", 1).limits
    rig.configure(play="fast")
    await rig.running("fast.py")
    prev = speed(rig.last[1])
    for _ in range(5000):
        cmds = await rig.tick()
        s = speed(cmds[1])
        assert s <= lim.max_speed_mps + 1e-9
        assert abs(cmds[1].velocity.angular_radps) <= lim.max_angular_radps + 1e-9
        # at most the acceleration limit times the step's dt (within the span measured)
        lo, hi = rig.step_span
        assert s - prev <= lim.max_accel_mps2 * min(0.1, hi - lo) + 1e-9
        prev = s
        if s >= lim.max_speed_mps - 1e-9:
            break
    assert prev == pytest.approx(lim.max_speed_mps)  # asked 10 m/s: held at the limit
    # a Target with a speed limit above the robot's: the robot's own holds
    rig.configure(play="rush")
    await rig.running("rush.py")
    for _ in range(100):
        cmds = await rig.tick()
        assert speed(cmds[1]) <= lim.max_speed_mps + 1e-9


async def test_kick_speed(rig: Rig, tmp_path: Path) -> None:
    await rig.running("rush.py")
    rig.referee("FORCE_START")
    await rig.tick()
    e = rig.targets()[1]
    assert e.kick_speed_mps == 6.5  # asked 50
    cmds = await rig.tick()
    assert cmds[1].kick_speed_mps == 6.5
    rig.referee("STOP")  # the game is stopped: no kick at all
    cmds = await rig.tick()
    assert all(c.kick_speed_mps == 0.0 for c in cmds.values())


async def test_a_play_that_stops_answering_stops_its_robots(rig: Rig, tmp_path: Path) -> None:
    """The stale stop for team code: a spin leaves no last command repeated; the robots get
    a stop entry (zero, no ramp) from the next tick on, and the error is shown."""
    write(tmp_path, "hangs.py", "import time\nfrom touchline import Velocity\nN = [0]\n"
                                "def play(game):\n    N[0] += 1\n"
                                "    while N[0] > 5:\n        pass\n"
                                "    return {rid: Velocity(1.0, 0.0, 0.0) for rid in game.mine}\n")
    rig.registry.rescan()
    rig.configure(play="hangs")
    await rig.running("hangs.py")
    moving = 0
    for _ in range(5):
        cmds = await rig.tick()
        moving += any(speed(c) > 0 for c in cmds.values())
    assert moving >= 3
    cmds = await rig.tick()  # the 6th call spins: this tick gives up after the budget
    assert cmds and all(speed(c) == 0.0 for c in cmds.values())
    assert {s[0] for s in rig.strategy.stopped} == {1, 2, 3}
    for e in rig.targets().values():
        assert e.stop
    for _ in range(3):
        assert all(speed(c) == 0.0 for c in (await rig.tick()).values())


async def test_a_worker_the_machine_does_not_run_is_held_not_killed(
        rig: Rig, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A healthy play whose worker is not scheduled (SIGSTOP, a real process signal, past
    the old wall-clock limit of 0.75 s at a 10 ms budget): its robots get zero commands the
    whole time (never its last command, never driving blind), the reason says the machine
    is busy, and its worker is not ended: after SIGCONT the same worker drives again. (The
    wall-clock backstop is put far off so that a loaded test machine cannot reach it; it is
    tested on its own in test_python_worker.py.)"""
    import os
    import signal

    from backend.teamcode import runner as runner_mod

    monkeypatch.setattr(runner_mod, "WALL_FACTOR", 100.0, raising=False)
    write(tmp_path, "steady.py", SPEED.format(fwd=1.0))
    rig.registry.rescan()
    rig.configure(play="steady", team_budget_ms=10.0)
    await rig.running("steady.py")
    runner = rig.plays.runners["steady.py"]
    run = rig.registry.runs["steady.py"]

    async def ticks_until(cond: Any, what: str) -> None:
        for _ in range(2000):
            await rig.tick()
            if cond():
                return
        raise AssertionError(f"never: {what} ({run})")

    await ticks_until(lambda: all(speed(c) > 0.5 for c in rig.last.values()), "driving")
    pid = runner.pid  # type: ignore[attr-defined]
    os.kill(pid, signal.SIGSTOP)
    held = 0
    try:
        # ticks until the station looked at the unanswered call past the old limit
        for _ in range(20000):
            cmds = await rig.tick()
            watched = getattr(runner, "watched", None)
            if run.state == "error" or (watched is not None and not watched.done()
                                        and watched.seen[0] > 1.0):
                break
            if not any(speed(c) > 0 for c in cmds.values()):
                held += 1
        assert run.state == "running" and runner.pid == pid, run.error  # type: ignore
        cmds = await rig.tick()
        assert cmds and all(speed(c) == 0.0 for c in cmds.values())
        assert {rid for rid, _play, _why in rig.strategy.stopped} == {1, 2, 3}
        assert all(why.startswith("late: its previous tick has not answered yet (the machine "
                                  "is busy") for _rid, _play, why in rig.strategy.stopped), \
            rig.strategy.stopped
        assert held > 0
    finally:
        os.kill(pid, signal.SIGCONT)
    await ticks_until(lambda: all(speed(c) > 0.5 for c in rig.last.values()), "driving again")
    assert run.state == "running" and runner.pid == pid  # type: ignore[attr-defined]
